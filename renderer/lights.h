// Lights: point, spot, directional, sphere area light and constant environment, and the light
// selection distribution (proportional to an estimate of each light's power).
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

class Light {
 public:
  explicit Light(const LightDesc& desc);
  const LightDesc& desc() const { return desc_; }
  LightType type() const { return desc_.type; }
  bool isDelta() const { return desc_.type == LightType::Point || desc_.type == LightType::Spot || desc_.type == LightType::Directional; }
  // Samples a direction from `p` toward the light; false when it contributes nothing.
  bool sample(const Vec3& p, Vec2 u, LightSample& out) const;
  // Solid-angle pdf of sample() producing direction wi from p (0 for delta lights).
  float pdf(const Vec3& p, const Vec3& wi) const;
  // Radiance seen along a ray that hits this light (sphere) or escapes (environment).
  Rgb emitted() const { return radiance_; }
  // Ray-sphere hit distance, or infinity (sphere lights only).
  float intersect(const Ray& ray, float tMax) const;
  // Power estimate for light selection; `sceneRadius` sizes directional and environment lights.
  float power(float sceneRadius) const;

 private:
  LightDesc desc_;
  Rgb radiance_{0.0f};  // color * intensity
  Vec3 direction_{0.0f, -1.0f, 0.0f};
  float cosOuter_ = 0.0f, cosInner_ = 1.0f;
};

// Picks a light with probability proportional to its power (a discrete CDF). Entries are the
// scene's lights followed by its emissive volumes (when they are sampled as lights).
class LightSampler {
 public:
  LightSampler() = default;
  explicit LightSampler(const std::vector<float>& powers);
  bool empty() const { return cdf_.empty(); }
  int sample(float u, float& pmf) const;
  // 0 for a light the sampler never picks (every light dark: the sampler is empty).
  float pmf(int index) const { return static_cast<size_t>(index) < pmf_.size() ? pmf_[static_cast<size_t>(index)] : 0.0f; }

 private:
  std::vector<float> cdf_, pmf_;
};

}  // namespace candela
