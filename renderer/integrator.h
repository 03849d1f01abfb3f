// The volumetric path tracer. One tracking loop (tracking.h); this file decides what each
// collision does, by named pieces of the strategy:
// - event probabilities: conventional analog absorb / scatter / null with P = mu_a/mu_bar,
//   mu_s/mu_bar, mu_n/mu_bar and emission added at absorption (METHOD.md s.2, the talk's Fig. 1
//   left), or emission gathered at every collision with P_a = P_n = 1, absorption as a weight
//   (strategy.emission.gather_every_collision; talk 2.1);
// - majorant policy: the medium's per-cell mu_bar, optionally emission-aware (medium.cpp);
// - light sampler: lights and, with strategy.emission.light_sampling, emissive volumes by their
//   energy grid (Algorithm 2), all chosen by power; emission met along a phase/BSDF-sampled ray is
//   MIS-weighted against that (METHOD.md s.3).
// Scattering does next-event estimation (ratio-tracked transmittance, or Algorithm 1 toward
// emissive volumes), then samples HG; surfaces are diffuse.
//
// Path length: at most render.max_depth scattering/bounce vertices. The last vertex takes all its
// direct light by NEE (weight 1) and its continuation gathers only volume emission, so every
// strategy computes exactly the same truncated image.
#pragma once

#include "scene.h"

namespace candela {

class PathTracer {
 public:
  explicit PathTracer(const Scene& scene) : scene_(scene) {}
  // Radiance arriving along the camera ray (scene-linear RGB). May be non-finite on a bug; the film
  // rejects and counts such samples.
  Rgb radiance(const Ray& cameraRay, Rng& rng) const;

 private:
  // Direct light at a point by light sampling. `g` is used for medium points (normal == 0), else a
  // diffuse BSDF with `albedo` around `normal`. `useMis` weights area/environment lights against
  // phase/BSDF sampling with the power heuristic.
  Rgb directLight(const Vec3& p, const Vec3& wo, float g, const Vec3& normal, const Rgb& albedo, bool useMis, Rng& rng) const;
  // Transmittance between p and p + wi * distance: surfaces and sphere lights occlude; media by
  // ratio tracking.
  float visibility(const Vec3& p, const Vec3& wi, float distance, int targetLight, Rng& rng) const;
  // Distance to the nearest surface or sphere light along a ray (what stops emission gathering).
  float nearestOccluder(const Ray& ray) const;

 public:
  // Solid-angle pdf of the volume-light technique producing direction w from x: the mixture
  // sum_m pmf_m p_m(w) over emissive volumes (Algorithm 2 for each).
  float volumeLightPdf(const Vec3& x, const Vec3& w) const;

 private:

  const Scene& scene_;
};

}  // namespace candela
