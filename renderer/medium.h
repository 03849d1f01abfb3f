// One heterogeneous medium: its grids (compact NanoVDB form), its parameters and its majorant grid.
// Coefficients (docs/method.md s.0): mu_t(x) = density(x) * sigma_t_scale (grey), mu_s = albedo * mu_t,
// mu_a = (1 - albedo) * mu_t, HG phase with g, source term mu_a * Le (or E per unit length).
#pragma once

#include "blackbody.h"
#include "emission_light.h"
#include "majorant.h"
#include "scene_desc.h"
#include "voxel_grid.h"

#include <memory>
#include <optional>
#include <string>

namespace candela {

class Medium {
 public:
  // `temperature` / `emission` may be invalid grids when the emission mode does not use them.
  Medium(const VolumeDesc& desc, VoxelGrid density, VoxelGrid temperature, VoxelGrid emission);

  // Per-voxel emission colour (color_grid: Cd's x, y, z), multiplying grid emission. Call before
  // applyStrategy builds anything from the emission (Scene::build does).
  void setColorGrids(VoxelGrid r, VoxelGrid g, VoxelGrid b);
  const VolumeDesc& desc() const { return desc_; }
  const std::string& name() const { return desc_.name; }
  const VoxelGrid& densityGrid() const { return density_; }
  const MajorantGrid& majorantGrid() const { return majorant_; }
  // The majorant cells are this many times strategy.majorant.cell_size (majorant.coarsen_thin).
  int majorantCoarsening() const { return coarsening_; }
  // The majorant at the asked-for cell size, coarsened or not: where the medium may be non-zero, as
  // finely as the strategy asks (probe placement).
  const MajorantGrid& occupancyGrid() const { return occupancy_.empty() ? majorant_ : occupancy_; }
  const Mat4& indexFromWorld() const { return indexFromWorld_; }
  const Mat4& worldFromIndex() const { return worldFromIndex_; }
  bool emissive() const { return emissive_; }
  // Emission per unit length (EmissionUnits::PerLength): emits where nothing absorbs, so the
  // majorant keeps collisions there and the analog estimator gathers it at every collision.
  bool emitsPerLength() const { return emissive_ && perLength_; }
  float sigmaTScale() const { return desc_.sigma_t_scale; }
  const Rgb& albedo() const { return albedo_; }
  float albedoAverage() const { return albedoAverage_; }
  float g() const { return desc_.g; }
  // World-space bounds of the majorant domain (for framing and light sizes).
  void worldBounds(Vec3& lo, Vec3& hi) const;

  // Applies the strategy, rebuilding only what depends on what changed: the majorant grid (its
  // structure or cell size), the emission maxima (the majorant layout), the emission light (its
  // grid cell size, or light sampling turned on); the per-cell mu_bar is recomputed always (cheap).
  void applyStrategy(const StrategySettings& strategy);
  // The combined majorant mu_bar of a cell of the majorant grid (world units).
  float cellMajorant(int cell) const { return cellMajorant_[static_cast<size_t>(cell)]; }
  // The majorant of mu_t alone (no emission term): light rays, which need only the transmittance
  // there (tracking.h), walk it.
  float transmittanceCellMajorant(int cell) const { return transmittanceMajorant_[static_cast<size_t>(cell)]; }
  // Per majorant cell, the maximum of lum(source) over its footprint, when built (an emission term in
  // the strategy's majorant, or emission per unit length); empty otherwise.
  const std::vector<float>& emissionMaxima() const { return emissionMaxima_; }
  // A small positive weight for every cell the medium may be in (emissionAlongRay): the maxima are
  // of the source at voxel centres, and sigma_t x Le of two trilinear fields can exceed them between
  // voxels (a dense voxel with no emission beside an emitting one with no density).
  float emissionFloor() const { return emissionFloor_; }
  // The combined majorant mu_bar at an index-space point (0 outside the majorant domain).
  float majorantAt(const Vec3& indexPos) const {
    if (majorant_.empty()) return 0.0f;
    const Vec3 c = (indexPos - majorant_.origin()) / majorant_.cellExtent();
    const glm::ivec3& res = majorant_.resolution();
    if (!(c.x >= 0.0f && c.y >= 0.0f && c.z >= 0.0f && c.x < res.x && c.y < res.y && c.z < res.z)) return 0.0f;
    return cellMajorant_[static_cast<size_t>(majorant_.cellIndex(static_cast<int>(c.x), static_cast<int>(c.y), static_cast<int>(c.z)))];
  }
  // The radiance scale of the medium's emission: its mean Le over emitting cells weighted by mu_a,
  // times 1 - exp(-tau_a) across them (radiance units: what a ray through it gathers), or its mean E
  // times the voxel size (per unit length). The emission weight's unit when it is relative.
  float emissionRadianceScale() const { return radianceScale_; }
  // The absorption optical depth across the emitting cells that scales it (0 per unit length).
  float emissionOpticalDepth() const { return emissionDepth_; }
  // Geometric-mean voxel edge in world units (the emission cap's c / voxel_size).
  float voxelSize() const { return voxelSize_; }
  // The emissive volume as a light (null unless emissive and light sampling is on).
  const EmissionLight* emissionLight() const { return emissionLight_.get(); }
  // Position of this medium in the scene's list (for per-medium weights in the hot loop).
  int index() const { return index_; }
  void setIndex(int index) { index_ = index; }

