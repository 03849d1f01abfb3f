// The panels: Parameters (generated from the settings structs' visit()), the comparison panel,
// snapshots, the timeline and the status bar.
#include "viewer_impl.h"

#include "atomic_file.h"
#include "auto_strategy.h"
#include "error_chart.h"
#include "message_severity.h"
#include "param_editor.h"

#include <algorithm>
#include <climits>
#include <cstdio>
#include <fstream>

namespace candela {

namespace fs = std::filesystem;

// Each pane's label over its image: strategy, spp, time it got, error and agreement.
void Viewer::drawPaneLabels() {
  if (region_ && frame_ && !compare_ && frame_->width > 0) {
    // The render region's outline, through the zoom, with its samples.
    const ImageCanvas::Rect r = canvas_.paneRect(0);
    const ViewWindow& v = canvas_.view();
    auto at = [&](float px, float py) {
      const float u = px / static_cast<float>(frame_->width), w = py / static_cast<float>(frame_->height);
      return ImVec2(r.x + (u - v.u0) / (v.u1 - v.u0) * r.w, r.y + (w - v.v0) / (v.v1 - v.v0) * r.h);
    };
    ImDrawList* draw = ImGui::GetForegroundDrawList();
    const ImVec2 a = at(static_cast<float>(region_->x), static_cast<float>(region_->y));
    const ImVec2 b = at(static_cast<float>(region_->x + region_->w), static_cast<float>(region_->y + region_->h));
    draw->PushClipRect(ImVec2(r.x, r.y), ImVec2(r.x + r.w, r.y + r.h), true);
    draw->AddRect(a, b, IM_COL32(255, 200, 60, 230), 0.0f, 0, 1.5f);
    char label[64];
    std::snprintf(label, sizeof(label), "region  %d spp", frame_->regionFilm.spp());
    draw->AddText(ImVec2(a.x + 4.0f, a.y + 2.0f), IM_COL32(255, 200, 60, 255), label);
    draw->PopClipRect();
  }
  if (comparedSnapshot_ && frame_ && !compare_) {
    // Live render against a snapshot: which side is which.
    ImDrawList* draw = ImGui::GetForegroundDrawList();
    const ImageCanvas::Rect r = canvas_.rect();
    const Snapshot* snap = snapshots_.find(comparedSnapshot_);
    if (canvas_.wipe()) canvas_.drawDivider(draw);
    draw->AddRectFilled(ImVec2(r.x, r.y), ImVec2(r.x + 160, r.y + 24), IM_COL32(0, 0, 0, 150));
    draw->AddText(ImVec2(r.x + 8, r.y + 4), IM_COL32(255, 255, 255, 255), "live");
    const std::string label = snap ? "snapshot " + snap->label : "snapshot";
    // Wipe: the snapshot is right of the divider, labelled top right; two panes: the second one.
    const ImageCanvas::Rect second = canvas_.paneRect(1);
    const float x = canvas_.wipe() ? r.x + r.w - 260 : second.x, y = canvas_.wipe() ? r.y : second.y;
    draw->AddRectFilled(ImVec2(x, y), ImVec2(x + 260, y + 24), IM_COL32(0, 0, 0, 150));
    draw->AddText(ImVec2(x + 8, y + 4), IM_COL32(255, 220, 120, 255), label.c_str());
    return;
  }
  if (!compFrame_) return;
  ImDrawList* draw = ImGui::GetForegroundDrawList();
  const ImageCanvas::Rect r = canvas_.rect();
  const size_t n = compFrame_->panes.size();
  if (!compFrame_->status.empty())
    draw->AddText(ImVec2(r.x + 10, r.y + 10), IM_COL32(255, 220, 120, 255), compFrame_->status.c_str());
  const bool wipe = canvas_.wipe() && n == 2;
  if (wipe) canvas_.drawDivider(draw);
  // The slowest pane's time: a pane ahead of it (auto, charged its decision) waits for the others.
  double behind = 1e300;
  for (const auto& p : compFrame_->panes) behind = std::min(behind, p.seconds);
  for (size_t i = 0; i < n; ++i) {
    const PaneState& p = compFrame_->panes[i];
    const ImageCanvas::Rect pane = canvas_.paneRect(static_cast<int>(i));
    const float x = wipe ? (i == 0 ? r.x : r.x + r.w * 0.5f) : pane.x, y = wipe ? r.y : pane.y;
    const std::string line = paneTitle(p) + (p.film ? "  " + std::to_string(p.film->spp()) + " spp" : "");
    const float paneWidth = wipe ? r.w * 0.5f : pane.w;
    std::string figures, agreement;
    if (p.preparing) {
      figures = p.strategy.preset == "auto" ? "preparing: auto tries its candidates on a small image" : "preparing the scene";
    } else if (!p.series.empty()) {
      // Noise as an artist reads it: the RMS error relative to the pixel, sqrt(relMSE); estimated
      // from the pane's own variance until a reference exists.
      char e[96];
      std::snprintf(e, sizeof(e), "noise %.1f%%%s  ", 100.0 * std::sqrt(std::max(0.0, p.series.back().relmse)),
                    p.series.back().estimated ? " (est.)" : "");
      figures = e;
    } else if (!p.autoChoice.empty() && p.seconds > behind + 0.05) {
      char e[96];
      std::snprintf(e, sizeof(e), "deciding took %.2f s; the others catch up  ", p.seconds);
      figures = e;
    }
    ImU32 agreeColor = IM_COL32(170, 170, 170, 255);
    if (!p.agreementTested && n > 1 && !p.preparing) agreement = "matches the others? checked at " + std::to_string(kAgreementMinSpp) + " spp";
    if (p.agreementTested) {
      agreement = p.agreement.agree ? "matches the others" : "DIFFERS from the others";
      agreeColor = p.agreement.agree ? IM_COL32(130, 220, 130, 255) : IM_COL32(255, 80, 70, 255);
    }
    // Narrow panes (four in a row) put the agreement on a line of its own rather than under
    // the next pane's label; every line is clipped to its pane.
    const bool oneLine = ImGui::CalcTextSize((figures + agreement).c_str()).x + 16.0f <= paneWidth;
    const float height = oneLine || agreement.empty() || figures.empty() ? 40.0f : 58.0f;
    draw->PushClipRect(ImVec2(x, y), ImVec2(x + paneWidth, y + height), true);
    draw->AddRectFilled(ImVec2(x, y), ImVec2(x + paneWidth, y + height), IM_COL32(0, 0, 0, 150));
    if (wipe && i == 1) draw->AddText(ImVec2(x + paneWidth - 60, y + 3), paneColor(i), "(right)");
    draw->AddText(ImGui::GetFont(), ImGui::GetFontSize() * 1.2f, ImVec2(x + 8, y + 3), paneColor(i), line.c_str());
    if (oneLine) {
      draw->AddText(ImVec2(x + 8, y + 22), agreeColor, (figures + agreement).c_str());
    } else {
      draw->AddText(ImVec2(x + 8, y + 22), agreeColor, figures.empty() ? agreement.c_str() : figures.c_str());
      if (!figures.empty()) draw->AddText(ImVec2(x + 8, y + 40), agreeColor, agreement.c_str());
    }
    draw->PopClipRect();
    // The grid's lines: left of every pane but the first column's, above every pane below the first row.
    if (!wipe && x > r.x + 1.0f) draw->AddLine(ImVec2(x, y), ImVec2(x, y + pane.h), IM_COL32(20, 20, 20, 255), 2.0f);
    if (!wipe && y > r.y + 1.0f) draw->AddLine(ImVec2(x, y), ImVec2(x + pane.w, y), IM_COL32(20, 20, 20, 255), 2.0f);
  }
  // A grid cell no pane fills (three panes in 2 x 2) shows the error-versus-time chart, labelled, so
  // the window and a saved figure carry the curves beside the images.
  if (!wipe && canvas_.columns() * canvas_.rows() > static_cast<int>(n) && n > 0) {
    const ImageCanvas::Rect cell = canvas_.paneRect(static_cast<int>(n));
    const ImVec2 origin(cell.x + 8.0f, cell.y + 30.0f), size(cell.w - 16.0f, cell.h - 38.0f);
    if (size.x > 80.0f && size.y > 60.0f) {
      draw->AddRectFilled(ImVec2(cell.x, cell.y), ImVec2(cell.x + cell.w, cell.y + cell.h), IM_COL32(25, 25, 28, 255));
      draw->AddLine(ImVec2(cell.x, cell.y), ImVec2(cell.x, cell.y + cell.h), IM_COL32(20, 20, 20, 255), 2.0f);
      draw->AddLine(ImVec2(cell.x, cell.y), ImVec2(cell.x + cell.w, cell.y), IM_COL32(20, 20, 20, 255), 2.0f);
      const bool estimated = !compFrame_->hasReference;
      draw->AddText(ImVec2(cell.x + 8.0f, cell.y + 6.0f), IM_COL32(200, 200, 200, 255),
                    estimated ? "error against time (log-log), each pane's own estimate" : "error against the reference, against time (log-log)");
      drawErrorChart(draw, *compFrame_, origin, size);
    }
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
    bool wipe = canvas_.wipe();
    if (ImGui::Checkbox("Wipe", &wipe)) canvas_.setWipe(wipe);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Show both panes in one frame, split by a divider you drag on the image");
  } else {
    canvas_.setWipe(false);
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
    try {
      writeTextAtomically(path, comparisonCsv(*compFrame_));
      report("wrote " + path);
    } catch (const std::exception& e) {
      report(std::string("export failed: ") + e.what());
    }
  }
  ImGui::SameLine();
  if (ImGui::Button("Save figure")) writeFigure("");
  ImGui::SameLine();
  if (ImGui::Button("Restart")) restartComparison();
}

// Display values by luminance, with what the screen clips; recomputed at most four times a second
// from the image shown (the live render, or the comparison's first pane), and only while open.
void Viewer::drawHistogram() {
  if (!ImGui::TreeNode("Histogram and clipping")) return;
  if (ImGui::Checkbox("Clipping view (H): red at white, blue at black", &clippingView_)) applyDisplay();
  const Film* film = frame_ && !frame_->preview ? &frame_->film : nullptr;
  uint64_t version = frame_ ? frame_->version : 0;
  if (!film && compFrame_)
    for (const auto& p : compFrame_->panes)
      if (p.film) {
        film = p.film.get(), version = compFrame_->version;
        break;
      }
  if (film && version != histogramVersion_ && secondsSince(histogramTime_) > 0.25) {
    std::vector<float> rgb = film->meanImage();
    colors_.applyCpu(display_, rgb);
    histogram_ = displayHistogram(rgb, 64);
    histogramVersion_ = version;
    histogramTime_ = ViewerClock::now();
  }
  if (histogram_.total > 0) {
    const float peak = *std::max_element(histogram_.counts.begin(), histogram_.counts.end());
    ImGui::PlotHistogram("##histogram", histogram_.counts.data(), static_cast<int>(histogram_.counts.size()), 0, nullptr, 0.0f, peak,
                         ImVec2(ImGui::GetContentRegionAvail().x, 70.0f));
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Pixels by display luminance, black (left) to white (right)");
    const ImVec4 warn(1.0f, 0.75f, 0.3f, 1.0f);
    ImGui::TextColored(histogram_.overShare() > 0.01 ? warn : ImGui::GetStyleColorVec4(ImGuiCol_Text), "clipped at white %.1f%%",
                       100.0 * histogram_.overShare());
    ImGui::SameLine();
    ImGui::TextColored(histogram_.underShare() > 0.01 ? warn : ImGui::GetStyleColorVec4(ImGuiCol_Text), "  at black %.1f%%",
                       100.0 * histogram_.underShare());
  } else {
    ImGui::TextDisabled("no image yet");
  }
  ImGui::TreePop();
}

void Viewer::drawPanel() {
  int ww, wh;
  glfwGetWindowSize(window_, &ww, &wh);
  ImGui::SetNextWindowPos(ImVec2(ww - panelWidth_, menuHeight_));
  ImGui::SetNextWindowSize(ImVec2(panelWidth_, wh - menuHeight_ - statusHeight_ - timelineHeight_));
  ImGui::Begin("Parameters", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  ImGui::PushItemWidth(-170.0f);

  if (ImGui::CollapsingHeader("Display", ImGuiTreeNodeFlags_DefaultOpen)) {
    ParamEditor editor;
    editor.choices["display"] = colors_.displays();
    editor.choices["view"] = colors_.views(display_.display);
    std::vector<std::string> looks{""};
    for (const auto& l : colors_.looks()) looks.push_back(l);
    editor.choices["look"] = looks;
    DisplaySettings d = display_;
    d.visit(editor);
    if (editor.changed) setDisplay(d, "panel");
    drawHistogram();
    if (!importSummary_.empty()) {
      ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyleColorVec4(ImGuiCol_TextDisabled));
      ImGui::TextWrapped("Opened as a volume: %s", importSummary_.c_str());
      ImGui::PopStyleColor();
      // The up axis, selectable: Z-up data is turned upright by -90 degrees about X, then reframed.
      const bool zUp = !edited_.volumes.empty() && edited_.volumes[0].transform.rotate_deg.x == -90.0f;
      auto setUp = [&](float degrees) {
        for (auto& v : edited_.volumes) v.transform.rotate_deg.x = degrees;
        reframeOnNextImage_ = true;
        submitEdit();
      };
      ImGui::TextUnformatted("Up axis of the file:");
      ImGui::SameLine();
      if (ImGui::RadioButton("Y", !zUp) && zUp) setUp(0.0f);
      ImGui::SameLine();
      if (ImGui::RadioButton("Z (Blender)", zUp) && !zUp) setUp(-90.0f);
      bool ground = hasGround();
      if (ImGui::Checkbox("Ground plane", &ground)) placeGround(ground);
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("A grey plane under the volume that catches its shadow (surfaces, type plane)");
    }
  }
  drawSnapshots();
  if (!haveScene_) {
    ImGui::TextWrapped(session_.loading() ? "Loading..." : "No scene. File > Open.");
    ImGui::End();
    return;
  }
  bool changed = false;
  if (compare_) drawComparisonPanel();
  // One tree node per item, with its fields, what the item warns about and a Remove button.
  auto list = [&](const char* title, auto& items, auto label, auto warnings, auto configure) {
    if (!ImGui::CollapsingHeader(title, ImGuiTreeNodeFlags_DefaultOpen)) return false;
    int remove = -1;
    for (size_t i = 0; i < items.size(); ++i) {
      ImGui::PushID(static_cast<int>(i));
      if (ImGui::TreeNodeEx(label(items[i], i).c_str(), ImGuiTreeNodeFlags_DefaultOpen)) {
        ParamEditor editor;
        configure(editor, items[i]);
        items[i].visit(editor);
        changed |= editor.changed;
        for (const std::string& w : warnings(items[i])) {
          ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0f, 0.55f, 0.3f, 1.0f));
          ImGui::TextWrapped("%s", w.c_str());
          ImGui::PopStyleColor();
        }
        if (ImGui::SmallButton("Remove")) remove = static_cast<int>(i);
        ImGui::TreePop();
      }
      ImGui::PopID();
    }
    if (remove >= 0) items.erase(items.begin() + remove), changed = true;
    return true;
  };
  auto none = [](const auto&) { return std::vector<std::string>{}; };
  auto plain = [](ParamEditor&, const auto&) {};
  // A sun is set by where it stands in the sky, a spot by where it aims.
  auto angles = [](ParamEditor& e, const LightDesc& l) {
    e.directionSense = l.type == LightType::Directional ? -1 : l.type == LightType::Spot ? 1 : 0;
  };
  list("Volumes", edited_.volumes, [](const VolumeDesc& v, size_t i) { return v.name.empty() ? "volume " + std::to_string(i) : v.name; },
       [](const VolumeDesc& v) { return emissionWarnings(v); }, plain);
  if (list("Lights", edited_.lights, [](const LightDesc& l, size_t i) { return std::to_string(i) + ": " + enumName(l.type); }, none, angles)) {
    // The default rig's parts (and a point light) back after a Remove.
    if (ImGui::SmallButton("Add sun")) edited_.lights.push_back(defaultSun()), changed = true;
    ImGui::SameLine();
    if (ImGui::SmallButton("Add sky")) edited_.lights.push_back(defaultSky()), changed = true;
    ImGui::SameLine();
    if (ImGui::SmallButton("Add point light")) {
      LightDesc point;
      point.position = edited_.camera.look_at + Vec3(0.0f, 1.0f, 0.0f);
      edited_.lights.push_back(point), changed = true;
    }
  }
  list("Surfaces", edited_.surfaces, [](const SurfaceDesc& s, size_t i) { return std::to_string(i) + ": " + enumName(s.type); }, none, plain);
  if (ImGui::CollapsingHeader("Camera")) {
    ParamEditor editor;
    edited_.camera.visit(editor);
    changed |= editor.changed;
  }
  if (!compare_ && ImGui::CollapsingHeader("Render", ImGuiTreeNodeFlags_DefaultOpen)) {
    // The viewer refines until a limit the artist sets (0: until stopped), or while not paused.
    ImGui::TextDisabled("Refine until (0: no limit)");
    ParamEditor editor;
    limits_.visit(editor);
    if (editor.changed) session_.setLimits(limits_);
    if (ImGui::Button(paused_ ? "Resume (P)" : "Pause (P)")) togglePause();
    ImGui::SameLine();
    if (ImGui::Button("Restart")) beginLatency(session_.edit(edited_));
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Discard the accumulated samples and start again");
  }
  if (ImGui::CollapsingHeader("Render settings")) {
    ParamEditor editor;
    edited_.render.visit(editor);
    changed |= editor.changed;
  }
  if (!compare_ && ImGui::CollapsingHeader("Strategy (for rendering engineers)")) {
    ParamEditor editor;
    editor.choices["preset"] = strategyPresetNames();
    // Under auto as chosen, the fields show what auto decided (the running scene's strategy, not the
    // document's undecided one), and an edit to any of them takes that choice over as its preset.
    const StrategySettings* autoChoice = autoChoiceShown();
    if (autoChoice) {
      // What auto decided in one line; why, and the split's figures, on demand.
      ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(0.6f, 0.85f, 1.0f, 1.0f));
      ImGui::TextWrapped("auto chose %s", strategyInWords(frame_->autoChoice).c_str());
      ImGui::PopStyleColor();
      if (ImGui::TreeNode("Why (details)")) {
        ImGui::TextWrapped("%s", frame_->autoDecision.c_str());
        if (!frame_->adaptiveSplit.empty()) ImGui::TextWrapped("%s", frame_->adaptiveSplit.c_str());
        ImGui::TextDisabled("Editing a field below takes auto's choice over as the %s preset.",
                           takeOverAutoChoice(*autoChoice, frame_->autoChoice).preset.c_str());
        ImGui::TreePop();
      }
    } else if (frame_ && !frame_->adaptiveSplit.empty() && ImGui::TreeNode("Adaptive sampling (details)")) {
      ImGui::TextWrapped("%s", frame_->adaptiveSplit.c_str());
      ImGui::TreePop();
    }
    StrategySettings shown = autoChoice ? *autoChoice : edited_.strategy;
    shown.visit(editor);
    if (!editor.presetChosen.empty()) edited_.strategy = strategyPreset(editor.presetChosen);
    else if (editor.changed) edited_.strategy = autoChoice ? takeOverAutoChoice(shown, frame_->autoChoice) : shown;
    changed |= editor.changed;
  }
  ImGui::PopItemWidth();
  ImGui::End();
  if (changed) submitEdit("panel");
}

