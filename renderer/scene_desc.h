// The scene file model: what a scene JSON holds, as plain structs. It models no more than the
// built-in scenes need. Loading (scene_loader.cpp) validates every field and reports
// "FILE: FIELD: expected ..., got ..." for anything wrong.
#pragma once

#include "display_settings.h"
#include "input_limits.h"
#include "settings.h"

#include <string>
#include <vector>

namespace candela {

// World positions: what float arithmetic (and Embree) can represent (input_limits.h).
inline constexpr Range kCoordinate{-limits::kMaxCoordinate, limits::kMaxCoordinate};
inline constexpr Range kLength{1e-5, limits::kMaxCoordinate};
inline constexpr Range kRadianceScale{0.0, limits::kMaxRadiance};
inline constexpr Range kColour{0.0, 1e6};

struct CameraDesc {
  Vec3 position{0.0f, 1.0f, 5.0f};
  Vec3 look_at{0.0f};
  Vec3 up{0.0f, 1.0f, 0.0f};
  float fov_y = 40.0f;  // vertical field of view in degrees
  std::pair<int, int> resolution{640, 360};

  template <class V>
  void visit(V& v) {
    v.required("position", position, "Camera position (world units)", kCoordinate);
    v.required("look_at", look_at, "Point the camera looks at", kCoordinate);
    v.field("up", up, "Up direction (normalised; any length from 1e-6 to 1e6 per component; not parallel to the view)", kCoordinate);
    v.field("fov_y", fov_y, "Vertical field of view in degrees", Range{0.1, 179.0});
    v.field("resolution", resolution, "Image width and height in pixels", Range{1, 16384});
  }
};

// A built-in procedural volume: deterministic for a given type, seed and resolution. It is written to
// a real .vdb file in the cache and loaded like any other VDB.
struct GeneratorDesc {
  std::string type = "constant";  // constant | ramp | torch | mist | cloud | plume
  uint32_t seed = 1;
  int resolution = 64;            // voxels along the longest axis
  Vec3 size{1.0f};                // world extent of the generated grid before the volume transform
  float value = 1.0f;             // density of constant/ramp volumes (ramp: density at the +x end); shapes: their peak
  float temperature = 0.0f;       // constant/ramp: temperature written everywhere the density is

  template <class V>
  void visit(V& v) {
    v.required("type", type, "constant, ramp, torch, mist, cloud, plume, or invalid (NaN and negative voxels, for the stability suite)");
    v.field("seed", seed, "Noise seed");
    v.field("resolution", resolution, "Voxels along the longest axis", Range{2, 1024});
    v.field("size", size, "World extent of the grid (before the transform)", Range{1e-4, 1e6});
    v.field("value", value, "constant/ramp: density (ramp: at the +x end, 0 at the -x end); torch, mist, cloud, plume: multiplies the shape's density (peak 1)", Range{0.0, 1e6});
    v.field("temperature", temperature, "constant/ramp: temperature grid value where density is non-zero", Range{0.0, 1e6});
  }
};

enum class EmissionMode { None, Blackbody, Grid };
template <>
struct EnumNames<EmissionMode> {
  static const std::vector<std::pair<EmissionMode, const char*>>& get() {
    static const std::vector<std::pair<EmissionMode, const char*>> v{
        {EmissionMode::None, "none"}, {EmissionMode::Blackbody, "blackbody"}, {EmissionMode::Grid, "grid"}};
    return v;
  }
};

// How the emission value E(x) below enters the radiative transfer equation (docs/conventions.md):
// radiance: E is the radiance Le the medium emits; the source term is mu_a Le = (1 - albedo) sigma_t Le
//   (the talk's Eq. 1, physically based: a medium that does not absorb does not emit, so an albedo of
//   1 or zero density makes it dark);
// per_length: E is the source term itself, emitted radiance per unit length, whatever the density and
//   albedo (Cycles' and Arnold's emission strength, Houdini's emission scale: strength x grid).
enum class EmissionUnits { Radiance, PerLength };
template <>
struct EnumNames<EmissionUnits> {
  static const std::vector<std::pair<EmissionUnits, const char*>>& get() {
    static const std::vector<std::pair<EmissionUnits, const char*>> v{{EmissionUnits::Radiance, "radiance"},
                                                                      {EmissionUnits::PerLength, "per_length"}};
    return v;
  }
};

// E(x): blackbody(temperature * temperature_scale + temperature_offset) * intensity, or
// emission grid * color * intensity; `units` says whether E is Le (source mu_a Le) or the source.
struct EmissionDesc {
  EmissionMode mode = EmissionMode::None;
  EmissionUnits units = EmissionUnits::Radiance;
  float intensity = 1.0f;
  float temperature_scale = 1.0f;   // Kelvin per temperature-grid unit
  float temperature_offset = 0.0f;  // Kelvin added after scaling
  Vec3 color{1.0f};

