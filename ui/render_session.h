// The viewer's renderer, off the UI thread. A worker thread renders progressive passes of the
// current scene; a loader thread builds scenes (file opens, reloads and edits that change volumes,
// lights or surfaces) while the worker keeps rendering the last good one. Edits that only touch the
// strategy, camera or render settings apply between passes without a rebuild. Any request cancels
// the pass in flight (within milliseconds) and restarts accumulation with a quarter-resolution preview
// pass, so the first new image arrives fast.
//
// The UI thread only calls the non-blocking methods below: requests are queued and frames are
// shared, immutable snapshots.
#pragma once

#include "film.h"
#include "renderer.h"
#include "scene.h"
#include "view_settings.h"

#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

namespace candela {

// One published image. `request` is the id of the newest request it reflects, so the UI can time
// edit-to-first-image.
// A rectangle of the image in pixels, (x, y) its top-left corner.
struct RegionRect {
  int x = 0, y = 0, w = 0, h = 0;
  bool operator==(const RegionRect& o) const { return x == o.x && y == o.y && w == o.w && h == o.h; }
};

struct Frame {
  uint64_t version = 0;
  uint64_t request = 0;
  bool preview = false;     // quarter-resolution preview: `film` holds it, upscale to display
  Film film;                // sums and sums of squares: mean and standard error per pixel
  int width = 0, height = 0;  // the full image size (the preview's film is smaller)
  double seconds = 0.0;     // render time accumulated since the last restart
  double samplesPerSecond = 0.0;
  bool finished = false;    // a progress limit was reached
  std::shared_ptr<const SceneDesc> scene;  // the settings this frame was rendered with
  std::string autoDecision;  // with the auto strategy: what it chose and why (AutoDecision::summary)
  std::string autoChoice;    // ... and the candidate's name
  std::string adaptiveSplit;  // adaptive sampling's split once decided (SplitMap::summary), else empty
  double meanSplit = 1.0;     // ... its camera samples per film sample, over the pixels
  Vec3 sceneCenter{0.0f};   // bounds of the scene's content, for framing the camera
  float sceneRadius = 1.0f;
  Vec3 sceneMin{1.0f}, sceneMax{-1.0f};  // the box of the volumes and bounded surfaces (empty when min > max)
  // A render region: only its pixels refine, in `regionFilm` (region-sized, its own samples); `film`
  // holds the rest of the image as it was when the region was set. regionFilm.spp() is 0 without one.
  std::optional<RegionRect> region;
  Film regionFilm;
  // The mean image shown: film's, with the region's pixels from regionFilm once it has samples.
  std::vector<float> shownImage() const;
};

class RenderSession {
 public:
  // `yieldToUi`: its threads lower their priority below the UI thread's (thread_priority.h); the
  // viewer's sessions do, a headless user's need not.
  explicit RenderSession(RenderOptions options = {}, bool yieldToUi = false);
  ~RenderSession();
  RenderSession(const RenderSession&) = delete;
  RenderSession& operator=(const RenderSession&) = delete;

  // Builds `desc` on the loader thread and renders it when ready (a newly opened scene). Returns the
  // request id.
  uint64_t open(const SceneDesc& desc);
  // A live edit of the scene being shown: applied between passes when only the strategy, camera or
  // render settings differ, else rebuilt on the loader thread. Returns the request id.
  uint64_t edit(const SceneDesc& desc);
  void setLimits(const ProgressLimits& limits);
  // Paused: the pass in flight stops and no other starts; the samples so far stay shown. Edits still
  // apply (rebuilds included), and their images come on resume.
  void setPaused(bool paused);
  // A render region (clamped to the image; nullopt or an empty rectangle clears it): from the next
  // pass only its pixels refine, from their own first sample, and the progress limits apply to them.
  // Cleared, the whole image refines again from where it was.
  void setRegion(std::optional<RegionRect> region);
  bool paused() const { return paused_.load(); }
  // Called on the worker or loader thread whenever a frame or message is published (the viewer wakes
  // its event loop with it). Set before the first request.
  void setNotify(std::function<void()> notify) { notify_ = std::move(notify); }
  // Called on the loader thread before each build, with the description it is about to build (tests
  // hold a build back with it, to make requests while it runs). Set before the first request.
  void setBuildHook(std::function<void(const SceneDesc&)> hook) { buildHook_ = std::move(hook); }

  // The newest frame (null before the first). Cheap: a shared pointer copy.
  std::shared_ptr<const Frame> latest() const;
  // Messages for the user (build errors, warnings); each is returned once.
  std::vector<std::string> takeMessages();
  // After an open succeeds, the description it opened (`opened`); after a failed build, the last
  // good one, so the UI's fields return to what is rendering. `request` is the open's or the failed
  // build's request id. Each is returned once, oldest first. An open that a newer open replaced
  // before it finished is never shown and reports nothing; edits made while an open builds apply
  // to the opened scene.
  struct ShownDesc {
    SceneDesc desc;
    uint64_t request = 0;
    bool opened = false;
  };
  std::optional<ShownDesc> takeShownDesc();
  bool loading() const { return loading_.load(); }
  // A finished open whose description the UI has not taken yet (takeShownDesc): loading() is
  // already false then, but a scene did load.
  bool openPending() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return !shownDescUpdates_.empty();
  }

 private:
  void workerLoop();
  void loaderLoop();
  void message(const std::string& text);
  void publish(std::shared_ptr<Frame> frame);

  RenderOptions options_;
  mutable std::mutex mutex_;
  std::condition_variable workerWake_, loaderWake_;
  bool stop_ = false;
  uint64_t nextRequest_ = 0;

  // Worker state (guarded by mutex_ where shared).
  struct Target {
    SceneDesc desc;
    uint64_t request = 0;
  };
  std::optional<Target> target_;           // the newest desc the UI wants
  std::shared_ptr<Scene> builtScene_;      // a finished build waiting for the worker
  uint64_t builtRequest_ = 0;
  ProgressLimits limits_;
  bool limitsChanged_ = false;
  std::atomic<bool> cancelPass_{false};
  std::atomic<bool> paused_{false};
  std::optional<RegionRect> region_;  // guarded by mutex_
  bool regionChanged_ = false;

  // Loader state.
  std::optional<Target> buildRequest_;
  bool buildIsOpen_ = false;
  std::optional<SceneDesc> lastRequested_;  // structure of the newest open or edit
  std::atomic<bool> loading_{false};
  std::shared_ptr<const SceneDesc> shownDesc_;  // desc of the scene the worker renders
  uint64_t shownDescRequest_ = 0;                // the newest request shownDesc_ reflects
  std::shared_ptr<const SceneDesc> newestBuilt_;  // the newest successful build, shown or about to be
  uint64_t newestBuiltRequest_ = 0;
  std::shared_ptr<const ProbeSet> shownProbes_;  // its probes: they serve a rebuilt scene until it learns its own

  std::shared_ptr<const Frame> latest_;
  std::vector<std::string> messages_;
  std::deque<ShownDesc> shownDescUpdates_;  // oldest first: a failed edit never hides an open before it

  std::function<void()> notify_;
  std::function<void(const SceneDesc&)> buildHook_;
  std::thread worker_, loader_;
};

// Which parts of two descriptions differ: decides between a live update and a rebuild.
struct SceneDiff {
  bool strategy = false, camera = false, render = false, structure = false;
  bool any() const { return strategy || camera || render || structure; }
};
SceneDiff diffScenes(const SceneDesc& a, const SceneDesc& b);

}  // namespace candela
