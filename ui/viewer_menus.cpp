// The menu bar, the dialogs (open, save as, unsaved edits) and the keyboard shortcuts.
#include "viewer_impl.h"

#include <algorithm>

namespace candela {

namespace fs = std::filesystem;

void Viewer::drawMenuBar() {
  if (!ImGui::BeginMainMenuBar()) return;
  menuHeight_ = ImGui::GetWindowSize().y;
  const bool single = haveScene_ && !compare_;
  if (ImGui::BeginMenu("File")) {
    if (ImGui::MenuItem("Open scene or VDB...", "Ctrl+O")) showOpen_ = true;
    if (ImGui::MenuItem("Open image (EXR)...", "Ctrl+I")) showOpenImage_ = true;
    if (ImGui::MenuItem("Save", "Ctrl+S", false, single)) requestSave();
    if (ImGui::MenuItem("Save As...", "Ctrl+Shift+S", false, single)) showSaveAs_ = true;
    if (ImGui::MenuItem("Render sequence to disk...", nullptr, false, single && !sequenceRunning_)) {
      showRenderSequence_ = true;
      sequenceFirst_ = frames_.empty() ? edited_.render.frame : frames_.first;
      sequenceLast_ = frames_.empty() ? edited_.render.frame : frames_.last;
      sequenceSpp_ = edited_.render.spp;
      const std::string stem = fs::path(documentPath_.empty() ? scenePath_ : documentPath_).stem().string();
      if (sequencePattern_.empty()) sequencePattern_ = (fs::path("renders") / (stem + ".####.exr")).string();
    }
    if (ImGui::MenuItem("Reload scene", nullptr, false, !scenePath_.empty()))
      confirmDiscard("reload", [this] { openScene(scenePath_, sceneSettings_, scenePreset_); });
    ImGui::Separator();
    const bool image = frame_ != nullptr || (compFrame_ && !compFrame_->panes.empty());
    if (ImGui::MenuItem(compare_ ? "Save screenshot (figure and every pane)" : "Save screenshot", "S / F12", false, image)) screenshot("");
    if (ImGui::MenuItem(compare_ ? "Snapshot every pane" : "Snapshot", "K", false, image)) takeSnapshot();
    ImGui::Separator();
    if (ImGui::MenuItem("Quit", "Ctrl+Q")) requestQuit();
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("Edit")) {
    if (ImGui::MenuItem("Undo", "Ctrl+Z", false, history_.canUndo())) undo();
    if (ImGui::MenuItem("Redo", "Ctrl+Shift+Z", false, history_.canRedo())) redo();
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("View")) {
    if (ImGui::MenuItem("Frame volume", "F", false, haveScene_)) frameVolume();
    if (ImGui::MenuItem("Reset camera", "R / Home", false, haveScene_)) resetCamera();
    if (ImGui::MenuItem("Lock pixel readout", "L", canvas_.readoutLocked())) toggleReadoutLock();
    if (ImGui::MenuItem("Clear render region", "Esc", false, region_.has_value())) setRegion(std::nullopt);
    if (ImGui::MenuItem("Clipping view", "H", clippingView_)) clippingView_ = !clippingView_, applyDisplay();
    if (ImGui::MenuItem("Fit image", "0", !canvas_.oneToOne())) canvas_.resetZoom();
    if (ImGui::MenuItem("Actual pixels (1:1)", "1", canvas_.oneToOne())) canvas_.setOneToOne(true);
    if (ImGui::MenuItem(paused_ ? "Resume rendering" : "Pause rendering", "P", paused_, !compare_)) togglePause();
    if (ImGui::MenuItem("Snapshots", "Shift+K", showSnapshots_)) showSnapshots_ = !showSnapshots_;
    ImGui::Separator();
    for (const auto& [value, name] : EnumNames<ChannelView>::get())
      if (ImGui::MenuItem((std::string("Channel: ") + name).c_str(), value == ChannelView::RGB ? "C cycles" : nullptr, display_.channel == value)) {
        DisplaySettings d = display_;
        d.channel = value;
        setDisplay(d);
      }
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("Display")) {
    for (const auto& d : colors_.displays())
      if (ImGui::BeginMenu(d.c_str())) {
        for (const auto& v : colors_.views(d))
          if (ImGui::MenuItem(v.c_str(), nullptr, display_.display == d && display_.view == v)) {
            DisplaySettings s = display_;
            s.display = d, s.view = v;
            setDisplay(s);
          }
        ImGui::EndMenu();
      }
    if (ImGui::BeginMenu("Look")) {
      DisplaySettings s = display_;
      if (ImGui::MenuItem("(none)", nullptr, display_.look.empty())) s.look.clear(), setDisplay(s);
      for (const auto& l : colors_.looks())
        if (ImGui::MenuItem(l.c_str(), nullptr, display_.look == l)) s.look = l, setDisplay(s);
      ImGui::EndMenu();
    }
    ImGui::Separator();
    ImGui::TextDisabled("Config: %s", colors_.configPath().c_str());
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("Help")) {
    ImGui::MenuItem("Messages", nullptr, &showMessages_);
    ImGui::TextDisabled("Open: File > Open, Ctrl+O, or drop a scene (.json) or volume (.vdb) on the window");
    ImGui::TextDisabled("Mouse on the image: left tumble, middle track, right dolly, wheel dolly (Alt optional)");
    ImGui::TextDisabled("Image: Ctrl+wheel zoom, Shift+left drag pan, 0 fit, 1 actual pixels (all panes together)");
    ImGui::TextDisabled("Ctrl+click a pixel: guide inspector (distance densities along its ray); Ctrl+drag: render region, Esc clears it");
    ImGui::TextDisabled("Keys: F frame volume, R reset camera, L lock readout, C channel, E/Shift+E exposure, S screenshot, P pause");
    ImGui::TextDisabled("Ctrl+Z undo, Ctrl+Shift+Z redo, Ctrl+S save, K snapshot, Shift+K snapshots, Left/Right frame, Space play");
    ImGui::EndMenu();
  }
  ImGui::EndMainMenuBar();
}

void Viewer::drawDialogs() {
  // --- Open ---
  if (showOpen_) {
    showOpen_ = false;
    ImGui::OpenPopup("Open scene or VDB");
    openPath_ = scenePath_;
    // Scenes and volumes under assets/scenes and beside the current scene, listed once per opening.
    openCandidates_.clear();
    std::vector<fs::path> roots{fs::path(CANDELA_ASSET_DIR) / "scenes"};
    if (!scenePath_.empty()) roots.push_back(fs::path(scenePath_).parent_path());
    for (const auto& root : roots) {
      std::error_code ec;
      int visited = 0;
      for (auto it = fs::recursive_directory_iterator(root, ec); !ec && it != fs::recursive_directory_iterator() && ++visited < 5000;
           it.increment(ec)) {
        const std::string ext = it->path().extension().string();
        if (ext == ".json" || isVdbPath(it->path().string())) openCandidates_.push_back(fs::weakly_canonical(it->path()).string());
      }
    }
    std::sort(openCandidates_.begin(), openCandidates_.end());
    openCandidates_.erase(std::unique(openCandidates_.begin(), openCandidates_.end()), openCandidates_.end());
  }
  ImGui::SetNextWindowSize(ImVec2(640, 420), ImGuiCond_Appearing);
  if (ImGui::BeginPopupModal("Open scene or VDB")) {
    bool go = ImGui::InputText("path", &openPath_, ImGuiInputTextFlags_EnterReturnsTrue);
    ImGui::TextDisabled("Scenes (.json) and volumes (.vdb) found:");
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
      const std::string path = openPath_;
      ImGui::CloseCurrentPopup();
      confirmDiscard("open " + fs::path(path).filename().string(), [this, path] { openScene(path); });
    }
    ImGui::EndPopup();
  }

