#include "viewer.h"

#include "color_pipeline.h"
#include "comparison_session.h"
#include "error_chart.h"
#include "gl_display.h"
#include "guide_inspector_view.h"
#include "image_io.h"
#include "param_editor.h"
#include "render_session.h"

#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <deque>
#include <filesystem>
#include <fstream>
#include <optional>
#include <iostream>
#include <thread>

namespace candela {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

std::string defaultScenePath() { return std::string(CANDELA_ASSET_DIR) + "/scenes/torch-in-mist.json"; }

// A path next to `wanted` that does not exist yet: NAME.png, NAME-2.png, ...
std::string freshPath(const fs::path& wanted) {
  fs::path p = wanted;
  for (int i = 2; fs::exists(p) || fs::exists(fs::path(p).replace_extension(".exr")); ++i)
    p = wanted.parent_path() / (wanted.stem().string() + "-" + std::to_string(i) + wanted.extension().string());
  return p.string();
}

fs::file_time_type modificationTime(const std::string& path) {
  std::error_code ec;
  auto t = fs::last_write_time(path, ec);
  return ec ? fs::file_time_type{} : t;
}

// Edge-triggered key presses from GLFW (ImGui 1.86 has no named keys for letters).
class Keys {
 public:
  bool pressed(GLFWwindow* w, int key) {
    const bool down = glfwGetKey(w, key) == GLFW_PRESS;
    const bool was = down_[key];
    down_[key] = down;
    return down && !was;
  }

 private:
  bool down_[GLFW_KEY_LAST + 1] = {};
};

class Viewer {
 public:
  Viewer(GLFWwindow* window, const ViewerOptions& options)
      : window_(window), options_(options), session_(RenderOptions{options.threads, 32}) {
    session_.setNotify([] { glfwPostEmptyEvent(); });  // thread-safe: wakes the event wait below
    colors_ = ColorPipeline::load(options.ocioConfig);
    if (!colors_.message().empty()) report(colors_.message());
    display_ = colors_.resolve(display_);
    gl_ = std::make_unique<GlDisplay>();
    applyDisplay();
    if (options.afterSpp > 0) limits_.spp = options.afterSpp;
    session_.setLimits(limits_);
    if (!options.panes.empty()) {
      startComparisonMode(options.scenePath.empty() ? defaultScenePath() : options.scenePath);
      return;
    }
    openScene(options.scenePath.empty() ? defaultScenePath() : options.scenePath, options.settings, options.preset);
  }

  int run();

 private:
  // --- scene and edits ---
  void openScene(const std::string& path, const std::vector<std::string>& settings = {}, const std::string& preset = "") {
    try {
      SceneDesc desc = loadSceneDesc(path, settings, preset);
      scenePath_ = path;
      sceneSettings_ = settings;
      scenePreset_ = preset;
      sceneTime_ = modificationTime(path);
      pendingOpen_ = session_.open(desc);
    } catch (const std::exception& e) {
      report(std::string(e.what()) + (haveScene_ ? " (still showing the last good scene)" : ""));
      if (!haveScene_) scenePath_ = path;  // watch it, so fixing the file loads it
      sceneTime_ = modificationTime(path);
    }
  }
  // Validates the edited description (the same checks as a scene file) and sends it to the renderer.
  // A bad value is reported and the fields return to the last good state.
  void submitEdit() {
    try {
      SceneDesc valid = parseSceneDesc(sceneToJson(edited_), edited_.path);
      valid.path = edited_.path;
      if (compare_) {  // every pane shares the scene and camera: restart them together
        edited_ = valid;
        restartComparison();
        return;
      }
      beginLatency(session_.edit(valid));
    } catch (const std::exception& e) {
      report(std::string("edit rejected: ") + e.what());
      if (frame_ && frame_->scene) edited_ = *frame_->scene;
    }
  }
  void applySettingEdit(const std::string& assignment) {
    try {
      Json doc = sceneToJson(edited_);
      applySetting(doc, assignment, edited_.path + " (edit " + assignment + ")");
      SceneDesc valid = parseSceneDesc(doc, edited_.path);
      edited_ = valid;
      beginLatency(session_.edit(valid));
    } catch (const std::exception& e) {
      report(std::string("edit rejected: ") + e.what());
    }
  }
  void beginLatency(uint64_t request) {
    if (latencyRequest_ == 0) {  // time the first of a burst of edits (a drag edits every frame)
      latencyRequest_ = request;
      latencyStart_ = Clock::now();
    }
  }

  void report(const std::string& text) {
    std::cerr << "candela: " << text << "\n";
    messages_.push_back({text, Clock::now()});
    if (messages_.size() > 50) messages_.pop_front();
  }

  void applyDisplay() {
    const std::string error = gl_->setPipeline(colors_, display_);
    if (!error.empty()) report(error);
    outputDirty_ = true;
    for (size_t i = 0; i < paneGl_.size(); ++i) {
      paneGl_[i]->setPipeline(colors_, paneDisplay());
      paneDirty_[i] = true;
    }
  }

  // --- equal-time comparison ---
  void startComparisonMode(const std::string& path) {
    scenePath_ = path;
    try {
      edited_ = fileScene_ = loadSceneDesc(path, options_.settings);
      sceneTime_ = modificationTime(path);
      haveScene_ = true;
      for (const auto& name : options_.panes) paneSpecs_.push_back({name, strategyPreset(name, "--panes")});
      wipe_ = options_.wipe && paneSpecs_.size() == 2;
      if (options_.paneView == "absolute") paneView_ = PaneView::AbsoluteError;
      if (options_.paneView == "relative") paneView_ = PaneView::RelativeError;
      compare_ = std::make_unique<ComparisonSession>(RenderOptions{options_.threads, 32});
      compare_->setNotify([] { glfwPostEmptyEvent(); });
      if (!options_.referencePath.empty()) reference_ = readExr(options_.referencePath);
      restartComparison();
    } catch (const std::exception& e) {
      report(e.what());
    }
  }
  void restartComparison() {
    compare_->start(edited_, paneSpecs_, reference_, reference_.rgb.empty() ? options_.referenceSpp : 0,
                    strategyPreset(options_.referenceStrategy, "--reference-strategy"), options_.equalTime);
    figureDone_ = false;
  }
  void pollComparison();
  void drawComparisonPanel();
  void drawPaneLabels();
  bool writeFigure(const std::string& path);
  void captureFigure();
  std::optional<std::string> figureRequest_;
  int paneCount() const { return compare_ ? std::max<int>(1, static_cast<int>(paneSpecs_.size())) : 1; }
  std::vector<PaneSpec> paneSpecs_;
  enum class PaneView { Image, AbsoluteError, RelativeError };
  PaneView paneView_ = PaneView::Image;
  std::string referenceInput_;
  int referenceSppInput_ = 256;
  std::string referenceStrategyInput_ = "emission";
  void uploadPanes();
  // Error views are false colour: shown through the config's raw view when it has one.
  DisplaySettings paneDisplay() const {
    if (paneView_ == PaneView::Image || !compFrame_ || !compFrame_->reference) return display_;
    DisplaySettings raw;
    raw.display = colors_.resolve(display_).display;
    for (const auto& v : colors_.views(raw.display))
      if (v == "Raw") raw.view = v;
    return raw.view.empty() ? display_ : raw;
  }
  bool wipe_ = false;       // two panes in one frame, split at wipePosition_
  float wipePosition_ = 0.5f;
  bool draggingWipe_ = false;

  void pollSession();
  void pollSceneFile();
  void drawMenuBar();
  void drawPanel();
  void drawStatusBar();
  void drawOpenDialog();
  void handleCamera();
  void handleKeys();
  void frameVolume();
  bool screenshot(const std::string& requestedPath);
  void scripted();

