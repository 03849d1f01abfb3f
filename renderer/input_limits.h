// What the renderer can represent, in one place. Scene validation and every allocation whose size
// comes from input check against these bounds; each failed check is an InputError naming the file,
// the field and the bound, never a crash, a hang or a light or volume silently dropped.
#pragma once

#include <cstddef>
#include <string>

namespace candela {
namespace limits {

// World positions and translations, per component. Float keeps about 0.1 units of precision at
// 1e6, and squared distances (1e12) and Embree's ray arithmetic stay finite.
inline constexpr double kMaxCoordinate = 1e6;
// Directions (camera up, light directions) must be normalisable: length at least this.
inline constexpr double kMinDirectionLength = 1e-6;
// Radiance-like products (a light's intensity x colour, emission intensity x colour): products
// with solid angles, areas and majorants must stay finite in float (max 3.4e38).
inline constexpr double kMaxRadiance = 1e12;
// Optical depth of one voxel at the densest voxel (density x sigma_t_scale x voxel size). Denser
// media make the tracking step shorter than float can resolve along a ray.
inline constexpr double kMaxOpticalDepthPerVoxel = 1e4;
// World size of one voxel (the VDB's transform times the scene's scale).
inline constexpr double kMinVoxelSize = 1e-6;
inline constexpr double kMaxVoxelSize = 1e6;
// Voxels in a grid's active bounding box: building majorants visits each one.
inline constexpr double kMaxBoxVoxels = 4.0e9;
// Index coordinates of active voxels (int arithmetic on them must not overflow).
inline constexpr int kMaxIndexCoordinate = 1 << 28;
// Probes of a guided scene.
inline constexpr double kMaxProbes = 4.0e6;
// Nesting of JSON arrays and objects in a scene file or a --set value.
inline constexpr int kMaxJsonDepth = 64;
// Size of a scene file.
inline constexpr size_t kMaxSceneFileBytes = size_t{64} << 20;

}  // namespace limits

// The memory one input-sized structure (film, grid, probe set...) may take: 4 GiB by default;
// CANDELA_MAX_MEMORY_GB or the --max-memory flag of both executables change it.
size_t memoryBudgetBytes();
// CANDELA_MAX_MEMORY_GB checked exactly as --max-memory is (InputError naming it when it is not a
// finite number of GB above 0); both executables call it first.
void checkMemoryBudgetEnvironment();
void setMemoryBudgetBytes(size_t bytes);
// Throws InputError "WHERE: WHAT needs N GB, above the memory budget of M GB (...)" when `bytes`
// exceeds the budget; call it before allocating.
void checkMemoryBudget(double bytes, const std::string& where, const std::string& what);
// "1.5 GB", "320 MB".
std::string formatBytes(double bytes);

// Depth of the deepest nesting of arrays and objects in JSON text (strings skipped), stopping early
// once past `limit`. Checked before parsing so hostile input never recurses deeply.
int jsonNestingDepth(const std::string& text, int limit);
// Whether `s` is valid UTF-8 (JSON output and image metadata need it).
bool isValidUtf8(const std::string& s);

}  // namespace candela
