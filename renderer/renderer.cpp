#include "renderer.h"

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

namespace candela {

PixelSamplePositions::PixelSamplePositions(uint64_t pixelKey) {
  Rng start(hashCombine(pixelKey, 0x5032b1d5e4a3c6f7ULL), pixelKey);
  startX_ = start.uniform();
  startY_ = start.uniform();
}

ProgressiveRenderer::ProgressiveRenderer(std::shared_ptr<const Scene> scene, RenderOptions options)
    : scene_(std::move(scene)), options_(options) {}

bool ProgressiveRenderer::renderPass(Film& film, int spp, const std::atomic<bool>* cancel, const Camera* cameraOverride) {
  const Camera& camera = cameraOverride ? *cameraOverride : scene_->camera();
  const int w = camera.width(), h = camera.height();
  if (film.width() != w || film.height() != h) film.resize(w, h);
  Film& pass = pass_;
  pass.resize(w, h);  // zero-fills, keeping the arrays' storage
  const int tilesX = (w + options_.tileSize - 1) / options_.tileSize;
  const int tilesY = (h + options_.tileSize - 1) / options_.tileSize;
  const int firstSample = options_.firstSample + film.spp();
  const uint64_t seed = scene_->render().seed;
  std::atomic<bool> cancelled{false};
  PathTracer tracer(*scene_);
  // Camera rays of the scene's own camera share their pixel's cached guide table (camera_guides.h);
  // a preview's override camera builds per ray.
  const bool cachedGuides = !cameraOverride && cameraGuides_.prepare(*scene_, tracer, camera);
  // Measured q (camera_guides.h): a fresh film starts from the predicted q, so that the same
  // command gives the same image whatever this renderer rendered before.
  // Its blocks must each lie inside one tile (one thread writes a block).
  const bool measure = cachedGuides && cameraGuides_.measuring() && options_.tileSize % CameraGuides::kMeasureBlock == 0;
  if (measure && film.spp() == 0) cameraGuides_.restart(*scene_);
  // Adaptive sampling by splitting (sample_allocation.h): a fresh film starts unsplit, so that the
  // same command gives the same image. The viewer's preview camera renders as it always has.
  const int maxSplit = cameraOverride ? 1 : scene_->strategy().adaptive_split;
  if (maxSplit > 1 && (film.spp() == 0 || split_.empty())) split_.reset(w, h);
  const bool adaptive = maxSplit > 1;
  const bool measuringSplit = adaptive && !split_.decided();  // the figures the decision reads

  // Each thread's work counters before and after its tiles: summed over the threads that ran them.
  tbb::enumerable_thread_specific<WorkCounters> passWork;
  auto renderTile = [&](int tile) {
    const WorkCounters before = threadWork();
    uint64_t extraSamples = 0;  // split pixels' sub-samples beyond one per film sample
    const int x0 = (tile % tilesX) * options_.tileSize, y0 = (tile / tilesX) * options_.tileSize;
    const int x1 = std::min(w, x0 + options_.tileSize), y1 = std::min(h, y0 + options_.tileSize);
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) {
        if (cancel && cancel->load(std::memory_order_relaxed)) {
          cancelled = true;
          return;
        }
        // The next pixel's guide entry (half a cache line) arrives while this pixel's samples run.
        if (cachedGuides && x + 1 < x1) __builtin_prefetch(cameraGuides_.at(x + 1, y));
        const uint64_t pixelKey = hashCombine(seed, static_cast<uint64_t>(y) * static_cast<uint64_t>(w) + static_cast<uint64_t>(x));
        const PixelSamplePositions positions(pixelKey);
        const size_t pixel = static_cast<size_t>(y) * w + x;
        const double costBefore = measuringSplit ? threadWork().cost() : 0.0;
        const int split = adaptive ? split_.split(pixel) : 1;
        auto sample = [&](uint64_t streamIndex, uint64_t positionIndex, double share) {
          Rng rng(hashCombine(pixelKey, streamIndex), pixelKey);
          const Vec2 position = positions(positionIndex);
          const Ray ray = camera.generate(static_cast<float>(x) + position.x, static_cast<float>(y) + position.y);
          PathTracer::CameraVertexRecord record;
          const Rgb value = tracer.radiance(ray, cachedGuides ? cameraGuides_.at(x, y) : nullptr, rng, measure ? &record : nullptr);
          if (record.table) cameraGuides_.record(x, y, record, value, share);
          if (measuringSplit && Film::acceptable(value)) split_.addCameraSample(pixel, streamIndex, value);
          return value;
        };
        for (int s = 0; s < spp; ++s) {
          const uint64_t sampleIndex = static_cast<uint64_t>(firstSample + s);
          if (split == 1) {
            pass.addSample(x, y, sample(sampleIndex, adaptive ? split_.nextPosition(pixel, sampleIndex) : sampleIndex, 1.0));
            continue;
          }
          // A film sample of a split pixel: the mean of its sub-samples, a rejected one counted and
          // taken as 0 (as the film takes a rejected sample), so the mean stays normalised.
          Rgb total(0.0f);
          for (int j = 0; j < split; ++j) {
            // Random numbers of their own; positions that continue the pixel's R2 sequence
            // (sample_allocation.h), so the sub-samples stay stratified over the pixel.
            const Rgb value = sample(AdaptiveSplit::subSampleStream(sampleIndex, j), split_.nextPosition(pixel, sampleIndex), 1.0 / split);
            if (Film::acceptable(value)) total += value;
            else pass.countRejected(y);
          }
          pass.addSample(x, y, total / static_cast<float>(split));
        }
        if (measuringSplit) split_.addCost(pixel, static_cast<float>(threadWork().cost() - costBefore));
        extraSamples += static_cast<uint64_t>(split - 1) * static_cast<uint64_t>(spp);
      }
    WorkCounters& mine = passWork.local();
    mine += threadWork() - before;
    mine.samples += static_cast<uint64_t>(x1 - x0) * static_cast<uint64_t>(y1 - y0) * static_cast<uint64_t>(spp) + extraSamples;
  };
  const int tiles = tilesX * tilesY;
  auto run = [&] {
    tbb::parallel_for(tbb::blocked_range<int>(0, tiles, 1), [&](const tbb::blocked_range<int>& r) {
      for (int t = r.begin(); t != r.end(); ++t) {
        if (cancelled.load(std::memory_order_relaxed)) return;
        renderTile(t);
      }
    }, tbb::simple_partitioner());
  };
  if (options_.threads > 0) {
    tbb::task_arena arena(options_.threads);
    arena.execute(run);
  } else {
    run();
  }
  if (cancelled) return false;
  pass.setPassSpp(spp);
  film.addPass(pass);
  WorkCounters passTotal;
  for (const WorkCounters& w : passWork) passTotal += w;
  work_ += passTotal;
  if (measure) cameraGuides_.passFinished(*scene_, film, spp, passTotal.cost(), static_cast<double>(passTotal.samples) / (static_cast<double>(w) * h));
  if (adaptive) split_.passFinished(film, maxSplit, static_cast<uint64_t>(options_.firstSample + film.spp()));
  return true;
}

