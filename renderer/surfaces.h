// Diffuse surfaces (ground plane, boxes, spheres, cylinders) traced with Embree 3.
#pragma once

#include "scene_desc.h"

#include <memory>
#include <vector>

namespace candela {

struct SurfaceHit {
  float t = kInfinity;
  Vec3 normal{0.0f, 1.0f, 0.0f};  // unit, geometric (analytic for spheres and cylinder sides)
  Rgb albedo{0.0f};
  bool hit() const { return std::isfinite(t); }
};

class Surfaces {
 public:
  explicit Surfaces(const std::vector<SurfaceDesc>& surfaces);
  ~Surfaces();
  Surfaces(const Surfaces&) = delete;
  Surfaces& operator=(const Surfaces&) = delete;

  bool empty() const { return descs_.empty(); }
  SurfaceHit intersect(const Ray& ray, float tMax) const;
  bool occluded(const Ray& ray, float tMax) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::vector<SurfaceDesc> descs_;
};

}  // namespace candela