  // --- Open image ---
  if (showOpenImage_) {
    showOpenImage_ = false;
    ImGui::OpenPopup("Open image");
  }
  ImGui::SetNextWindowSize(ImVec2(640, 0), ImGuiCond_Appearing);
  if (ImGui::BeginPopupModal("Open image")) {
    ImGui::InputText("path", &openImagePath_);
    ImGui::TextDisabled("An OpenEXR image: a render to compare with, or the comparison's reference.");
    bool done = false;
    if (ImGui::Button("As a snapshot")) done = openImage(openImagePath_, false);
    if (compare_) {
      ImGui::SameLine();
      if (ImGui::Button("As the comparison's reference")) done = openImage(openImagePath_, true);
    }
    ImGui::SameLine();
    if (ImGui::Button("Cancel") || ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Escape))) done = true;
    if (done) ImGui::CloseCurrentPopup();
    ImGui::EndPopup();
  }

  // --- Render sequence ---
  if (showRenderSequence_) {
    showRenderSequence_ = false;
    ImGui::OpenPopup("Render sequence to disk");
  }
  ImGui::SetNextWindowSize(ImVec2(640, 0), ImGuiCond_Appearing);
  if (ImGui::BeginPopupModal("Render sequence to disk")) {
    ImGui::InputInt("first frame", &sequenceFirst_);
    ImGui::InputInt("last frame", &sequenceLast_);
    ImGui::InputInt("samples per pixel", &sequenceSpp_);
    ImGui::InputFloat("or seconds per frame (0: use spp)", &sequenceSeconds_);
    ImGui::InputText("output", &sequencePattern_);
    ImGui::TextDisabled("#### is the frame number; .exr keeps the scene-linear image, .png the display at this exposure.");
    ImGui::TextDisabled("The live render pauses while the sequence renders; the timeline shows its progress.");
    bool close = false;
    if (ImGui::Button("Render"))
      close = startSequenceRender(sequenceRequest(sequenceFirst_, sequenceLast_, std::max(0, sequenceSpp_), std::max(0.0f, sequenceSeconds_),
                                                  sequencePattern_));
    ImGui::SameLine();
    if (ImGui::Button("Cancel") || ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Escape))) close = true;
    if (close) ImGui::CloseCurrentPopup();
    ImGui::EndPopup();
  }

  // --- Save As ---
  if (showSaveAs_) {
    showSaveAs_ = false;
    ImGui::OpenPopup("Save scene as");
    saveAsPath_ = documentPath_.empty() ? (fs::current_path() / "scene.json").string() : documentPath_;
  }
  ImGui::SetNextWindowSize(ImVec2(640, 0), ImGuiCond_Appearing);
  if (ImGui::BeginPopupModal("Save scene as")) {
    bool go = ImGui::InputText("path", &saveAsPath_, ImGuiInputTextFlags_EnterReturnsTrue);
    ImGui::TextDisabled("A scene JSON; volume paths are written relative to it.");
    if (fs::exists(saveAsPath_)) ImGui::TextColored(ImVec4(1.0f, 0.75f, 0.3f, 1.0f), "%s exists and will be replaced", saveAsPath_.c_str());
    go |= ImGui::Button("Save");
    ImGui::SameLine();
    if (ImGui::Button("Cancel") || ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Escape))) {
      pendingAction_ = nullptr;  // a quit waiting for this save is cancelled too
      ImGui::CloseCurrentPopup();
    }
    if (go) {
      std::string path = saveAsPath_;
      if (fs::path(path).extension() != ".json") path += ".json";
      if (save(path)) {
        ImGui::CloseCurrentPopup();
        if (pendingAction_) {
          auto action = std::move(pendingAction_);
          pendingAction_ = nullptr;
          action();
        }
      }
    }
    ImGui::EndPopup();
  }

  // --- Unsaved edits ---
  if (showDiscard_) {
    showDiscard_ = false;
    ImGui::OpenPopup("Unsaved edits");
  }
  // Keys from the queue: a press and release between two frames is not lost.
  const bool enterKey = pressedThisFrame(GLFW_KEY_ENTER), dKey = pressedThisFrame(GLFW_KEY_D),
             escapeKey = pressedThisFrame(GLFW_KEY_ESCAPE);
  if (ImGui::BeginPopupModal("Unsaved edits", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
    ImGui::Text("%s has unsaved edits.", documentPath_.empty() ? "The scene" : fs::path(documentPath_).filename().string().c_str());
    ImGui::Text("Save them before you %s?", discardWhat_.c_str());
    ImGui::TextDisabled("Enter: save, D: discard, Esc: cancel");
    if (ImGui::Button("Save") || enterKey) {
      ImGui::CloseCurrentPopup();
      if (untitled_ || documentPath_.empty()) {
        showSaveAs_ = true;  // the action runs once saved
      } else if (save(documentPath_) && pendingAction_) {
        auto action = std::move(pendingAction_);
        pendingAction_ = nullptr;
        action();
      }
    }
    ImGui::SameLine();
    if (ImGui::Button("Discard") || dKey) {
      ImGui::CloseCurrentPopup();
      dirty_ = false;
      if (pendingAction_) {
        auto action = std::move(pendingAction_);
        pendingAction_ = nullptr;
        action();
      }
    }
    ImGui::SameLine();
    if (ImGui::Button("Cancel") || escapeKey) {
      pendingAction_ = nullptr;
      ImGui::CloseCurrentPopup();
    }
    ImGui::EndPopup();
  }
}

