#include "guide_inspector_view.h"

#include "thread_priority.h"

#include <imgui.h>

#include <algorithm>
#include <cstdio>

namespace candela {

GuideInspectorView::~GuideInspectorView() { join(); }

void GuideInspectorView::join() {
  if (worker_.joinable()) worker_.join();
}

bool GuideInspectorView::finished() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return !running_ && (result_ != nullptr || !error_.empty());
}

std::string GuideInspectorView::summary() const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (result_) return title_ + ": " + inspectionSummary(*result_);
  return error_;
}

void GuideInspectorView::request(const SceneDesc& desc, int x, int y) {
  desc_ = desc, x_ = x, y_ = y, open_ = true;
  pending_ = true;
  if (!busy()) start();
}

void GuideInspectorView::start() {
  join();  // the last one has finished: joining is immediate
  pending_ = false;
  running_ = true;
  const SceneDesc desc = desc_;
  const int x = x_, y = y_;
  const int seed = secondarySeed_;
  worker_ = std::thread([this, desc, x, y, seed] {
    lowerThisThreadsPriority();
    std::shared_ptr<const GuideInspection> r;
    std::string error;
    try {
      auto scene = Scene::build(desc);
      GuideInspectOptions options;
      options.secondary_seed = seed;
      options.light_samples = 128;
      r = std::make_shared<GuideInspection>(inspectGuide(*scene, x, y, options));
    } catch (const std::exception& e) {
      error = e.what();
    }
    char title[160];
    std::snprintf(title, sizeof title, "pixel (%d, %d), %s, %s ray", x, y, desc.strategy.preset.c_str(), seed >= 0 ? "secondary" : "camera");
    std::lock_guard<std::mutex> lock(mutex_);
    result_ = r;
    error_ = error;
    title_ = title;
    running_ = false;
  });
}

void GuideInspectorView::draw() {
  if (pending_ && !busy()) start();
  if (!open_) return;
  ImGui::SetNextWindowSize(ImVec2(620, 380), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowPos(ImVec2(40, 60), ImGuiCond_FirstUseEver);
  if (!ImGui::Begin("Guide inspector", &open_)) {
    ImGui::End();
    return;
  }
  std::shared_ptr<const GuideInspection> r;
  std::string title, error;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    r = result_, title = title_, error = error_;
  }
  bool secondary = secondarySeed_ >= 0;
  if (ImGui::Checkbox("secondary ray of the path with seed", &secondary)) {
    secondarySeed_ = secondary ? 1 : -1;
    request(desc_, x_, y_);
  }
  if (secondary) {
    ImGui::SameLine();
    ImGui::SetNextItemWidth(90);
    if (ImGui::InputInt("##seed", &secondarySeed_)) {
      secondarySeed_ = std::max(0, secondarySeed_);
      request(desc_, x_, y_);
    }
  }
  if (busy()) ImGui::TextDisabled("inspecting...");
  if (!error.empty()) ImGui::TextColored(ImVec4(1.0f, 0.45f, 0.35f, 1.0f), "%s", error.c_str());
  if (!r) {
    ImGui::TextDisabled("Ctrl+click a pixel to inspect its distance densities");
    ImGui::End();
    return;
  }
  ImGui::Text("%s: optical depth %.3g over [%.3g, %.3g]", title.c_str(), r->opticalDepth, r->tIn, r->tOut);
  const ImU32 colours[4] = {IM_COL32(235, 235, 235, 255), IM_COL32(230, 130, 50, 255), IM_COL32(70, 150, 230, 255), IM_COL32(90, 200, 110, 255)};
  ImGui::TextColored(ImColor(colours[0]), "ideal mu_s L_s T");
  ImGui::SameLine();
  ImGui::TextColored(ImColor(colours[1]), "guided V=%.3g", r->varianceGuided);
  ImGui::SameLine();
  ImGui::TextColored(ImColor(colours[2]), "tracked V=%.3g", r->varianceTracked);
  ImGui::SameLine();
  ImGui::TextColored(ImColor(colours[3]), "MIS (q %.2g) V=%.3g", r->mixtureProbability, r->varianceMis);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("V = int f^2/p / (int f)^2: 1 is perfect importance sampling");
  if (!r->note.empty()) ImGui::TextDisabled("%s", r->note.c_str());

  const ImVec2 avail = ImGui::GetContentRegionAvail();
  const ImVec2 size(std::max(200.0f, avail.x), std::max(120.0f, avail.y));
  const ImVec2 origin = ImGui::GetCursorScreenPos();
  ImGui::InvisibleButton("inspector chart", size);
  ImDrawList* draw = ImGui::GetWindowDrawList();
  draw->AddRectFilled(origin, ImVec2(origin.x + size.x, origin.y + size.y), IM_COL32(25, 25, 28, 255));
  double yMax = 0.0;
  for (size_t i = 0; i < r->t.size(); ++i) yMax = std::max({yMax, r->ideal[i], r->guidedPdf[i], r->trackedPdf[i], r->misPdf[i]});
  if (r->t.empty() || !(yMax > 0.0)) {
    ImGui::End();
    return;
  }
  yMax *= 1.05;
  const float left = 6.0f, bottom = 16.0f;
  const double x0 = r->tIn, x1 = std::max(r->tOut, r->tIn + 1e-6f);
  auto map = [&](double t, double v) {
    return ImVec2(origin.x + left + static_cast<float>((t - x0) / (x1 - x0)) * (size.x - 2 * left),
                  origin.y + 4.0f + static_cast<float>(1.0 - std::min(v, yMax) / yMax) * (size.y - bottom - 8.0f));
  };
  auto line = [&](const std::vector<double>& v, ImU32 colour) {
    for (size_t i = 1; i < r->t.size(); ++i) draw->AddLine(map(r->t[i - 1], v[i - 1]), map(r->t[i], v[i]), colour, 1.6f);
  };
  line(r->trackedPdf, colours[2]);
  line(r->misPdf, colours[3]);
  if (r->varianceGuided > 0.0) line(r->guidedPdf, colours[1]);
  line(r->ideal, colours[0]);
  for (const auto& k : r->knots) draw->AddCircleFilled(map(k.t, k.value), 3.0f, colours[1]);
  char label[64];
  std::snprintf(label, sizeof label, "t = %.3g", x0);
  draw->AddText(ImVec2(origin.x + left, origin.y + size.y - bottom + 1), IM_COL32(150, 150, 150, 255), label);
  std::snprintf(label, sizeof label, "t = %.3g", x1);
  draw->AddText(ImVec2(origin.x + size.x - 70, origin.y + size.y - bottom + 1), IM_COL32(150, 150, 150, 255), label);
  std::snprintf(label, sizeof label, "max %.3g / length", yMax);
  draw->AddText(ImVec2(origin.x + left, origin.y + 4), IM_COL32(150, 150, 150, 255), label);
  if (ImGui::IsItemHovered()) {
    const float u = (ImGui::GetIO().MousePos.x - origin.x - left) / (size.x - 2 * left);
    const size_t i = std::min(r->t.size() - 1, static_cast<size_t>(std::max(0.0f, u) * r->t.size()));
    ImGui::SetTooltip("t = %.4g\nideal %.4g\nguided %.4g\ntracked %.4g\nMIS %.4g\nT %.4g, mu_s %.4g, L_s %.4g", r->t[i], r->ideal[i],
                      r->guidedPdf[i], r->trackedPdf[i], r->misPdf[i], r->transmittance[i], r->sigmaS[i], r->inScattered[i]);
  }
  ImGui::End();
}

}  // namespace candela
