#include "lights.h"

#include <algorithm>

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

LightSampler::LightSampler(const std::vector<float>& powers) {
  if (powers.empty()) return;
  std::vector<float> power(powers.size());
  float total = 0.0f;
  for (size_t i = 0; i < powers.size(); ++i) total += power[i] = std::max(0.0f, std::isfinite(powers[i]) ? powers[i] : 0.0f);
  if (!(total > 0.0f)) return;
  pmf_.resize(powers.size());
  cdf_.resize(powers.size());
  float acc = 0.0f;
  for (size_t i = 0; i < powers.size(); ++i) {
    pmf_[i] = power[i] / total;
    acc += pmf_[i];
    cdf_[i] = acc;
  }
  cdf_.back() = 1.0f;
}

int LightSampler::sample(float u, float& pmf) const {
  const auto it = std::upper_bound(cdf_.begin(), cdf_.end(), u);
  int index = static_cast<int>(std::min<std::ptrdiff_t>(it - cdf_.begin(), static_cast<std::ptrdiff_t>(cdf_.size()) - 1));
  pmf = pmf_[static_cast<size_t>(index)];
  return index;
}

}  // namespace candela
