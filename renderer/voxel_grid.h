// A read-only float grid for the hot loop: a NanoVDB grid (compact, cache-friendly, no OpenVDB
// headers needed) plus the index-to-world transform. Sampling is trilinear in index space with voxel
// centres at integer coordinates, the same everywhere (rendering, majorants, tests): docs/method.md s.0.
#pragma once

#include "core.h"

#include <nanovdb/NanoVDB.h>
#include <nanovdb/util/GridHandle.h>
#include <nanovdb/util/HostBuffer.h>

#include <glm/gtc/matrix_transform.hpp>

#include <memory>
#include <string>

namespace candela {

struct IndexBox {
  glm::ivec3 min{0};
  glm::ivec3 max{-1};  // inclusive; empty when any max < min
  bool empty() const { return max.x < min.x || max.y < min.y || max.z < min.z; }
};

class VoxelGrid {
 public:
  VoxelGrid() = default;
  VoxelGrid(nanovdb::GridHandle<nanovdb::HostBuffer> handle, const Mat4& worldFromIndex, std::string name);

  bool valid() const { return grid_ != nullptr; }
  const std::string& name() const { return name_; }
  const Mat4& worldFromIndex() const { return worldFromIndex_; }
  // Bounding box of the active voxels, in index space.
  IndexBox activeBox() const { return activeBox_; }
  size_t memoryBytes() const { return handle_ ? handle_->size() : 0; }
  // Largest active value (NanoVDB's root statistics, computed when the grid was converted).
  float maxValue() const { return grid_ ? grid_->tree().root().maximum() : 0.0f; }

  // A per-thread view with an accessor cache. Cheap to create: make one per ray walk.
  class Sampler {
   public:
    explicit Sampler(const nanovdb::FloatGrid* grid) : acc_(grid->getAccessor()) {}
    float voxel(int i, int j, int k) const { return acc_.getValue(nanovdb::Coord(i, j, k)); }
    float trilinear(const Vec3& p) const {
      const Vec3 f0 = glm::floor(p);
      const glm::ivec3 i0(f0);
      const Vec3 w = p - f0;
      float v000, v100, v010, v110, v001, v101, v011, v111;
      if ((i0.x & 7) != 7 && (i0.y & 7) != 7 && (i0.z & 7) != 7) {
        // All eight voxels lie in one 8^3 leaf (about 2/3 of lookups): read them from the leaf's
        // array directly instead of through eight accessor calls. No leaf there means a tile or the
        // background: one constant value, and its trilinear interpolation is that value.
        const nanovdb::Coord c(i0.x, i0.y, i0.z);
        const auto* leaf = acc_.probeLeaf(c);
        if (!leaf) return acc_.getValue(c);
        const uint32_t o = nanovdb::NanoLeaf<float>::CoordToOffset(c);  // x-major: +64 x, +8 y, +1 z
        v000 = leaf->getValue(o), v001 = leaf->getValue(o + 1), v010 = leaf->getValue(o + 8), v011 = leaf->getValue(o + 9);
        v100 = leaf->getValue(o + 64), v101 = leaf->getValue(o + 65), v110 = leaf->getValue(o + 72), v111 = leaf->getValue(o + 73);
      } else {
        v000 = voxel(i0.x, i0.y, i0.z), v100 = voxel(i0.x + 1, i0.y, i0.z);
        v010 = voxel(i0.x, i0.y + 1, i0.z), v110 = voxel(i0.x + 1, i0.y + 1, i0.z);
        v001 = voxel(i0.x, i0.y, i0.z + 1), v101 = voxel(i0.x + 1, i0.y, i0.z + 1);
        v011 = voxel(i0.x, i0.y + 1, i0.z + 1), v111 = voxel(i0.x + 1, i0.y + 1, i0.z + 1);
      }
      const float x00 = v000 + w.x * (v100 - v000), x10 = v010 + w.x * (v110 - v010);
      const float x01 = v001 + w.x * (v101 - v001), x11 = v011 + w.x * (v111 - v011);
      const float y0 = x00 + w.y * (x10 - x00), y1 = x01 + w.y * (x11 - x01);
      return y0 + w.z * (y1 - y0);
    }

   private:
    nanovdb::FloatGrid::AccessorType acc_;
  };
  Sampler sampler() const { return Sampler(grid_); }

 private:
  std::shared_ptr<nanovdb::GridHandle<nanovdb::HostBuffer>> handle_;
  const nanovdb::FloatGrid* grid_ = nullptr;
  Mat4 worldFromIndex_{1.0f};
  IndexBox activeBox_;
  std::string name_;
};

}  // namespace candela
