#include "majorant.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace candela {

CoarseGrid CoarseGrid::over(const VoxelGrid& density, int cellSize) {
  CoarseGrid g;
  const IndexBox box = density.activeBox();
  if (box.empty()) return g;
  // Trilinear lookups are non-zero strictly inside (min - 1, max + 1): that is the domain.
  g.origin = Vec3(box.min) - 1.0f;
  const Vec3 extent = Vec3(box.max - box.min) + 2.0f;
  if (cellSize <= 0) {
    g.res = glm::ivec3(1);
    g.cellExtent = extent;
  } else {
    const float c = static_cast<float>(cellSize);
    g.res = glm::max(glm::ivec3(glm::ceil(extent / c)), glm::ivec3(1));
    g.cellExtent = Vec3(c);
  }
  return g;
}

MajorantGrid::MajorantGrid(const VoxelGrid& density, MajorantStructure structure, int cellSize) {
  layout_ = CoarseGrid::over(density, structure == MajorantStructure::Global ? 0 : std::max(1, cellSize));
  if (layout_.empty()) return;
  cells_ = footprintMaxima(layout_, density.activeBox(), [&density] {
    return [sampler = density.sampler()](int x, int y, int z) { return sampler.voxel(x, y, z); };
  });
}

std::vector<float> footprintMaxima(const CoarseGrid& layout, const IndexBox& box, const VoxelValueFactory& values) {
  std::vector<float> cells(layout.cellCount(), 0.0f);
  if (cells.empty() || box.empty()) return cells;
  // A lookup at p in a cell reads voxels floor(p) and floor(p) + 1, so a cell [lo, hi] needs voxels
  // lo .. hi + 1; we pad one more on each side. Each voxel updates every cell whose padded range
  // holds it. Slabs along z run in parallel; each writes a private copy, merged after.
  const glm::ivec3 vMin = box.min - 2, vMax = box.max + 2;
  const int slabs = std::max(1, std::min(16, vMax.z - vMin.z + 1));
  std::vector<std::vector<float>> partial(static_cast<size_t>(slabs), std::vector<float>(cells.size(), 0.0f));
  auto cellRange = [&](int v, int axis, int& k0, int& k1) {
    const float rel = static_cast<float>(v) - layout.origin[axis];
    const float c = layout.cellExtent[axis];
    k0 = std::max(0, static_cast<int>(std::ceil((rel - 2.0f) / c)) - 1);
    k1 = std::min(layout.res[axis] - 1, static_cast<int>(std::floor((rel + 1.0f) / c)));
    // Keep only cells whose padded voxel range [lo - 1, hi + 2] really contains v.
    while (k0 <= k1 && layout.origin[axis] + (k0 + 1) * c + 2.0f < static_cast<float>(v)) ++k0;
  };
  tbb::parallel_for(0, slabs, [&](int s) {
    const auto value = values();
    std::vector<float>& out = partial[static_cast<size_t>(s)];
    const int depth = vMax.z - vMin.z + 1;
    const int z0 = vMin.z + depth * s / slabs, z1 = vMin.z + depth * (s + 1) / slabs;
    for (int z = z0; z < z1; ++z) {
      int kz0, kz1;
      cellRange(z, 2, kz0, kz1);
      for (int y = vMin.y; y <= vMax.y; ++y) {
        int ky0, ky1;
        cellRange(y, 1, ky0, ky1);
        for (int x = vMin.x; x <= vMax.x; ++x) {
          const float v = value(x, y, z);
          if (!(v > 0.0f)) continue;
          int kx0, kx1;
          cellRange(x, 0, kx0, kx1);
          for (int kz = kz0; kz <= kz1; ++kz)
            for (int ky = ky0; ky <= ky1; ++ky)
              for (int kx = kx0; kx <= kx1; ++kx) {
                float& m = out[static_cast<size_t>(layout.cellIndex(kx, ky, kz))];
                m = std::max(m, v);
              }
        }
      }
    }
  });
  for (const auto& p : partial)
    for (size_t i = 0; i < cells.size(); ++i) cells[i] = std::max(cells[i], p[i]);
  return cells;
}

