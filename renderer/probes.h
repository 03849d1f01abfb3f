// Probe spheres for scattering distance sampling (talk s.2.2; docs/method.md s.4). Probes sit on a
// regular lattice over the non-empty part of the media (lattice points near which some medium can
// scatter), each with a radius of influence. The talk's scattering sample weight of a probe is
//     s(wo) = E[ mu_s(y) * rho(wo, w_light) * L_light * T(y, light) / p_light ]
// over y uniform in the sphere and every light (emissive volumes included), wo toward the camera
// origin, T by ratio tracking. The phase is the only factor that depends on wo, and it is smooth
// in y where mu_s L T is not (shadow edges, thin shafts), so each probe learns per light
//     u_l = E[ mu_s(y) * L_l * T(y, l) / p_l ]
// and the phase is applied when a ray gathers the probe: s(wo) = sum_l u_l rho(wo, w_l(x)) with
// w_l(x) the light's direction at the ray point x beside the probe. On a camera ray wo = -ray
// direction points exactly to the camera origin at every x, so s is the talk's weight with the
// phase evaluated where the ray is, not at the probe centre (the two differ near the camera, where
// the direction to it swings across a sphere by more than a g = 0.85 lobe is wide). Rays leaving a
// surface or a scattering vertex get the phase of their own direction the same way, and the
// weights do not depend on the camera: moving it needs no relearning.
#pragma once

#include "distance_sampler.h"
#include "majorant.h"
#include "rng.h"
#include "settings.h"

#include <atomic>
#include <memory>
#include <string>
#include <vector>

namespace candela {

class Scene;

struct Probe {
  Vec3 center{0.0f};
  float g = 0.0f;  // HG asymmetry of the media scattering in the sphere (their mu_s-weighted mean)
};

// Where a light's contribution at a probe comes from, for the phase applied at lookup.
struct ProbeLight {
  enum class Kind {
    Direction,  // directional light: `v` is the unit direction toward it
    Position,   // point, spot and sphere lights, emissive volumes (their emission centroid): `v`
    Diffuse,    // environment: light from all around, taken as isotropic (phase 1 / 4 pi)
  } kind = Kind::Diffuse;
  Vec3 v{0.0f};
};

// A point uniform in the ball of radius `radius` around `center`: the domain a probe learns over.
Vec3 uniformInBall(const Vec3& center, float radius, Rng& rng);

class ProbeSet {
 public:
  // Places and learns probes for the scene as it is now, probe_samples light samples per probe
  // (deterministic for a seed). Stops only at the settings' safety cap on time or when `cancel`
  // becomes true; probes not reached are then dropped and complete() is false.
  static std::shared_ptr<const ProbeSet> learn(const Scene& scene, const GuidingSettings& settings,
                                               const std::atomic<bool>* cancel = nullptr);

  const std::vector<Probe>& probes() const { return probes_; }
  const std::vector<ProbeLight>& lights() const { return lights_; }
  // Learned weight u_l of light l (the scene's lights, then its emissive volumes) at a probe.
  float lightWeight(size_t probe, size_t light) const { return weights_[probe * lights_.size() + light]; }
  // The scattering sample weight s(wo) of a probe for a ray point x beside it (see above).
  float weight(size_t probe, const Vec3& wo, const Vec3& x) const;
  float radius() const { return radius_; }
  float spacing() const { return spacing_; }
  int placed() const { return placed_; }          // lattice points kept before learning
  double learnSeconds() const { return seconds_; }
  bool complete() const { return static_cast<int>(probes_.size()) == placed_; }
  // The warning to show when learning was cut by the time cap (empty when complete).
  std::string incompleteWarning() const;

  // Appends a knot for each probe whose sphere the ray crosses within [t0, t1]: at the probe's
  // projection t on the ray, with value s(-ray direction) at ray.at(t).
  void gatherKnots(const Ray& ray, float t0, float t1, std::vector<DistanceKnot>& knots) const;

 private:
  void buildLookup(const Vec3& latticeOrigin);
  std::vector<Probe> probes_;
  std::vector<ProbeLight> lights_;
  std::vector<float> weights_;  // probes x lights, u_l of each probe
  float radius_ = 0.0f, spacing_ = 0.0f;
  int placed_ = 0;
  double seconds_ = 0.0;
  CoarseGrid lookup_;                // world-space cells of `spacing_`
  std::vector<uint32_t> cellStart_;  // CSR: probes overlapping each cell
  std::vector<uint32_t> cellProbes_;
};

}  // namespace candela
