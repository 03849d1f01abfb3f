#include "voxel_grid.h"

#include <stdexcept>

namespace candela {

VoxelGrid::VoxelGrid(nanovdb::GridHandle<nanovdb::HostBuffer> handle, const Mat4& worldFromIndex, std::string name)
    : handle_(std::make_shared<nanovdb::GridHandle<nanovdb::HostBuffer>>(std::move(handle))),
      worldFromIndex_(worldFromIndex),
      name_(std::move(name)) {
  grid_ = handle_->grid<float>();
  if (!grid_) throw std::runtime_error("internal: NanoVDB handle holds no float grid");
  const auto bbox = grid_->indexBBox();
  if (!grid_->tree().isEmpty() && !bbox.empty()) {
    activeBox_.min = glm::ivec3(bbox.min()[0], bbox.min()[1], bbox.min()[2]);
    activeBox_.max = glm::ivec3(bbox.max()[0], bbox.max()[1], bbox.max()[2]);
  }
}

}  // namespace candela