  // Image rectangle in window coordinates (top-left origin), aspect-fitted into the free area.
  struct Rect {
    float x = 0, y = 0, w = 0, h = 0;
    bool contains(float px, float py) const { return px >= x && py >= y && px < x + w && py < y + h; }
  };
  Rect imageRect() const;
  // A window rectangle (top-left origin, window units) in framebuffer pixels (bottom-left origin).
  struct PixelRect {
    int x = 0, y = 0, w = 0, h = 0;
  };
  PixelRect framebufferRect(const Rect& r) const {
    int fbw, fbh, ww, wh;
    glfwGetFramebufferSize(window_, &fbw, &fbh);
    glfwGetWindowSize(window_, &ww, &wh);
    const float sx = static_cast<float>(fbw) / std::max(1, ww), sy = static_cast<float>(fbh) / std::max(1, wh);
    return {static_cast<int>(r.x * sx), fbh - static_cast<int>((r.y + r.h) * sy), static_cast<int>(r.w * sx), static_cast<int>(r.h * sy)};
  }
  // Image zoom and pan (2D, on the displayed image; every pane shares it, so they stay in sync).
  ViewWindow view_;
  float zoom_ = 1.0f;
  ImVec2 viewCenter_{0.5f, 0.5f};
  void updateView() {
    zoom_ = std::clamp(zoom_, 1.0f, 64.0f);
    const float half = 0.5f / zoom_;
    viewCenter_.x = std::clamp(viewCenter_.x, half, 1.0f - half);
    viewCenter_.y = std::clamp(viewCenter_.y, half, 1.0f - half);
    view_ = {viewCenter_.x - half, viewCenter_.y - half, viewCenter_.x + half, viewCenter_.y + half};
  }
  // Image coordinates (fractions, v down) under a window point, through the zoom (one pane's rect
  // for side-by-side panes).
  ImVec2 imageUv(const Rect& r, ImVec2 p) const {
    float fx = (p.x - r.x) / std::max(1.0f, r.w), fy = (p.y - r.y) / std::max(1.0f, r.h);
    return ImVec2(view_.u0 + fx * (view_.u1 - view_.u0), view_.v0 + fy * (view_.v1 - view_.v0));
  }

  GLFWwindow* window_;
  ViewerOptions options_;
  RenderSession session_;
  ColorPipeline colors_;
  std::unique_ptr<GlDisplay> gl_;
  DisplaySettings display_;
  ProgressLimits limits_;

  std::string scenePath_, scenePreset_;
  std::vector<std::string> sceneSettings_;
  fs::file_time_type sceneTime_{};
  Clock::time_point lastPoll_ = Clock::now();
  uint64_t pendingOpen_ = 0;
  bool haveScene_ = false;
  SceneDesc edited_;    // what the panels edit
  SceneDesc fileScene_; // as opened (camera reset)

  std::unique_ptr<ComparisonSession> compare_;
  std::shared_ptr<const ComparisonFrame> compFrame_;
  uint64_t compVersion_ = 0;
  std::vector<std::unique_ptr<GlDisplay>> paneGl_;
  std::vector<bool> paneDirty_;
  Image reference_;
  bool figureDone_ = false;
  std::shared_ptr<const Frame> frame_;
  uint64_t uploadedVersion_ = 0;
  bool outputDirty_ = true;

  std::deque<std::pair<std::string, Clock::time_point>> messages_;
  bool showMessages_ = false, showOpen_ = false;
  std::string openPath_;
  std::vector<std::string> openCandidates_;

  Keys keys_;
  int dragButton_ = -1;
  bool readoutLocked_ = false;
  GuideInspectorView inspector_;  // Ctrl+click on a pixel
  bool inspectDone_ = false, inspectReported_ = false;
  int lockedX_ = 0, lockedY_ = 0;

  uint64_t latencyRequest_ = 0;
  Clock::time_point latencyStart_;
  double lastLatencyMs_ = 0.0;
  std::vector<double> latencies_;
  std::deque<double> frameTimes_;

  const float panelWidth_ = 420.0f;
  float statusHeight_ = 0.0f, menuHeight_ = 0.0f;

