// Camera-ray guide tables reused across passes (talk s.2.2's cost; docs/method.md, "Scattering
// distance sampling"). While the camera, the probes and the guiding settings stay put, the camera
// rays through a pixel differ only by their sub-pixel jitter, so gathering probe knots and building
// a piecewise-linear table for every camera sample repeats the same work. Each pixel's table is
// built once, from its centre ray, over that ray's medium interval; every camera ray through the
// pixel shares it as it stands (GuidedDistance::share), a density in the distance t from the camera.
// It then depends on the ray's pixel alone, never on the walk, so MIS stays unbiased; where a
// jittered ray's interval reaches past the centre ray's, the tracked technique alone samples. Any
// change of the key (camera, probe set, strategy but q) rebuilds the tables; a new q (or
// guiding.bright_pixel_probability) only refreshes each pixel's.
//
// Each pixel's q starts from guiding.guided_probability and, with guiding.bright_pixel_probability, grows
// where the probes predict that bright single scattering is the pixel's light (a sun shaft): by the
// pixel's prediction over the image's mean, times the prediction's share against an upper bound of
// the emission along the centre ray (emissionBoundAlongRay), up to that setting. Both come from the
// centre ray, so q stays a function of the pixel alone (MIS unbiased, the same on any thread count).
//
// With guiding.measured_pixel_probability the samples then set q, per block of pixels. A camera
// sample's vertex (guided or tracked) adds direct light D = f(t) / p_q(t), p_q = q p_g + (1 - q)
// p_t, and at its t both densities are known, so D p_q / p_q' is what q' would have added there:
// - E[D^2] under q' is E[D^2 p_q / p_q'] (one-sample MIS draws t from the mixture p_q);
// - the covariance of D with the rest of the sample R (the walk's emission, the tracked vertex's
//   continuation) changes too, and on a flame-lit ray it is what decides: a walk that scatters
//   before the flame adds D and misses the flame's emission, one that passes adds no D, so the
//   tracked vertex's D is anti-correlated with R and a guided one is not. E[R D] under q' is
//   reweighted per technique: R D p_q / p_q' times (1 - q') / (1 - q) where the tracked vertex was
//   drawn, q' / q where the guided one was (the walk, and so R, does not depend on q).
// With the block's measured variance V (the film's) and work per sample W, q' predicts
// V + (E'[D^2] - E[D^2]) + 2 (E'[R D] - E[R D]) and W + (q' - q) c, c the work of a guided vertex;
// the block takes the q' whose product is least. q is set between passes, from passes already
// rendered, so every sample is drawn with a q fixed before it: the image stays unbiased, and the
// same passes give the same q on any thread count. The probes say where single scattering is; this
// says whether guiding it lowers the pixel's noise per unit of work.
#pragma once

#include "distance_sampler.h"
#include "film.h"
#include "integrator.h"
#include "scene.h"

#include <algorithm>
#include <array>
#include <string>
#include <vector>

