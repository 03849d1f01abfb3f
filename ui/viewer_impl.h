// The viewer's parts, private to ui/. The Viewer owns the window's state and the document (the
// scene being looked at: open, edit, save, undo); the other concerns live in their own files:
//   image_canvas.h     the image area: zoom, pan, wipe, panes, readout (tev's ImageCanvas)
//   viewer_panels.cpp  the Parameters panel, the comparison panel, snapshots, timeline, status bar
//   viewer_menus.cpp   the menu bar, the open / save / confirm dialogs and the keyboard shortcuts
//   viewer_output.cpp  screenshots and comparison figures
//   scripted_driver.h  scripted runs (--screenshot, --figure, --measure-latency, --edit, ...)
#pragma once

#include "color_pipeline.h"
#include "comparison_session.h"
#include "edit_history.h"
#include "gl_display.h"
#include "histogram.h"
#include "guide_inspector_view.h"
#include "image_canvas.h"
#include "param_editor.h"
#include "render_session.h"
#include "scripted_driver.h"
#include "sequence.h"
#include "sequence_render.h"
#include "snapshot_store.h"
#include "vdb_import.h"
#include "view_settings.h"
#include "viewer.h"

#include <imgui.h>

#include <atomic>
#include <chrono>
#include <climits>
#include <deque>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <utility>
#include <string>
#include <vector>

namespace candela {

using ViewerClock = std::chrono::steady_clock;
inline double secondsSince(ViewerClock::time_point t) { return std::chrono::duration<double>(ViewerClock::now() - t).count(); }

std::string defaultScenePath();
// When runViewer started (before the window opened).
ViewerClock::time_point launchTime();
// A path next to `wanted` that does not exist yet: NAME.png, NAME-2.png, ...
std::string freshPath(const std::filesystem::path& wanted);
std::filesystem::file_time_type modificationTime(const std::string& path);
// Whether two looks render differently (not only in how they are displayed).
bool rendersDifferently(const SceneDesc& a, const SceneDesc& b);

// Every key press GLFW reports, in order, kept until the next UI frame handles it: a key pressed and
// released between two frames, or pressed eight times, counts as often as it was pressed (ImGui 1.86
// sees only the keys held at a frame, and has no named keys for letters).
struct KeyPress {
  int key = 0;
  int mods = 0;  // GLFW_MOD_* at the press
  bool repeat = false;
  bool ctrl() const { return (mods & GLFW_MOD_CONTROL) != 0; }
  bool shift() const { return (mods & GLFW_MOD_SHIFT) != 0; }
};

class KeyQueue {
 public:
  void push(const KeyPress& k) { pending_.push_back(k); }
  // The presses since the last call, oldest first.
  std::vector<KeyPress> take() { return std::exchange(pending_, {}); }

 private:
  std::vector<KeyPress> pending_;
};

class Viewer {
 public:
  Viewer(GLFWwindow* window, const ViewerOptions& options);
  ~Viewer();
  int run();

 private:
  friend class ScriptedDriver;

  // --- the document: open, edit, save, undo (viewer.cpp) ---
  void openScene(const std::string& path, const std::vector<std::string>& settings = {}, const std::string& preset = "");
  // Validates the edited description (the same checks as a scene file) and sends it to the renderer.
  // A bad value is reported and the fields return to the last good state. `group` joins the edit to
  // the previous undo step of the same gesture.
  void submitEdit(const std::string& group = "");
  void applySettingEdit(const std::string& assignment);
  // Under auto as chosen, once an image shows what it decided: the strategy that runs (preset
  // "auto"), which the Strategy panel shows in its fields and which an edit of a strategy field takes
  // over (takeOverAutoChoice). Null otherwise.
  const StrategySettings* autoChoiceShown() const;
  void beginLatency(uint64_t request);
  nlohmann::json lookState() const;  // {"scene", "display"}: what undo and snapshots keep
  void restoreLook(const nlohmann::json& look, const std::string& what);
  void recordEdit(const std::string& group = "");
  void undo();
  void redo();
  bool save(const std::string& path);
  void requestSave();  // Ctrl+S: save, or Save As for a document never saved
  // Runs `action` now, or after asking when there are unsaved edits (Save / Discard / Cancel).
  void confirmDiscard(const std::string& what, std::function<void()> action);
  void updateTitle();
  void requestQuit();  // the window's close button, Ctrl+Q, File > Quit: asks about unsaved edits
  void report(const std::string& text);
  void applyDisplay();
  // Auto exposure from this image, for the document (display_.autoExposure was set: no exposure given).
  void chooseExposure(const std::vector<float>& rgb);
  void setDisplay(const DisplaySettings& display, const std::string& group = "display");
  void pollSession();
  void pollSceneFile();
  void pollDrops();
  void frameVolume();
  bool hasGround() const;       // a ground plane among the surfaces
  void placeGround(bool on);    // under the volumes as they stand now (defaultGround), or none
  void resetCamera();  // the camera the document was opened with
  void handleCamera();

