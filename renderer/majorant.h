// Majorant grid and its 3D DDA (docs/method.md s.1). A coarse grid over a density grid's index
// space; each cell stores the largest voxel value any trilinear lookup inside the cell can touch
// (its footprint, padded by one voxel), so maxDensity bounds the density everywhere in the cell.
// The global majorant is the one-cell case. The DDA walks a ray through the cells and yields
// segments [t0, t1) with a constant majorant; the ray parameter t is shared with world space.
#pragma once

#include "settings.h"
#include "voxel_grid.h"

#include <functional>
#include <vector>

namespace candela {

// The layout of a coarse grid over a density grid's index space: cells of `cellExtent` index units
// from `origin`. Shared by the majorant grid and the emission-energy grid, and walked by the DDA.
struct CoarseGrid {
  Vec3 origin{0.0f};
  Vec3 cellExtent{1.0f};
  glm::ivec3 res{0};
  bool empty() const { return res.x <= 0 || res.y <= 0 || res.z <= 0; }
  size_t cellCount() const { return empty() ? 0 : static_cast<size_t>(res.x) * res.y * res.z; }
  int cellIndex(int x, int y, int z) const { return (z * res.y + y) * res.x + x; }
  glm::ivec3 cellCoords(int index) const { return {index % res.x, (index / res.x) % res.y, index / (res.x * res.y)}; }
  Vec3 domainMax() const { return origin + cellExtent * Vec3(res); }
  // The layout covering a density grid's trilinear support (active box padded by one voxel) with
  // cells of `cellSize` voxels, or one cell when cellSize <= 0.
  static CoarseGrid over(const VoxelGrid& density, int cellSize);
};

// Per-voxel values for footprintMaxima(): the factory makes one callable per worker thread (each
// holding its own accessor caches).
using VoxelValueFactory = std::function<std::function<float(int, int, int)>()>;

// For every cell of `layout`, the largest voxel value any trilinear lookup inside the cell can read
// (its footprint padded by one voxel, docs/method.md s.1). Voxels outside `box` padded by 2 are skipped.
std::vector<float> footprintMaxima(const CoarseGrid& layout, const IndexBox& box, const VoxelValueFactory& values);

class MajorantGrid {
 public:
  MajorantGrid() = default;
  // Builds over the density grid's active box, one cell per `cellSize` voxels (structure Grid) or a
  // single cell (Global).
  MajorantGrid(const VoxelGrid& density, MajorantStructure structure, int cellSize);

  bool empty() const { return cells_.empty(); }
  const CoarseGrid& layout() const { return layout_; }
  const glm::ivec3& resolution() const { return layout_.res; }
  const Vec3& origin() const { return layout_.origin; }      // index-space lower corner of the domain
  const Vec3& cellExtent() const { return layout_.cellExtent; }  // index-space size of one cell
  Vec3 domainMax() const { return layout_.domainMax(); }
  int cellIndex(int x, int y, int z) const { return layout_.cellIndex(x, y, z); }
  float maxDensity(int index) const { return cells_[static_cast<size_t>(index)]; }
  const std::vector<float>& maxDensities() const { return cells_; }
  size_t cellCount() const { return cells_.size(); }
  // The same domain in ceil(res / factor) cells along each axis, each holding the largest of the
  // cells it overlaps: a majorant wherever this one is (where factor divides res, the very grid a
  // build with factor x the cell size gives).
  MajorantGrid coarsened(int factor) const;

 private:
  CoarseGrid layout_;
  std::vector<float> cells_;
};

// Walks the cells a ray crosses, in order (Amanatides and Woo 1987). The ray is given in the
// grid's index space (origin o, unnormalised direction d); t is the same parameter as in world space.
class MajorantDda {
 public:
  MajorantDda() = default;
  MajorantDda(const CoarseGrid& grid, const Vec3& o, const Vec3& d, float tMin, float tMax);
  MajorantDda(const MajorantGrid& grid, const Vec3& o, const Vec3& d, float tMin, float tMax)
      : MajorantDda(grid.layout(), o, d, tMin, tMax) {}
  // Next segment with t0 < t1; false when the ray has left the domain or passed tMax.
  bool next(float& t0, float& t1, int& cell);

 private:
  glm::ivec3 cellPos_{0}, step_{0}, res_{0};
  Vec3 tNext_{0.0f}, tDelta_{0.0f};
  float t_ = 0.0f, tEnd_ = -1.0f;
};

}  // namespace candela
