// OpenVDB -> NanoVDB loading. Heavy headers live here on purpose (see TOOLCHAIN.md build costs).
#include "vdb_io.h"

#include "fields.h"

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
  if (!std::filesystem::exists(path)) throw InputError(path + ": " + field + ": the VDB file does not exist");
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