// L: lock the readout on the pixel under the cursor, in the image shown (live, or the comparison's panes).
void Viewer::toggleReadoutLock() {
  if (frame_) canvas_.toggleReadoutLock(frame_->width, frame_->height);
  else if (compare_ && compFrame_) canvas_.toggleReadoutLock(compFrame_->width, compFrame_->height);
}

bool Viewer::pressedThisFrame(int key) const {
  return std::any_of(framePresses_.begin(), framePresses_.end(), [key](const KeyPress& k) { return k.key == key && !k.repeat; });
}

// Every press queued since the last frame, in order (KeyQueue): eight presses of E are four stops.
void Viewer::handleKeys() {
  ImGuiIO& io = ImGui::GetIO();
  if (io.WantCaptureKeyboard) return;  // typed into a field
  if (ImGui::IsPopupOpen("", ImGuiPopupFlags_AnyPopup)) return;
  for (const KeyPress& k : framePresses_) {
    // Held keys repeat only where holding means "more": exposure and the timeline.
    if (k.repeat && k.key != GLFW_KEY_E && k.key != GLFW_KEY_LEFT && k.key != GLFW_KEY_RIGHT) continue;
    if (k.ctrl()) {
      switch (k.key) {
        case GLFW_KEY_Z: k.shift() ? redo() : undo(); break;
        case GLFW_KEY_Y: redo(); break;
        case GLFW_KEY_S: k.shift() ? void(showSaveAs_ = true) : requestSave(); break;
        case GLFW_KEY_O: showOpen_ = true; break;
        case GLFW_KEY_I: showOpenImage_ = true; break;
        case GLFW_KEY_Q: requestQuit(); break;
        default: break;
      }
      continue;
    }
    switch (k.key) {
      case GLFW_KEY_F:
        if (haveScene_) frameVolume();
        break;
      case GLFW_KEY_R:
      case GLFW_KEY_HOME:
        if (haveScene_) resetCamera();
        break;
      case GLFW_KEY_L: toggleReadoutLock(); break;
      case GLFW_KEY_S:
      case GLFW_KEY_F12: screenshot(""); break;
      case GLFW_KEY_C: {
        DisplaySettings d = display_;
        d.channel = static_cast<ChannelView>((static_cast<int>(d.channel) + 1) % 5);
        setDisplay(d);
        break;
      }
      case GLFW_KEY_E: {  // exposure: E up, Shift+E down
        DisplaySettings d = display_;
        d.exposure += k.shift() ? -0.5f : 0.5f;
        d.autoExposure = false;
        setDisplay(d);
        break;
      }
      case GLFW_KEY_K:
        if (k.shift()) showSnapshots_ = !showSnapshots_;
        else takeSnapshot();
        break;
      case GLFW_KEY_LEFT:
        if (!frames_.empty()) setFrame(neighbourFrame(-1));
        break;
      case GLFW_KEY_RIGHT:
        if (!frames_.empty()) setFrame(neighbourFrame(+1));
        break;
      case GLFW_KEY_SPACE:
        if (!frames_.empty()) playing_ = !playing_;
        break;
      case GLFW_KEY_0: canvas_.resetZoom(); break;
      case GLFW_KEY_1: canvas_.setOneToOne(true); break;
      case GLFW_KEY_P: togglePause(); break;
      case GLFW_KEY_ESCAPE:
        if (region_) setRegion(std::nullopt);
        break;
      case GLFW_KEY_H:
        clippingView_ = !clippingView_;
        applyDisplay();
        break;
      default: break;
    }
  }
}

}  // namespace candela
