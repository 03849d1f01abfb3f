// Guided distance sampling along a ray's medium interval [t0, t1] (talk s.2.2; docs/method.md s.4).
// - Piecewise-linear: knots (t_k, s_k) from the probes a ray crosses define a piecewise-linear
//   density (flat beyond the first and last knot), mixed with a uniform floor so the support is
//   complete: p(t) = floor / (t1 - t0) + (1 - floor) * lin(t) / integral(lin). No knots: uniform.
// - Equi-angular (Kulla and Fajardo 2012): for a point c at distance D from the ray, whose
//   projection is at t = delta, p(t) = D / ((theta1 - theta0) (D^2 + (t - delta)^2)); a mixture over
//   several points weighted by light power.
// Both sample t by inverting their CDF and evaluate their pdf at any t (for MIS).
#pragma once

#include "core.h"

#include <algorithm>
#include <vector>

namespace candela {

struct DistanceKnot {
  float t = 0.0f;
  float value = 0.0f;
};

// True when some knot predicts light scattered (a positive value): a density of knots that all
// predict none would be its floor alone.
inline bool knotsCarryLight(const std::vector<DistanceKnot>& knots) {
  for (const DistanceKnot& k : knots)
    if (k.value > 0.0f) return true;
  return false;
}

// The knots' integral over [t0, t1], flat beyond the outer knots as the density built from them
// is: what the probes predict the segment scatters toward its origin (single scattering, without
// the transmittance back to the origin). Knots sorted by t.
inline double knotsIntegral(const std::vector<DistanceKnot>& knots, float t0, float t1) {
  if (knots.empty()) return 0.0;
  double sum = static_cast<double>(knots.front().value) * std::max(0.0f, knots.front().t - t0) +
               static_cast<double>(knots.back().value) * std::max(0.0f, t1 - knots.back().t);
  for (size_t k = 1; k < knots.size(); ++k)
    sum += 0.5 * (static_cast<double>(knots[k].value) + knots[k - 1].value) * (knots[k].t - knots[k - 1].t);
  return sum;
}

// A piecewise-linear density's tables, stored elsewhere (a PiecewiseLinearDistance, or a pixel's
// entry in the camera-ray cache): segment ends ts, values vs at them, cumulative area cdf, n each.
struct PiecewiseLinearView {
  const float* ts = nullptr;
  const float* vs = nullptr;
  const float* cdf = nullptr;
  uint32_t n = 0;
  float t0 = 0.0f, t1 = 1.0f;
  float area = 0.0f;
  float uniformShare = 1.0f;  // the floor (1 when there is nothing to follow)

  float sample(float u, float& pdf) const;
  float pdf(float t) const;

 private:
  float linear(float t) const;
};

// What a pixel's camera rays use for their guided sample (renderer/camera_guides.h): the pixel's
// table, and the one-sample probability q of keeping the guided vertex. q = 0: the
// pixel's rays get no guided sample at all (tracking alone serves them).
// 32 bytes per pixel: the table's header and q, its ts, vs and cdf back to back from `data`. In the
// viewer's, bench's and report's 1-spp passes every camera sample reads its pixel's entry from
// memory no other sample of the pass touches; with the view's three pointers stored inline an
// entry took a whole 64-byte line (docs/performance.md, "The camera-ray guide in 32 bytes").
struct alignas(32) CameraRayGuide {
  const float* data = nullptr;  // ts, vs, cdf (n each); null: no table, no guided sample
  uint32_t n = 0;
  float t0 = 0.0f, t1 = 1.0f, area = 0.0f, uniformShare = 1.0f;
  float guidedProbability = 0.0f;

  bool hasTable() const { return data != nullptr; }
  PiecewiseLinearView view() const { return {data, data + n, data + 2 * n, n, t0, t1, area, uniformShare}; }
  // Asks for every cache line of the table (ts, vs and cdf, 12 n bytes) ahead of its use.
  void prefetchTable() const {
    const uintptr_t end = reinterpret_cast<uintptr_t>(data + 3 * n);
    for (uintptr_t line = reinterpret_cast<uintptr_t>(data) & ~uintptr_t{63}; line < end; line += 64)
      __builtin_prefetch(reinterpret_cast<const void*>(line));
  }
};
static_assert(sizeof(CameraRayGuide) == 32, "one guide entry per pixel: half a cache line");

class PiecewiseLinearDistance {
 public:
  // Knots may be unsorted (they are sorted here) and may lie outside [t0, t1] (clamped).
  void build(float t0, float t1, std::vector<DistanceKnot>& knots, float floor);
  float sample(float u, float& pdf) const { return view().sample(u, pdf); }
  float pdf(float t) const { return view().pdf(t); }
  float t0() const { return t0_; }
  float t1() const { return t1_; }
  PiecewiseLinearView view() const {
    return {ts_.data(), vs_.data(), cdf_.data(), static_cast<uint32_t>(ts_.size()), t0_, t1_, area_, uniformShare_};
  }

 private:
  float t0_ = 0.0f, t1_ = 1.0f;
  float uniformShare_ = 1.0f;  // floor (1 when there is nothing to follow)
  std::vector<float> ts_, vs_, cdf_;  // segment ends, values at them, cumulative area
  float area_ = 0.0f;
};

struct EquiAngularTarget {
  Vec3 point{0.0f};
  float weight = 1.0f;  // selection weight (light power)
};

class EquiAngularDistance {
 public:
  // Targets with weight > 0; an empty list gives the uniform density.
  void build(const Ray& ray, float t0, float t1, const std::vector<EquiAngularTarget>& targets);
  float sample(float u, float& pdf) const;
  float pdf(float t) const;

 private:
  struct Lobe {
    float delta, d, theta0, theta1, weight;
  };
  float t0_ = 0.0f, t1_ = 1.0f;
  std::vector<Lobe> lobes_;
};

// The guided distance density of one ray segment, the distance-sampler piece of a strategy:
// piecewise-linear from probe knots, or an equi-angular mixture, over the segment's medium
// interval [t0, t1]. It can also share a piecewise-linear density built once per pixel (a cached
// camera-ray table over the pixel's centre ray's interval, renderer/camera_guides.h): every camera
// ray through the pixel samples and evaluates it at its own distances t. Any such density is a valid
// sampling choice for MIS as long as it depends on the ray alone, never on the walk; where it is zero
// on a ray (past the centre ray's interval) the tracked technique alone covers it.
class GuidedDistance {
 public:
  std::vector<DistanceKnot> knots;  // scratch: the probes' knots of the segment being built
  // one_sample MIS: the probability that this segment keeps the guided vertex (the settings' q, or
  // the pixel's own q from the camera cache, camera_guides.h).
  float guidedProbability = 0.5f;

  // From `knots` (sorted and clamped here).
  void buildPiecewiseLinear(float t0, float t1, float floor);
  void buildEquiAngular(const Ray& ray, float t0, float t1, const std::vector<EquiAngularTarget>& targets);
  // Shares `table` (a view of a pixel's cached camera-ray density over its centre ray's medium
  // interval, renderer/camera_guides.h, whose arrays outlive this density's use) instead of
  // building one.
  void share(const PiecewiseLinearView& table) { kind_ = Kind::Shared, shared_ = table; }

  float sample(float u, float& pdf) const;
  float pdf(float t) const;

 private:
  enum class Kind { Linear, EquiAngular, Shared } kind_ = Kind::Linear;
  PiecewiseLinearDistance linear_;
  EquiAngularDistance equiAngular_;
  PiecewiseLinearView shared_;
};

}  // namespace candela
