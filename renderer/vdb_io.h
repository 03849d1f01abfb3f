// Loading float grids from OpenVDB files into the compact NanoVDB form. This file and
// procedural.cpp are the only places that include OpenVDB headers.
#pragma once

#include "voxel_grid.h"

#include <string>
#include <vector>

namespace candela {

struct LoadedGrid {
  VoxelGrid grid;
  size_t sanitizedVoxels = 0;  // NaN, Inf or negative values replaced by 0 on load
  bool fromLevelSet = false;   // a level set, loaded as the fog volume it bounds
  IndexBox positiveBox;        // the active voxels above 0 (what emits, for an emission grid)
};

// Loads the named float grids from `path`. Throws InputError naming the file and grid for a missing
// or unreadable file, a missing grid (listing those present) or a grid that is not float.
// `field` names the scene field that asked for the grid, for the message.
std::vector<LoadedGrid> loadVdbGrids(const std::string& path, const std::vector<std::string>& gridNames,
                                     const std::string& field);

// Loads the named vec3s grid (a colour: Cd) as three float grids, x, y and z, with the same checks.
std::vector<LoadedGrid> loadVdbVectorGrid(const std::string& path, const std::string& name, const std::string& field);

}  // namespace candela

namespace candela {

// What a VDB file holds, read without loading voxels where the file carries the statistics (OpenVDB
// writes each grid's active bounding box as metadata); recognised float grids are read for their
// value range.
struct VdbGridInfo {
  std::string name;
  std::string type;           // OpenVDB's value type: "float", "vec3s", ...
  bool isFloat = false;        // a scalar grid Candela reads: float, or double read as float
  Vec3 worldMin{0.0f}, worldMax{0.0f};  // world bounds of the active voxels (empty grid: equal)
  float maxValue = 0.0f;      // float grids read by describeVdbFile only (else 0)
  bool read = false;          // whether maxValue was measured
  bool levelSet = false;      // its class is level set (a signed distance field): loaded as its fog volume
};
struct VdbFileInfo {
  std::vector<VdbGridInfo> grids;
  // Metadata keys of the file and its grids that name the application that wrote it ("blender/...",
  // "creator" values): the importer guesses the up axis from them.
  std::vector<std::string> metadata;
  const VdbGridInfo* find(const std::string& name) const {
    for (const auto& g : grids)
      if (g.name == name) return &g;
    return nullptr;
  }
};

// Lists the grids of `path` (same structure checks as loadVdbGrids). Float grids named in
// `measure` are read to find their largest value.
VdbFileInfo describeVdbFile(const std::string& path, const std::vector<std::string>& measure = {});

}  // namespace candela
