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
};

// Loads the named float grids from `path`. Throws InputError naming the file and grid for a missing
// or unreadable file, a missing grid (listing those present) or a grid that is not float.
// `field` names the scene field that asked for the grid, for the message.
std::vector<LoadedGrid> loadVdbGrids(const std::string& path, const std::vector<std::string>& gridNames,
                                     const std::string& field);

}  // namespace candela