  // Scripted state.
  Clock::time_point start_ = Clock::now();
  bool editsDone_ = false, screenshotDone_ = false;
  int measureIndex_ = 0;
  Clock::time_point measureNext_;
  Clock::time_point measureStart_;
  int measureFrames_ = 0;
  std::vector<std::pair<std::string, double>> measured_;
  bool quitNow_ = false;
  int busyFrames_ = 3;
  int exitCode_ = 0;
};

Viewer::Rect Viewer::imageRect() const {
  int ww, wh;
  glfwGetWindowSize(window_, &ww, &wh);
  Rect area{0.0f, menuHeight_, std::max(1.0f, ww - panelWidth_), std::max(1.0f, wh - menuHeight_ - statusHeight_)};
  float aspect = 0.0f;
  if (compare_ && compFrame_ && compFrame_->width > 0)
    aspect = (wipe_ ? 1 : paneCount()) * static_cast<float>(compFrame_->width) / static_cast<float>(compFrame_->height);
  else if (frame_)
    aspect = static_cast<float>(frame_->width) / static_cast<float>(frame_->height);
  if (aspect <= 0.0f) return area;
  Rect r = area;
  if (area.w / area.h > aspect) {
    r.w = area.h * aspect;
    r.x = area.x + 0.5f * (area.w - r.w);
  } else {
    r.h = area.w / aspect;
    r.y = area.y + 0.5f * (area.h - r.h);
  }
  return r;
}

void Viewer::pollSession() {
  for (const auto& m : session_.takeMessages()) report(m);
  // After an open, the scene as loaded (also what Reset camera returns to); after a failed build,
  // the last good scene, so the fields show what is rendering.
  if (auto shown = session_.takeShownDesc()) {
    edited_ = *shown;
    if (pendingOpen_) fileScene_ = *shown, pendingOpen_ = 0;
    haveScene_ = true;
  }
  auto latest = session_.latest();
  if (latest && latest->version != uploadedVersion_) {
    frame_ = latest;
    uploadedVersion_ = latest->version;
    gl_->uploadImage(latest->film.width(), latest->film.height(), latest->film.meanImage());
    outputDirty_ = true;
    if (!haveScene_ && latest->scene) edited_ = *latest->scene, fileScene_ = edited_, haveScene_ = true;
  }
}

void Viewer::pollComparison() {
  if (!compare_) return;
  for (const auto& m : compare_->takeMessages()) report(m);
  auto latest = compare_->latest();
  if (!latest || latest->version == compVersion_) return;
  const bool referenceChanged = !compFrame_ || (compFrame_->reference != nullptr) != (latest->reference != nullptr);
  compFrame_ = latest;
  compVersion_ = latest->version;
  if (referenceChanged) applyDisplay();  // the error views switch to the raw view once a reference exists
  while (paneGl_.size() < latest->panes.size()) {
    paneGl_.push_back(std::make_unique<GlDisplay>());
    paneGl_.back()->setPipeline(colors_, paneDisplay());
    paneDirty_.push_back(true);
  }
  uploadPanes();
}

void Viewer::uploadPanes() {
  if (!compFrame_) return;
  const bool error = paneView_ != PaneView::Image && compFrame_->reference;
  for (size_t i = 0; i < compFrame_->panes.size() && i < paneGl_.size(); ++i) {
    const auto& film = compFrame_->panes[i].film;
    if (!film) continue;
    std::vector<float> image = film->meanImage();
    // Error views: false colour (shown through the raw view, see paneDisplay()).
    if (error && image.size() == compFrame_->reference->size())
      image = errorFalseColour(image, *compFrame_->reference, paneView_ == PaneView::RelativeError);
    paneGl_[i]->uploadImage(film->width(), film->height(), image);
    paneDirty_[i] = true;
  }
}

// Each pane's label over its image: strategy, spp, time it got, error and agreement.
void Viewer::drawPaneLabels() {
  if (!compFrame_) return;
  ImDrawList* draw = ImGui::GetForegroundDrawList();
  const Rect r = imageRect();
  const size_t n = compFrame_->panes.size();
  if (!compFrame_->status.empty())
    draw->AddText(ImVec2(r.x + 10, r.y + 10), IM_COL32(255, 220, 120, 255), compFrame_->status.c_str());
  const bool wipe = wipe_ && n == 2;
  if (wipe) {
    const float x = r.x + r.w * wipePosition_;
    draw->AddLine(ImVec2(x, r.y), ImVec2(x, r.y + r.h), IM_COL32(255, 255, 255, 200), 2.0f);
    draw->AddCircleFilled(ImVec2(x, r.y + r.h * 0.5f), 6.0f, IM_COL32(255, 255, 255, 220));
  }
  for (size_t i = 0; i < n; ++i) {
    const PaneState& p = compFrame_->panes[i];
    const float x = wipe ? (i == 0 ? r.x : r.x + r.w * 0.5f) : r.x + r.w * static_cast<float>(i) / static_cast<float>(n);
    char line[256];
    std::snprintf(line, sizeof(line), "%s  %d spp  %.2f s", p.label.c_str(), p.film ? p.film->spp() : 0, p.seconds);
    draw->AddRectFilled(ImVec2(x, r.y), ImVec2(x + r.w / n, r.y + 40), IM_COL32(0, 0, 0, 150));
    if (wipe && i == 1) draw->AddText(ImVec2(x + r.w / n - 60, r.y + 3), paneColor(i), "(right)");
    draw->AddText(ImGui::GetFont(), ImGui::GetFontSize() * 1.2f, ImVec2(x + 8, r.y + 3), paneColor(i), line);
    std::string second;
    if (!p.series.empty()) {
      char e[96];
      std::snprintf(e, sizeof(e), "relMSE %.3g  eff %.3g  ", p.series.back().relmse, p.efficiency());
      second = e;
    }
    ImU32 agreeColor = IM_COL32(170, 170, 170, 255);
    if (!p.agreementTested && n > 1) second += "agreement from " + std::to_string(kAgreementMinSpp) + " spp";
    if (p.agreementTested) {
      second += p.agreement.agree ? "agrees" : "DISAGREES";
      agreeColor = p.agreement.agree ? IM_COL32(130, 220, 130, 255) : IM_COL32(255, 80, 70, 255);
    }
    draw->AddText(ImVec2(x + 8, r.y + 22), agreeColor, second.c_str());
    if (i > 0 && !wipe) draw->AddLine(ImVec2(x, r.y), ImVec2(x, r.y + r.h), IM_COL32(20, 20, 20, 255), 2.0f);
  }
}

void Viewer::drawComparisonPanel() {
  if (!ImGui::CollapsingHeader("Comparison", ImGuiTreeNodeFlags_DefaultOpen)) return;
  if (!compFrame_) {
    ImGui::TextDisabled("starting...");
    return;
  }
  for (size_t i = 0; i < compFrame_->panes.size(); ++i) {
    const PaneState& p = compFrame_->panes[i];
    ImGui::TextColored(ImColor(paneColor(i)).Value, "%-13s", p.label.c_str());
    ImGui::SameLine();
    if (!p.series.empty())
      ImGui::Text("%6.2f s %5d spp  MSE %.3g  relMSE %.3g  eff %.3g", p.seconds, p.series.back().spp, p.series.back().mse,
                  p.series.back().relmse, p.efficiency());
    else
      ImGui::Text("%6.2f s %5d spp", p.seconds, p.film ? p.film->spp() : 0);
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("Efficiency = 1 / (relMSE x time).\n%s\nAgreement: %s (largest |z| %.2f vs threshold %.2f over %d region tests%s%s)",
                        kRelMseFormula, !p.agreementTested ? "not tested yet" : (p.agreement.agree ? "agrees" : "DISAGREES"),
                        p.agreement.maxAbsZ, p.agreement.threshold, p.agreement.tests, p.agreement.worst.empty() ? "" : "; worst ",
                        p.agreement.worst.c_str());
  }
  drawErrorChart(*compFrame_, ImVec2(ImGui::GetContentRegionAvail().x, 200.0f));
  // Each pane's strategy: a preset plus any edits, generated like the single view's Strategy panel.
  bool restart = false;
  int remove = -1;
  for (size_t i = 0; i < paneSpecs_.size(); ++i) {
    ImGui::PushID(static_cast<int>(i));
    const bool open = ImGui::TreeNodeEx("pane", 0, "pane %zu: %s", i + 1, paneSpecs_[i].label.c_str());
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("This pane's strategy settings; any edit restarts every pane (equal time)");
    if (open) {
      ParamEditor editor;
      editor.choices["preset"] = strategyPresetNames();
      paneSpecs_[i].strategy.visit(editor);
      if (!editor.presetChosen.empty()) paneSpecs_[i].strategy = strategyPreset(editor.presetChosen);
      if (editor.changed) {
        paneSpecs_[i].label = paneSpecs_[i].strategy.preset + (toJson(paneSpecs_[i].strategy) == toJson(strategyPreset(paneSpecs_[i].strategy.preset)) ? "" : "*");
        restart = true;
      }
      if (paneSpecs_.size() > 1 && ImGui::Button("Remove pane")) remove = static_cast<int>(i);
      ImGui::TreePop();
    }
    ImGui::PopID();
  }
  if (remove >= 0) paneSpecs_.erase(paneSpecs_.begin() + remove), restart = true;
  if (paneSpecs_.size() < 4 && ImGui::Button("Add pane")) {
    paneSpecs_.push_back({"emission", strategyPreset("emission")});
    restart = true;
  }
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Up to four panes; each starts as the emission preset");
  {
    const char* views[] = {"image", "absolute error", "relative error"};
    int view = static_cast<int>(paneView_);
    if (ImGui::Combo("pane view", &view, views, 3)) {
      paneView_ = static_cast<PaneView>(view);
      applyDisplay();
      uploadPanes();
    }
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("Error views need a reference. False colour, log scale 0.01 (black) to 10 (white):\n"
                        "absolute |I - R| / mean(R); relative |I - R| / sqrt(R^2 + eps), eps as in relMSE");
    ImGui::InputText("reference EXR", &referenceInput_);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Path of a scene-linear EXR of this scene and camera, at the panes' resolution");
    ImGui::SameLine();
    if (ImGui::Button("Load")) {
      try {
        reference_ = readExr(referenceInput_);
        restartComparison();
      } catch (const std::exception& e) {
        report(e.what());
      }
    }
    ImGui::DragInt("reference spp", &referenceSppInput_, 4.0f, 1, 1 << 20, "%d", ImGuiSliderFlags_AlwaysClamp);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Render a reference at this spp before the panes restart; cached on disk by scene and settings hash");
    if (ImGui::BeginCombo("reference strategy", referenceStrategyInput_.c_str())) {
      for (const auto& name : strategyPresetNames())
        if (ImGui::Selectable(name.c_str(), name == referenceStrategyInput_)) referenceStrategyInput_ = name;
      ImGui::EndCombo();
    }
    if (ImGui::Button("Render reference")) {
      reference_ = Image();
      options_.referenceSpp = referenceSppInput_;
      options_.referenceStrategy = referenceStrategyInput_;
      restartComparison();
    }
  }
  if (paneSpecs_.size() == 2) {
    ImGui::SameLine();
    ImGui::Checkbox("Wipe", &wipe_);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Show both panes in one frame, split by a divider you drag on the image");
  } else {
    wipe_ = false;
  }
  if (restart) {
    paneGl_.clear();
    paneDirty_.clear();
    restartComparison();
  }
  if (ImGui::Button("Export CSV")) {
    const std::string path = freshPath(fs::path("screenshots") / (fs::path(scenePath_).stem().string() + "-comparison.csv"));
    std::error_code ec;
    fs::create_directories("screenshots", ec);
    std::ofstream(path) << comparisonCsv(*compFrame_);
    report("wrote " + path);
  }
  ImGui::SameLine();
  if (ImGui::Button("Save figure")) writeFigure("");
  ImGui::SameLine();
  if (ImGui::Button("Restart")) restartComparison();
}

bool Viewer::writeFigure(const std::string& path) {
  if (!compFrame_ || compFrame_->panes.empty()) {
    report("figure: nothing to compare yet");
    return false;
  }
  figureRequest_ = path.empty() ? freshPath(fs::path("screenshots") / (fs::path(scenePath_).stem().string() + "-comparison.png")) : path;
  return true;
}

// Reads the panes and their labels back from the frame just drawn (before the swap): the figure is
// what the window shows. Writes PATH.png, one EXR per pane and the error series as CSV.
void Viewer::captureFigure() {
  const std::string path = *figureRequest_;
  figureRequest_.reset();
  try {
    const auto [x, y, w, h] = framebufferRect(imageRect());
    DisplayImage image;
    image.width = w;
    image.height = h;
    std::vector<uint8_t> rows(3 * static_cast<size_t>(w) * h);
    glReadBuffer(GL_BACK);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(x, y, w, h, GL_RGB, GL_UNSIGNED_BYTE, rows.data());
    image.rgb8.resize(rows.size());
    for (int row = 0; row < h; ++row)  // GL reads bottom-up
      std::copy_n(rows.begin() + 3 * static_cast<size_t>(h - 1 - row) * w, 3 * static_cast<size_t>(w),
                  image.rgb8.begin() + 3 * static_cast<size_t>(row) * w);
    Json panes = Json::array();
    for (const auto& p : compFrame_->panes) {
      Json j{{"label", p.label}, {"seconds", p.seconds}, {"last_slice_seconds", p.lastSlice}, {"spp", p.film ? p.film->spp() : 0}, {"strategy", toJson(p.strategy)}};
      if (!p.series.empty()) j["relmse"] = p.series.back().relmse, j["mse"] = p.series.back().mse, j["efficiency"] = p.efficiency();
      if (p.agreementTested) j["agrees"] = p.agreement.agree;
      panes.push_back(j);
    }
    image.metadata["scene"] = scenePath_;
    image.metadata["panes"] = panes.dump();
    image.metadata["settings"] = sceneToJson(edited_).dump();
    image.metadata["display"] = toJson(colors_.resolve(display_)).dump();
    if (fs::path(path).has_parent_path()) fs::create_directories(fs::path(path).parent_path());
    writeDisplayPng(path, image);
    const fs::path stem = fs::path(path).replace_extension("");
    for (const auto& p : compFrame_->panes) {
      if (!p.film) continue;
      Image exr;
      exr.width = p.film->width();
      exr.height = p.film->height();
      exr.rgb = p.film->meanImage();
      exr.metadata = {{"scene", scenePath_}, {"strategy", toJson(p.strategy).dump()}, {"spp", std::to_string(p.film->spp())},
                      {"time_s", std::to_string(p.seconds)}};
      writeExr(stem.string() + "-" + p.label + ".exr", exr);
    }
    std::ofstream(stem.string() + ".csv") << comparisonCsv(*compFrame_);
    report("figure: wrote " + path + ", one EXR per pane and " + stem.string() + ".csv");
    figureDone_ = true;
  } catch (const std::exception& e) {
    report(std::string("figure failed: ") + e.what());
    exitCode_ = 1;
    figureDone_ = true;
  }
}

void Viewer::pollSceneFile() {
  if (secondsSince(lastPoll_) < 0.5 || scenePath_.empty()) return;
  lastPoll_ = Clock::now();
  const auto t = modificationTime(scenePath_);
  if (t != sceneTime_ && t != fs::file_time_type{}) {
    report("reloading " + scenePath_ + " (the file changed)");
    if (compare_) {
      sceneTime_ = t;
      try {
        edited_ = fileScene_ = loadSceneDesc(scenePath_, options_.settings);
        restartComparison();
      } catch (const std::exception& e) {
        report(std::string(e.what()) + " (still comparing the last good scene)");
      }
      return;
    }
    openScene(scenePath_, sceneSettings_, scenePreset_);
  }
}

void Viewer::frameVolume() {
  if (!frame_) return;
  CameraDesc& c = edited_.camera;
  const Vec3 dir = glm::normalize(c.position - c.look_at);
  // The vertical field of view is the narrower one in a landscape image; use the narrower of the two.
  const float aspect = static_cast<float>(frame_->width) / static_cast<float>(frame_->height);
  const float tanHalfY = std::tan(glm::radians(c.fov_y) * 0.5f);
  const float halfFov = std::atan(std::min(tanHalfY, tanHalfY * aspect));
  const float distance = frame_->sceneRadius / std::sin(halfFov) * 1.05f;
  c.look_at = frame_->sceneCenter;
  c.position = c.look_at + dir * distance;
  submitEdit();
}

void Viewer::handleCamera() {
  ImGuiIO& io = ImGui::GetIO();
  if (!haveScene_) return;
  const Rect r = imageRect();
  // Ctrl+wheel zooms the image about the cursor, Shift+drag pans it, 0 fits it again (2D only: the
  // camera and the render do not change, so accumulation goes on).
  if (!io.WantCaptureMouse && r.contains(io.MousePos.x, io.MousePos.y) && io.KeyCtrl && io.MouseWheel != 0.0f) {
    Rect pane = r;
    if (compare_ && !wipe_ && paneCount() > 1) {
      pane.w = r.w / paneCount();
      pane.x = r.x + pane.w * std::floor((io.MousePos.x - r.x) / pane.w);
    }
    const ImVec2 before = imageUv(pane, io.MousePos);
    zoom_ *= std::exp(io.MouseWheel * 0.2f);
    updateView();
    const ImVec2 after = imageUv(pane, io.MousePos);
    viewCenter_.x += before.x - after.x;
    viewCenter_.y += before.y - after.y;
    updateView();
    return;
  }
  if (io.KeyShift && dragButton_ < 0 && !io.WantCaptureMouse && io.MouseDown[0] && r.contains(io.MousePos.x, io.MousePos.y)) {
    const float paneW = compare_ && !wipe_ ? r.w / paneCount() : r.w;
    viewCenter_.x -= io.MouseDelta.x / std::max(1.0f, paneW) / zoom_;
    viewCenter_.y -= io.MouseDelta.y / std::max(1.0f, r.h) / zoom_;
    updateView();
    return;
  }
  // In wipe mode a left drag near the divider moves it (the panes stay in sync: one frame).
  if (compare_ && wipe_) {
    const float divider = r.x + r.w * wipePosition_;
    if (!draggingWipe_ && dragButton_ < 0 && !io.WantCaptureMouse && io.MouseClicked[0] && r.contains(io.MousePos.x, io.MousePos.y) &&
        std::abs(io.MousePos.x - divider) < 8.0f)
      draggingWipe_ = true;
    if (draggingWipe_) {
      if (!io.MouseDown[0]) draggingWipe_ = false;
      wipePosition_ = std::clamp((io.MousePos.x - r.x) / std::max(1.0f, r.w), 0.0f, 1.0f);
      return;
    }
  }
  // Ctrl+click inspects the pixel's distance densities (guide_inspector_view.h) instead of tumbling.
  if (io.KeyCtrl && dragButton_ < 0 && !io.WantCaptureMouse && io.MouseClicked[0] && r.contains(io.MousePos.x, io.MousePos.y) && frame_) {
    const ImVec2 uv = imageUv(r, io.MousePos);
    inspector_.request(edited_, static_cast<int>(uv.x * edited_.camera.resolution.first),
                       static_cast<int>(uv.y * edited_.camera.resolution.second));
    return;
  }
  // Start a drag only on the image and only when ImGui does not want the mouse.
  if (dragButton_ < 0 && !io.WantCaptureMouse && r.contains(io.MousePos.x, io.MousePos.y)) {
    for (int b = 0; b < 3; ++b)
      if (io.MouseClicked[b]) dragButton_ = b;
    // The delta of the click frame may include a jump to where the click happened: not a drag.
    if (dragButton_ >= 0) return;
  }
  if (dragButton_ >= 0 && !io.MouseDown[dragButton_]) dragButton_ = -1;
  CameraDesc& c = edited_.camera;
  bool moved = false;
  const Vec3 forward = glm::normalize(c.look_at - c.position);
  const Vec3 right = glm::normalize(glm::cross(forward, c.up));
  const Vec3 up = glm::cross(right, forward);
  const float distance = glm::length(c.look_at - c.position);
  const float dx = io.MouseDelta.x, dy = io.MouseDelta.y;
  // Maya: Alt+left tumble, Alt+middle track, Alt+right dolly; plain buttons do the same here.
  if (dragButton_ >= 0 && (dx != 0.0f || dy != 0.0f)) {
    if (dragButton_ == 0) {
      const Vec3 worldUp = glm::normalize(c.up);
      Vec3 offset = c.position - c.look_at;
      const Mat4 yaw = glm::rotate(Mat4(1.0f), -dx * 0.008f, worldUp);
      offset = Vec3(yaw * glm::vec4(offset, 0.0f));
      const Vec3 newRight = Vec3(yaw * glm::vec4(right, 0.0f));
      const Mat4 pitch = glm::rotate(Mat4(1.0f), -dy * 0.008f, newRight);
      const Vec3 pitched = Vec3(pitch * glm::vec4(offset, 0.0f));
      // Stop short of the poles, where the up vector would flip.
      if (std::abs(glm::dot(glm::normalize(pitched), worldUp)) < 0.995f) offset = pitched;
      c.position = c.look_at + offset;
    } else if (dragButton_ == 2) {
      const float factor = std::exp(dy * 0.01f);
      c.position = c.look_at + (c.position - c.look_at) * factor;
    } else {
      const float pixelSize = 2.0f * distance * std::tan(glm::radians(c.fov_y) * 0.5f) / std::max(1.0f, r.h);
      const Vec3 shift = (-dx * right + dy * up) * pixelSize;
      c.position += shift;
      c.look_at += shift;
    }
    moved = true;
  }
  if (!io.WantCaptureMouse && r.contains(io.MousePos.x, io.MousePos.y) && io.MouseWheel != 0.0f) {
    c.position = c.look_at + (c.position - c.look_at) * std::exp(-io.MouseWheel * 0.1f);
    moved = true;
  }
  if (moved) submitEdit();
}

void Viewer::handleKeys() {
  ImGuiIO& io = ImGui::GetIO();
  const bool ctrl = io.KeyCtrl;
  // Query every key each frame so edges are tracked even while a text field has focus.
  const bool f = keys_.pressed(window_, GLFW_KEY_F), r = keys_.pressed(window_, GLFW_KEY_R), home = keys_.pressed(window_, GLFW_KEY_HOME),
             l = keys_.pressed(window_, GLFW_KEY_L), s = keys_.pressed(window_, GLFW_KEY_S), f12 = keys_.pressed(window_, GLFW_KEY_F12),
             c = keys_.pressed(window_, GLFW_KEY_C), o = keys_.pressed(window_, GLFW_KEY_O), e = keys_.pressed(window_, GLFW_KEY_E),
             zero = keys_.pressed(window_, GLFW_KEY_0);
  if (io.WantCaptureKeyboard) return;
  if (f && haveScene_) frameVolume();
  if ((r || home) && haveScene_) {
    edited_.camera = fileScene_.camera;
    submitEdit();
  }
  if (l) {
    readoutLocked_ = !readoutLocked_;
    if (readoutLocked_ && frame_) {
      const Rect rect = imageRect();
      const ImVec2 uv = imageUv(rect, io.MousePos);
      lockedX_ = std::clamp(static_cast<int>(uv.x * frame_->width), 0, frame_->width - 1);
      lockedY_ = std::clamp(static_cast<int>(uv.y * frame_->height), 0, frame_->height - 1);
    }
  }
  if (f12 || (s && !ctrl)) screenshot("");
  if (c) {
    display_.channel = static_cast<ChannelView>((static_cast<int>(display_.channel) + 1) % 5);
    applyDisplay();
  }
  if (e) {  // exposure: E up, Shift+E down
    display_.exposure += io.KeyShift ? -0.5f : 0.5f;
    applyDisplay();
  }
  if (o && ctrl) showOpen_ = true;
  if (zero) zoom_ = 1.0f, viewCenter_ = ImVec2(0.5f, 0.5f), updateView();
}

void Viewer::drawMenuBar() {
  if (!ImGui::BeginMainMenuBar()) return;
  menuHeight_ = ImGui::GetWindowSize().y;
  if (ImGui::BeginMenu("File")) {
    if (ImGui::MenuItem("Open scene...", "Ctrl+O")) showOpen_ = true;
    if (ImGui::MenuItem("Reload scene", nullptr, false, !scenePath_.empty())) openScene(scenePath_, sceneSettings_, scenePreset_);
    if (ImGui::MenuItem("Save screenshot", "S / F12", false, frame_ != nullptr)) screenshot("");
    ImGui::Separator();
    if (ImGui::MenuItem("Quit")) glfwSetWindowShouldClose(window_, 1);
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("View")) {
    if (ImGui::MenuItem("Frame volume", "F", false, haveScene_)) frameVolume();
    if (ImGui::MenuItem("Reset camera", "R / Home", false, haveScene_)) edited_.camera = fileScene_.camera, submitEdit();
    if (ImGui::MenuItem("Lock pixel readout", "L", readoutLocked_)) readoutLocked_ = !readoutLocked_;
    ImGui::Separator();
    for (const auto& [value, name] : EnumNames<ChannelView>::get())
      if (ImGui::MenuItem((std::string("Channel: ") + name).c_str(), value == ChannelView::RGB ? "C cycles" : nullptr, display_.channel == value))
        display_.channel = value, applyDisplay();
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("Display")) {
    for (const auto& d : colors_.displays())
      if (ImGui::BeginMenu(d.c_str())) {
        for (const auto& v : colors_.views(d))
          if (ImGui::MenuItem(v.c_str(), nullptr, display_.display == d && display_.view == v))
            display_.display = d, display_.view = v, applyDisplay();
        ImGui::EndMenu();
      }
    if (ImGui::BeginMenu("Look")) {
      if (ImGui::MenuItem("(none)", nullptr, display_.look.empty())) display_.look.clear(), applyDisplay();
      for (const auto& l : colors_.looks())
        if (ImGui::MenuItem(l.c_str(), nullptr, display_.look == l)) display_.look = l, applyDisplay();
      ImGui::EndMenu();
    }
    ImGui::Separator();
    ImGui::TextDisabled("Config: %s", colors_.configPath().c_str());
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("Help")) {
    ImGui::MenuItem("Messages", nullptr, &showMessages_);
    ImGui::TextDisabled("Mouse on the image: left tumble, middle track, right dolly, wheel dolly (Alt optional)");
    ImGui::TextDisabled("Image: Ctrl+wheel zoom, Shift+left drag pan, 0 fit (all panes together)");
    ImGui::TextDisabled("Ctrl+click a pixel: guide inspector (distance densities along its ray)");
    ImGui::TextDisabled("Keys: F frame volume, R reset camera, L lock readout, C channel, E/Shift+E exposure, S screenshot");
    ImGui::EndMenu();
  }
  ImGui::EndMainMenuBar();
}

void Viewer::drawPanel() {
  int ww, wh;
  glfwGetWindowSize(window_, &ww, &wh);
  ImGui::SetNextWindowPos(ImVec2(ww - panelWidth_, menuHeight_));
  ImGui::SetNextWindowSize(ImVec2(panelWidth_, wh - menuHeight_ - statusHeight_));
  ImGui::Begin("Parameters", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  ImGui::PushItemWidth(-170.0f);

  if (ImGui::CollapsingHeader("Display", ImGuiTreeNodeFlags_DefaultOpen)) {
    ParamEditor editor;
    editor.choices["display"] = colors_.displays();
    editor.choices["view"] = colors_.views(display_.display);
    std::vector<std::string> looks{""};
    for (const auto& l : colors_.looks()) looks.push_back(l);
    editor.choices["look"] = looks;
    display_.visit(editor);
    if (editor.changed) {
      display_ = colors_.resolve(display_);
      applyDisplay();
    }
  }
  if (!compare_ && ImGui::CollapsingHeader("Progress", ImGuiTreeNodeFlags_DefaultOpen)) {
    ParamEditor editor;
    limits_.visit(editor);
    if (editor.changed) session_.setLimits(limits_);
    if (ImGui::Button("Restart")) beginLatency(session_.edit(edited_));
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Discard the accumulated samples and start again");
  }
  if (!haveScene_) {
    ImGui::TextWrapped(session_.loading() ? "Loading..." : "No scene. File > Open.");
    ImGui::End();
    return;
  }
  bool changed = false;
  if (compare_) drawComparisonPanel();
  if (!compare_ && ImGui::CollapsingHeader("Strategy", ImGuiTreeNodeFlags_DefaultOpen)) {
    ParamEditor editor;
    editor.choices["preset"] = strategyPresetNames();
    edited_.strategy.visit(editor);
    if (!editor.presetChosen.empty()) edited_.strategy = strategyPreset(editor.presetChosen);
    changed |= editor.changed;
  }
  if (ImGui::CollapsingHeader("Render")) {
    ParamEditor editor;
    edited_.render.visit(editor);
    changed |= editor.changed;
  }
  if (ImGui::CollapsingHeader("Camera")) {
    ParamEditor editor;
    edited_.camera.visit(editor);
    changed |= editor.changed;
  }
  auto list = [&](const char* title, auto& items, auto label) {
    if (!ImGui::CollapsingHeader(title, ImGuiTreeNodeFlags_DefaultOpen)) return;
    for (size_t i = 0; i < items.size(); ++i) {
      ImGui::PushID(static_cast<int>(i));
      if (ImGui::TreeNodeEx(label(items[i], i).c_str(), ImGuiTreeNodeFlags_DefaultOpen)) {
        ParamEditor editor;
        items[i].visit(editor);
        changed |= editor.changed;
        ImGui::TreePop();
      }
      ImGui::PopID();
    }
  };
  list("Volumes", edited_.volumes, [](const VolumeDesc& v, size_t i) { return v.name.empty() ? "volume " + std::to_string(i) : v.name; });
  list("Lights", edited_.lights, [](const LightDesc& l, size_t i) { return std::to_string(i) + ": " + enumName(l.type); });
  list("Surfaces", edited_.surfaces, [](const SurfaceDesc& s, size_t i) { return std::to_string(i) + ": " + enumName(s.type); });
  ImGui::PopItemWidth();
  ImGui::End();
  if (changed) submitEdit();
}

void Viewer::drawStatusBar() {
  int ww, wh;
  glfwGetWindowSize(window_, &ww, &wh);
  const float line = ImGui::GetTextLineHeightWithSpacing();
  statusHeight_ = 3.0f * line + 2.0f * ImGui::GetStyle().WindowPadding.y;
  ImGui::SetNextWindowPos(ImVec2(0.0f, wh - statusHeight_));
  ImGui::SetNextWindowSize(ImVec2(static_cast<float>(ww), statusHeight_));
  ImGui::Begin("Status", nullptr,
               ImGuiWindowFlags_NoTitleBar | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoScrollbar |
                   ImGuiWindowFlags_NoSavedSettings);
  double fps = 0.0;
  if (frameTimes_.size() > 1) fps = (frameTimes_.size() - 1) / (frameTimes_.back() - frameTimes_.front());
  if (frame_) {
    const Film& film = frame_->film;
    char latency[32] = "-";
    if (!latencies_.empty()) std::snprintf(latency, sizeof(latency), "%.0f ms", lastLatencyMs_);
    ImGui::Text("%s | %s | %dx%d | %d spp%s | %.1f s | %.3g samples/s | rejected %llu | edit->image %s | UI %.0f fps%s",
                scenePath_.c_str(), frame_->scene ? frame_->scene->strategy.preset.c_str() : "", frame_->width, frame_->height,
                frame_->preview ? 0 : film.spp(), frame_->preview ? " (preview)" : (frame_->finished ? " (done)" : ""), frame_->seconds,
                frame_->samplesPerSecond, static_cast<unsigned long long>(film.rejectedSamples()), latency, fps,
                session_.loading() ? " | loading..." : "");
    if (const std::string w = film.rejectedSamplesWarning(); !w.empty()) {
      ImGui::SameLine();
      ImGui::TextColored(ImVec4(1.0f, 0.35f, 0.3f, 1.0f), "| WARNING: %s", w.c_str());
    }
  } else if (compare_) {
    ImGui::Text("%s | equal-time comparison of %d strategies%s | UI %.0f fps", scenePath_.c_str(), paneCount(),
                compFrame_ && !compFrame_->status.empty() ? (" | " + compFrame_->status).c_str() : "", fps);
  } else {
    ImGui::Text("%s | %s", scenePath_.c_str(), session_.loading() ? "loading..." : "no image");
  }
  // Pixel readout: scene-linear values under the cursor (or at the locked pixel).
  ImGuiIO& io = ImGui::GetIO();
  const Rect r = imageRect();
  int px = -1, py = -1;
  if (readoutLocked_) {
    px = lockedX_, py = lockedY_;
  } else if (frame_ && r.contains(io.MousePos.x, io.MousePos.y)) {
    const ImVec2 uv = imageUv(r, io.MousePos);
    px = static_cast<int>(uv.x * frame_->width);
    py = static_cast<int>(uv.y * frame_->height);
  }
  if (frame_ && px >= 0 && px < frame_->width && py >= 0 && py < frame_->height) {
    const Film& film = frame_->film;
    const int fx = px * film.width() / frame_->width, fy = py * film.height() / frame_->height;
    const Rgb m = film.mean(fx, fy), se = film.standardError(fx, fy);
    ImGui::Text("pixel (%d, %d)%s  RGB %.5g %.5g %.5g  std. error %.3g %.3g %.3g  (%d spp)", px, py, readoutLocked_ ? " [locked: L]" : "", m.r,
                m.g, m.b, se.r, se.g, se.b, film.spp());
  } else {
    ImGui::TextDisabled("pixel readout: hover the image (L locks)");
  }
  // The newest message stays visible for 10 seconds; Help > Messages keeps them all.
  if (!messages_.empty() && secondsSince(messages_.back().second) < 10.0)
    ImGui::TextColored(ImVec4(1.0f, 0.45f, 0.35f, 1.0f), "%s", messages_.back().first.c_str());
  ImGui::End();

  if (showMessages_) {
    ImGui::SetNextWindowSize(ImVec2(700, 300), ImGuiCond_FirstUseEver);
    if (ImGui::Begin("Messages", &showMessages_))
      for (const auto& m : messages_) ImGui::TextWrapped("%s", m.first.c_str());
    ImGui::End();
  }
}

void Viewer::drawOpenDialog() {
  if (showOpen_) {
    ImGui::OpenPopup("Open scene");
    showOpen_ = false;
    openPath_ = scenePath_;
    // Scenes under assets/scenes and beside the current scene, listed once per opening of the dialog.
    openCandidates_.clear();
    std::vector<fs::path> roots{fs::path(CANDELA_ASSET_DIR) / "scenes"};
    if (!scenePath_.empty()) roots.push_back(fs::path(scenePath_).parent_path());
    for (const auto& root : roots) {
      std::error_code ec;
      int depth = 0;
      for (auto it = fs::recursive_directory_iterator(root, ec); !ec && it != fs::recursive_directory_iterator() && ++depth < 5000;
           it.increment(ec))
        if (it->path().extension() == ".json") openCandidates_.push_back(fs::weakly_canonical(it->path()).string());
    }
    std::sort(openCandidates_.begin(), openCandidates_.end());
    openCandidates_.erase(std::unique(openCandidates_.begin(), openCandidates_.end()), openCandidates_.end());
  }
  ImGui::SetNextWindowSize(ImVec2(640, 420), ImGuiCond_Appearing);
  if (!ImGui::BeginPopupModal("Open scene")) return;
  bool go = ImGui::InputText("path", &openPath_, ImGuiInputTextFlags_EnterReturnsTrue);
  ImGui::TextDisabled("Scenes found:");
  ImGui::BeginChild("scenes", ImVec2(0, -ImGui::GetFrameHeightWithSpacing()), true);
  for (const auto& f : openCandidates_)
    if (ImGui::Selectable(f.c_str(), f == openPath_, ImGuiSelectableFlags_AllowDoubleClick)) {
      openPath_ = f;
      if (ImGui::IsMouseDoubleClicked(0)) go = true;
    }
  ImGui::EndChild();
  go |= ImGui::Button("Open");
  ImGui::SameLine();
  if (ImGui::Button("Cancel") || ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Escape))) ImGui::CloseCurrentPopup();
  if (go) {
    openScene(openPath_);
    ImGui::CloseCurrentPopup();
  }
  ImGui::EndPopup();
}

