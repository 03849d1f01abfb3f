// An emissive volume as a light source (talk s.2.1, Algorithm 2; docs/method.md s.3). A coarse
// emission-energy-distribution grid over the medium stores, per cell, the integral of
// mu_a * lum(Le) over the cell; a discrete CDF picks a cell, a uniform point y inside it gives the
// direction w = normalize(y - x). The solid-angle pdf of w is
//     p(w) = sum over cells v crossed by the ray (x, w) of P(v) / volume(v) * (t1^3 - t0^3) / 3,
// the volume density converted to solid angle (Jacobian t^2) and integrated along the ray.
#pragma once

#include "lights.h"
#include "majorant.h"

#include <vector>

namespace candela {

class Medium;

class EmissionLight {
 public:
  // Builds the grid with cells of `cellSize` voxels. Empty when the medium emits nothing.
  EmissionLight(const Medium& medium, int cellSize);

  bool empty() const { return cdf_.empty(); }
  const Medium& medium() const { return *medium_; }
  // Radiant power estimate (luminance): 4 pi times the integral of mu_a lum(Le) over the volume.
  float power() const { return power_; }
  const CoarseGrid& layout() const { return layout_; }
  int cellSize() const { return cellSize_; }
  // Energy-weighted centre of the emission (world), the equi-angular target for this volume.
  const Vec3& centroid() const { return centroid_; }
  // Its entry in the light selection: a source of its power at the centroid, as large as its spread.
  LightImportance importance() const;

  // Samples a direction from world point x toward the emission; returns false if it cannot.
  bool sample(const Vec3& x, float u0, float u1, float u2, float u3, Vec3& wi) const;
  // Solid-angle pdf of sample() producing the unit world direction w from x (Algorithm 2).
  float pdf(const Vec3& x, const Vec3& w) const;
  // Probability of a cell and its world volume (for tests).
  float cellProbability(int cell) const { return cellPdf_[static_cast<size_t>(cell)]; }
  float cellVolume() const { return cellVolume_; }

 private:
  const Medium* medium_;
  int cellSize_;
  CoarseGrid layout_;
  std::vector<float> cellPdf_;   // P(v)
  std::vector<int> cellOf_;      // non-empty cells, in CDF order
  std::vector<float> cdf_;
  float cellVolume_ = 0.0f;      // world volume of one cell (the transform is affine)
  float power_ = 0.0f;
  Vec3 centroid_{0.0f};
  float spread2_ = 0.0f;  // energy-weighted mean squared distance from the centroid (world units^2)
};

}  // namespace candela
