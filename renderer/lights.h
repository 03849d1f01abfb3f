// Lights: point, spot, directional, sphere area light and constant environment, and the light
// selection distribution (in proportion to an estimate of each light's fluence at the shading point).
#pragma once

#include "scene_desc.h"

#include <vector>

namespace candela {

struct LightSample {
  Vec3 wi{0.0f};        // unit direction from the shading point toward the light
  float distance = 0.0f;  // to the light point (infinity for directional and environment)
  Rgb radiance{0.0f};   // arriving radiance (delta lights: the irradiance-like term, no cosine)
  float pdf = 0.0f;     // solid-angle pdf; 1 for delta lights
  bool delta = false;
};

// How bright a light looks from a point, roughly: its unoccluded fluence (incident radiance integrated
// over the sphere, in luminance). Finite lights: intensity / (d^2 + spread2), d the distance to
// `position` (spread2, the light's squared size, keeps it finite at and inside the light); lights at
// infinity: a constant. Occlusion and media are ignored: it only steers the light selection.
struct LightImportance {
  float intensity = 0.0f;  // finite lights: fluence times squared distance, far away
  Vec3 position{0.0f};
  float spread2 = 0.0f;
  float fluence = 0.0f;    // lights at infinity
  bool atInfinity = false;

  float at(const Vec3& p) const;
};

class Light {
 public:
  explicit Light(const LightDesc& desc);
  const LightDesc& desc() const { return desc_; }
  LightType type() const { return desc_.type; }
  bool isDelta() const { return desc_.type == LightType::Point || desc_.type == LightType::Spot || desc_.type == LightType::Directional; }
  // A light with a position that equi-angular sampling can aim at (point, spot, sphere).
  bool hasPosition() const { return desc_.type == LightType::Point || desc_.type == LightType::Spot || desc_.type == LightType::Sphere; }
  // Samples a direction from `p` toward the light; false when it contributes nothing.
  bool sample(const Vec3& p, Vec2 u, LightSample& out) const;
  // Solid-angle pdf of sample() producing direction wi from p (0 for delta lights).
  float pdf(const Vec3& p, const Vec3& wi) const;
  // Radiance seen along a ray that hits this light (sphere) or escapes (environment).
  Rgb emitted() const { return radiance_; }
  // Ray-sphere hit distance, or infinity (sphere lights only).
  float intersect(const Ray& ray, float tMax) const;
  // Power estimate (equi-angular target weights, input checks); `sceneRadius` sizes directional and
  // environment lights.
  float power(float sceneRadius) const;
  // Its entry in the light selection (LightImportance).
  LightImportance importance() const;

 private:
  LightDesc desc_;
  Rgb radiance_{0.0f};  // color * intensity
  Vec3 direction_{0.0f, -1.0f, 0.0f};
  float cosOuter_ = 0.0f, cosInner_ = 1.0f;
};

// Picks a light for next-event estimation with a probability that depends on the shading point: in
// proportion to each light's estimated fluence there (LightImportance), mixed with a uniform share
// (kDefensiveShare) so that a light the estimate underrates (an occluded key light, a sky seen
// through a window) is still sampled. A global, power-based choice spends most samples on whatever
// is largest (a faint sky around a whole scene outweighed a torch flame 6 to 1, and a sun a campfire
// 240 to 1), however far it is from the point. Entries are the scene's lights followed by its
// emissive volumes (when they are sampled as lights). The pmf is a function of the point only, so
// the MIS weights that use it (phase-sampled rays meeting a light) stay exact (docs/method.md s.3).
class LightSampler {
 public:
  // 0.2 measured 4-11% less efficient than 0.1 on god-rays and shed-fire (a sky or a campfire taking
  // samples from the sun) and no better on torch-in-mist.
  static constexpr float kDefensiveShare = 0.1f;

  LightSampler() = default;
  explicit LightSampler(std::vector<LightImportance> lights);
  bool empty() const { return lit_ == 0; }
  int size() const { return static_cast<int>(lights_.size()); }
  // Draws a light for point p; `pmf` receives its probability. -1 when the sampler is empty.
  int sample(const Vec3& p, float u, float& pmf) const;
  // The probability that sample(p, ...) picks `index`: 0 for a dark light or an empty sampler.
  float pmf(const Vec3& p, int index) const;

 private:
  // The sum of the lit lights' estimates at p, and a light's probability given its estimate and that sum.
  float totalWeight(const Vec3& p) const;
  float share(float weight, float total) const;
  std::vector<LightImportance> lights_;
  std::vector<bool> dark_;
  int lit_ = 0;
};

}  // namespace candela
