#include "render_session.h"

#include "thread_priority.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace candela {

SceneDiff diffScenes(const SceneDesc& a, const SceneDesc& b) {
  SceneDiff d;
  d.strategy = toJson(a.strategy) != toJson(b.strategy);
  d.camera = toJson(a.camera) != toJson(b.camera);
  d.render = toJson(a.render) != toJson(b.render);
  Json sa = sceneToJson(a), sb = sceneToJson(b);
  for (const char* key : {"camera", "render", "strategy", "display", "description"}) sa.erase(key), sb.erase(key);
  // Another frame reads other VDB files: a rebuild, not a render-settings change.
  d.structure = sa != sb || a.path != b.path || a.render.frame != b.render.frame;
  return d;
}

RenderSession::RenderSession(RenderOptions options, bool yieldToUi) : options_(options) {
  // Both yield to the UI thread, and so do the TBB workers they start (thread_priority.h).
  worker_ = std::thread([this, yieldToUi] {
    if (yieldToUi) lowerThisThreadsPriority();
    workerLoop();
  });
  loader_ = std::thread([this, yieldToUi] {
    if (yieldToUi) lowerThisThreadsPriority();
    loaderLoop();
  });
}

RenderSession::~RenderSession() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cancelPass_ = true;
  workerWake_.notify_all();
  loaderWake_.notify_all();
  loader_.join();
  worker_.join();
}

uint64_t RenderSession::open(const SceneDesc& desc) {
  std::lock_guard<std::mutex> lock(mutex_);
  const uint64_t id = ++nextRequest_;
  buildRequest_ = Target{desc, id};
  buildIsOpen_ = true;
  lastRequested_ = desc;
  loading_ = true;
  loaderWake_.notify_one();
  return id;
}

uint64_t RenderSession::edit(const SceneDesc& desc) {
  std::lock_guard<std::mutex> lock(mutex_);
  const uint64_t id = ++nextRequest_;
  // Structural changes (volumes, lights, surfaces) need a build; the worker applies the strategy,
  // camera and render settings itself, to whichever scene it has.
  if (buildRequest_ && buildIsOpen_) {
    // An open not yet started builds the edited scene; it keeps the open's id, which the UI waits for.
    buildRequest_->desc = desc;
  } else if (!lastRequested_ || diffScenes(*lastRequested_, desc).structure) {
    buildRequest_ = Target{desc, id};
    loading_ = true;
    loaderWake_.notify_one();
  } else if (buildRequest_) {
    buildRequest_->desc = desc;  // a queued build picks up the newest settings too
  }
  lastRequested_ = desc;
  target_ = Target{desc, id};
  cancelPass_ = true;
  workerWake_.notify_one();
  return id;
}

void RenderSession::setLimits(const ProgressLimits& limits) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (toJson(limits) == toJson(limits_)) return;
  limits_ = limits;
  limitsChanged_ = true;
  workerWake_.notify_one();
}

std::shared_ptr<const Frame> RenderSession::latest() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return latest_;
}

std::vector<std::string> RenderSession::takeMessages() {
  std::lock_guard<std::mutex> lock(mutex_);
  return std::exchange(messages_, {});
}

std::optional<RenderSession::ShownDesc> RenderSession::takeShownDesc() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (shownDescUpdates_.empty()) return std::nullopt;
  ShownDesc oldest = std::move(shownDescUpdates_.front());
  shownDescUpdates_.pop_front();
  return oldest;
}

void RenderSession::message(const std::string& text) {
  std::lock_guard<std::mutex> lock(mutex_);
  messages_.push_back(text);
}

std::vector<float> Frame::shownImage() const {
  std::vector<float> image = film.meanImage();
  if (!region || regionFilm.spp() == 0 || film.width() != width || film.height() != height) return image;
  const std::vector<float> inside = regionFilm.meanImage();
  for (int y = 0; y < regionFilm.height(); ++y)
    std::copy_n(inside.begin() + 3 * static_cast<size_t>(y) * regionFilm.width(), 3 * static_cast<size_t>(regionFilm.width()),
                image.begin() + 3 * (static_cast<size_t>(region->y + y) * width + region->x));
  return image;
}