bool Viewer::screenshot(const std::string& requestedPath) {
  if (!frame_ || !gl_->outputWidth()) {
    report("screenshot: no image yet");
    return false;
  }
  std::string pngPath = requestedPath;
  if (pngPath.empty()) {
    const std::time_t now = std::time(nullptr);
    char stamp[32];
    std::strftime(stamp, sizeof(stamp), "%Y%m%d-%H%M%S", std::localtime(&now));
    const std::string stem = fs::path(scenePath_).stem().string();
    pngPath = freshPath(fs::path("screenshots") / (stem + "-" + stamp + ".png"));
  }
  const std::string exrPath = fs::path(pngPath).replace_extension(".exr").string();
  try {
    if (fs::path(pngPath).has_parent_path()) fs::create_directories(fs::path(pngPath).parent_path());
    std::map<std::string, std::string> meta;
    meta["scene"] = scenePath_;
    if (frame_->scene) {
      meta["strategy"] = toJson(frame_->scene->strategy).dump();
      meta["settings"] = sceneToJson(*frame_->scene).dump();
    }
    meta["display"] = toJson(colors_.resolve(display_)).dump();
    meta["ocio_config"] = colors_.configPath();
    meta["spp"] = std::to_string(frame_->preview ? 0 : frame_->film.spp());
    meta["time_s"] = std::to_string(frame_->seconds);
    meta["rejected_samples"] = std::to_string(frame_->film.rejectedSamples());
    DisplayImage png;
    png.width = gl_->outputWidth();
    png.height = gl_->outputHeight();
    png.rgb8 = gl_->readOutput();
    png.metadata = meta;
    writeDisplayPng(pngPath, png);
    Image exr;
    exr.width = frame_->film.width();
    exr.height = frame_->film.height();
    exr.rgb = frame_->film.meanImage();
    exr.metadata = meta;
    writeExr(exrPath, exr);
    report("screenshot: wrote " + pngPath + " and " + exrPath);
    return true;
  } catch (const std::exception& e) {
    report(std::string("screenshot failed: ") + e.what());
    return false;
  }
}