// The sequence being rendered to disk: which frame, how far, and a Cancel button.
void Viewer::drawSequenceProgress() {
  if (!sequenceRunning_) return;
  const SequenceProgress p = sequenceJob_.progress();
  char label[128];
  std::snprintf(label, sizeof(label), "rendering frame %d (%d of %d done) %.0f%%", p.frame, p.done, p.total, 100.0 * p.fraction());
  ImGui::ProgressBar(static_cast<float>(p.fraction()), ImVec2(320.0f, 0.0f), label);
  ImGui::SameLine();
  if (ImGui::SmallButton("Cancel sequence")) sequenceJob_.cancel();
  ImGui::SameLine();
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
  if (frames_.empty()) drawSequenceProgress();  // a sequence shows it in the timeline
  if (frame_) {
    const Film& film = frame_->film;
    char latency[32] = "-";
    if (!latencies_.empty()) std::snprintf(latency, sizeof(latency), "%.0f ms", lastLatencyMs_);
    char split[48] = "";
    if (!frame_->preview && frame_->meanSplit > 1.0) std::snprintf(split, sizeof(split), " (adaptive: x%.2f camera samples)", frame_->meanSplit);
    ImGui::Text("%s%s | %s | %dx%d | %d spp%s%s | %.1f s | %.3g samples/s | rejected %llu | edit->image %s | UI %.0f fps%s",
                dirty_ ? "* " : "", (documentPath_.empty() ? scenePath_ : documentPath_).c_str(),
                frame_->scene ? (frame_->autoChoice.empty() ? frame_->scene->strategy.preset : "auto: " + frame_->autoChoice).c_str() : "", frame_->width, frame_->height,
                frame_->preview ? 0 : film.spp(), split, frame_->preview ? " (preview)" : (paused_ ? " (paused)" : frame_->finished ? " (done)" : ""), frame_->seconds,
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
  int px = -1, py = -1;
  const int underCursor = canvas_.imageAt(ImGui::GetIO().MousePos);
  const char* locked = canvas_.readoutLocked() ? " [locked: L]" : "";
  auto filmReadout = [&](const Film& film, int fx, int fy) {
    const Rgb m = film.mean(fx, fy), se = film.standardError(fx, fy);
    ImGui::Text("pixel (%d, %d)%s  RGB %.5g %.5g %.5g  std. error %.3g %.3g %.3g  (%d spp)", px, py, locked, m.r, m.g, m.b, se.r, se.g, se.b,
                film.spp());
  };
  const Snapshot* comparedSnapshot = comparedSnapshot_ && frame_ && !compare_ ? snapshots_.find(comparedSnapshot_) : nullptr;
  if (comparedSnapshot && underCursor == 1 && comparedSnapshot->image.width == frame_->width && comparedSnapshot->image.height == frame_->height &&
      canvas_.readoutPixel(frame_->width, frame_->height, px, py)) {
    // Over the snapshot: its own values (it keeps the mean only).
    const float* v = &comparedSnapshot->image.rgb[3 * (static_cast<size_t>(py) * frame_->width + px)];
    ImGui::TextColored(ImVec4(1.0f, 0.86f, 0.47f, 1.0f), "snapshot %s", comparedSnapshot->label.c_str());
    ImGui::SameLine();
    ImGui::Text("pixel (%d, %d)%s  RGB %.5g %.5g %.5g  (%d spp)", px, py, locked, v[0], v[1], v[2], comparedSnapshot->spp);
  } else if (frame_ && canvas_.readoutPixel(frame_->width, frame_->height, px, py)) {
    const Film& film = frame_->film;
    filmReadout(film, px * film.width() / frame_->width, py * film.height() / frame_->height);
  } else if (compare_ && compFrame_ && !compFrame_->panes.empty() && canvas_.readoutPixel(compFrame_->width, compFrame_->height, px, py)) {
    // A comparison: the pane under the cursor (its strategy named and coloured), so the same pixel can
    // be read in each pane in turn, the readout locked on it.
    const size_t k = std::min(compFrame_->panes.size() - 1, static_cast<size_t>(underCursor));
    const PaneState& pane = compFrame_->panes[k];
    if (pane.film && pane.film->width() == compFrame_->width && pane.film->height() == compFrame_->height) {
      ImGui::TextColored(ImGui::ColorConvertU32ToFloat4(paneColor(k)), "%s", pane.label.c_str());
      ImGui::SameLine();
      filmReadout(*pane.film, px, py);
    } else {
      ImGui::TextDisabled("pixel (%d, %d): %s has no image yet", px, py, pane.label.c_str());
    }
  } else {
    ImGui::TextDisabled("pixel readout: hover the image (L locks)");
  }
  // The newest message stays visible for 10 seconds (an error for 20); Help > Messages keeps them all.
  // Coloured by severity: information plain, warnings amber, errors red.
  auto colour = [](const std::string& text) {
    switch (messageSeverity(text)) {
      case Severity::Error: return ImVec4(1.0f, 0.42f, 0.35f, 1.0f);
      case Severity::Warning: return ImVec4(1.0f, 0.75f, 0.3f, 1.0f);
      default: return ImGui::GetStyleColorVec4(ImGuiCol_Text);
    }
  };
  if (!messages_.empty()) {
    const auto& [text, when] = messages_.back();
    if (secondsSince(when) < (messageSeverity(text) == Severity::Error ? 20.0 : 10.0)) ImGui::TextColored(colour(text), "%s", text.c_str());
  }
  ImGui::End();

  if (showMessages_) {
    ImGui::SetNextWindowSize(ImVec2(700, 300), ImGuiCond_FirstUseEver);
    if (ImGui::Begin("Messages", &showMessages_))
      for (const auto& m : messages_) {
        ImGui::PushStyleColor(ImGuiCol_Text, colour(m.first));
        ImGui::TextWrapped("%s", m.first.c_str());
        ImGui::PopStyleColor();
      }
    ImGui::End();
  }
}

// --- snapshots ---

namespace {

GLuint uploadThumbnail(const Snapshot& s) {
  GLuint tex = 0;
  glGenTextures(1, &tex);
  glBindTexture(GL_TEXTURE_2D, tex);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, s.thumbWidth, s.thumbHeight, 0, GL_RGB, GL_UNSIGNED_BYTE, s.thumbnail.data());
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glBindTexture(GL_TEXTURE_2D, 0);
  return tex;
}

}  // namespace

void Viewer::takeSnapshot() {
  if (compare_) {
    // The comparison: one snapshot per pane that has an image, labelled with its strategy.
    int kept = 0;
    for (const PaneState& p : compFrame_ ? compFrame_->panes : std::vector<PaneState>{}) {
      if (!p.film || p.film->spp() == 0) continue;
      try {
        nlohmann::json look = lookState();
        look["strategy"] = toJson(p.strategy);
        const Snapshot& s = snapshots_.add(p.film->image(), look, p.film->spp(), paneTitle(p));
        thumbnails_[s.id] = uploadThumbnail(s);
        ++kept;
      } catch (const std::exception& e) {
        report(std::string("snapshot failed: ") + e.what());
      }
    }
    if (kept == 0) report("snapshot: no pane has an image yet");
    else showSnapshots_ = true, report("snapshot: kept " + std::to_string(kept) + " panes");
    return;
  }
  if (!frame_ || frame_->preview || frame_->film.spp() == 0) {
    report("snapshot: no image yet");
    return;
  }
  try {
    const Snapshot& s = snapshots_.add(frame_->film.image(), lookState(), frame_->film.spp(),
                                       frame_->scene ? frame_->scene->strategy.preset : edited_.strategy.preset);
    thumbnails_[s.id] = uploadThumbnail(s);
    showSnapshots_ = true;
    report("snapshot " + s.label + " kept in " + s.path);
  } catch (const std::exception& e) {
    report(std::string("snapshot failed: ") + e.what());
  }
}

bool Viewer::openImage(const std::string& path, bool asReference) {
  try {
    if (!isExrPath(path)) throw InputError(path + ": expected an OpenEXR image (.exr)");
    Image image = readExr(path);
    if (asReference) {
      if (!compare_) throw InputError(path + ": a reference is for the comparison view (--panes, or candela with no scene)");
      if (compFrame_ && (image.width != compFrame_->width || image.height != compFrame_->height))
        throw InputError(path + ": expected a " + std::to_string(compFrame_->width) + "x" + std::to_string(compFrame_->height) +
                         " image, the panes' size; got " + std::to_string(image.width) + "x" + std::to_string(image.height));
      reference_ = std::move(image);
      restartComparison();
      report("reference: " + path + " (the panes' errors are measured against it)");
      return true;
    }
    int spp = 0;
    if (auto it = image.metadata.find("spp"); it != image.metadata.end()) spp = std::atoi(it->second.c_str());
    const Snapshot& s = snapshots_.add(image, lookState(), spp, fs::path(path).filename().string());
    thumbnails_[s.id] = uploadThumbnail(s);
    showSnapshots_ = true;
    report("opened " + path + " as snapshot " + s.label);
    if (frame_ && !compare_ && image.width == frame_->width && image.height == frame_->height) compareSnapshot(s.id);
    return true;
  } catch (const std::exception& e) {
    report(std::string("could not open the image: ") + e.what());
    return false;
  }
}

void Viewer::compareSnapshot(int id) {
  const Snapshot* s = snapshots_.find(id);
  if (!s) {
    comparedSnapshot_ = 0;
    return;
  }
  if (!snapshotGl_) snapshotGl_ = std::make_unique<GlDisplay>();
  // Shown as it was seen: through the snapshot's own display settings (exposure, view, look).
  DisplaySettings seen = display_;
  try {
    if (s->look.contains("display")) fromJson(s->look["display"], seen, s->path, "display");
  } catch (const std::exception&) {
    seen = display_;
  }
  snapshotGl_->setPipeline(colors_, colors_.resolve(seen));
  snapshotGl_->uploadImage(s->image.width, s->image.height, s->image.rgb);
  snapshotDirty_ = true;
  comparedSnapshot_ = id;
}

// A section of the Parameters panel (it never covers the image being compared).
void Viewer::drawSnapshots() {
  if (compare_) return;
  ImGui::SetNextItemOpen(showSnapshots_);
  showSnapshots_ = ImGui::CollapsingHeader("Snapshots");
  if (!showSnapshots_) return;
  if (ImGui::Button("Snapshot (K)")) takeSnapshot();
  ImGui::SameLine();
  if (comparedSnapshot_) {
    bool wipe = canvas_.wipe();
    if (ImGui::Checkbox("Wipe", &wipe)) canvas_.setWipe(wipe);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("On: live left of a divider you drag, snapshot right of it. Off: side by side");
    ImGui::SameLine();
    if (ImGui::Button("Stop comparing")) comparedSnapshot_ = 0;
  }
  ImGui::TextDisabled("Kept on disk in %s", snapshots_.directory().c_str());
  int remove = 0;
  for (auto it = snapshots_.snapshots().rbegin(); it != snapshots_.snapshots().rend(); ++it) {
    const Snapshot& s = *it;
    ImGui::PushID(s.id);
    ImGui::Separator();
    if (!thumbnails_.count(s.id)) thumbnails_[s.id] = uploadThumbnail(s);
    const float w = 120.0f, h = w * static_cast<float>(s.thumbHeight) / static_cast<float>(std::max(1, s.thumbWidth));
    ImGui::Image(reinterpret_cast<ImTextureID>(static_cast<intptr_t>(thumbnails_[s.id])), ImVec2(w, h));
    ImGui::SameLine();
    ImGui::BeginGroup();
    ImGui::Text("%s%s", s.label.c_str(), s.id == comparedSnapshot_ ? "  (compared)" : "");
    if (ImGui::Button("Compare")) {
      compareSnapshot(s.id);
      canvas_.setWipe(true);
    }
    ImGui::SameLine();
    if (ImGui::Button("Side by side")) {
      compareSnapshot(s.id);
      canvas_.setWipe(false);
    }
    if (ImGui::Button("Restore settings")) {
      restoreLook(s.look, "restore snapshot");
      recordEdit();
    }
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Make this snapshot's scene and display settings the current ones (undoable)");
    ImGui::SameLine();
    if (ImGui::Button("Delete")) remove = s.id;
    ImGui::EndGroup();
    ImGui::PopID();
  }
  if (snapshots_.snapshots().empty()) ImGui::TextWrapped("No snapshots yet. K keeps the current image and its settings.");
  if (remove) {
    if (thumbnails_.count(remove)) glDeleteTextures(1, &thumbnails_[remove]), thumbnails_.erase(remove);
    if (comparedSnapshot_ == remove) comparedSnapshot_ = 0;
    snapshots_.remove(remove);
  }
}

// --- the timeline ---

void Viewer::setFrame(int frame) {
  if (frames_.empty() || !haveScene_) return;
  if (frame > frames_.last) frame = frames_.first;  // wraps, as a looping flipbook does
  if (frame < frames_.first) frame = frames_.last;
  if (frame == edited_.render.frame) return;
  edited_.render.frame = frame;
  frameStepTo_ = frame;
  frameStepStart_ = ViewerClock::now();
  frameLatencyPending_ = true;
  submitEdit("frame");
}

int Viewer::neighbourFrame(int direction) const {
  int frame = edited_.render.frame;
  for (int tried = 0; tried <= frames_.last - frames_.first; ++tried) {
    frame += direction;
    if (frame > frames_.last) frame = frames_.first;
    if (frame < frames_.first) frame = frames_.last;
    if (!unloadableFrames_.count(frame)) return frame;
  }
  return edited_.render.frame;
}

void Viewer::pollTimeline() {
  if (frames_.empty() || !frame_ || !frame_->scene) return;
  const bool current = frame_->scene->render.frame == edited_.render.frame && !frame_->preview && frame_->film.spp() > 0 && !session_.loading();
  if (!current) return;
  if (frameLatencyPending_) {
    frameLatencyPending_ = false;
    unloadableFrames_.erase(edited_.render.frame);  // it loads now (the file was fixed)
    lastFrameStepMs_ = 1000.0 * secondsSince(frameStepStart_);
    std::printf("frame %d: first image %.0f ms after the step\n", edited_.render.frame, lastFrameStepMs_);
    std::fflush(stdout);
  }
  // The next frame's grids load in the background while this one renders.
  if (!prefetcher_) prefetcher_ = std::make_unique<FramePrefetcher>();
  SceneDesc next = edited_;
  next.render.frame = neighbourFrame(+1);
  if (prefetchedFrame_ != next.render.frame && !prefetcher_->busy()) {
    prefetchedFrame_ = next.render.frame;
    prefetcher_->prefetch(next);
  }
  const bool frameDone = frame_->film.spp() >= playSpp_ || (playSeconds_ > 0.0f && frame_->seconds >= playSeconds_);
  if (playing_ && frameDone) {
    if (next.render.frame == edited_.render.frame && !unloadableFrames_.empty()) {
      playing_ = false;
      report("playback paused: no other frame of the sequence could be loaded");
    } else {
      setFrame(next.render.frame);
    }
  }
}

void Viewer::drawTimeline() {
  if (frames_.empty() || compare_) {
    timelineHeight_ = 0.0f;
    return;
  }
  int ww, wh;
  glfwGetWindowSize(window_, &ww, &wh);
  timelineHeight_ = ImGui::GetFrameHeightWithSpacing() + 2.0f * ImGui::GetStyle().WindowPadding.y;
  ImGui::SetNextWindowPos(ImVec2(0.0f, wh - statusHeight_ - timelineHeight_));
  ImGui::SetNextWindowSize(ImVec2(static_cast<float>(ww), timelineHeight_));
  ImGui::Begin("Timeline", nullptr,
               ImGuiWindowFlags_NoTitleBar | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoScrollbar |
                   ImGuiWindowFlags_NoSavedSettings);
  drawSequenceProgress();
  if (ImGui::Button("|<")) setFrame(frames_.first);
  ImGui::SameLine();
  if (ImGui::Button("<")) setFrame(neighbourFrame(-1));
  ImGui::SameLine();
  if (ImGui::Button(playing_ ? "Pause" : "Play")) playing_ = !playing_;
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Renders each frame to the spp on the right, then steps (Space)");
  ImGui::SameLine();
  if (ImGui::Button(">")) setFrame(neighbourFrame(+1));
  ImGui::SameLine();
  if (ImGui::Button(">|")) setFrame(frames_.last);
  ImGui::SameLine();
  ImGui::SetNextItemWidth(static_cast<float>(ww) - 640.0f);
  int frame = edited_.render.frame;
  if (ImGui::SliderInt("##frame", &frame, frames_.first, frames_.last, "frame %d") && frame != edited_.render.frame) setFrame(frame);
  ImGui::SameLine();
  ImGui::SetNextItemWidth(90.0f);
  ImGui::DragInt("spp", &playSpp_, 1.0f, 1, 1 << 16);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Play steps on once a frame has this many samples per pixel...");
  ImGui::SameLine();
  ImGui::SetNextItemWidth(70.0f);
  ImGui::DragFloat("s", &playSeconds_, 0.05f, 0.0f, 3600.0f, "%.1f");
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("...or this many seconds of rendering, whichever comes first (0: spp only)");
  ImGui::SameLine();
  if (lastFrameStepMs_ > 0.0)
    ImGui::TextDisabled("%d frames, step %.0f ms", frames_.count, lastFrameStepMs_);
  else
    ImGui::TextDisabled("%d frames", frames_.count);
  if (!unloadableFrames_.empty()) {
    std::string list;
    for (int f : unloadableFrames_) list += (list.empty() ? "" : ", ") + std::to_string(f);
    if (unloadableFrames_.size() > 6) list = std::to_string(unloadableFrames_.size()) + " frames";
    ImGui::SameLine();
    ImGui::TextColored(ImVec4(1.0f, 0.6f, 0.3f, 1.0f), "passed: %s", list.c_str());
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Frames that could not be loaded: Play and the step buttons pass them, the slider tries them again");
  }
  ImGui::End();
}

}  // namespace candela
