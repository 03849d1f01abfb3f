// Camera-ray guide tables reused across passes (talk s.2.2's cost; docs/method.md, "Scattering
// distance sampling"). While the camera, the probes and the guiding settings stay put, the camera
// rays through a pixel differ only by their sub-pixel jitter, so gathering probe knots and building
// a piecewise-linear table for every camera sample repeats the same work. Each pixel's table is
// built once, from its centre ray, over that ray's medium interval; every camera ray through the
// pixel shares it as it stands (GuidedDistance::share), a density in the distance t from the camera.
// It then depends on the ray's pixel alone, never on the walk, so MIS stays unbiased; where a
// jittered ray's interval reaches past the centre ray's, the tracked technique alone samples. Any
// change of the key (camera, probe set, strategy but q) rebuilds the tables; a new q (or region
// map of q, or guiding.bright_pixel_probability) only refreshes each pixel's.
//
// Each pixel's q starts from guidedProbabilityAt and, with guiding.bright_pixel_probability, grows
// where the probes predict that bright single scattering is the pixel's light (a sun shaft): by the
// pixel's prediction over the image's mean, times the prediction's share against an upper bound of
// the emission along the centre ray (emissionBoundAlongRay), up to that setting. Both come from the
// centre ray, so q stays a function of the pixel alone (MIS unbiased, the same on any thread count).
#pragma once

#include "distance_sampler.h"
#include "scene.h"

#include <string>
#include <vector>

namespace candela {

class PathTracer;

// The one-sample probability q for the camera rays through pixel (x, y) of a width x height image:
// the settings' guided_probability, or where `auto` chose scattering sampling by region (its
// pilot's region map, auto_strategy.h) the q of the pixel's region, 0 where tracking alone did
// better. A function of the pixel alone, so MIS stays unbiased.
float guidedProbabilityAt(const Scene& scene, int x, int y, int width, int height);

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
    return bytes_ + guides_.size() * (sizeof(CameraRayGuide) + 1);
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

 private:
  std::string key_;             // what the tables depend on
  std::string probabilityKey_;  // what the pixels' q depend on
  int width_ = 0, height_ = 0;
  std::vector<std::vector<float>> rows_;  // per image row, each pixel's ts, vs, cdf, back to back
  size_t bytes_ = 0;                       // the rows' tables
  std::vector<CameraRayGuide> guides_;  // each pixel's table view and q
  std::vector<char> present_;
  std::vector<float> predicted_;
  std::vector<float> brightness_;  // see brightness()
  float probabilityAt(const Scene& scene, int x, int y) const;  // the pixel's q (a pixel with a table)
  void refreshProbabilities(const Scene& scene);                 // every kept pixel's q from probabilityAt
  float dimThreshold_ = 0.0f;
  size_t dimPixels_ = 0;
  int builds_ = 0;
};

}  // namespace candela
