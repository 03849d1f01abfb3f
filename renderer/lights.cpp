#include "lights.h"

#include <algorithm>
#include <cmath>

namespace candela {

Light::Light(const LightDesc& desc) : desc_(desc) {
  radiance_ = desc.color * desc.intensity;
  if (desc.type == LightType::Spot || desc.type == LightType::Directional) direction_ = glm::normalize(desc.direction);
  if (desc.type == LightType::Spot) {
    cosOuter_ = std::cos(glm::radians(desc.cone_angle_deg));
    cosInner_ = std::cos(glm::radians(desc.cone_angle_deg - desc.cone_falloff_deg));
  }
}

bool Light::sample(const Vec3& p, Vec2 u, LightSample& out) const {
  switch (desc_.type) {
    case LightType::Point:
    case LightType::Spot: {
      const Vec3 toLight = desc_.position - p;
      const float d2 = glm::dot(toLight, toLight);
      if (d2 <= 0.0f) return false;
      out.distance = std::sqrt(d2);
      out.wi = toLight / out.distance;
      out.radiance = radiance_ / d2;
      if (desc_.type == LightType::Spot) {
        const float cosAngle = glm::dot(-out.wi, direction_);
        if (cosAngle <= cosOuter_) return false;
        if (cosAngle < cosInner_) {
          const float t = (cosAngle - cosOuter_) / std::max(cosInner_ - cosOuter_, 1e-8f);
          out.radiance *= t * t * (3.0f - 2.0f * t);
        }
      }
      out.pdf = 1.0f;
      out.delta = true;
      return true;
    }
    case LightType::Directional:
      out.wi = -direction_;
      out.distance = kInfinity;
      out.radiance = radiance_;
      out.pdf = 1.0f;
      out.delta = true;
      return true;
    case LightType::Sphere: {
      const Vec3 toCenter = desc_.position - p;
      const float d2 = glm::dot(toCenter, toCenter);
      const float r2 = desc_.radius * desc_.radius;
      if (d2 <= r2 * 1.0001f) return false;  // inside the light: it is opaque, nothing to sample
      // Uniform sampling of the cone of directions the sphere subtends (pbrt's approach).
      const float dist = std::sqrt(d2);
      const Vec3 axis = toCenter / dist;
      const float cosMax = std::sqrt(std::max(0.0f, 1.0f - r2 / d2));
      const float cosTheta = 1.0f - u.x * (1.0f - cosMax);
      const float sinTheta = std::sqrt(std::max(0.0f, 1.0f - cosTheta * cosTheta));
      const float phi = 2.0f * kPi * u.y;
      out.wi = glm::normalize(toWorld(Vec3(sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta), axis));
      const float hit = intersect(Ray{p, out.wi}, kInfinity);
      out.distance = std::isfinite(hit) ? hit : dist;
      out.radiance = radiance_;
      out.pdf = 1.0f / (2.0f * kPi * (1.0f - cosMax));
      out.delta = false;
      return true;
    }
    case LightType::Environment: {
      const float z = 1.0f - 2.0f * u.x;
      const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
      const float phi = 2.0f * kPi * u.y;
      out.wi = Vec3(r * std::cos(phi), r * std::sin(phi), z);
      out.distance = kInfinity;
      out.radiance = radiance_;
      out.pdf = kInv4Pi;
      out.delta = false;
      return true;
    }
  }
  return false;
}

float Light::pdf(const Vec3& p, const Vec3& wi) const {
  if (desc_.type == LightType::Environment) return kInv4Pi;
  if (desc_.type != LightType::Sphere) return 0.0f;
  const Vec3 toCenter = desc_.position - p;
  const float d2 = glm::dot(toCenter, toCenter);
  const float r2 = desc_.radius * desc_.radius;
  if (d2 <= r2 * 1.0001f) return 0.0f;
  const float cosMax = std::sqrt(std::max(0.0f, 1.0f - r2 / d2));
  if (glm::dot(wi, toCenter) < cosMax * std::sqrt(d2)) return 0.0f;
  return 1.0f / (2.0f * kPi * (1.0f - cosMax));
}

float Light::intersect(const Ray& ray, float tMax) const {
  if (desc_.type != LightType::Sphere) return kInfinity;
  const Vec3 oc = ray.origin - desc_.position;
  const float b = glm::dot(oc, ray.direction);
  const float c = glm::dot(oc, oc) - desc_.radius * desc_.radius;
  const float disc = b * b - c;
  if (disc < 0.0f) return kInfinity;
  const float s = std::sqrt(disc);
  float t = -b - s;
  if (t <= 1e-5f) t = -b + s;
  return (t > 1e-5f && t < tMax) ? t : kInfinity;
}

float Light::power(float sceneRadius) const {
  const float lum = luminance(radiance_);
  switch (desc_.type) {
    case LightType::Point: return 4.0f * kPi * lum;
    case LightType::Spot: return 2.0f * kPi * (1.0f - 0.5f * (cosOuter_ + cosInner_)) * lum;
    case LightType::Directional: return kPi * sceneRadius * sceneRadius * lum;
    case LightType::Sphere: return 4.0f * kPi * kPi * desc_.radius * desc_.radius * lum;
    case LightType::Environment: return 4.0f * kPi * kPi * sceneRadius * sceneRadius * lum;
  }
  return 0.0f;
}

LightImportance Light::importance() const {
  LightImportance out;
  const float lum = std::max(0.0f, luminance(radiance_));
  out.position = desc_.position;
  switch (desc_.type) {
    case LightType::Point:
    case LightType::Spot: out.intensity = lum; break;  // radiance_ is the intensity: fluence I / d^2
    case LightType::Sphere:
      // Radiance L over a disc of radius r seen from d: fluence about pi r^2 L / d^2.
      out.intensity = kPi * desc_.radius * desc_.radius * lum;
      out.spread2 = desc_.radius * desc_.radius;
      break;
    case LightType::Directional:
      out.atInfinity = true;
      out.fluence = lum;  // radiance_ is the irradiance of the parallel beam
      break;
    case LightType::Environment:
      out.atInfinity = true;
      out.fluence = 4.0f * kPi * lum;
      break;
  }
  return out;
}

float LightImportance::at(const Vec3& p) const {
  if (atInfinity) return fluence;
  const Vec3 d = position - p;
  // The floor keeps a point light's own position finite; it is far below any shading distance.
  return intensity / std::max(glm::dot(d, d) + spread2, 1e-12f);
}

LightSampler::LightSampler(std::vector<LightImportance> lights) : lights_(std::move(lights)) {
  dark_.resize(lights_.size());
  for (size_t i = 0; i < lights_.size(); ++i) {
    const LightImportance& l = lights_[i];
    const float scale = l.atInfinity ? l.fluence : l.intensity;
    dark_[i] = !(scale > 0.0f) || !std::isfinite(scale) || !std::isfinite(l.spread2) || !std::isfinite(l.position.x) ||
               !std::isfinite(l.position.y) || !std::isfinite(l.position.z);
    lit_ += !dark_[i];
  }
}

float LightSampler::totalWeight(const Vec3& p) const {
  float total = 0.0f;
  for (size_t i = 0; i < lights_.size(); ++i)
    if (!dark_[i]) total += lights_[i].at(p);
  return total;
}

float LightSampler::share(float weight, float total) const {
  const float uniform = 1.0f / static_cast<float>(lit_);
  // A point so far that every weight underflows (or one that overflows) falls back to uniform.
  if (!(total > 0.0f) || !std::isfinite(total)) return uniform;
  return (1.0f - kDefensiveShare) * (weight / total) + kDefensiveShare * uniform;
}

float LightSampler::pmf(const Vec3& p, int index) const {
  if (lit_ == 0 || index < 0 || static_cast<size_t>(index) >= lights_.size() || dark_[static_cast<size_t>(index)]) return 0.0f;
  return share(lights_[static_cast<size_t>(index)].at(p), totalWeight(p));
}

int LightSampler::sample(const Vec3& p, float u, float& pmf) const {
  pmf = 0.0f;
  if (lit_ == 0) return -1;
  const float total = totalWeight(p);
  int last = -1;
  float acc = 0.0f;
  for (size_t i = 0; i < lights_.size(); ++i) {
    if (dark_[i]) continue;
    const float probability = share(lights_[i].at(p), total);
    last = static_cast<int>(i);
    acc += probability;
    if (u < acc) {
      pmf = probability;
      return last;
    }
  }
  // Rounding left u above the sum: the last lit light, with the probability pmf() reports.
  pmf = this->pmf(p, last);
  return last;
}

}  // namespace candela