void RenderSession::setRegion(std::optional<RegionRect> region) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (region && (region->w <= 0 || region->h <= 0)) region.reset();
    region_ = region;
    regionChanged_ = true;
  }
  cancelPass_ = true;
  workerWake_.notify_one();
}

void RenderSession::setPaused(bool paused) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    paused_ = paused;
  }
  if (paused) cancelPass_ = true;
  workerWake_.notify_one();
}

void RenderSession::publish(std::shared_ptr<Frame> frame) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    frame->version = latest_ ? latest_->version + 1 : 1;
    latest_ = std::move(frame);
  }
  if (notify_) notify_();
}

void RenderSession::loaderLoop() {
  for (;;) {
    Target request;
    bool isOpen = false;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      loaderWake_.wait(lock, [&] { return stop_ || buildRequest_; });
      if (stop_) return;
      request = std::move(*buildRequest_);
      isOpen = buildIsOpen_;
      buildRequest_.reset();
      buildIsOpen_ = false;
    }
    std::vector<std::string> warnings;
    std::shared_ptr<Scene> scene;
    std::string error;
    std::shared_ptr<const ProbeSet> serving;
    if (!isOpen) {
      std::lock_guard<std::mutex> lock(mutex_);
      serving = shownProbes_;
    }
    if (buildHook_) buildHook_(request.desc);
    try {
      const auto buildStart = std::chrono::steady_clock::now();
      scene = Scene::build(request.desc, &warnings, serving);
      if (std::getenv("CANDELA_TRACE"))
        std::fprintf(stderr, "trace: build %.1f ms\n", 1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - buildStart).count());
    } catch (const std::exception& e) {
      error = e.what();
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      // A newer open queued while this one built replaces it, as if it had never been asked for:
      // the UI neither shows nor reports a file it has already moved on from.
      const bool superseded = isOpen && buildRequest_ && buildIsOpen_;
      if (!superseded)
        for (const auto& w : warnings) messages_.push_back("warning: " + w);
      if (superseded) {
        // Nothing to show; the newer open is next.
      } else if (scene) {
        builtScene_ = scene;
        builtRequest_ = request.request;
        newestBuilt_ = std::make_shared<const SceneDesc>(scene->desc());
        newestBuiltRequest_ = request.request;
        if (isOpen) {
          shownDescUpdates_.push_back(ShownDesc{request.desc, request.request, true});
          // An open replaces what the UI showed before it; edits made while it built are newer
          // requests on top of it (edit() sent them after this open) and stay the target.
          if (!target_ || target_->request < request.request) target_ = Target{request.desc, request.request};
        }
        cancelPass_ = true;
        workerWake_.notify_one();
      } else {
        // The last good scene: the newest build when the worker has not shown it yet (taken or not),
        // else what the worker renders, with the live edits it has applied since.
        const std::shared_ptr<const SceneDesc> lastGood = newestBuilt_ && newestBuiltRequest_ > shownDescRequest_ ? newestBuilt_ : shownDesc_;
        messages_.push_back(error + (lastGood ? " (still showing the last good scene)" : ""));
        workerWake_.notify_one();  // rendering resumes on the last good scene
        // The UI's fields go back to what is rendering, unless a newer request is queued.
        if (!buildRequest_) {
          if (lastGood) {
            shownDescUpdates_.push_back(ShownDesc{*lastGood, request.request, false});
            target_ = Target{*lastGood, request.request};
            lastRequested_ = *lastGood;
          } else {
            lastRequested_.reset();
          }
        }
      }
      if (!buildRequest_) loading_ = false;
    }
    if (notify_) notify_();  // outside the lock: the callback may query the session
  }
}

