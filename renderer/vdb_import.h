// Opening a bare .vdb as a scene: the grids recognised by the names simulation tools write, the up
// axis, a camera framed on the volume and a default light rig (docs/conventions.md, "Opening a VDB").
// The result is an ordinary SceneDesc: every choice made here is a field the artist can edit, save
// and reload.
#pragma once

#include "scene_desc.h"
#include "vdb_io.h"

#include <string>
#include <vector>

namespace candela {

enum class UpAxis { Auto, Y, Z };
template <>
struct EnumNames<UpAxis> {
  static const std::vector<std::pair<UpAxis, const char*>>& get() {
    static const std::vector<std::pair<UpAxis, const char*>> v{{UpAxis::Auto, "auto"}, {UpAxis::Y, "y"}, {UpAxis::Z, "z"}};
    return v;
  }
};

struct VdbImportOptions {
  UpAxis up = UpAxis::Auto;  // auto: Z-up when the file says Blender wrote it, else Y-up
  bool light_rig = true;     // a sun and a sky; without it only emission lights the volume
  bool ground = true;        // a grey ground plane under the volume that catches its shadow

  template <class V>
  void visit(V& v) {
    v.field("up", up, "Up axis of the file: auto (Z when Blender wrote it, else Y), y or z");
    v.field("light_rig", light_rig, "Add the default sun and sky");
    v.field("ground", ground, "Add a ground plane under the volume that catches its shadow");
  }
};

// Grid names simulation tools write, in order of preference (first found wins).
const std::vector<std::string>& densityGridNames();      // density, density_smoke, smoke, ...
const std::vector<std::string>& temperatureGridNames();  // temperature, heat, ...
const std::vector<std::string>& flameGridNames();        // flame, fire, fuel, ...
const std::vector<std::string>& colorGridNames();        // Cd, color, emission_color, ... (vec3)

// What the importer decided, for messages (the viewer's status, the CLI's output).
struct VdbImportReport {
  std::string densityGrid, emissionGrid, emissionMode;
  bool densityIsLevelSet = false;  // a signed distance field, rendered as the fog volume it bounds
  UpAxis up = UpAxis::Y;
  std::string upReason;
  std::string sequence;                   // the frame pattern, when the file is one frame of several
  std::vector<std::string> ignoredGrids;  // present but unused (vector grids such as Cd, velocity)
  std::string summary() const;
};

// True for paths the viewer and CLI open as a volume rather than a scene file.
bool isVdbPath(const std::string& path);

// Builds a scene around the VDB at `vdbPath`. The scene's path is STEM.json beside the VDB (not
// written: File > Save writes it), and the volume's file is relative to it. Throws InputError naming
// the file when no density grid is found (listing the grids present).
SceneDesc sceneFromVdb(const std::string& vdbPath, const VdbImportOptions& options = {}, VdbImportReport* report = nullptr);

// The default light rig: a warm sun from the side of the opened view and a pale blue sky.
LightDesc defaultSun();
LightDesc defaultSky();
// The ground an opened volume stands on: a grey plane at `height` (the bottom of its bounds), reaching
// far past a volume of bounding radius `radius`.
SurfaceDesc defaultGround(float height, float radius);

// Points the camera at the world box lo..hi from `direction` (from the target toward the camera),
// far enough that the box's bounding sphere fills the narrower field of view.
void frameCamera(CameraDesc& camera, const Vec3& lo, const Vec3& hi, const Vec3& direction);

// Opens a scene file or a .vdb (sceneFromVdb); `settings` are --set edits applied to either.
SceneDesc loadSceneOrVdb(const std::string& path, const std::vector<std::string>& settings = {}, const std::string& preset = "",
                         const VdbImportOptions& options = {}, VdbImportReport* report = nullptr);

}  // namespace candela