double ProgressiveRenderer::renderBudget(Film& film, int spp, double seconds, int passSpp) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  if (seconds <= 0.0) {
    while (film.spp() < spp) renderPass(film, std::min(passSpp, spp - film.spp()));
    return elapsed();
  }
  // A watchdog cancels the pass in flight when the clock runs out: the budget is honoured to within
  // milliseconds, and the unfinished pass is discarded.
  std::atomic<bool> cancel{false};
  std::atomic<bool> finished{false};
  std::thread watchdog([&] {
    while (!finished.load()) {
      if (elapsed() >= seconds) {
        cancel = true;
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  });
  while (!cancel.load()) {
    if (!renderPass(film, passSpp, &cancel)) break;
  }
  finished = true;
  watchdog.join();
  return elapsed();
}

void renderSideBySide(std::vector<EqualTimeRun>& runs, double budget, int passSpp) {
  using Clock = std::chrono::steady_clock;
  while (true) {
    EqualTimeRun* next = nullptr;
    for (EqualTimeRun& r : runs)
      if ((r.seconds < budget || r.film.spp() == 0) && (!next || r.seconds < next->seconds)) next = &r;
    if (!next) return;
    const auto start = Clock::now();
    next->renderer->renderPass(next->film, passSpp);
    next->seconds += std::chrono::duration<double>(Clock::now() - start).count();
  }
}

}  // namespace candela
