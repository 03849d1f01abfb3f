// OpenVDB -> NanoVDB loading. Heavy headers live here on purpose (see TOOLCHAIN.md build costs).
#include "vdb_io.h"

#include "fields.h"
#include "input_limits.h"

#include <openvdb/openvdb.h>
#include <nanovdb/util/OpenToNanoVDB.h>

#include <cmath>
#include <filesystem>
#include <mutex>

namespace candela {

namespace {

void initOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

Mat4 toGlm(const openvdb::math::Mat4d& m) {
  // OpenVDB multiplies row vectors (p' = p M, translation in row 3); glm uses column vectors with
  // translation in column 3, so element (i, j) maps to glm's m[i][j].
  Mat4 out;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) out[i][j] = static_cast<float>(m(i, j));
  return out;
}

}  // namespace

std::vector<LoadedGrid> loadVdbGrids(const std::string& path, const std::vector<std::string>& gridNames,
                                     const std::string& field) {
  initOpenVdb();
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec || !fs::exists(status))
    throw InputError(path + ": " + field + ": the VDB file does not exist" + (ec && fs::exists(status) ? " (" + ec.message() + ")" : ""));
  if (!fs::is_regular_file(status))
    throw InputError(path + ": " + field + ": expected a VDB file, got " + (fs::is_directory(status) ? "a directory" : "a device, pipe or socket"));
  openvdb::io::File file(path);
  try {
    file.open(false);
  } catch (const std::exception& e) {
    throw InputError(path + ": " + field + ": cannot read the VDB file (" + e.what() + "); is it truncated or not a VDB?");
  }
  std::vector<LoadedGrid> out;
  for (const std::string& name : gridNames) {
    if (!file.hasGrid(name)) {
      std::string present;
      for (auto it = file.beginName(); it != file.endName(); ++it) present += (present.empty() ? "" : ", ") + *it;
      file.close();
      throw InputError(path + ": " + field + ": expected a grid named \"" + name + "\", the file holds: " +
                       (present.empty() ? "no grids" : present));
    }
    openvdb::GridBase::Ptr base;
    try {
      base = file.readGrid(name);
    } catch (const std::exception& e) {
      file.close();
      throw InputError(path + ": " + field + ": cannot read grid \"" + name + "\" (" + e.what() + "); is the file truncated?");
    }
    auto floatGrid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
    if (!floatGrid) {
      file.close();
      throw InputError(path + ": " + field + ": grid \"" + name + "\" is of type " + base->valueType() + ", expected float");
    }
    if (!floatGrid->transform().isLinear()) {
      file.close();
      throw InputError(path + ": " + field + ": grid \"" + name + "\" has a non-linear (frustum) transform, expected a linear one");
    }
    // What the renderer can represent (input_limits.h), checked before any dense or NanoVDB copy.
    const auto fail = [&](const std::string& what) {
      file.close();
      throw InputError(path + ": " + field + ": grid \"" + name + "\" " + what);
    };
    const openvdb::math::Mat4d map = floatGrid->transform().baseMap()->getAffineMap()->getMat4();
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        if (!std::isfinite(map(i, j)) || std::abs(map(i, j)) > 1e12) fail("has a non-finite or absurd index-to-world transform");
    const double det = std::abs(map.getMat3().det());
    if (!(det > 0.0)) fail("has a degenerate (flat) index-to-world transform");
    const double voxelSize = std::cbrt(det);
    if (voxelSize < limits::kMinVoxelSize || voxelSize > limits::kMaxVoxelSize)
      fail("has voxels " + std::to_string(voxelSize) + " world units wide; expected between 1e-6 and 1e6");
    if (floatGrid->background() != 0.0f)
      fail("has background value " + std::to_string(floatGrid->background()) + "; expected 0 (the value outside the active voxels)");
    const openvdb::CoordBBox box = floatGrid->evalActiveVoxelBoundingBox();
    if (!box.empty()) {
      for (int a = 0; a < 3; ++a)
        if (std::abs(box.min()[a]) > limits::kMaxIndexCoordinate || std::abs(box.max()[a]) > limits::kMaxIndexCoordinate)
          fail("has active voxels at index " + std::to_string(std::max(std::abs(box.min()[a]), std::abs(box.max()[a]))) +
               "; expected indices within 2^28");
      const openvdb::Coord dim = box.dim();
      const double boxVoxels = static_cast<double>(dim.x()) * dim.y() * dim.z();
      if (boxVoxels > limits::kMaxBoxVoxels)
        fail("has active voxels spanning " + std::to_string(dim.x()) + " x " + std::to_string(dim.y()) + " x " + std::to_string(dim.z()) +
             " voxels; expected a bounding box of at most 4e9 voxels (are there stray voxels far from the rest?)");
    }
    checkMemoryBudget(2.0 * static_cast<double>(floatGrid->memUsage()), path + ": " + field, "grid \"" + name + "\"");
    LoadedGrid loaded;
    // NaN, Inf and negative values would poison majorants and the film: replace them with 0.
    for (auto it = floatGrid->tree().beginValueAll(); it; ++it) {
      const float v = *it;
      if (!std::isfinite(v) || v < 0.0f) {
        it.setValue(0.0f);
        ++loaded.sanitizedVoxels;
      }
    }
    const Mat4 worldFromIndex = toGlm(floatGrid->transform().baseMap()->getAffineMap()->getMat4());
    auto handle = nanovdb::openToNanoVDB(*floatGrid);
    loaded.grid = VoxelGrid(std::move(handle), worldFromIndex, name);
    out.push_back(std::move(loaded));
  }
  file.close();
  return out;
}

}  // namespace candela
