// Probe spheres for scattering distance sampling (talk s.2.2; METHOD.md s.4). Probes sit on a
// regular lattice over the non-empty part of the media (lattice points near which some medium can
// scatter), each with a radius of influence. Each learns a scattering sample weight
//     s = E[ mu_s(y) * rho(w_cam, w_light) * L_light * T(y, light) / p_light ],
// y uniform in the sphere, the light (emissive volumes included) chosen by the scene's light
// sampler, w_cam toward the camera origin, T by ratio tracking; and the same with an isotropic phase
// for rays that do not start at the camera (the guided direct light of later segments). A ray gathers the probes whose
// sphere it crosses as knots (projection on the ray, s) of a piecewise-linear distance density.
#pragma once

#include "distance_sampler.h"
#include "majorant.h"
#include "settings.h"

#include <atomic>
#include <memory>
#include <vector>

namespace candela {

class Scene;

struct Probe {
  Vec3 center{0.0f};
  float weight = 0.0f;            // scattering sample weight s (luminance), phase toward the camera origin
  float isotropicWeight = 0.0f;   // the same with an isotropic phase, for rays that do not start at the camera
};

class ProbeSet {
 public:
  // Places and learns probes for the scene as it is now; stops at the settings' time budget or when
  // `cancel` becomes true (probes not reached are dropped).
  static std::shared_ptr<const ProbeSet> learn(const Scene& scene, const GuidingSettings& settings,
                                               const std::atomic<bool>* cancel = nullptr);

  const std::vector<Probe>& probes() const { return probes_; }
  float radius() const { return radius_; }
  float spacing() const { return spacing_; }
  int placed() const { return placed_; }          // lattice points kept before learning
  double learnSeconds() const { return seconds_; }
  bool complete() const { return static_cast<int>(probes_.size()) == placed_; }

  // Appends a knot for each probe whose sphere the ray crosses within [t0, t1]. Camera rays take
  // the weight learned with the phase toward the camera origin; any other ray (leaving a surface or a
  // scattering vertex, whose direction the probes could not know) takes the isotropic weight.
  void gatherKnots(const Ray& ray, float t0, float t1, bool cameraRay, std::vector<DistanceKnot>& knots) const;

 private:
  void buildLookup(const Vec3& latticeOrigin);
  std::vector<Probe> probes_;
  float radius_ = 0.0f, spacing_ = 0.0f;
  int placed_ = 0;
  double seconds_ = 0.0;
  CoarseGrid lookup_;                // world-space cells of `spacing_`
  std::vector<uint32_t> cellStart_;  // CSR: probes overlapping each cell
  std::vector<uint32_t> cellProbes_;
};

}  // namespace candela