  template <class V>
  void visit(V& v) {
    v.field("mode", mode, "none, blackbody (temperature grid) or grid (emission grid x color)");
    v.field("units", units,
            "radiance: the value is the radiance Le, emitted as (1 - albedo) sigma_t Le (an albedo of 1 or zero density emits nothing); "
            "per_length: the value is emitted per unit length whatever the density (Cycles / Arnold emission strength)");
    v.field("intensity", intensity, "Multiplies the emission (radiance, or radiance per world unit in per_length units)", kRadianceScale);
    v.field("temperature_scale", temperature_scale,
            "Blackbody: Kelvin per temperature-grid unit. Kelvin = grid x scale + offset; the colour is Planck's at that temperature "
            "scaled so 1500 K has luminance 1 (x intensity): 0.00035 at 1000 K (dull red), 60 at 2000 K, 3900 at 3000 K (orange), "
            "4e5 at 6500 K (white), as physics says. Below about 700 K it is black",
            Range{0.0, 1e6});
    v.field("temperature_offset", temperature_offset, "Blackbody: Kelvin added after scaling (the temperature where the grid is 0)", Range{-1e5, 1e5});
    v.field("color", color, "Emission colour (grid mode)", kColour);
  }
};

struct TransformDesc {
  Vec3 translate{0.0f};
  Vec3 rotate_deg{0.0f};  // applied X, then Y, then Z
  Vec3 scale{1.0f};

  template <class V>
  void visit(V& v) {
    v.field("translate", translate, "World translation", kCoordinate);
    v.field("rotate_deg", rotate_deg, "Rotation in degrees about X, then Y, then Z", Range{-36000.0, 36000.0});
    v.field("scale", scale, "Scale along each axis", Range{1e-6, 1e6});
  }
};

struct VolumeDesc {
  std::string name;
  std::string file;  // .vdb path, relative to the scene file
  std::string density_grid = "density";
  std::string temperature_grid;  // needed by blackbody emission
  std::string emission_grid;     // needed by grid emission
  std::string color_grid;        // optional vec3 grid (Cd) colouring grid emission per voxel
  bool has_generator = false;
  GeneratorDesc generator;
  TransformDesc transform;
  float sigma_t_scale = 1.0f;  // extinction per unit density per world unit
  Vec3 albedo{0.8f};
  float g = 0.0f;  // Henyey-Greenstein anisotropy
  EmissionDesc emission;

  template <class V>
  void visit(V& v) {
    v.field("name", name, "Label used in messages and the UI");
    v.field("file", file, "OpenVDB file (relative to the scene file)");
    v.field("density_grid", density_grid, "Name of the float density grid");
    v.field("temperature_grid", temperature_grid, "Name of the float temperature grid (blackbody emission)");
    v.field("emission_grid", emission_grid, "Name of the float emission grid (grid emission)");
    v.field("color_grid", color_grid,
            "Name of a vec3 grid (Cd) that colours grid emission per voxel: E = emission grid x Cd x color x intensity (empty: none)");
    if (V::kWriting ? has_generator : v.has("generator")) {
      has_generator = true;
      v.object("generator", generator, "Built-in procedural volume instead of a file");
    }
    v.object("transform", transform, "Placement of the grid in the world");
    v.field("sigma_t_scale", sigma_t_scale, "Extinction per unit density per world unit", Range{0.0, 1e6});
    v.field("albedo", albedo, "Single-scattering albedo mu_s / mu_t per channel", kUnit);
    v.field("g", g, "Henyey-Greenstein anisotropy: -1 back, 0 isotropic, 1 forward", Range{-0.999, 0.999});
    v.object("emission", emission, "Volume emission");
  }
};

enum class LightType { Point, Spot, Directional, Sphere, Environment };
template <>
struct EnumNames<LightType> {
  static const std::vector<std::pair<LightType, const char*>>& get() {
    static const std::vector<std::pair<LightType, const char*>> v{{LightType::Point, "point"},
                                                                  {LightType::Spot, "spot"},
                                                                  {LightType::Directional, "directional"},
                                                                  {LightType::Sphere, "sphere"},
                                                                  {LightType::Environment, "environment"}};
    return v;
  }
};

// One light. Which fields apply depends on `type`; the others are errors in a scene file.
// point/spot: intensity in W/sr-like units (radiance * area); directional: irradiance;
// sphere and environment: radiance.
struct LightDesc {
  LightType type = LightType::Point;
  Vec3 color{1.0f};
  float intensity = 1.0f;
  Vec3 position{0.0f};
  Vec3 direction{0.0f, -1.0f, 0.0f};  // spot: where it points; directional: where the light travels
  float radius = 0.1f;                // sphere
  float cone_angle_deg = 30.0f;       // spot: half-angle of the full cone
  float cone_falloff_deg = 5.0f;      // spot: width of the soft edge inside the cone