void Viewer::scripted() {
  if (compare_) {
    // Scripted comparison: the figure once every pane has had --equal-time seconds.
    if (!options_.figurePath.empty() && !figureDone_ && !figureRequest_ && compFrame_ && compFrame_->status.empty() &&
        !compFrame_->panes.empty()) {
      bool done = options_.equalTime > 0.0;
      for (const auto& p : compFrame_->panes) done = done && p.film && p.seconds >= options_.equalTime;
      if (done) writeFigure(options_.figurePath);
    }
    if (options_.quit && (options_.figurePath.empty() || figureDone_)) quitNow_ = true;
    if (options_.quit && !compFrame_ && secondsSince(start_) > 5.0) {
      report("the comparison could not start; quitting");
      exitCode_ = 1;
      quitNow_ = true;
    }
    return;
  }
  const bool fullFrame = frame_ && !frame_->preview && frame_->film.spp() > 0 && !session_.loading();
  if (!fullFrame) {
    // A scripted run whose scene never loads must not wait forever.
    if (options_.quit && !haveScene_ && !session_.loading() && secondsSince(start_) > 2.0) {
      report("no scene could be loaded; quitting");
      exitCode_ = 1;
      quitNow_ = true;
    }
    return;
  }
  if (!editsDone_) {
    for (const auto& e : options_.editsAfterStart) applySettingEdit(e);
    editsDone_ = true;
    if (!options_.editsAfterStart.empty()) return;  // let the edits reach the renderer first
  }
  if (options_.measureEdits > 0 && measureIndex_ <= options_.measureEdits) {
    // Alternate edits of three kinds an artist makes: a strategy value, the camera, a volume value.
    if (measureIndex_ == 0) {
      measureStart_ = Clock::now();
      measureNext_ = Clock::now();
      measureFrames_ = 0;
    }
    if (Clock::now() >= measureNext_ && latencyRequest_ == 0) {
      if (measureIndex_ == options_.measureEdits) {
        ++measureIndex_;
        return;
      }
      const int kind = measureIndex_ % 3;
      std::string label;
      const bool up = (measureIndex_ / 3) % 2 == 0;  // every edit changes something
      if (kind == 0) {
        edited_.strategy.majorant.emission_weight = edited_.strategy.majorant.emission_weight == 10.0f ? 5.0f : 10.0f;
        label = "strategy (emission weight)";
      } else if (kind == 1) {
        const float angle = 0.05f * (up ? 1.0f : -1.0f);
        Vec3 offset = edited_.camera.position - edited_.camera.look_at;
        offset = Vec3(glm::rotate(Mat4(1.0f), angle, Vec3(0, 1, 0)) * glm::vec4(offset, 0.0f));
        edited_.camera.position = edited_.camera.look_at + offset;
        label = "camera (tumble)";
      } else {
        if (!edited_.volumes.empty()) edited_.volumes[0].emission.intensity *= up ? 1.25f : 0.8f;
        label = "volume (emission intensity, rebuild)";
      }
      measured_.push_back({label, -1.0});
      submitEdit();
      ++measureIndex_;
      measureNext_ = Clock::now() + std::chrono::milliseconds(400);
    }
    return;
  }
  if (options_.measureEdits > 0 && measureIndex_ == options_.measureEdits + 1) {
    ++measureIndex_;
    const double wall = secondsSince(measureStart_);
    std::map<std::string, std::vector<double>> byKind;
    for (const auto& [label, ms] : measured_)
      if (ms >= 0.0) byKind[label].push_back(ms);
    std::printf("edit-to-first-image latency (%dx%d, %u hardware threads):\n", frame_->width, frame_->height, std::thread::hardware_concurrency());
    for (auto& [label, v] : byKind) {
      std::sort(v.begin(), v.end());
      std::printf("  %-40s median %6.1f ms  max %6.1f ms  (%zu edits)\n", label.c_str(), v[v.size() / 2], v.back(), v.size());
    }
    std::printf("UI frame rate while rendering: %.1f fps over %.1f s\n", measureFrames_ / wall, wall);
    std::fflush(stdout);
  }
  if (options_.inspectPixel.size() == 2 && !inspectDone_) {
    inspector_.request(edited_, options_.inspectPixel[0], options_.inspectPixel[1]);
    inspectDone_ = true;
  }
  if (inspectDone_ && !inspector_.finished()) return;  // a scripted screenshot shows the chart
  if (inspectDone_ && !inspectReported_) {
    std::printf("inspector: %s\n", inspector_.summary().c_str());
    std::fflush(stdout);
    inspectReported_ = true;
  }
  if (!options_.screenshotPath.empty() && !screenshotDone_) {
    const bool ready = (options_.afterSpp > 0 && frame_->film.spp() >= options_.afterSpp) ||
                       (options_.afterSeconds > 0.0 && frame_->seconds >= options_.afterSeconds) ||
                       (options_.afterSpp <= 0 && options_.afterSeconds <= 0.0);
    if (!ready) return;
    screenshotDone_ = true;
    if (!screenshot(options_.screenshotPath)) exitCode_ = 1;
  }
  if (options_.quit && (options_.screenshotPath.empty() || screenshotDone_)) quitNow_ = true;
}

