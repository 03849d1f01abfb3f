// Henyey-Greenstein phase function. Convention: wo points away from the scattering point toward
// where the light goes (the previous vertex), wi toward where it comes from; cos = dot(wo, wi), so
// g > 0 (forward scattering) peaks at wi = -wo.
#pragma once

#include "core.h"

namespace candela {

inline float hgPhase(float cosTheta, float g) {
  const float denom = 1.0f + g * g + 2.0f * g * cosTheta;
  return kInv4Pi * (1.0f - g * g) / (denom * std::sqrt(std::max(denom, 1e-12f)));
}

// Phase value for a pair of directions in the convention above.
inline float hgEval(const Vec3& wo, const Vec3& wi, float g) { return hgPhase(glm::dot(wo, wi), g); }

// Samples wi with density hgEval(wo, wi, g); returns the pdf (equal to the phase value).
inline Vec3 hgSample(const Vec3& wo, float g, Vec2 u, float& pdf) {
  float cosTheta;
  if (std::abs(g) < 1e-3f) {
    cosTheta = 1.0f - 2.0f * u.x;
  } else {
    const float sq = (1.0f - g * g) / (1.0f + g - 2.0f * g * u.x);
    cosTheta = -(1.0f + g * g - sq * sq) / (2.0f * g);
  }
  cosTheta = glm::clamp(cosTheta, -1.0f, 1.0f);
  const float sinTheta = std::sqrt(std::max(0.0f, 1.0f - cosTheta * cosTheta));
  const float phi = 2.0f * kPi * u.y;
  // cosTheta is measured from wo in hgPhase's convention, so build around wo.
  const Vec3 wi = toWorld(Vec3(sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta), wo);
  pdf = hgPhase(cosTheta, g);
  return wi;
}

}  // namespace candela