  // Per-thread lookups with accessor caches. Positions are in this medium's density index space.
  class Sampler {
   public:
    explicit Sampler(const Medium& m);
    float sigmaT(const Vec3& indexPos) const { return density_.trilinear(indexPos) * medium_->desc_.sigma_t_scale; }
    // E at the point: the emission value (Le in radiance units, the source itself per_length).
    Rgb emission(const Vec3& indexPos) const;
    // The source term at the point (talk Eq. 1), given the medium's sigma_t there: mu_a Le in
    // radiance units, E whatever the density per_length (docs/conventions.md, "Emission").
    Rgb source(const Vec3& indexPos, float sigmaT) const {
      if (medium_->perLength_) return emission(indexPos);
      if (!(sigmaT > 0.0f)) return Rgb(0.0f);
      return (Rgb(1.0f) - medium_->albedo_) * sigmaT * emission(indexPos);
    }
    // Luminance of the source term at a voxel centre, for majorants and the emission light's cells
    // (radiance units use the average albedo, as the event probabilities do).
    float sourceLuminanceAtVoxel(int x, int y, int z) const;

   private:
    const Medium* medium_;
    VoxelGrid::Sampler density_;
    VoxelGrid::Sampler aux_;
    struct ColorSamplers {
      VoxelGrid::Sampler r, g, b;
    };
    std::optional<ColorSamplers> color_;  // only with a colour grid: other media pay nothing per ray
  };

 private:
  VolumeDesc desc_;
  VoxelGrid density_, aux_;  // aux: temperature (blackbody) or emission grid
  VoxelGrid colorR_, colorG_, colorB_;  // optional per-voxel emission colour (grid mode)
  Mat4 colorFromDensityIndex_{1.0f};
  Mat4 worldFromIndex_{1.0f}, indexFromWorld_{1.0f};
  Mat4 auxFromDensityIndex_{1.0f};
  bool auxSameIndex_ = true;
  bool emissive_ = false;
  bool perLength_ = false;
  Rgb albedo_{0.0f};
  float albedoAverage_ = 0.0f;
  MajorantGrid majorant_;
  MajorantGrid occupancy_;  // the uncoarsened grid, only when majorant_ is coarsened
  MajorantStructure builtStructure_ = MajorantStructure::Grid;
  int builtCellSize_ = -1;
  bool builtCoarsen_ = false;
  float builtSafetyFactor_ = 1.0f;
  int coarsening_ = 1;  // majorant cells are this many times strategy.majorant.cell_size
  std::vector<float> emissionMaxima_;  // per majorant cell: max of lum(source) over the footprint
  float radianceScale_ = 0.0f;
  float emissionDepth_ = 0.0f;  // tau_a across the emitting cells (radianceScale_)
  std::unique_ptr<EmissionLight> emissionLight_;
  std::vector<float> cellMajorant_;
  std::vector<float> transmittanceMajorant_;
  float emissionFloor_ = 1.0f;
  float voxelSize_ = 1.0f;
  int index_ = 0;
};

// The volume placement as a matrix: translate * rotateZ * rotateY * rotateX * scale.
Mat4 transformMatrix(const TransformDesc& t);

}  // namespace candela
