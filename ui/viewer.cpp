// The viewer's core: the window loop (after Dear ImGui's GLFW/OpenGL3 example) and the document,
// the scene being looked at: open (scene files and bare VDBs), live edits, undo and redo, save, the
// unsaved-edits mark and the questions before anything would be lost. See viewer_impl.h for where
// the other concerns live.
#include "viewer_impl.h"

#include "auto_strategy.h"

#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <thread>

namespace candela {

namespace fs = std::filesystem;

std::string defaultScenePath() { return std::string(CANDELA_ASSET_DIR) + "/scenes/torch-in-mist.json"; }

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

Viewer::Viewer(GLFWwindow* window, const ViewerOptions& options)
    : window_(window),
      options_(options),
      session_(RenderOptions{options.threads, 32}, /*yieldToUi=*/true),
      canvas_(window),
      snapshots_(SnapshotStore::sessionDirectory()) {
  openStart_ = ViewerClock::now();
  openLatencyPending_ = true;
  session_.setNotify([] { glfwPostEmptyEvent(); });  // thread-safe: wakes the event wait in run()
  if (options.holdBuildsMs > 0)
    session_.setBuildHook([this, ms = options.holdBuildsMs](const SceneDesc&) {
      std::this_thread::sleep_for(std::chrono::milliseconds(ms));
      // The scripted edits land while the file loads however long the UI takes between two frames;
      // the cap is a safety net only.
      const auto cap = std::chrono::steady_clock::now() + std::chrono::seconds(60);
      while (holdBuildForScriptedEdits_.load() && std::chrono::steady_clock::now() < cap)
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    });
  colors_ = ColorPipeline::load(options.ocioConfig);
  if (!colors_.message().empty()) report(colors_.message());
  display_ = colors_.resolve(display_);
  gl_ = std::make_unique<GlDisplay>();
  applyDisplay();
  if (options.afterSpp > 0) limits_.spp = options.afterSpp;
  session_.setLimits(limits_);
  // Files dropped on the window open like File > Open (after asking about unsaved edits).
  glfwSetWindowUserPointer(window_, this);
  glfwSetDropCallback(window_, [](GLFWwindow* w, int count, const char** paths) {
    auto* self = static_cast<Viewer*>(glfwGetWindowUserPointer(w));
    for (int i = 0; i < count; ++i) self->droppedPaths_.push_back(paths[i]);
  });
  // Key presses are queued as GLFW reports them (ImGui's backend, installed after us, chains to this).
  glfwSetKeyCallback(window_, [](GLFWwindow* w, int key, int, int action, int mods) {
    auto* self = static_cast<Viewer*>(glfwGetWindowUserPointer(w));
    if (self && key >= 0 && action != GLFW_RELEASE) self->keys_.push({key, mods, action == GLFW_REPEAT});
  });
  // Closing the window with unsaved edits asks first.
  glfwSetWindowCloseCallback(window_, [](GLFWwindow* w) {
    glfwSetWindowShouldClose(w, GLFW_FALSE);
    static_cast<Viewer*>(glfwGetWindowUserPointer(w))->requestQuit();
  });
  if (!options.panes.empty()) {
    startComparisonMode(options.scenePath.empty() ? defaultScenePath() : options.scenePath);
    return;
  }
  openScene(options.scenePath.empty() ? defaultScenePath() : options.scenePath, options.settings, options.preset);
}

Viewer::~Viewer() {
  for (auto& [id, tex] : thumbnails_) glDeleteTextures(1, &tex);
  glfwSetWindowUserPointer(window_, nullptr);
}

// --- the document ---

void Viewer::openScene(const std::string& path, const std::vector<std::string>& settings, const std::string& preset) {
  try {
    VdbImportReport imported;
    VdbImportOptions import;
    import.up = options_.upAxis == "z" ? UpAxis::Z : options_.upAxis == "y" ? UpAxis::Y : UpAxis::Auto;
    SceneDesc desc = loadSceneOrVdb(path, settings, preset, import, &imported);
    const bool vdb = isVdbPath(path);
    // Opening over an open still loading keeps the document from before the first: it still renders.
    if (!pendingOpen_) {
      beforeOpen_.reset();
      if (haveScene_)
        beforeOpen_ = DocumentState{scenePath_, documentPath_, scenePreset_, importSummary_, sceneSettings_, sceneTime_, untitled_, dirty_,
                                    display_, history_, frames_, fileScene_};
    }
    scenePath_ = path;
    documentPath_ = desc.path;
    untitled_ = vdb;
    sceneSettings_ = settings;
    scenePreset_ = preset;
    sceneTime_ = modificationTime(path);
    importSummary_ = vdb ? imported.summary() : "";
    if (vdb) report("opened " + path + " as a volume: " + importSummary_);
    // The look the file was saved with; a file that gives no exposure (a bare VDB, a scene without
    // display.exposure) gets one that shows it once it renders (pollSession).
    display_ = colors_.resolve(desc.display);
    applyDisplay();
    edited_ = desc;
    edited_.display = display_;
    frames_ = sceneFrames(desc);
    unloadableFrames_.clear();
    playing_ = false;
    history_.reset(lookState());
    dirty_ = false;  // an opened VDB is untitled (Save asks where) but holds no edits yet
    comparedSnapshot_ = 0;
    openStart_ = ViewerClock::now();
    openLatencyPending_ = true;
    // Reset camera goes to the opened file's camera from here on, even while the file loads.
    fileScene_ = desc;
    pendingOpen_ = session_.open(desc);
    updateTitle();
  } catch (const std::exception& e) {
    report(std::string("could not open ") + path + ": " + e.what() + (haveScene_ ? " (still showing the last good scene)" : ""));
    // With a scene on screen nothing changes: the document, its file watch and its samples stay.
    // Without one, watch the file that failed, so fixing it loads it.
    if (!haveScene_) scenePath_ = path, sceneTime_ = modificationTime(path);
  }
}

bool rendersDifferently(const SceneDesc& a, const SceneDesc& b) { return diffScenes(a, b).any(); }

nlohmann::json Viewer::lookState() const {
  SceneDesc withDisplay = edited_;
  withDisplay.display = display_;
  return sceneToJson(withDisplay);
}

void Viewer::restoreLook(const nlohmann::json& look, const std::string& what) {
  try {
    SceneDesc desc = parseSceneDesc(look, edited_.path);
    const std::string path = edited_.path;
    desc.path = path;
    const bool rendered = rendersDifferently(desc, edited_);
    edited_ = desc;
    edited_.path = path;
    display_ = colors_.resolve(desc.display);
    applyDisplay();
    if (compare_) {
      restartComparison();
    } else if (rendered) {
      beginLatency(session_.edit(edited_));
    }
    dirty_ = true;
    updateTitle();
  } catch (const std::exception& e) {
    report(what + " failed: " + e.what());
  }
}

void Viewer::recordEdit(const std::string& group) {
  history_.record(lookState(), group);
  dirty_ = true;
  updateTitle();
}

void Viewer::submitEdit(const std::string& group) {
  try {
    SceneDesc valid = parseSceneDesc(sceneToJson(edited_), edited_.path);
    valid.path = edited_.path;
    edited_ = valid;
    recordEdit(group);
    if (compare_) {  // every pane shares the scene and camera: restart them together
      restartComparison();
      return;
    }
    beginLatency(session_.edit(valid));
  } catch (const std::exception& e) {
    report(std::string("edit rejected: ") + e.what());
    if (frame_ && frame_->scene) {
      const std::string path = edited_.path;
      edited_ = *frame_->scene;
      edited_.path = path;
    }
  }
}

const StrategySettings* Viewer::autoChoiceShown() const {
  if (!frame_ || !frame_->scene || frame_->autoChoice.empty() || !needsAutoResolve(edited_.strategy)) return nullptr;
  return &frame_->scene->strategy;
}

void Viewer::applySettingEdit(const std::string& assignment) {
  try {
    Json doc = sceneToJson(edited_);
    // A strategy field edited under auto starts from what auto chose, as in the Strategy panel.
    const bool strategyField = assignment.rfind("strategy.", 0) == 0 && assignment.rfind("strategy.preset", 0) != 0;
    if (const StrategySettings* chosen = autoChoiceShown(); chosen && strategyField)
      doc["strategy"] = toJson(takeOverAutoChoice(*chosen, frame_->autoChoice));
    applySetting(doc, assignment, edited_.path + " (edit " + assignment + ")");
    SceneDesc valid = parseSceneDesc(doc, edited_.path);
    const bool rendered = rendersDifferently(valid, edited_);
    edited_ = valid;
    if (toJson(valid.display) != toJson(display_)) {
      display_ = colors_.resolve(valid.display);
      applyDisplay();
    }
    recordEdit();
    if (rendered) beginLatency(session_.edit(valid));  // a display edit needs no new samples
  } catch (const std::exception& e) {
    report(std::string("edit rejected: ") + e.what());
  }
}

void Viewer::setDisplay(const DisplaySettings& display, const std::string& group) {
  const bool exposureSet = display.exposure != display_.exposure;
  display_ = colors_.resolve(display);
  if (exposureSet) display_.autoExposure = false;  // the artist's exposure, never replaced
  applyDisplay();
  recordEdit(group);
}

void Viewer::undo() {
  if (auto state = history_.undo()) {
    restoreLook(*state, "undo");
    report("undo (" + std::to_string(history_.undoSteps()) + " more)");
  }
}

void Viewer::redo() {
  if (auto state = history_.redo()) {
    restoreLook(*state, "redo");
    report("redo (" + std::to_string(history_.redoSteps()) + " more)");
  }
}

bool Viewer::save(const std::string& path) {
  if (!haveScene_) {
    report("save: no scene to save");
    return false;
  }
  try {
    SceneDesc desc = edited_;
    desc.display = display_;
    const SceneDesc saved = saveSceneDesc(desc, path);
    edited_.path = saved.path;
    edited_.volumes = saved.volumes;  // relative paths now relative to the saved file
    fileScene_.path = edited_.path;
    fileScene_.volumes = edited_.volumes;
    documentPath_ = scenePath_ = path;
    sceneSettings_.clear();
    scenePreset_.clear();
    sceneTime_ = modificationTime(path);  // our own write is not an outside change to reload
    untitled_ = false;
    dirty_ = false;
    // The renderer keeps going: the saved scene is the one it renders (only the paths are new).
    history_.amend(lookState());
    updateTitle();
    report("saved " + path);
    return true;
  } catch (const std::exception& e) {
    report(std::string("save failed: ") + e.what() + " (nothing was lost: the edits are still here)");
    return false;
  }
}

void Viewer::requestSave() {
  if (untitled_ || documentPath_.empty()) {
    showSaveAs_ = true;
    return;
  }
  save(documentPath_);
}

void Viewer::confirmDiscard(const std::string& what, std::function<void()> action) {
  if (!dirty_) {
    action();
    return;
  }
  discardWhat_ = what;
  pendingAction_ = std::move(action);
  showDiscard_ = true;
  glfwPostEmptyEvent();
}

void Viewer::requestQuit() {
  // A scripted --quit run never waits for an answer.
  if (!dirty_ || closeConfirmed_ || options_.quit) {
    glfwSetWindowShouldClose(window_, GLFW_TRUE);
    return;
  }
  confirmDiscard("quit", [this] {
    closeConfirmed_ = true;
    glfwSetWindowShouldClose(window_, GLFW_TRUE);
  });
}

void Viewer::updateTitle() {
  std::string name = documentPath_.empty() ? "Candela" : fs::path(documentPath_).filename().string();
  if (untitled_) name += " (new, from " + fs::path(scenePath_).filename().string() + ")";
  const std::string title = (dirty_ ? "* " : "") + name + " - Candela";
  if (title != title_) {
    title_ = title;
    glfwSetWindowTitle(window_, title.c_str());
  }
}

void Viewer::beginLatency(uint64_t request) {
  if (latencyRequest_ == 0) {  // time the first of a burst of edits (a drag edits every frame)
    latencyRequest_ = request;
    latencyStart_ = ViewerClock::now();
  }
}

SequenceRenderRequest Viewer::sequenceRequest(int first, int last, int spp, double seconds, const std::string& pattern) const {
  SequenceRenderRequest r;
  r.scene = edited_;
  r.scene.display = display_;
  r.first = first, r.last = last;
  r.spp = spp, r.seconds = seconds;
  r.pattern = pattern;
  r.exposure = display_.exposure;
  r.autoExposure = display_.autoExposure;
  r.threads = options_.threads;
  return r;
}

bool Viewer::startSequenceRender(const SequenceRenderRequest& request) {
  try {
    sequenceJob_.start(request);
  } catch (const std::exception& e) {
    report(std::string("render sequence: ") + e.what());
    return false;
  }
  sequenceRunning_ = true;
  // The cores go to the sequence; the live render resumes when it ends.
  pausedForSequence_ = !paused_;
  if (pausedForSequence_) paused_ = true, session_.setPaused(true);
  report("rendering frames " + std::to_string(request.first) + "-" + std::to_string(request.last) + " to " + request.pattern);
  return true;
}

void Viewer::pollSequenceRender() {
  if (!sequenceRunning_) return;
  const SequenceProgress p = sequenceJob_.progress();
  busyFrames_ = std::max(busyFrames_, 1);  // the progress bar moves
  if (p.running) return;
  sequenceRunning_ = false;
  if (pausedForSequence_) paused_ = false, session_.setPaused(false), pausedForSequence_ = false;
  std::string text = "render sequence: " + std::string(p.cancelled ? "cancelled; " : "") + "wrote " + std::to_string(p.written.size()) +
                     " of " + std::to_string(p.total) + " frames";
  if (!p.written.empty()) text += " (last " + p.written.back() + ")";
  report(text);
  for (const auto& f : p.failed) report("render sequence: could not render " + f);
}

void Viewer::setRegion(std::optional<RegionRect> region) {
  region_ = region;
  session_.setRegion(region);
  if (region)
    report("render region " + std::to_string(region->w) + "x" + std::to_string(region->h) + " at (" + std::to_string(region->x) + ", " +
           std::to_string(region->y) + "): only it refines (Esc clears it)");
  else
    report("render region cleared: the whole image refines");
}

void Viewer::togglePause() {
  if (compare_) return;  // equal time: the panes run together or not at all
  paused_ = !paused_;
  session_.setPaused(paused_);
  report(paused_ ? "paused (P resumes)" : "resumed");
}

void Viewer::report(const std::string& text) {
  std::cerr << "candela: " << text << "\n";
  messages_.push_back({text, ViewerClock::now()});
  if (messages_.size() > 50) messages_.pop_front();
}

void Viewer::applyDisplay() {
  const std::string error = gl_->setPipeline(colors_, display_);
  if (!error.empty()) report(error);
  gl_->setClippingView(clippingView_);
  outputDirty_ = true;
  histogramVersion_ = 0;  // the histogram is of display values: computed again
  for (size_t i = 0; i < paneGl_.size(); ++i) {
    paneGl_[i]->setClippingView(clippingView_);
    paneGl_[i]->setPipeline(colors_, paneDisplay());
    paneDirty_[i] = true;
  }
}

void Viewer::pollSession() {
  for (const auto& m : session_.takeMessages()) report(m);
  while (auto shown = session_.takeShownDesc()) {
    if (shown->opened) {
      // The open finished. The fields already hold its scene and any edits made while it loaded
      // (they went to the session after the open, which applies them on top): keep them.
      if (shown->request == pendingOpen_) openedRequest_ = pendingOpen_, pendingOpen_ = 0, beforeOpen_.reset();
    } else {
      // A failed build: the fields go back to the last good scene, which is what renders. The
      // edits made on top of what failed went with it, so no image will answer the one being timed.
      latencyRequest_ = 0;
      const std::string path = edited_.path;
      edited_ = shown->desc;
      if (pendingOpen_ && shown->request >= pendingOpen_) {
        pendingOpen_ = 0;  // the open (or an edit made while it loaded) failed
        restoreDocumentBeforeOpen();
      } else {
        if (!path.empty()) edited_.path = path;
        history_.revertCurrent(lookState());  // undo never replays the edit that failed
      }
      if (frameLatencyPending_) {
        // The frame stepped to failed to load (a missing or truncated file in the sequence): the
        // timeline stays on the frame that renders. Play and the step buttons pass that frame from
        // now on, as a flipbook plays over a hole, rather than retry it on every image or press.
        frameLatencyPending_ = false;
        unloadableFrames_.insert(frameStepTo_);
        report("frame " + std::to_string(frameStepTo_) + " could not be loaded (still on frame " + std::to_string(edited_.render.frame) +
               "): Play and the step buttons pass it; the slider tries it again");
      }
    }
    haveScene_ = true;
  }
  auto latest = session_.latest();
  if (latest && latest->version != uploadedVersion_) {
    frame_ = latest;
    uploadedVersion_ = latest->version;
    gl_->uploadImage(latest->film.width(), latest->film.height(), latest->shownImage());
    outputDirty_ = true;
    if (!haveScene_ && latest->scene) edited_ = *latest->scene, fileScene_ = edited_, haveScene_ = true;
    const bool full = !latest->preview && latest->film.spp() > 0;
    if (full && openLatencyPending_ && !pendingOpen_ && latest->request >= openedRequest_) {
      openLatencyPending_ = false;
      openStartSeconds_ = secondsSince(openStart_);
      // The first open is timed from the launch too: what an artist waits for after `candela fire.vdb`.
      static bool first = true;
      char launch[64] = "";
      if (first) std::snprintf(launch, sizeof(launch), "%.0f ms after launch, ", 1000.0 * secondsSince(launchTime()));
      first = false;
      std::printf("first image: %s%.0f ms after opening %s (%d spp)\n", launch, 1000.0 * openStartSeconds_, scenePath_.c_str(),
                  latest->film.spp());
      std::fflush(stdout);
    }
    if (reframeOnNextImage_ && !latest->preview && latest->scene && !latest->scene->volumes.empty() && !edited_.volumes.empty() &&
        toJson(latest->scene->volumes[0]) == toJson(edited_.volumes[0])) {
      reframeOnNextImage_ = false;
      // The volume turned upright: the ground goes under it again, and the camera frames it.
      if (hasGround()) placeGround(true);
      frameVolume();
    }
  }
  // Auto exposure: from the first image of the document with a few samples, so noise does not decide
  // it; checked on the image shown rather than on a new one, since a render that reached its limit
  // while another file loaded (and failed) sends none. An exposure the artist set clears
  // autoExposure (setDisplay).
  if (display_.autoExposure && frame_ && !frame_->preview && std::max(frame_->film.spp(), frame_->regionFilm.spp()) >= 4 && !pendingOpen_ &&
      frame_->request >= openedRequest_)
    chooseExposure(frame_->shownImage());
}

void Viewer::chooseExposure(const std::vector<float>& rgb) {
  display_.exposure = autoExposureStops(rgb);
  display_.autoExposure = false;
  applyDisplay();
  // Every undo step that had no exposure of its own takes this one (edits made before the first
  // image keep it too); a step whose exposure the artist set keeps that.
  history_.fillEverywhere(nlohmann::json::json_pointer("/display/exposure"), display_.exposure);
  history_.amend(lookState());
  char text[64];
  std::snprintf(text, sizeof(text), "auto exposure: %+.2f stops (E / Shift+E to change)", display_.exposure);
  report(text);
}

void Viewer::restoreDocumentBeforeOpen() {
  if (!beforeOpen_) {
    fileScene_ = edited_;
    return;
  }
  DocumentState& d = *beforeOpen_;
  // Edits made while the file loaded were edits of that file: they go with it, and the artist is
  // told so rather than left to find the look changed back.
  const std::string failed = fs::path(scenePath_).filename().string();
  const bool editedWhileLoading = history_.canUndo();
  scenePath_ = d.scenePath;
  documentPath_ = d.documentPath;
  scenePreset_ = d.scenePreset;
  importSummary_ = d.importSummary;
  sceneSettings_ = d.sceneSettings;
  sceneTime_ = d.sceneTime;
  untitled_ = d.untitled;
  dirty_ = d.dirty;
  display_ = d.display;
  history_ = d.history;
  frames_ = d.frames;
  unloadableFrames_.clear();
  fileScene_ = d.fileScene;
  beforeOpen_.reset();
  openLatencyPending_ = false;
  edited_.display = display_;
  applyDisplay();
  updateTitle();
  report("the document is still " + (documentPath_.empty() ? scenePath_ : documentPath_) +
         (editedWhileLoading ? "; the edits made while " + failed + " loaded went with it" : ""));
}

void Viewer::pollSceneFile() {
  if (secondsSince(lastPoll_) < 0.5 || scenePath_.empty() || untitled_) return;
  lastPoll_ = ViewerClock::now();
  const auto t = modificationTime(scenePath_);
  if (t != sceneTime_ && t != fs::file_time_type{}) {
    sceneTime_ = t;
    if (dirty_ && haveScene_) {
      report(scenePath_ + " changed on disk; not reloaded over your unsaved edits (File > Reload scene loads it)");
      return;
    }
    report("reloading " + scenePath_ + " (the file changed)");
    if (compare_) {
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

void Viewer::pollDrops() {
  if (droppedPaths_.empty()) return;
  const std::string path = droppedPaths_.front();
  droppedPaths_.clear();  // several files: the first opens
  confirmDiscard("open " + fs::path(path).filename().string(), [this, path] { openScene(path); });
}

int Viewer::imageWidth() const {
  if (compare_ && compFrame_) return compFrame_->width;
  return frame_ ? frame_->width : 0;
}

float Viewer::imageAspect() const {
  if (compare_ && compFrame_ && compFrame_->width > 0) return static_cast<float>(compFrame_->width) / static_cast<float>(compFrame_->height);
  if (frame_) return static_cast<float>(frame_->width) / static_cast<float>(frame_->height);
  return 0.0f;
}

bool Viewer::hasGround() const {
  return std::any_of(edited_.surfaces.begin(), edited_.surfaces.end(), [](const SurfaceDesc& s) { return s.type == SurfaceType::Plane; });
}

void Viewer::placeGround(bool on) {
  auto& surfaces = edited_.surfaces;
  surfaces.erase(std::remove_if(surfaces.begin(), surfaces.end(), [](const SurfaceDesc& s) { return s.type == SurfaceType::Plane; }),
                 surfaces.end());
  if (on && frame_ && frame_->sceneMin.x <= frame_->sceneMax.x)
    surfaces.push_back(defaultGround(frame_->sceneMin.y, 0.5f * glm::length(frame_->sceneMax - frame_->sceneMin)));
  submitEdit();
}

void Viewer::resetCamera() {
  edited_.camera = fileScene_.camera;
  submitEdit();
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
  if (canvas_.handleMouse()) return;
  const ImageCanvas::Rect r = canvas_.rect();
  const bool over = !io.WantCaptureMouse && r.contains(io.MousePos);
  // Ctrl+drag draws a render region; Ctrl+click inspects the pixel's distance densities
  // (guide_inspector_view.h). Neither tumbles.
  if (io.KeyCtrl && dragButton_ < 0 && over && io.MouseClicked[0] && frame_ && !compare_) {
    regionDragStart_ = io.MousePos;
    regionDragging_ = true;
    return;
  }
  if (regionDragging_) {
    const ImVec2 a = regionDragStart_, b = io.MousePos;
    const bool moved = std::abs(b.x - a.x) > 4.0f || std::abs(b.y - a.y) > 4.0f;
    const ImageCanvas::Rect pane = canvas_.paneRect(0);
    auto pixel = [&](ImVec2 p) {
      const ImVec2 uv = canvas_.imageUv(pane, p);
      return ImVec2(std::clamp(uv.x, 0.0f, 1.0f) * static_cast<float>(edited_.camera.resolution.first),
                    std::clamp(uv.y, 0.0f, 1.0f) * static_cast<float>(edited_.camera.resolution.second));
    };
    if (moved) {
      ImDrawList* draw = ImGui::GetForegroundDrawList();
      draw->AddRect(ImVec2(std::min(a.x, b.x), std::min(a.y, b.y)), ImVec2(std::max(a.x, b.x), std::max(a.y, b.y)), IM_COL32(255, 200, 60, 255), 0.0f, 0, 1.5f);
    }
    if (!io.MouseDown[0]) {
      regionDragging_ = false;
      if (moved) {
        const ImVec2 p0 = pixel(ImVec2(std::min(a.x, b.x), std::min(a.y, b.y))), p1 = pixel(ImVec2(std::max(a.x, b.x), std::max(a.y, b.y)));
        setRegion(RegionRect{static_cast<int>(p0.x), static_cast<int>(p0.y), std::max(1, static_cast<int>(std::ceil(p1.x - p0.x))),
                             std::max(1, static_cast<int>(std::ceil(p1.y - p0.y)))});
      } else {
        const ImVec2 p = pixel(a);
        inspector_.request(edited_, static_cast<int>(p.x), static_cast<int>(p.y));
      }
    }
    return;
  }
  // Start a drag only on the image and only when ImGui does not want the mouse.
  if (dragButton_ < 0 && over) {
    for (int b = 0; b < 3; ++b)
      if (io.MouseClicked[b]) dragButton_ = b;
    // The delta of the click frame may include a jump to where the click happened: not a drag.
    if (dragButton_ >= 0) return;
  }
  if (dragButton_ >= 0 && !io.MouseDown[dragButton_]) {
    dragButton_ = -1;
    history_.endGroup();  // one tumble, one undo step
  }
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
  if (over && io.MouseWheel != 0.0f) {
    c.position = c.look_at + (c.position - c.look_at) * std::exp(-io.MouseWheel * 0.1f);
    moved = true;
    // Wheel steps within half a second of each other are one dolly: one undo step.
    if (secondsSince(lastWheel_) > 0.5) history_.endGroup();
    lastWheel_ = ViewerClock::now();
  }
  if (moved) submitEdit("camera");
}

// --- equal-time comparison ---

void Viewer::startComparisonMode(const std::string& path) {
  scenePath_ = documentPath_ = path;
  try {
    edited_ = fileScene_ = loadSceneDesc(path, options_.settings);
    sceneTime_ = modificationTime(path);
    haveScene_ = true;
    // The file's look; with no exposure in it, one for every pane from the first pane image.
    display_ = colors_.resolve(edited_.display);
    applyDisplay();
    history_.reset(lookState());
    for (const auto& name : options_.panes) paneSpecs_.push_back({name, strategyPreset(name, "--panes")});
    canvas_.setWipe(options_.wipe && paneSpecs_.size() == 2);
    if (options_.paneView == "absolute") paneView_ = PaneView::AbsoluteError;
    if (options_.paneView == "relative") paneView_ = PaneView::RelativeError;
    compare_ = std::make_unique<ComparisonSession>(RenderOptions{options_.threads, 32}, /*yieldToUi=*/true);
    compare_->setNotify([] { glfwPostEmptyEvent(); });
    if (!options_.referencePath.empty()) reference_ = readExr(options_.referencePath);
    restartComparison();
    updateTitle();
  } catch (const std::exception& e) {
    report(e.what());
  }
}

void Viewer::restartComparison() {
  compare_->start(edited_, paneSpecs_, reference_, reference_.rgb.empty() ? options_.referenceSpp : 0,
                  strategyPreset(options_.referenceStrategy, "--reference-strategy"), options_.equalTime);
  figureDone_ = false;
}

DisplaySettings Viewer::paneDisplay() const {
  // Error views are false colour: shown through the config's raw view when it has one.
  if (paneView_ == PaneView::Image || !compFrame_ || !compFrame_->reference) return display_;
  DisplaySettings raw;
  raw.display = colors_.resolve(display_).display;
  for (const auto& v : colors_.views(raw.display))
    if (v == "Raw") raw.view = v;
  return raw.view.empty() ? display_ : raw;
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
  // One exposure for every pane, chosen once from the first pane image with a few samples.
  if (display_.autoExposure)
    for (const auto& p : latest->panes)
      if (p.film && p.film->spp() >= 4) {
        chooseExposure(p.film->meanImage());
        break;
      }
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

// --- the loop ---

int Viewer::run() {
  const double targetFrame = 1.0 / 60.0;
  auto frameStart = ViewerClock::now();
  while (!glfwWindowShouldClose(window_) && !quitNow_) {
    const auto lastFrame = frameStart;
    frameStart = ViewerClock::now();
    // Redraw continuously only while the user interacts (and a few frames after, so ImGui settles);
    // otherwise sleep until an input event or a new image wakes us: the cores stay with the renderer.
    if (busyFrames_ > 0 || script_.active(*this) || playing_) {
      // At most ~60 fps, but a new image (glfwPostEmptyEvent) or input wakes us at once.
      glfwWaitEventsTimeout(std::max(0.0, targetFrame - secondsSince(lastFrame)));
    } else {
      glfwWaitEventsTimeout(0.5);
    }
    busyFrames_ = std::max(0, busyFrames_ - 1);
    framePresses_ = keys_.take();
    if (!framePresses_.empty()) busyFrames_ = 3;
    try {
      pollSession();
      pollComparison();
      pollSceneFile();
      pollDrops();
      pollTimeline();
      pollSequenceRender();
    } catch (const std::exception& e) {
      report(e.what());
    }

    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    try {
      drawMenuBar();
      drawStatusBar();
      drawTimeline();
      int ww, wh;
      glfwGetWindowSize(window_, &ww, &wh);
      canvas_.layout({0.0f, menuHeight_, std::max(1.0f, ww - panelWidth_), std::max(1.0f, wh - menuHeight_ - statusHeight_ - timelineHeight_)},
                     imageAspect(), compare_ ? paneCount() : (comparedSnapshot_ && frame_ ? 2 : 1), imageWidth());
      drawPanel();
      inspector_.draw();
      drawDialogs();
      drawPaneLabels();
      handleCamera();
      handleKeys();
      // A widget edit ends when no widget is active: the next one is a new undo step.
      ImGuiIO& io = ImGui::GetIO();
      if (!ImGui::IsAnyItemActive() && dragButton_ < 0 && !io.MouseDown[0]) {
        if (gestureActive_) history_.endGroup();
        gestureActive_ = false;
      } else {
        gestureActive_ = true;
      }
    } catch (const std::exception& e) {
      report(std::string("UI error: ") + e.what());
    }
    {
      ImGuiIO& io = ImGui::GetIO();
      const bool interacting = ImGui::IsAnyItemActive() || io.MouseDelta.x != 0.0f || io.MouseDelta.y != 0.0f || io.MouseWheel != 0.0f ||
                               io.MouseDown[0] || io.MouseDown[1] || io.MouseDown[2] || io.WantTextInput ||
                               ImGui::IsPopupOpen("", ImGuiPopupFlags_AnyPopup);
      if (interacting) busyFrames_ = 3;
    }
    ImGui::Render();

    int fbw, fbh;
    glfwGetFramebufferSize(window_, &fbw, &fbh);
    static const bool trace = std::getenv("CANDELA_TRACE") != nullptr;
    const auto outputStart = ViewerClock::now();
    const bool rendered = frame_ && outputDirty_;
    if (frame_ && outputDirty_) {
      // At the film's resolution: a preview's few pixels go through OCIO cheaply and are upscaled by
      // the blit, which matters when the GPU is a software rasteriser sharing the render cores.
      gl_->renderOutput(frame_->film.width(), frame_->film.height());
      outputDirty_ = false;
      if (trace) glFinish();
    }
    const auto outputEnd = ViewerClock::now();
    glViewport(0, 0, fbw, fbh);
    glClearColor(0.11f, 0.11f, 0.12f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    if (frame_) {
      const Snapshot* snap = comparedSnapshot_ ? snapshots_.find(comparedSnapshot_) : nullptr;
      if (snap && snapshotGl_) {
        if (snapshotDirty_) snapshotGl_->renderOutput(snap->image.width, snap->image.height), snapshotDirty_ = false;
        canvas_.drawPair(*gl_, *snapshotGl_);  // live left, snapshot right
      } else {
        canvas_.draw(*gl_, frame_->width, frame_->preview);
      }
    }
    if (compFrame_ && !compFrame_->panes.empty()) {
      std::vector<const GlDisplay*> panes;
      for (size_t i = 0; i < compFrame_->panes.size() && i < paneGl_.size(); ++i) {
        const auto& film = compFrame_->panes[i].film;
        if (!film) {
          panes.push_back(nullptr);
          continue;
        }
        if (paneDirty_[i]) paneGl_[i]->renderOutput(film->width(), film->height()), paneDirty_[i] = false;
        panes.push_back(paneGl_[i].get());
      }
      canvas_.drawPanes(panes);
    }
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    if (figureRequest_) captureFigure();
    if (canvasCaptureRequest_) captureCanvas();
    glfwSwapBuffers(window_);
    if (trace && rendered)
      std::fprintf(stderr, "trace: frame: before output %.1f ms, output %.1f ms, draw+swap %.1f ms\n",
                   1e3 * std::chrono::duration<double>(outputStart - frameStart).count(),
                   1e3 * std::chrono::duration<double>(outputEnd - outputStart).count(), 1e3 * secondsSince(outputEnd));

    // Latency: the first image of a request is on screen now.
    if (latencyRequest_ && frame_ && frame_->request >= latencyRequest_) {
      lastLatencyMs_ = 1000.0 * secondsSince(latencyStart_);
      latencies_.push_back(lastLatencyMs_);
      if (trace) std::fprintf(stderr, "trace: edit->image %.1f ms\n", lastLatencyMs_);
      script_.editMeasured(lastLatencyMs_);
      latencyRequest_ = 0;
    }
    frameTimes_.push_back(std::chrono::duration<double>(ViewerClock::now().time_since_epoch()).count());
    while (frameTimes_.size() > 60) frameTimes_.pop_front();
    try {
      script_.step(*this);
    } catch (const std::exception& e) {
      report(e.what());
    }
  }
  return exitCode_;
}

ViewerClock::time_point launchTime() {
  static const ViewerClock::time_point t = ViewerClock::now();
  return t;
}

int runViewer(const ViewerOptions& options) {
  launchTime();  // the clock the first image is timed from starts before the window opens
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
  glfwSwapInterval(0);  // our own frame pacing; vsync would add a frame of latency
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // fixed layout; nothing to remember between runs
  ImGui::StyleColorsDark();
  // Installed after our callbacks: ImGui's backend chains to the ones set before it.
  int code = 0;
  {
    Viewer viewer(window, options);
    ImGui_ImplGlfw_InitForOpenGL(window, true);
    ImGui_ImplOpenGL3_Init("#version 330 core");
    code = viewer.run();
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
  }
  ImGui::DestroyContext();
  glfwDestroyWindow(window);
  glfwTerminate();
  return code;
}

}  // namespace candela
