#include "vdb_import.h"

#include "blackbody.h"
#include "sequence.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace candela {

namespace fs = std::filesystem;

const std::vector<std::string>& densityGridNames() {
  static const std::vector<std::string> v{"density", "density_smoke", "smoke", "Density", "dens", "soot"};
  return v;
}
const std::vector<std::string>& temperatureGridNames() {
  static const std::vector<std::string> v{"temperature", "heat", "Temperature", "temp"};
  return v;
}
const std::vector<std::string>& flameGridNames() {
  static const std::vector<std::string> v{"flame", "fire", "flames", "fuel", "Flame"};
  return v;
}

const std::vector<std::string>& colorGridNames() {
  static const std::vector<std::string> v{"Cd", "color", "colour", "emission_color", "emission_colour", "Color"};
  return v;
}

bool isVdbPath(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".vdb";
}

std::string VdbImportReport::summary() const {
  std::string s = "density \"" + densityGrid + "\"";
  if (densityIsLevelSet) s += " (a level set: rendered as the fog volume it bounds)";
  s += emissionGrid.empty() ? ", no emission" : ", emission " + emissionMode + " from \"" + emissionGrid + "\"";
  s += std::string(", ") + (up == UpAxis::Z ? "Z-up" : "Y-up") + " (" + upReason + ")";
  if (!sequence.empty()) s += ", sequence " + sequence;
  if (!ignoredGrids.empty()) {
    s += ", not used:";
    for (const auto& g : ignoredGrids) s += " " + g;
  }
  return s;
}

LightDesc defaultSun() {
  LightDesc sun;
  sun.type = LightType::Directional;
  // From the side of the opened volume's three-quarter view (frameCamera's direction), about 100
  // degrees round from the camera and 35 degrees up: smoke shows a lit and a shadowed side.
  sun.direction = glm::normalize(Vec3(-0.68f, -0.57f, 0.46f));
  sun.color = Vec3(1.0f, 0.93f, 0.82f);
  sun.intensity = 3.0f;
  return sun;
}

SurfaceDesc defaultGround(float height, float radius) {
  SurfaceDesc ground;
  ground.type = SurfaceType::Plane;
  ground.height = height;
  ground.size = 50.0f * std::max(radius, 1e-3f);  // to the horizon from the framed view
  ground.albedo = Vec3(0.18f);  // mid grey: the volume, not the ground, draws the eye
  return ground;
}

LightDesc defaultSky() {
  LightDesc sky;
  sky.type = LightType::Environment;
  sky.color = Vec3(0.45f, 0.6f, 0.85f);
  sky.intensity = 0.25f;
  return sky;
}

void frameCamera(CameraDesc& camera, const Vec3& lo, const Vec3& hi, const Vec3& direction) {
  const Vec3 center = 0.5f * (lo + hi);
  const float radius = std::max(1e-4f, 0.5f * glm::length(hi - lo));
  const float aspect = static_cast<float>(camera.resolution.first) / static_cast<float>(std::max(1, camera.resolution.second));
  const float tanHalfY = std::tan(glm::radians(camera.fov_y) * 0.5f);
  const float halfFov = std::atan(std::min(tanHalfY, tanHalfY * aspect));
  // The bounding sphere just inside the narrower field of view: a box's corners rarely face the
  // camera, so the whole sphere would leave the volume small in frame.
  const float distance = radius / std::sin(halfFov) * 0.8f;
  camera.look_at = center;
  camera.position = center + glm::normalize(direction) * distance;
  camera.up = Vec3(0.0f, 1.0f, 0.0f);
}

namespace {

const VdbGridInfo* firstFloat(const VdbFileInfo& info, const std::vector<std::string>& names) {
  for (const auto& n : names)
    if (const VdbGridInfo* g = info.find(n); g && g->isFloat) return g;
  return nullptr;
}

// Blender (Mantaflow bakes and its volume export) writes Z-up data and says so in its metadata keys.
bool writtenByBlender(const VdbFileInfo& info, std::string& why) {
  for (const auto& m : info.metadata) {
    std::string lower = m;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (lower.rfind("blender/", 0) == 0 || lower.find("=blender") != std::string::npos || lower.find("mantaflow") != std::string::npos) {
      why = "metadata \"" + m.substr(0, 60) + "\" says Blender wrote it";
      return true;
    }
  }
  return false;
}

}  // namespace

