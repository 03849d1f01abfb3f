// Basic types shared by the whole renderer: vectors (glm), rays, RGB radiance, constants.
#pragma once

#include <glm/glm.hpp>

#include <cmath>
#include <cstdint>
#include <limits>

namespace candela {

using Vec3 = glm::vec3;
using Vec2 = glm::vec2;
using Mat4 = glm::mat4;
using Rgb = glm::vec3;  // scene-linear Rec.709 radiance or reflectance

constexpr float kPi = 3.14159265358979323846f;
constexpr float kInvPi = 1.0f / kPi;
constexpr float kInv4Pi = 1.0f / (4.0f * kPi);
constexpr float kInfinity = std::numeric_limits<float>::infinity();

struct Ray {
  Vec3 origin{0.0f};
  Vec3 direction{0.0f, 0.0f, 1.0f};  // unit length in world space
  Vec3 at(float t) const { return origin + t * direction; }
};

inline float luminance(const Rgb& c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; }
inline float maxComponent(const Rgb& c) { return glm::max(c.r, glm::max(c.g, c.b)); }
inline float average(const Rgb& c) { return (c.r + c.g + c.b) * (1.0f / 3.0f); }
inline bool isFinite(const Rgb& c) { return std::isfinite(c.r) && std::isfinite(c.g) && std::isfinite(c.b); }
inline bool isBlack(const Rgb& c) { return c.r == 0.0f && c.g == 0.0f && c.b == 0.0f; }
// Corner c (0-7; bit 0 picks x, bit 1 y, bit 2 z) of the box [lo, hi].
inline Vec3 boxCorner(const Vec3& lo, const Vec3& hi, int c) {
  return Vec3((c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z);
}

// Builds an orthonormal basis around a unit vector n (Duff et al. 2017).
inline void orthonormalBasis(const Vec3& n, Vec3& t, Vec3& b) {
  const float sign = std::copysign(1.0f, n.z);
  const float a = -1.0f / (sign + n.z);
  const float c = n.x * n.y * a;
  t = Vec3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
  b = Vec3(c, sign + n.y * n.y * a, -n.y);
}

inline Vec3 toWorld(const Vec3& local, const Vec3& n) {
  Vec3 t, b;
  orthonormalBasis(n, t, b);
  return local.x * t + local.y * b + local.z * n;
}

// Power heuristic (beta = 2) and balance heuristic for two-technique MIS.
inline float powerHeuristic(float pdfA, float pdfB) {
  const float a = pdfA * pdfA, b = pdfB * pdfB;
  return a + b > 0.0f ? a / (a + b) : 0.0f;
}

}  // namespace candela