namespace candela {

class PathTracer;

class CameraGuides {
 public:
  // Makes the tables match `camera` and the tracer's scene and probes; rebuilds (in parallel)
  // only when something they depend on changed. Returns false when the strategy has no probe
  // guiding (then there is nothing to cache).
  bool prepare(const Scene& scene, const PathTracer& tracer, const Camera& camera);
  // The pixel's table and q. A pixel whose centre ray gets no guided sample (no
  // medium, thicker than guiding.max_optical_depth, no probe light, dimmer than
  // guiding.dim_pixel_floor of the image's mean prediction) has no table and q = 0: its rays get none
  // either, a choice by pixel that spares every camera sample the interval and thickness walks.
  const CameraRayGuide* at(int x, int y) const {
    return &guides_[static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x)];
  }
  size_t bytes() const {
    return bytes_ + guides_.size() * sizeof(CameraRayGuide);
  }
  int builds() const { return builds_; }  // how many times the tables were (re)built
  // The probes' prediction of the light scattered along the pixel's centre ray (knotsIntegral; 0
  // where it gets no guided sample for another reason), the threshold below which a pixel is left
  // to tracking (guiding.dim_pixel_floor x the image's mean prediction), and how many pixels that left.
  float predictedLight(int x, int y) const {
    return predicted_.empty() ? 0.0f : predicted_[static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x)];
  }
  float dimThreshold() const { return dimThreshold_; }
  // The factor guiding.bright_pixel_probability raises the pixel's q by (before the clamp): its
  // prediction over the image's mean x its share against the emission bound, the share taken only
  // where the prediction exceeds the mean (below it q stays at its base either way). 0 without a
  // table.
  float brightness(int x, int y) const {
    return brightness_.empty() ? 0.0f : brightness_[static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x)];
  }
  size_t dimPixels() const { return dimPixels_; }

  // Measured q (guiding.measured_pixel_probability; see above). measuring(): the pixels record
  // their samples, pooled over blocks of kMeasureBlock x kMeasureBlock pixels (a pixel's own few
  // samples would choose mostly by their noise); a block lies inside one render tile, so only the
  // thread rendering that tile writes it. record() comes from that thread.
  // restart() puts every pixel back at its predicted q (a fresh film: the same command gives the
  // same image); passFinished() takes the pass's work (WorkCounters::cost(), summed over its tiles:
  // read per pixel, the counters' conversions were 3% of a `full` camera sample in 1-spp passes),
  // sets the measured q at 16, 32, 64... samples since then and says whether it did. The
  // candidates are kMeasuredProbabilities up to the larger of guiding.guided_probability and
  // guiding.bright_pixel_probability.
  static constexpr std::array<float, 6> kMeasuredProbabilities{0.0f, 0.05f, 0.1f, 0.2f, 0.35f, 0.5f};
  static constexpr int kMeasureBlock = 8;
  bool measuring() const { return measuring_; }
  // `share`: the camera sample's share of its film sample, 1 / k for one of a split pixel's k
  // sub-samples (sample_allocation.h), whose film sample's variance is a k-th of theirs.
  void record(int x, int y, const PathTracer::CameraVertexRecord& vertex, const Rgb& sample, double share = 1.0);
  void restart(const Scene& scene);
  // `cameraSamples`: the pass's camera samples per pixel (more than `spp` where pixels split), which
  // time the decisions, so that a split render decides after as many camera samples as any other.
  bool passFinished(const Scene& scene, const Film& film, int spp, double passWork, double cameraSamples);
  size_t measuredDecisions() const { return measuredDecisions_; }  // how many times passFinished set q
  // What the samples recorded since the last restart predict for kMeasuredProbabilities[candidate]
  // everywhere: the change of the image's variance per sample, summed over pixels and channels
  // (the film's sampleVariance). For tests and the record's arithmetic.
  double measuredVarianceChange(size_t candidate) const;
  // How many pixels with a table have each of kMeasuredProbabilities as their q, and last, how many
  // have another (a predicted q, before the first measured one).
  std::vector<size_t> pixelsByProbability() const;

 private:
  size_t index(int x, int y) const { return static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x); }
  size_t block(int x, int y) const {
    return static_cast<size_t>(y / kMeasureBlock) * static_cast<size_t>(blocksX_) + static_cast<size_t>(x / kMeasureBlock);
  }
  struct BlockRect {
    int x0, y0, x1, y1;
  };
  BlockRect blockRect(size_t b) const {
    const int x0 = static_cast<int>(b % static_cast<size_t>(blocksX_)) * kMeasureBlock;
    const int y0 = static_cast<int>(b / static_cast<size_t>(blocksX_)) * kMeasureBlock;
    return {x0, y0, std::min(width_, x0 + kMeasureBlock), std::min(height_, y0 + kMeasureBlock)};
  }
  // Sums over a block's recorded samples. D: the camera vertex's direct light; R: the rest of the
  // sample.
  struct BlockMeasure {
    double samples = 0.0, guided = 0.0, guidedWork = 0.0;  // film samples (a split pixel's k sub-samples make one)
    double cameraSamples = 0.0;                            // camera samples, sub-samples each
    // Per channel: the change in the sum of the samples' squares that each candidate q' would
    // bring, (D p_q / p_q')^2-type terms less D^2 and twice the same for R D (see above).
    std::array<std::array<double, 3>, kMeasuredProbabilities.size()> change{};
  };
  std::vector<BlockMeasure> measures_;
  int blocksX_ = 0;
  bool measuring_ = false;
  int measuredSamples_ = 0;                             // film samples per pixel since the last restart
  double measuredCameraSamples_ = 0.0, nextDecision_ = 16.0;  // camera samples per pixel
  double measuredWork_ = 0.0;  // the passes' work since the last restart
  size_t measuredDecisions_ = 0;
  void resetMeasures();

  std::string key_;             // what the tables depend on
  std::string probabilityKey_;  // what the pixels' q depend on
  int width_ = 0, height_ = 0;
  std::vector<std::vector<float>> rows_;  // per image row, each pixel's ts, vs, cdf, back to back
  size_t bytes_ = 0;                       // the rows' tables
  std::vector<CameraRayGuide> guides_;  // each pixel's table view and q
  std::vector<float> predicted_;
  std::vector<float> brightness_;  // see brightness()
  float probabilityAt(const Scene& scene, int x, int y) const;  // the pixel's q (a pixel with a table)
  void refreshProbabilities(const Scene& scene);                 // every kept pixel's q from probabilityAt
  float dimThreshold_ = 0.0f;
  size_t dimPixels_ = 0;
  int builds_ = 0;
};

}  // namespace candela