SceneDesc sceneFromVdb(const std::string& vdbPath, const VdbImportOptions& options, VdbImportReport* reportOut) {
  std::vector<std::string> measure;
  for (const auto* list : {&densityGridNames(), &temperatureGridNames(), &flameGridNames()})
    measure.insert(measure.end(), list->begin(), list->end());
  const VdbFileInfo info = describeVdbFile(vdbPath, measure);
  VdbImportReport report;

  const VdbGridInfo* density = firstFloat(info, densityGridNames());
  if (!density) {
    // A file with a single float grid of another name (a "fog" export): use that.
    std::vector<const VdbGridInfo*> floats;
    for (const auto& g : info.grids)
      if (g.isFloat) floats.push_back(&g);
    if (floats.size() == 1) density = floats[0];
  }
  if (!density) {
    std::string present;
    for (const auto& g : info.grids) present += (present.empty() ? "" : ", ") + g.name + " (" + g.type + ")";
    throw InputError(vdbPath + ": density_grid: expected a float grid named one of density, density_smoke, smoke, soot; the file holds: " +
                     (present.empty() ? "no grids" : present));
  }
  SceneDesc scene;
  const fs::path vdb(vdbPath);
  scene.path = (vdb.parent_path() / (vdb.stem().string() + ".json")).string();
  scene.render.spp = 256;
  scene.render.max_depth = 16;
  scene.display.autoExposure = true;  // nothing in a VDB says how bright it reads

  VolumeDesc volume;
  volume.name = vdb.stem().string();
  volume.file = vdb.filename().string();
  // One frame of a simulation cache (fire.0012.vdb beside fire.0013.vdb): open the sequence at it.
  std::string pattern;
  int frame = 1;
  if (detectSequence(vdbPath, pattern, frame)) {
    volume.file = fs::path(pattern).filename().string();
    scene.render.frame = frame;
    std::string stem = fs::path(pattern).stem().string();
    stem = stem.substr(0, stem.find('#'));
    while (!stem.empty() && (stem.back() == '.' || stem.back() == '_' || stem.back() == '-')) stem.pop_back();
    if (!stem.empty()) scene.path = (vdb.parent_path() / (stem + ".json")).string(), volume.name = stem;
    report.sequence = volume.file;
  }
  volume.density_grid = density->name;
  report.densityGrid = density->name;
  report.densityIsLevelSet = density->levelSet;
  volume.albedo = Vec3(0.9f);
  // Density is extinction per world unit, the Cycles / Houdini convention (docs/conventions.md).
  volume.sigma_t_scale = 1.0f;

  const VdbGridInfo* flame = firstFloat(info, flameGridNames());
  const VdbGridInfo* temperature = firstFloat(info, temperatureGridNames());
  // Emission per unit length, as Cycles, Houdini and Arnold shade fire: the flame glows whatever the
  // smoke's density there. Its peak is set so that a ray across the thinnest side of the volume
  // gathers a radiance of about 8.
  const Vec3 extent = glm::max(density->worldMax - density->worldMin, Vec3(1e-6f));
  const float across = std::max(1e-6f, std::min(extent.x, std::min(extent.y, extent.z)));
  if (flame && flame->maxValue > 0.0f) {
    volume.emission.mode = EmissionMode::Grid;
    volume.emission.units = EmissionUnits::PerLength;
    volume.emission_grid = flame->name;
    volume.emission.color = Vec3(1.0f, 0.45f, 0.12f);
    volume.emission.intensity = 8.0f / (flame->maxValue * luminance(Rgb(1.0f, 0.45f, 0.12f)) * across);
    report.emissionGrid = flame->name;
    report.emissionMode = "grid (per unit length)";
    // A colour grid (Cd) colours the flame per voxel instead of the fire colour.
    for (const auto& n : colorGridNames())
      if (const VdbGridInfo* cd = info.find(n); cd && cd->type == "vec3s") {
        volume.color_grid = cd->name;
        volume.emission.color = Vec3(1.0f);
        volume.emission.intensity = 8.0f / (flame->maxValue * across);
        report.emissionMode += ", coloured by \"" + cd->name + "\"";
        break;
      }
  } else if (temperature && temperature->maxValue > 0.0f) {
    // Kelvin when the values look like Kelvin, else a normalised simulation temperature whose peak
    // maps to 2000 K (500 K, where a blackbody turns black, at zero).
    volume.emission.mode = EmissionMode::Blackbody;
    volume.emission.units = EmissionUnits::PerLength;
    volume.temperature_grid = temperature->name;
    if (temperature->maxValue >= 200.0f) {
      volume.emission.temperature_scale = 1.0f;
      volume.emission.temperature_offset = 0.0f;
    } else {
      volume.emission.temperature_scale = 1500.0f / temperature->maxValue;
      volume.emission.temperature_offset = 500.0f;
    }
    const float peakKelvin = temperature->maxValue * volume.emission.temperature_scale + volume.emission.temperature_offset;
    const float peak = luminance(blackbodyExact(std::min(peakKelvin, 12000.0f)));
    volume.emission.intensity = peak > 0.0f ? std::min(8.0f / (peak * across), 1e6f) : 1.0f;
    report.emissionGrid = temperature->name;
    report.emissionMode = "blackbody (per unit length)";
  }
  for (const auto& g : info.grids)
    if (g.name != volume.density_grid && g.name != report.emissionGrid && g.name != volume.color_grid) report.ignoredGrids.push_back(g.name + (g.isFloat ? "" : " (" + g.type + ")"));

  // Up axis: Z-up data is turned to Candela's Y-up by -90 degrees about X ((x, y, z) -> (x, z, -y)).
  std::string why;
  UpAxis up = options.up;
  if (up == UpAxis::Auto) {
    up = writtenByBlender(info, why) ? UpAxis::Z : UpAxis::Y;
    if (up == UpAxis::Y) why = "nothing in the file says otherwise";
  } else {
    why = "chosen";
  }
  report.up = up;
  report.upReason = why;
  if (up == UpAxis::Z) volume.transform.rotate_deg = Vec3(-90.0f, 0.0f, 0.0f);
  scene.volumes.push_back(volume);

  // World bounds after the up-axis rotation, for the camera and the ground of the light rig.
  Vec3 lo = density->worldMin, hi = density->worldMax;
  if (up == UpAxis::Z) {
    const Vec3 a(lo.x, lo.z, -hi.y), b(hi.x, hi.z, -lo.y);
    lo = a, hi = b;
  }
  if (!(hi.x > lo.x)) lo = Vec3(-0.5f), hi = Vec3(0.5f);  // an empty grid: frame a unit box
  scene.camera.resolution = {640, 360};
  scene.camera.fov_y = 35.0f;
  // Three-quarter view from slightly above, as a turntable starts.
  frameCamera(scene.camera, lo, hi, Vec3(0.45f, 0.25f, 1.0f));

  if (options.light_rig) scene.lights = {defaultSun(), defaultSky()};
  if (options.ground) scene.surfaces = {defaultGround(lo.y, 0.5f * glm::length(hi - lo))};
  // A new scene: the auto strategy chooses (auto_strategy.h).
  scene.strategy = strategyPreset("auto");
  if (reportOut) *reportOut = report;
  return scene;
}

SceneDesc loadSceneOrVdb(const std::string& path, const std::vector<std::string>& settings, const std::string& preset,
                         const VdbImportOptions& options, VdbImportReport* report) {
  if (!isVdbPath(path)) return loadSceneDesc(path, settings, preset);
  SceneDesc scene = sceneFromVdb(path, options, report);
  if (settings.empty() && preset.empty()) return scene;
  // The same edits a scene file takes, validated the same way (errors name the VDB).
  Json doc = sceneToJson(scene);
  if (!preset.empty()) doc["strategy"] = Json{{"preset", preset}};
  for (const auto& s : settings) applySetting(doc, s, path + " (--set " + s.substr(0, 80) + ")");
  SceneDesc edited = parseSceneDesc(doc, scene.path);
  return edited;
}

}  // namespace candela
