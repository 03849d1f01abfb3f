// Camera-ray guide tables reused across passes (talk s.2.2's cost; docs/method.md, "Scattering
// distance sampling"). While the camera, the probes and the guiding settings stay put, the camera
// rays through a pixel differ only by their sub-pixel jitter, so gathering probe knots and building
// a piecewise-linear table for every camera sample repeats the same work. Each pixel's table is
// built once, from its centre ray, over the unit interval of that ray's medium interval; every
// camera ray through the pixel borrows it, mapped onto its own interval (GuidedDistance::borrow).
// The density then depends on the ray's pixel and position alone, never on the walk, so MIS stays
// unbiased. Any change of the key (camera, probe set, guiding settings) rebuilds the tables.
#pragma once

#include "distance_sampler.h"
#include "scene.h"

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
  // The pixel's unit-interval table, or null when its centre ray gets no guided sample (rays
  // through it then build their own density, as without the cache).
  const PiecewiseLinearView* at(int x, int y) const {
    const size_t i = static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x);
    return present_[i] ? &views_[i] : nullptr;
  }
  size_t bytes() const { return data_.size() * sizeof(float) + views_.size() * (sizeof(PiecewiseLinearView) + 1); }
  int builds() const { return builds_; }  // how many times the tables were (re)built

 private:
  std::string key_;
  int width_ = 0, height_ = 0;
  std::vector<float> data_;  // every pixel's ts, vs, cdf, back to back
  std::vector<PiecewiseLinearView> views_;
  std::vector<char> present_;
  int builds_ = 0;
};

}  // namespace candela