  // --- equal-time comparison (viewer.cpp, panels) ---
  void startComparisonMode(const std::string& path);
  void restartComparison();
  void pollComparison();
  void uploadPanes();
  int paneCount() const { return compare_ ? std::max<int>(1, static_cast<int>(paneSpecs_.size())) : 1; }
  DisplaySettings paneDisplay() const;

  // --- snapshots and the timeline (viewer_panels.cpp) ---
  void takeSnapshot();
  // File > Open image: an EXR (an earlier render, a reference) kept as a snapshot to compare with,
  // or, in the comparison, as the reference the panes' errors are measured against.
  bool openImage(const std::string& path, bool asReference);
  void compareSnapshot(int id);
  void drawSnapshots();
  void drawTimeline();
  void setFrame(int frame);
  int neighbourFrame(int direction) const;
  void toggleReadoutLock();  // the next (+1) or previous (-1) frame that may load, wrapping
  void pollTimeline();

  // --- panels and menus ---
  void drawMenuBar();
  void drawPanel();
  void drawComparisonPanel();
  void drawPaneLabels();
  void drawStatusBar();
  void drawDialogs();
  void handleKeys();

  // --- output (viewer_output.cpp) ---
  bool screenshot(const std::string& requestedPath);
  bool writeFigure(const std::string& path);
  void captureFigure();
  void captureCanvas();
  DisplayImage readCanvas() const;
  void addComparisonMetadata(std::map<std::string, std::string>& meta) const;
  std::optional<std::string> canvasCaptureRequest_;

  float imageAspect() const;
  int imageWidth() const;  // of the image shown (one pane's), 0 before the first

  GLFWwindow* window_;
  ViewerOptions options_;
  // Scripted --edit-while-loading: the dropped file's build is held until the edits are made (read on
  // the build thread, so declared before the session that joins it).
  std::atomic<bool> holdBuildForScriptedEdits_{false};
  RenderSession session_;
  ColorPipeline colors_;
  std::unique_ptr<GlDisplay> gl_;
  DisplaySettings display_;
  ProgressLimits limits_;
  ImageCanvas canvas_;

  // The document.
  std::string scenePath_;     // the file opened (scene JSON or .vdb), watched for changes
  std::string documentPath_;  // where Save writes (a scene JSON)
  bool untitled_ = false;     // never saved (an opened VDB): Save asks where
  bool dirty_ = false;        // edits since the last open or save
  std::string scenePreset_;
  std::vector<std::string> sceneSettings_;
  std::filesystem::file_time_type sceneTime_{};
  ViewerClock::time_point lastPoll_ = ViewerClock::now();
  uint64_t pendingOpen_ = 0;
  // The last open that loaded: frames of older requests show the scene from before it.
  uint64_t openedRequest_ = 0;
  bool haveScene_ = false;
  SceneDesc edited_;     // what the panels edit
  SceneDesc fileScene_;  // as opened (camera reset)
  EditHistory history_;
  bool gestureActive_ = false;  // a drag or a widget edit in progress: its edits are one undo step
  ViewerClock::time_point lastWheel_;
  bool reframeOnNextImage_ = false;  // after the up axis changes: frame the volume once it is rebuilt
  std::string importSummary_;
  std::string title_;
  std::vector<std::string> droppedPaths_;
  // The document before the open in flight, restored if that open fails to build: the title, Save
  // and the file watcher keep naming the scene that still renders, never the file that failed.
  struct DocumentState {
    std::string scenePath, documentPath, scenePreset, importSummary;
    std::vector<std::string> sceneSettings;
    std::filesystem::file_time_type sceneTime{};
    bool untitled = false, dirty = false;
    DisplaySettings display;
    EditHistory history;
    FrameRange frames;
    SceneDesc fileScene;
  };
  std::optional<DocumentState> beforeOpen_;
  void restoreDocumentBeforeOpen();

  // Dialogs.
  std::deque<std::pair<std::string, ViewerClock::time_point>> messages_;
  bool showMessages_ = false, showOpen_ = false, showSaveAs_ = false, showDiscard_ = false, showOpenImage_ = false;
  std::string openPath_, saveAsPath_, openImagePath_;
  std::vector<std::string> openCandidates_;
  std::string discardWhat_;
  std::function<void()> pendingAction_;
  bool closeConfirmed_ = false;