MajorantGrid MajorantGrid::coarsened(int factor) const {
  if (empty() || factor <= 1) return *this;
  MajorantGrid out;
  out.layout_ = layout_;
  const glm::ivec3 fine = layout_.res, coarse = (fine + factor - 1) / factor;
  out.layout_.res = coarse;
  // The same domain, so walks reach no further: res / ceil(res / factor) fine cells per coarse cell
  // along each axis (factor of them when it divides res).
  out.layout_.cellExtent = layout_.cellExtent * Vec3(fine) / Vec3(coarse);
  // Coarse cell k spans fine cells k res / res' .. ceil((k + 1) res / res') - 1 (integers: no rounding).
  auto span = [&](int axis, int k, int& lo, int& hi) {
    lo = k * fine[axis] / coarse[axis];
    hi = std::min(fine[axis] - 1, ((k + 1) * fine[axis] + coarse[axis] - 1) / coarse[axis] - 1);
  };
  out.cells_.assign(out.layout_.cellCount(), 0.0f);
  for (int kz = 0; kz < coarse.z; ++kz)
    for (int ky = 0; ky < coarse.y; ++ky)
      for (int kx = 0; kx < coarse.x; ++kx) {
        int x0, x1, y0, y1, z0, z1;
        span(0, kx, x0, x1), span(1, ky, y0, y1), span(2, kz, z0, z1);
        float m = 0.0f;
        for (int z = z0; z <= z1; ++z)
          for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x) m = std::max(m, cells_[static_cast<size_t>(layout_.cellIndex(x, y, z))]);
        out.cells_[static_cast<size_t>(out.layout_.cellIndex(kx, ky, kz))] = m;
      }
  return out;
}

MajorantDda::MajorantDda(const CoarseGrid& grid, const Vec3& o, const Vec3& d, float tMin, float tMax) {
  if (grid.empty()) return;
  res_ = grid.res;
  // Work in cell coordinates: c = (p - origin) / cellExtent.
  const Vec3 co = (o - grid.origin) / grid.cellExtent;
  const Vec3 cd = d / grid.cellExtent;
  float t0 = tMin, t1 = tMax;
  for (int a = 0; a < 3; ++a) {
    if (cd[a] == 0.0f) {
      if (co[a] < 0.0f || co[a] > static_cast<float>(res_[a])) return;
      continue;
    }
    float ta = (0.0f - co[a]) / cd[a];
    float tb = (static_cast<float>(res_[a]) - co[a]) / cd[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (!(t0 < t1)) return;
  t_ = t0;
  tEnd_ = t1;
  const Vec3 p = co + t0 * cd;
  for (int a = 0; a < 3; ++a) {
    cellPos_[a] = std::clamp(static_cast<int>(std::floor(p[a])), 0, res_[a] - 1);
    if (cd[a] > 0.0f) {
      step_[a] = 1;
      tNext_[a] = t0 + (static_cast<float>(cellPos_[a] + 1) - p[a]) / cd[a];
      tDelta_[a] = 1.0f / cd[a];
    } else if (cd[a] < 0.0f) {
      step_[a] = -1;
      tNext_[a] = t0 + (static_cast<float>(cellPos_[a]) - p[a]) / cd[a];
      tDelta_[a] = -1.0f / cd[a];
    } else {
      step_[a] = 0;
      tNext_[a] = kInfinity;
      tDelta_[a] = kInfinity;
    }
  }
}

bool MajorantDda::next(float& t0, float& t1, int& cell) {
  while (t_ < tEnd_) {
    const int axis = tNext_.x < tNext_.y ? (tNext_.x < tNext_.z ? 0 : 2) : (tNext_.y < tNext_.z ? 1 : 2);
    const float exit = std::min(tNext_[axis], tEnd_);
    const glm::ivec3 current = cellPos_;
    const float enter = t_;
    t_ = exit;
    cellPos_[axis] += step_[axis];
    tNext_[axis] += tDelta_[axis];
    if (cellPos_[axis] < 0 || cellPos_[axis] >= res_[axis]) tEnd_ = std::min(tEnd_, exit);
    if (exit > enter) {
      t0 = enter;
      t1 = exit;
      cell = (current.z * res_.y + current.y) * res_.x + current.x;
      return true;
    }
  }
  return false;
}

}  // namespace candela
