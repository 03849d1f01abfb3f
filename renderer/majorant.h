// Majorant grid and its 3D DDA (METHOD.md section 1). A coarse grid over a density grid's index
// space; each cell stores the largest voxel value any trilinear lookup inside the cell can touch
// (its footprint, padded by one voxel), so maxDensity bounds the density everywhere in the cell.
// The global majorant is the one-cell case. The DDA walks a ray through the cells and yields
// segments [t0, t1) with a constant majorant; the ray parameter t is shared with world space.
#pragma once

#include "settings.h"
#include "voxel_grid.h"

#include <vector>

namespace candela {

class MajorantGrid {
 public:
  MajorantGrid() = default;
  // Builds over the density grid's active box, one cell per `cellSize` voxels (structure Grid) or a
  // single cell (Global).
  MajorantGrid(const VoxelGrid& density, MajorantStructure structure, int cellSize);

  bool empty() const { return cells_.empty(); }
  const glm::ivec3& resolution() const { return res_; }
  const Vec3& origin() const { return origin_; }      // index-space lower corner of the domain
  const Vec3& cellExtent() const { return cell_; }    // index-space size of one cell
  Vec3 domainMax() const { return origin_ + cell_ * Vec3(res_); }
  int cellIndex(int x, int y, int z) const { return (z * res_.y + y) * res_.x + x; }
  float maxDensity(int index) const { return cells_[static_cast<size_t>(index)]; }
  const std::vector<float>& maxDensities() const { return cells_; }
  size_t cellCount() const { return cells_.size(); }

 private:
  Vec3 origin_{0.0f};
  Vec3 cell_{1.0f};
  glm::ivec3 res_{0};
  std::vector<float> cells_;
};

// Walks the cells a ray crosses, in order (Amanatides and Woo 1987). The ray is given in the
// grid's index space (origin o, unnormalised direction d); t is the same parameter as in world space.
class MajorantDda {
 public:
  MajorantDda() = default;
  MajorantDda(const MajorantGrid& grid, const Vec3& o, const Vec3& d, float tMin, float tMax);
  // Next segment with t0 < t1; false when the ray has left the domain or passed tMax.
  bool next(float& t0, float& t1, int& cell);

 private:
  glm::ivec3 cellPos_{0}, step_{0}, res_{0};
  Vec3 tNext_{0.0f}, tDelta_{0.0f};
  float t_ = 0.0f, tEnd_ = -1.0f;
};

}  // namespace candela