  template <class V>
  void visit(V& v) {
    v.required("type", type, "point, spot, directional, sphere or environment");
    v.field("color", color, "Light colour (scene-linear)", kColour);
    v.field("intensity", intensity, "Multiplies the colour (intensity x colour at most 1e12)", kRadianceScale);
    if (type == LightType::Point || type == LightType::Spot || type == LightType::Sphere)
      v.field("position", position, "Light position", kCoordinate);
    if (type == LightType::Spot || type == LightType::Directional)
      v.field("direction", direction, "Spot: where it points; directional: where the light travels (normalised; any length up to 1e6 per component)", kCoordinate);
    if (type == LightType::Sphere) v.field("radius", radius, "Sphere radius", kLength);
    if (type == LightType::Spot) {
      v.field("cone_angle_deg", cone_angle_deg, "Half-angle of the cone in degrees", Range{0.1, 90.0});
      v.field("cone_falloff_deg", cone_falloff_deg, "Soft edge width in degrees", Range{0.0, 90.0});
    }
  }
};

enum class SurfaceType { Plane, Box, Sphere, Cylinder };
template <>
struct EnumNames<SurfaceType> {
  static const std::vector<std::pair<SurfaceType, const char*>>& get() {
    static const std::vector<std::pair<SurfaceType, const char*>> v{{SurfaceType::Plane, "plane"},
                                                                    {SurfaceType::Box, "box"},
                                                                    {SurfaceType::Sphere, "sphere"},
                                                                    {SurfaceType::Cylinder, "cylinder"}};
    return v;
  }
};

// Diffuse surfaces traced with Embree. plane: horizontal ground at `height` of half-width `size`;
// box: min/max corners; sphere: center/radius; cylinder: vertical, base center, radius, height.
struct SurfaceDesc {
  SurfaceType type = SurfaceType::Plane;
  Vec3 albedo{0.5f};
  float height = 0.0f;
  float size = 100.0f;
  Vec3 min{-0.5f};
  Vec3 max{0.5f};
  Vec3 center{0.0f};
  float radius = 0.5f;
  float length = 1.0f;

  template <class V>
  void visit(V& v) {
    v.required("type", type, "plane, box, sphere or cylinder");
    v.field("albedo", albedo, "Diffuse reflectance", kUnit);
    if (type == SurfaceType::Plane) {
      v.field("height", height, "Height of the ground plane", kCoordinate);
      v.field("size", size, "Half-width of the plane", kLength);
    }
    if (type == SurfaceType::Box) {
      v.required("min", min, "Lower corner", kCoordinate);
      v.required("max", max, "Upper corner", kCoordinate);
    }
    if (type == SurfaceType::Sphere || type == SurfaceType::Cylinder) {
      v.required("center", center, type == SurfaceType::Sphere ? "Centre" : "Centre of the bottom cap", kCoordinate);
      v.required("radius", radius, "Radius", kLength);
    }
    if (type == SurfaceType::Cylinder) v.required("length", length, "Height of the cylinder", kLength);
  }
};

struct SceneDesc {
  std::string path;  // the file it came from ("" when built in code); relative volume paths resolve against it
  std::string description;
  CameraDesc camera;
  DisplaySettings display;  // how the look was seen (the renderer ignores it; the viewer and PNGs use it)
  RenderSettings render;
  StrategySettings strategy;
  std::vector<VolumeDesc> volumes;
  std::vector<LightDesc> lights;
  std::vector<SurfaceDesc> surfaces;
};

// Why a volume that asks to emit would render dark (albedo 1 or black colour in radiance units, zero
// intensity), one line each; empty when it emits or asks for no emission. Scene::build reports them
// as warnings and the viewer shows them beside the volume's fields.
std::vector<std::string> emissionWarnings(const VolumeDesc& volume);

// Reads and validates a scene file. `preset` (when not empty) replaces the file's strategy with that
// preset; `settings` are --set style edits applied to the JSON after it and before validation, so
// their errors read like the file's own.
SceneDesc loadSceneDesc(const std::string& path, const std::vector<std::string>& settings = {}, const std::string& preset = "");
SceneDesc parseSceneDesc(const Json& doc, const std::string& path);
Json sceneToJson(const SceneDesc& scene);
// Writes `scene` to `path` as a scene file (pretty JSON, written to a temporary file and renamed, so
// a failed save never truncates the old file). Relative volume paths are rewritten to stay correct
// from the new location; absolute ones are kept. Returns the scene as saved (path = `path`).
SceneDesc saveSceneDesc(const SceneDesc& scene, const std::string& path);
// The document a scene file holds, before validation. Rejects what is not a regular file, files
// over 64 MB and nesting deeper than limits::kMaxJsonDepth.
Json readSceneJson(const std::string& path);
// JSON text parsed with the same checks; errors name `origin`.
Json parseJsonText(const std::string& text, const std::string& origin);

}  // namespace candela
