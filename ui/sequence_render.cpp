#include "sequence_render.h"

#include "auto_strategy.h"
#include "image_io.h"
#include "renderer.h"
#include "scene.h"
#include "sequence.h"
#include "thread_priority.h"

#include <chrono>
#include <filesystem>
#include <unistd.h>

namespace candela {

namespace fs = std::filesystem;

SequenceRenderJob::~SequenceRenderJob() {
  cancel();
  wait();
}

void SequenceRenderJob::cancel() { cancel_ = true; }

void SequenceRenderJob::wait() {
  if (worker_.joinable()) worker_.join();
}

SequenceProgress SequenceRenderJob::progress() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return progress_;
}

void SequenceRenderJob::start(const SequenceRenderRequest& request) {
  const std::string& out = request.pattern;
  if (!hasFramePattern(out))
    throw InputError(out + ": expected an output pattern with the frame number in it (e.g. renders/fire.####.exr)");
  if (!isExrPath(out) && fs::path(out).extension() != ".png" && fs::path(out).extension() != ".PNG")
    throw InputError(out + ": expected an output ending in .exr or .png");
  if (request.last < request.first) throw InputError("frames: expected first <= last, got " + std::to_string(request.first) + "-" +
                                                     std::to_string(request.last));
  if (static_cast<long long>(request.last) - request.first + 1 > kMaxFramesInRange)
    throw InputError("frames: expected at most " + std::to_string(kMaxFramesInRange) + " frames");
  if (request.spp <= 0 && !(request.seconds > 0.0)) throw InputError("expected samples per pixel or seconds per frame above 0");
  cancel();
  wait();
  cancel_ = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    progress_ = SequenceProgress{};
    progress_.running = true;
    progress_.total = request.last - request.first + 1;
    progress_.frame = request.first;
  }
  worker_ = std::thread([this, request] {
    if (yieldToUi_) lowerThisThreadsPriority();
    run(request);
  });
}

void SequenceRenderJob::run(SequenceRenderRequest request) {
  using Clock = std::chrono::steady_clock;
  const bool png = !isExrPath(request.pattern);
  bool exposureChosen = !request.autoExposure;
  for (int f = request.first; f <= request.last && !cancel_; ++f) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      progress_.frame = f;
      progress_.frameFraction = 0.0;
    }
    const std::string path = substituteFrame(request.pattern, f);
    try {
      SceneDesc desc = request.scene;
      desc.render.frame = f;
      if (request.seconds > 0.0) desc.render.time_s = static_cast<float>(request.seconds);
      else desc.render.spp = request.spp, desc.render.time_s = 0.0f;
      auto scene = Scene::build(desc);
      ProgressiveRenderer renderer(scene, RenderOptions{request.threads, 32});
      Film film = continueFromPilot(*scene, request.seconds > 0.0 ? 0 : request.spp);
      const auto start = Clock::now();
      bool stopped = false;
      for (;;) {
        const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
        const bool done = request.seconds > 0.0 ? elapsed >= request.seconds : film.spp() >= request.spp;
        if (done) break;
        const int pass = request.seconds > 0.0 ? 1 : std::min(4, request.spp - film.spp());
        if (!renderer.renderPass(film, pass, &cancel_)) {
          stopped = true;
          break;
        }
        std::lock_guard<std::mutex> lock(mutex_);
        progress_.frameFraction = request.seconds > 0.0 ? std::min(1.0, elapsed / request.seconds)
                                                        : static_cast<double>(film.spp()) / request.spp;
      }
      if (stopped) break;  // cancelled: this frame is not written
      Image image = film.image();
      if (!exposureChosen) request.exposure = autoExposureStops(image.rgb), exposureChosen = true;
      image.metadata["scene"] = request.scene.path;
      image.metadata["settings"] = sceneToJson(desc).dump();
      image.metadata["spp"] = std::to_string(film.spp());
      image.metadata["frame"] = std::to_string(f);
      image.metadata["exposure"] = std::to_string(request.exposure);
      if (const AutoDecision* d = scene->autoDecision()) image.metadata["auto_decision"] = d->summary();
      // Both writers write atomically (atomic_file.h).
      if (png) writePng(path, image, request.exposure);
      else writeExr(path, image);
      std::lock_guard<std::mutex> lock(mutex_);
      progress_.written.push_back(path);
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(mutex_);
      progress_.failed.push_back("frame " + std::to_string(f) + ": " + e.what());
    }
    std::lock_guard<std::mutex> lock(mutex_);
    ++progress_.done;
    progress_.frameFraction = 0.0;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  progress_.running = false;
  progress_.cancelled = cancel_.load();
}

}  // namespace candela
