// The volumetric path tracer. One tracking loop (tracking.h); this file decides what each
// collision does. The conventional estimator (METHOD.md s.2 "conventional", the talk's Fig. 1 left):
// analog absorb / scatter / null events with P = mu_a/mu_bar, mu_s/mu_bar, mu_n/mu_bar; emission is
// added at absorption; scattering does next-event estimation to the lights (ratio-tracked
// transmittance, MIS with phase sampling for area and environment lights), then samples HG.
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

  const Scene& scene_;
};

}  // namespace candela
