// Adaptive sampling by splitting (docs/method.md s.4d): blocks of pixels whose noise per unit of
// work is high take k camera samples per film sample, and the film keeps their mean. Every pixel
// keeps the same number of film samples whatever its k, and k is chosen from earlier samples only,
// so k changes the variance of later samples and never their expectation: the image is unchanged.
#pragma once

#include "core.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace candela {

class Film;

// What a split chose: k per pixel and the gains the film's own figures predict for it.
struct SplitMap {
  std::vector<uint8_t> split;                        // per pixel; empty: one camera sample everywhere
  double predictedMse = 1.0, predictedRelMse = 1.0;  // efficiency over no split, by MSE and relMSE x work
  double meanSplit = 1.0, splitShare = 0.0;          // mean k over the pixels; share of pixels with k > 1
  bool oneSided = false;  // kept for one metric's gain (AdaptiveSplit::kOneSidedGain), the other's near level
  int decidedAt = 0;                                 // camera samples per pixel it was measured on
  std::string summary() const;
};

// Per-pixel figures of camera samples, and the split they call for.
//
// The split is decided once, after 4 camera samples per pixel, and kept: the film weighs its samples
// equally (that keeps it unbiased), so a film sample of k sub-samples counts as much as one of one,
// and a k that changed during the render would give the samples with less variance too little
// weight. A pixel that goes from 1 to k = 8 halfway through gets the variance of 227 camera
// samples from 576, so a later, better-informed decision lost more than it won.
//
// Per 8 x 8 block: its pixels' variance per camera sample, absolute and relative to the image (the
// report's MSE and relMSE; a pixel's mean is the film's), and its work per camera sample (work.h's
// cost). k is proportional to sqrt(variance / work), the allocation that
// minimises variance x work, for a variance that weighs the two metrics by alpha and 1 - alpha;
// the split kept is the one of least work whose predicted gain, by the worse of the two metrics,
// is within 10% of the largest, and only when that gain is at least 10%. The gain is cross-validated:
// the split one half of the samples calls for, scored by the other half's figures, since a split
// fitted to the same samples it is scored on finds gains in their noise (on the cloud, x1.2
// predicted that way measured x0.8).
//
// Failing that, a split for one metric: a small bright region (a torch's flame core, 1-2% of the
// pixels) can carry most of the image's MSE and little of its relMSE, so that any split gains the
// one and loses a little of the other. Such a split is kept when it predicts x1.5 or more by one
// metric and no worse than x0.98 by the other, and adds at most 2% to the work per film sample: the
// other metric loses about what the work adds, and the prediction of that loss erred by about 3% on
// the low side (docs/performance.md, "A split for one metric").
class AdaptiveSplit {
 public:
  static constexpr int kBlock = 8;       // pixels along each side of a block that shares one k
  static constexpr int kFirstDecision = 4;  // camera samples per pixel before the first split
  static constexpr int kMaxSplit = 16;
  static constexpr uint64_t kSubStreamBase = uint64_t(1) << 40;  // sub-samples' random streams start here

  // Forgets everything: a fresh film (or a new size).
  void reset(int width, int height);
  bool empty() const { return width_ == 0; }
  bool decided() const { return decided_; }
  // k of pixel p for this pass (1 before the first split and where none is called for).
  int split(size_t p) const { return map_.split.empty() ? 1 : map_.split[p]; }
  // The position index (PixelSamplePositions) of pixel p's next camera sample, `sampleIndex` for a
  // film that has never split. Once split, each pixel's positions run on contiguously from there
  // (R2 is low-discrepancy on any contiguous range), past every position its earlier samples took.
  uint64_t nextPosition(size_t p, uint64_t sampleIndex) { return positions_.empty() ? sampleIndex : positions_[p]++; }
  // The random stream of sub-sample j of film sample `sampleIndex` (j = 0: the film sample's own).
  static uint64_t subSampleStream(uint64_t sampleIndex, int j) {
    return j == 0 ? sampleIndex : kSubStreamBase + sampleIndex * kMaxSplit + static_cast<uint64_t>(j);
  }
  // Pixel p's camera sample of film sample `sampleIndex` (accepted ones only; before the decision
  // each film sample is one camera sample), and the pixel's work in a pass.
  void addCameraSample(size_t p, uint64_t sampleIndex, const Rgb& value) {
    std::vector<float>& s = sumSquares_[sampleIndex & 1];
    s[3 * p] += value.r * value.r, s[3 * p + 1] += value.g * value.g, s[3 * p + 2] += value.b * value.b;
    count_[sampleIndex & 1][p] += 1.0f;
  }
  void addCost(size_t p, float cost) { cost_[p] += cost; }
  // After a pass: decides again when the schedule says so (returns true then). `film` holds the
  // means; `nextSampleIndex` is the film's next sample index (where positions continue).
  bool passFinished(const Film& film, int maxSplit, uint64_t nextSampleIndex);
  // The split in force, once decided.
  const SplitMap* map() const { return decided_ ? &map_ : nullptr; }

  // The decision itself, from per-pixel means (the film) and, per half of the samples (even and odd
  // film samples), camera-sample sums of squares and counts, and each pixel's work: exposed for the
  // tests.
  using Halves = std::array<std::vector<float>, 2>;
  static SplitMap decide(const Film& film, const Halves& sumSquares, const Halves& count, const std::vector<float>& cost, int maxSplit);
  static constexpr double kMinimumGain = 1.1;  // the cross-validated gain a split must predict
  static constexpr double kNearBest = 0.9;     // kept: the least work among splits within this of the best gain
  // A split for one metric, where no split gains kMinimumGain by both: the largest gain by one metric
  // among the splits that predict at least kOneSidedGain by it and kOneSidedFloor by the other,
  // and cost at most kOneSidedWork times the work per film sample.
  static constexpr double kOneSidedGain = 1.5;
  static constexpr double kOneSidedFloor = 0.98;
  static constexpr double kOneSidedWork = 1.02;

 private:
  int width_ = 0;  // 0: nothing measured yet
  Halves sumSquares_, count_;
  std::vector<float> cost_;
  std::vector<uint64_t> positions_;
  SplitMap map_;
  bool decided_ = false;
  double cameraSamples_ = 0.0;
};

}  // namespace candela