void RenderSession::workerLoop() {
  using Clock = std::chrono::steady_clock;
  std::shared_ptr<Scene> scene;
  std::unique_ptr<ProgressiveRenderer> renderer;
  Film film;
  uint64_t shownRequest = 0;
  uint64_t seenTarget = 0;  // newest target examined (a structural one waits for its build)
  bool needPreview = false;
  double seconds = 0.0;
  int passSpp = 1;
  ProgressLimits limits;
  bool finishedPublished = false;
  double rate = 5e5;  // camera samples per second, measured; sizes the preview pass

  std::optional<RegionRect> region;  // the render region, clamped to the image (regionFilm: its samples)
  std::optional<RegionRect> regionAsked;
  Film regionFilm;
  double regionSeconds = 0.0;
  std::shared_ptr<const Film> usedPilot;  // the auto pilot's film a restart last started from
  auto restart = [&] {
    film = Film();
    regionFilm = Film();
    regionSeconds = 0.0;
    seconds = 0.0;
    passSpp = 1;
    needPreview = true;
    finishedPublished = false;
    // A new auto decision that piloted this very view: its samples are the first ones (once; after
    // any later edit the image starts afresh), and they make the preview pass unnecessary.
    const AutoDecision* d = scene ? scene->autoDecision() : nullptr;
    if (d && d->pilotFilm && d->pilotFilm != usedPilot) {
      usedPilot = d->pilotFilm;
      film = continueFromPilot(*scene, limits.spp);
      needPreview = film.spp() == 0;
    }
  };
  auto makeFrame = [&] {
    auto frame = std::make_shared<Frame>();
    frame->request = shownRequest;
    frame->width = scene->camera().width();
    frame->height = scene->camera().height();
    frame->seconds = seconds;
    frame->scene = std::make_shared<const SceneDesc>(scene->desc());
    if (const AutoDecision* d = scene->autoDecision()) frame->autoDecision = d->summary(), frame->autoChoice = d->label();
    if (const SplitMap* split = renderer ? renderer->adaptiveSplit() : nullptr) frame->adaptiveSplit = split->summary(), frame->meanSplit = split->meanSplit;
    frame->sceneCenter = scene->center();
    frame->sceneRadius = scene->radius();
    frame->sceneMin = scene->boundsMin(), frame->sceneMax = scene->boundsMax();
    frame->region = region;
    if (region) frame->regionFilm = regionFilm;
    return frame;
  };

  for (;;) {
    std::shared_ptr<Scene> built;
    std::optional<Target> target;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      auto finished = [&] {
        const bool inRegion = region && film.spp() > 0;
        const Film& refining = inRegion ? regionFilm : film;
        return (limits.spp > 0 && refining.spp() >= limits.spp) || (limits.time_s > 0.0f && (inRegion ? regionSeconds : seconds) >= limits.time_s);
      };
      workerWake_.wait(lock, [&] {
        return stop_ || builtScene_ || limitsChanged_ || regionChanged_ || (target_ && target_->request > seenTarget) ||
               (scene && !finished() && !loading_ && !paused_);
      });
      if (stop_) return;
      cancelPass_ = false;
      if (builtScene_) {
        built = std::exchange(builtScene_, nullptr);
        shownRequest = builtRequest_;
      }
      if (target_ && target_->request > shownRequest) target = target_;
      if (target_) seenTarget = std::max(seenTarget, target_->request);
      if (regionChanged_) {
        regionAsked = region_;
        regionChanged_ = false;
        regionFilm = Film();
        regionSeconds = 0.0;
        finishedPublished = false;
      }
      if (limitsChanged_) {
        const bool lowered = (limits_.spp > 0 && (limits.spp == 0 || limits_.spp < limits.spp));
        limits = limits_;
        limitsChanged_ = false;
        finishedPublished = false;
        if (lowered && film.spp() > limits.spp && scene) restart();  // honour a lower spp limit exactly
      }
    }
    if (built) {
      scene = built;
      renderer = std::make_unique<ProgressiveRenderer>(scene, options_);
      restart();
    }
    static const bool trace = std::getenv("CANDELA_TRACE") != nullptr;
    const auto applyStart = Clock::now();
    if (scene && target) {
      // Apply what can change without a rebuild. A structural change waits for its build.
      const SceneDiff diff = diffScenes(scene->desc(), target->desc);
      if (!diff.structure) {
        try {
          if (diff.strategy) scene->applyStrategy(target->desc.strategy);
          if (diff.camera) scene->setCamera(target->desc.camera);
          if (diff.render) scene->setRender(target->desc.render);
        } catch (const std::exception& e) {
          message(std::string(e.what()) + " (edit not applied)");
        }
        shownRequest = target->request;
        if (diff.any()) restart();
      }
    }
    if (!scene) continue;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      shownDesc_ = std::make_shared<const SceneDesc>(scene->desc());
      shownDescRequest_ = shownRequest;
      shownProbes_ = scene->probes();
    }

    if (paused_) continue;  // the edits are applied; their image comes on resume
    // The film that refines: the render region's once the image has had a first pass (so that the
    // rest of it shows), else the whole image's.
    region.reset();
    if (regionAsked) {
      const int W = scene->camera().width(), H = scene->camera().height();
      RegionRect r;
      r.x = std::clamp(regionAsked->x, 0, W - 1), r.y = std::clamp(regionAsked->y, 0, H - 1);
      r.w = std::clamp(regionAsked->w, 1, W - r.x), r.h = std::clamp(regionAsked->h, 1, H - r.y);
      if (regionFilm.spp() > 0 && !(regionFilm.width() == r.w && regionFilm.height() == r.h)) regionFilm = Film(), regionSeconds = 0.0;
      region = r;
    }
    const bool inRegion = region && film.spp() > 0;
    std::optional<Camera> regionCamera;
    if (inRegion) regionCamera = scene->camera().window(region->x, region->y, region->w, region->h);
    Film& refining = inRegion ? regionFilm : film;
    double& refiningSeconds = inRegion ? regionSeconds : seconds;
    auto reached = [&] {
      return (limits.spp > 0 && refining.spp() >= limits.spp) || (limits.time_s > 0.0f && refiningSeconds >= limits.time_s);
    };
    if (reached()) {
      if (!finishedPublished) {
        auto frame = makeFrame();
        frame->film = film;
        frame->finished = true;
        frame->samplesPerSecond = seconds > 0.0 ? film.spp() * double(film.width()) * film.height() / seconds : 0.0;
        publish(frame);
        finishedPublished = true;
      }
      continue;
    }

    const auto start = Clock::now();
    if (needPreview) {
      // A quarter-resolution pass of the same view: the first image after an edit in milliseconds.
      CameraDesc small = scene->desc().camera;
      Film preview;
      // Size the preview to take about 10 ms at the measured rate: blocky, but immediate.
      const double pixels = double(scene->camera().width()) * scene->camera().height();
      const int factor = std::clamp(static_cast<int>(std::ceil(std::sqrt(pixels / (0.010 * std::max(1e5, rate))))), 2, 16);
      small.resolution = {std::max(1, scene->camera().width() / factor), std::max(1, scene->camera().height() / factor)};
      const Camera sizedCamera(small);
      const auto previewStart = Clock::now();
      if (!renderer->renderPass(preview, 1, &cancelPass_, &sizedCamera)) continue;
      rate = std::max(rate * 0.5, preview.width() * double(preview.height()) / std::max(1e-4, std::chrono::duration<double>(Clock::now() - previewStart).count()));
      if (trace)
        std::fprintf(stderr, "trace: apply %.1f ms, preview %.1f ms\n", 1e3 * std::chrono::duration<double>(previewStart - applyStart).count(),
                     1e3 * std::chrono::duration<double>(Clock::now() - previewStart).count());
      needPreview = false;
      auto frame = makeFrame();
      frame->preview = true;
      frame->film = std::move(preview);
      publish(frame);
      continue;
    }
    int spp = passSpp;
    if (limits.spp > 0) spp = std::min(spp, limits.spp - refining.spp());
    if (!renderer->renderPass(refining, spp, &cancelPass_, inRegion ? &*regionCamera : nullptr)) continue;
    const double passSeconds = std::chrono::duration<double>(Clock::now() - start).count();
    refiningSeconds += passSeconds;
    rate = spp * double(refining.width()) * refining.height() / std::max(1e-4, passSeconds);
    // Aim for passes of about a tenth of a second: frequent updates, little per-pass overhead.
    if (passSeconds < 0.05) passSpp = std::min(passSpp * 2, 256);
    else if (passSeconds > 0.25 && passSpp > 1) passSpp /= 2;
    if (paused_) continue;  // a pass that ended as the pause came: its samples show on resume
    auto frame = makeFrame();
    frame->film = film;
    frame->samplesPerSecond = seconds > 0.0 ? film.spp() * double(film.width()) * film.height() / seconds : 0.0;
    frame->finished = reached();
    finishedPublished = frame->finished;
    publish(frame);
  }
}

}  // namespace candela