  // Comparison panes.
  std::unique_ptr<ComparisonSession> compare_;
  std::shared_ptr<const ComparisonFrame> compFrame_;
  uint64_t compVersion_ = 0;
  std::vector<std::unique_ptr<GlDisplay>> paneGl_;
  std::vector<bool> paneDirty_;
  std::vector<PaneSpec> paneSpecs_;
  enum class PaneView { Image, AbsoluteError, RelativeError };
  PaneView paneView_ = PaneView::Image;
  std::string referenceInput_;
  int referenceSppInput_ = 256;
  std::string referenceStrategyInput_ = "emission";
  Image reference_;
  bool figureDone_ = false;
  std::optional<std::string> figureRequest_;

  // The live image.
  std::shared_ptr<const Frame> frame_;
  uint64_t uploadedVersion_ = 0;
  bool outputDirty_ = true;

  // Snapshots: compared with the live image in the canvas (wipe or side by side).
  SnapshotStore snapshots_;
  std::map<int, GLuint> thumbnails_;
  int comparedSnapshot_ = 0;  // 0: none
  std::unique_ptr<GlDisplay> snapshotGl_;
  bool snapshotDirty_ = false;
  bool showSnapshots_ = false;

  // The timeline of a scene whose volumes name a frame pattern.
  FrameRange frames_;
  bool playing_ = false;
  int playSpp_ = 16;
  float playSeconds_ = 0.0f;
  int frameStepTo_ = 0;  // the frame the last step asked for
  // Frames that failed to load since the sequence was opened (a missing or truncated file): Play and
  // the step buttons pass them; the slider and |< >| still try them, and one that loads leaves the set.
  std::set<int> unloadableFrames_;
  ViewerClock::time_point frameStepStart_;
  bool frameLatencyPending_ = false;
  double lastFrameStepMs_ = 0.0;
  std::unique_ptr<FramePrefetcher> prefetcher_;
  int prefetchedFrame_ = INT_MIN;

  KeyQueue keys_;
  std::vector<KeyPress> framePresses_;  // this UI frame's presses, taken once at its start
  bool pressedThisFrame(int key) const;
  int dragButton_ = -1;
  GuideInspectorView inspector_;  // Ctrl+click on a pixel

  uint64_t latencyRequest_ = 0;
  ViewerClock::time_point latencyStart_;
  double lastLatencyMs_ = 0.0;
  std::vector<double> latencies_;
  std::deque<double> frameTimes_;
  double openStartSeconds_ = 0.0;  // time of the open that the first image is timed from
  ViewerClock::time_point openStart_;
  bool openLatencyPending_ = false;

  const float panelWidth_ = 420.0f;
  float statusHeight_ = 0.0f, menuHeight_ = 0.0f, timelineHeight_ = 0.0f;

  ScriptedDriver script_;
  bool quitNow_ = false;
  int busyFrames_ = 3;
  int exitCode_ = 0;
  bool paused_ = false;  // P: the render holds its samples until resumed
  // File > Render sequence: the job, its dialog's fields, and whether the live render was paused for it.
  SequenceRenderJob sequenceJob_{/*yieldToUi=*/true};
  bool sequenceRunning_ = false, pausedForSequence_ = false, showRenderSequence_ = false;
  int sequenceFirst_ = 1, sequenceLast_ = 1, sequenceSpp_ = 64;
  float sequenceSeconds_ = 0.0f;
  std::string sequencePattern_;
  // The look as edited and shown (its exposure, or auto exposure from the first frame when none was
  // chosen yet), over frames first-last.
  SequenceRenderRequest sequenceRequest(int first, int last, int spp, double seconds, const std::string& pattern) const;
  bool startSequenceRender(const SequenceRenderRequest& request);
  void pollSequenceRender();
  void drawSequenceProgress();
  bool clippingView_ = false;  // H: red where the display clips at white, blue at black
  DisplayHistogram histogram_;
  uint64_t histogramVersion_ = 0;
  ViewerClock::time_point histogramTime_;
  void drawHistogram();
  void togglePause();
  // The render region (Ctrl+drag on the image; Esc clears it): only its pixels refine.
  std::optional<RegionRect> region_;
  bool regionDragging_ = false;
  ImVec2 regionDragStart_;
  void setRegion(std::optional<RegionRect> region);
};

}  // namespace candela
