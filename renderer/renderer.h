// Progressive rendering: passes of N samples per pixel accumulate into a Film. Tiles render in
// parallel with TBB; a pass can be cancelled at any moment (checked between samples, so within a few
// milliseconds) and a cancelled pass leaves the film untouched. Each camera sample draws from its own
// random stream keyed by (seed, pixel, sample index), so a seed and spp give the same image
// whatever the thread count or tile schedule.
#pragma once

#include "sample_allocation.h"
#include "work.h"

#include "camera_guides.h"
#include "film.h"
#include "integrator.h"
#include "scene.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <vector>

namespace candela {

// Where a pixel's camera samples lie inside it, in [0, 1)^2 (docs/method.md s.4c): Roberts' R2
// sequence, the additive recurrence n (1 / g, 1 / g^2) modulo 1 with g the plastic number, from a
// random start per pixel (hashed from `pixelKey`: the seed and the pixel). Each position is uniform
// over the pixel, so every sample's expectation is the pixel's value; the first n positions of a
// pixel cover it about evenly for every n, which takes most of the footprint's share of the
// variance off a pixel's mean (at 64 spp 13% less MSE on torch-in-mist and 3% on fire, the same
// relMSE; docs/performance.md, "Stratified sub-pixel positions"). A pixel's samples are then not
// independent of each other: their shared start is why a pixel's sample variance overstates its
// mean's error a little, and s.4b says why auto's joined images stay unbiased.
// Built once per pixel: the start's hash and random numbers are the pixel's, not each sample's.
class PixelSamplePositions {
 public:
  explicit PixelSamplePositions(uint64_t pixelKey);

  // The position of the pixel's sample `sampleIndex`.
  Vec2 operator()(uint64_t sampleIndex) const {
    // 1 / g and 1 / g^2, g = 1.32471795724... (x^3 = x + 1): the two-dimensional golden ratio,
    // whose additive recurrence has the lowest discrepancy known for every prefix (Roberts 2018).
    constexpr double kStepX = 0.75487766624669276, kStepY = 0.56984029099805327;
    const double n = static_cast<double>(sampleIndex);  // exact below 2^53: any sample count the limits allow
    const double x = startX_ + n * kStepX, y = startY_ + n * kStepY;
    // Below 1 after rounding to float as well: a position never lands on the next pixel's edge.
    constexpr float kBelowOne = 0x1.fffffep-1f;
    return Vec2(std::min(static_cast<float>(x - std::floor(x)), kBelowOne), std::min(static_cast<float>(y - std::floor(y)), kBelowOne));
  }

 private:
  double startX_, startY_;
};

struct RenderOptions {
  int threads = 0;     // 0: all hardware threads
  int tileSize = 32;
  // The sample index of a film's first sample: a film's n-th sample draws stream firstSample + n and
  // lies at PixelSamplePositions(pixel)(firstSample + n). Auto's pilot renders its candidates on
  // disjoint index ranges, so that their images can join the final one (auto_strategy.h) as
  // samples of one sequence per pixel, each with fresh random numbers.
  int firstSample = 0;
};

class ProgressiveRenderer {
 public:
  ProgressiveRenderer(std::shared_ptr<const Scene> scene, RenderOptions options = {});

  // Renders `spp` more samples per pixel into `film` (resized to the camera if needed). Returns
  // false, leaving `film` unchanged, if `cancel` became true during the pass. `camera` overrides the
  // scene's camera (the viewer's low-resolution preview after an edit uses the same view, fewer pixels).
  bool renderPass(Film& film, int spp, const std::atomic<bool>* cancel = nullptr, const Camera* camera = nullptr);

  // Renders until `spp` samples per pixel or, when `seconds` > 0, until the clock runs out (the
  // unfinished pass is discarded). Returns the seconds spent.
  double renderBudget(Film& film, int spp, double seconds, int passSpp = 1);

  // Where the next film's samples start (RenderOptions::firstSample): auto's pilot renders every
  // candidate image with one renderer, so that they share its camera-ray guide tables.
  void setFirstSample(int firstSample) { options_.firstSample = firstSample; }

  const Scene& scene() const { return *scene_; }
  // The work of every pass rendered so far (work.h): counted, so the same on any machine.
  const WorkCounters& work() const { return work_; }
  const CameraGuides& cameraGuides() const { return cameraGuides_; }
  // The adaptive split of the current film (StrategySettings::adaptive_split), once decided.
  const SplitMap* adaptiveSplit() const { return split_.map(); }

 private:
  std::shared_ptr<const Scene> scene_;
  RenderOptions options_;
  CameraGuides cameraGuides_;  // per-pixel camera-ray guide tables, kept across passes
  // The pass buffer, cleared and reused: allocated afresh, its arrays (over glibc's mmap threshold
  // from about 200 x 200 pixels) were mapped and page-faulted in every pass, which cost 30% of the
  // samples of a 1-spp-pass bench on fire at 240 x 240.
  Film pass_;
  WorkCounters work_;
  // Adaptive sampling by splitting (StrategySettings::adaptive_split): the current film's figures
  // and split.
  AdaptiveSplit split_;
};

// One strategy's render in an equal-time comparison (bench, report).
struct EqualTimeRun {
  ProgressiveRenderer* renderer = nullptr;
  Film film;             // auto's kept pilot samples, or empty
  double seconds = 0.0;  // charged so far: auto's decision (its pilot), then every pass rendered
};

// Renders every run until its `seconds` reach `budget`, side by side: one pass of `passSpp` at a
// time, always of the run with the least time so far (the viewer's comparison panes schedule their
// passes the same way, live, in ui/comparison_session.cpp). Rendered one after another, each strategy
// met the machine as it was then; the clock's 15-30% swings between runs of one command (another
// process, a frequency change) then fell on one strategy and not its rival, and a ratio between two
// of them moved by up to 15% between runs. Side by side, a slow spell falls on all alike. A pass is
// never cut short (each is charged what it took: the last one overshoots the budget by one pass), and
// every run renders at least one, so that each has an image to measure.
void renderSideBySide(std::vector<EqualTimeRun>& runs, double budget, int passSpp = 1);

}  // namespace candela