int Viewer::run() {
  const double targetFrame = 1.0 / 60.0;
  auto frameStart = Clock::now();
  while (!glfwWindowShouldClose(window_) && !quitNow_) {
    const auto lastFrame = frameStart;
    frameStart = Clock::now();
    // Redraw continuously only while the user interacts (and a few frames after, so ImGui settles);
    // otherwise sleep until an input event or a new image wakes us: the cores stay with the renderer.
    const bool measuring = options_.measureEdits > 0 && measureIndex_ <= options_.measureEdits;
    if (busyFrames_ > 0 || measuring || !options_.screenshotPath.empty() || !options_.figurePath.empty()) {
      // At most ~60 fps, but a new image (glfwPostEmptyEvent) or input wakes us at once.
      glfwWaitEventsTimeout(std::max(0.0, targetFrame - secondsSince(lastFrame)));
    } else {
      glfwWaitEventsTimeout(0.5);
    }
    busyFrames_ = std::max(0, busyFrames_ - 1);
    try {
      pollSession();
      pollComparison();
      pollSceneFile();
    } catch (const std::exception& e) {
      report(e.what());
    }

    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    try {
      drawMenuBar();
      drawStatusBar();
      drawPanel();
      inspector_.draw();
      drawOpenDialog();
      drawPaneLabels();
      handleCamera();
      handleKeys();
    } catch (const std::exception& e) {
      report(std::string("UI error: ") + e.what());
    }
    {
      ImGuiIO& io = ImGui::GetIO();
      const bool interacting = ImGui::IsAnyItemActive() || io.MouseDelta.x != 0.0f || io.MouseDelta.y != 0.0f || io.MouseWheel != 0.0f ||
                               io.MouseDown[0] || io.MouseDown[1] || io.MouseDown[2] || io.WantTextInput || ImGui::IsPopupOpen("", ImGuiPopupFlags_AnyPopup);
      if (interacting) busyFrames_ = 3;
    }
    ImGui::Render();

    int fbw, fbh, ww, wh;
    glfwGetFramebufferSize(window_, &fbw, &fbh);
    glfwGetWindowSize(window_, &ww, &wh);
    static const bool trace = std::getenv("CANDELA_TRACE") != nullptr;
    const auto outputStart = Clock::now();
    const bool rendered = frame_ && outputDirty_;
    if (frame_ && outputDirty_) {
      // At the film's resolution: a preview's few pixels go through OCIO cheaply and are upscaled by
      // the blit, which matters when the GPU is a software rasteriser sharing the render cores.
      gl_->renderOutput(frame_->film.width(), frame_->film.height());
      outputDirty_ = false;
      if (trace) glFinish();
    }
    const auto outputEnd = Clock::now();
    glViewport(0, 0, fbw, fbh);
    glClearColor(0.11f, 0.11f, 0.12f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    if (frame_) {
      const PixelRect p = framebufferRect(imageRect());
      gl_->blitToWindow(p.x, p.y, p.w, p.h, !frame_->preview && p.w >= 2 * frame_->width * (view_.u1 - view_.u0), view_);
    }
    if (compFrame_ && !compFrame_->panes.empty()) {
      const Rect r = imageRect();
      const size_t n = compFrame_->panes.size();
      const bool wipe = wipe_ && n == 2;
      for (size_t i = 0; i < n && i < paneGl_.size(); ++i) {
        const auto& film = compFrame_->panes[i].film;
        if (!film) continue;
        if (paneDirty_[i]) paneGl_[i]->renderOutput(film->width(), film->height()), paneDirty_[i] = false;
        if (wipe) {
          // Pane 1 left of the divider, pane 2 right of it, in the same frame.
          const PixelRect p = framebufferRect(r);
          const float a = i == 0 ? 0.0f : wipePosition_, b = i == 0 ? wipePosition_ : 1.0f;
          paneGl_[i]->blitToWindow(p.x, p.y, p.w, p.h, false, view_, a, b);
          continue;
        }
        const PixelRect p = framebufferRect(Rect{r.x + r.w * static_cast<float>(i) / static_cast<float>(n), r.y, r.w / n, r.h});
        paneGl_[i]->blitToWindow(p.x, p.y, p.w, p.h, false, view_);
      }
    }
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    if (figureRequest_) captureFigure();
    glfwSwapBuffers(window_);
    if (trace && rendered)
      std::fprintf(stderr, "trace: frame: before output %.1f ms, output %.1f ms, draw+swap %.1f ms\n",
                   1e3 * std::chrono::duration<double>(outputStart - frameStart).count(),
                   1e3 * std::chrono::duration<double>(outputEnd - outputStart).count(), 1e3 * secondsSince(outputEnd));

    // Latency: the first image of a request is on screen now.
    if (latencyRequest_ && frame_ && frame_->request >= latencyRequest_) {
      lastLatencyMs_ = 1000.0 * secondsSince(latencyStart_);
      latencies_.push_back(lastLatencyMs_);
      if (std::getenv("CANDELA_TRACE")) std::fprintf(stderr, "trace: edit->image %.1f ms\n", lastLatencyMs_);
      for (auto it = measured_.rbegin(); it != measured_.rend(); ++it)
        if (it->second < 0.0) {
          it->second = lastLatencyMs_;
          break;
        }
      latencyRequest_ = 0;
    }
    frameTimes_.push_back(std::chrono::duration<double>(Clock::now().time_since_epoch()).count());
    while (frameTimes_.size() > 60) frameTimes_.pop_front();
    ++measureFrames_;
    try {
      scripted();
    } catch (const std::exception& e) {
      report(e.what());
    }
  }
  return exitCode_;
}

}  // namespace

int runViewer(const ViewerOptions& options) {
  glfwSetErrorCallback([](int code, const char* text) { std::cerr << "candela: GLFW error " << code << ": " << text << "\n"; });
  if (!glfwInit()) {
    std::cerr << "candela: cannot initialise GLFW (is there a display? under CI use xvfb-run -a)\n";
    return 2;
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GL_TRUE);
  GLFWwindow* window = glfwCreateWindow(options.windowWidth, options.windowHeight, "Candela", nullptr, nullptr);
  if (!window) {
    std::cerr << "candela: cannot create an OpenGL 3.3 core window\n";
    glfwTerminate();
    return 2;
  }
  glfwMakeContextCurrent(window);
  // Keys are polled once a frame; sticky keys keep a press that was released between two frames.
  glfwSetInputMode(window, GLFW_STICKY_KEYS, GLFW_TRUE);
  glfwSwapInterval(0);  // our own frame pacing; vsync would add a frame of latency
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // fixed layout; nothing to remember between runs
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(window, true);
  ImGui_ImplOpenGL3_Init("#version 330 core");
  int code = 0;
  {
    Viewer viewer(window, options);
    code = viewer.run();
  }
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  glfwDestroyWindow(window);
  glfwTerminate();
  return code;
}

}  // namespace candela
