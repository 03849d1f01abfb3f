#include "scene_desc.h"
#include "atomic_file.h"
#include "auto_strategy.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace candela {

namespace {

template <class S>
std::vector<S> readList(const Json& doc, const char* key, const std::string& file) {
  std::vector<S> out;
  if (!doc.contains(key)) return out;
  const Json& list = doc[key];
  if (!list.is_array()) throw InputError(file + ": " + key + ": expected an array, got " + shortJson(list));
  for (size_t i = 0; i < list.size(); ++i) {
    S s;
    fromJson(list[i], s, file, std::string(key) + "." + std::to_string(i));
    out.push_back(s);
  }
  return out;
}

void checkVolume(const VolumeDesc& v, const std::string& file, const std::string& path) {
  if (v.file.empty() == !v.has_generator)
    throw InputError(file + ": " + path + ": expected exactly one of \"file\" or \"generator\"");
  if (v.has_generator) {
    static const char* types[] = {"constant", "ramp", "torch", "mist", "cloud", "plume", "invalid"};
    bool known = false;
    for (const char* t : types) known |= v.generator.type == t;
    if (!known)
      throw InputError(file + ": " + path + ".generator.type: expected one of constant, ramp, torch, mist, cloud, plume, invalid, got \"" +
                       v.generator.type + "\"");
  }
  if (v.has_generator) {
    // Every axis needs at least 2 voxels at this resolution; a thinner axis would be padded to 2
    // voxels and render far thicker than asked.
    const Vec3& size = v.generator.size;
    const float voxel = maxComponent(size) / static_cast<float>(v.generator.resolution);
    for (int a = 0; a < 3; ++a)
      if (size[a] < 2.0f * voxel)
        throw InputError(file + ": " + path + ".generator.size: axis " + "xyz"[a] + " (" + std::to_string(size[a]) +
                         ") gets fewer than 2 voxels at resolution " + std::to_string(v.generator.resolution) +
                         " (voxel size " + std::to_string(voxel) + "); expected every axis at least 2 voxels thick");
  }
  if (v.emission.mode == EmissionMode::Grid && static_cast<double>(v.emission.intensity) * maxComponent(v.emission.color) > limits::kMaxRadiance)
    throw InputError(file + ": " + path + ".emission.intensity: expected intensity x colour at most 1e12");
  if (v.emission.mode == EmissionMode::Blackbody && !v.has_generator && v.temperature_grid.empty())
    throw InputError(file + ": " + path + ".temperature_grid: expected a grid name, since emission.mode is \"blackbody\"");
  if (v.emission.mode == EmissionMode::Grid && !v.has_generator && v.emission_grid.empty())
    throw InputError(file + ": " + path + ".emission_grid: expected a grid name, since emission.mode is \"grid\"");
}

}  // namespace

Json readSceneJson(const std::string& path) {
  namespace fs = std::filesystem;
  // Only regular files: a directory, device (/dev/zero), pipe or socket would hang or eat memory.
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec) throw InputError(path + ": cannot open the scene file (" + ec.message() + ")");
  if (!fs::is_regular_file(status))
    throw InputError(path + ": expected a scene file (JSON), got " + (fs::is_directory(status) ? "a directory" : "a device, pipe or socket"));
  const auto size = fs::file_size(path, ec);
  if (ec) throw InputError(path + ": cannot read the scene file (" + ec.message() + ")");
  if (size > limits::kMaxSceneFileBytes)
    throw InputError(path + ": expected a scene file of at most 64 MB, got " + formatBytes(static_cast<double>(size)) +
                     " (volumes belong in .vdb files)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open the scene file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parseJsonText(ss.str(), path);
}

Json parseJsonText(const std::string& text, const std::string& origin) {
  if (jsonNestingDepth(text, limits::kMaxJsonDepth) > limits::kMaxJsonDepth)
    throw InputError(origin + ": arrays and objects nest deeper than " + std::to_string(limits::kMaxJsonDepth) +
                     " levels; expected a scene file");
  try {
    return Json::parse(text);
  } catch (const Json::exception& e) {
    // parse_error (syntax, invalid UTF-8) and out_of_range (numbers past double, such as 1e309).
    throw InputError(origin + ": not valid JSON (" + std::string(e.what()) + ")");
  }
}

SceneDesc parseSceneDesc(const Json& doc, const std::string& file) {
  if (!doc.is_object()) throw InputError(file + ": (top level): expected an object");
  static const char* known[] = {"camera", "render", "strategy", "volumes", "lights", "surfaces", "display", "description"};
  for (auto it = doc.begin(); it != doc.end(); ++it) {
    bool ok = false;
    for (const char* k : known) ok |= it.key() == k;
    if (!ok)
      throw InputError(file + ": " + it.key() +
                       ": unknown field (expected one of: camera, render, strategy, volumes, lights, surfaces, display, description)");
  }
  if (doc.contains("description") && !doc["description"].is_string())
    throw InputError(file + ": description: expected a string");
  SceneDesc scene;
  scene.path = file;
  if (doc.contains("description")) scene.description = doc["description"].get<std::string>();
  if (doc.contains("display")) fromJson(doc["display"], scene.display, file, "display");
  scene.display.autoExposure = !(doc.contains("display") && doc["display"].is_object() && doc["display"].contains("exposure"));
  if (!doc.contains("camera")) throw InputError(file + ": camera: required field is missing");
  fromJson(doc["camera"], scene.camera, file, "camera");
  if (doc.contains("render")) fromJson(doc["render"], scene.render, file, "render");
  // No strategy block: Candela chooses (auto_strategy.h), as it does for an opened VDB.
  scene.strategy = doc.contains("strategy") ? strategyFromJson(doc["strategy"], file, "strategy") : autoBaseStrategy();
  scene.volumes = readList<VolumeDesc>(doc, "volumes", file);
  scene.lights = readList<LightDesc>(doc, "lights", file);
  scene.surfaces = readList<SurfaceDesc>(doc, "surfaces", file);
  for (size_t i = 0; i < scene.volumes.size(); ++i) checkVolume(scene.volumes[i], file, "volumes." + std::to_string(i));
  for (size_t i = 0; i < scene.lights.size(); ++i) {
    const LightDesc& l = scene.lights[i];
    const double radiance = static_cast<double>(l.intensity) * maxComponent(l.color);
    if (radiance > limits::kMaxRadiance)
      throw InputError(file + ": lights." + std::to_string(i) + ".intensity: expected intensity x colour at most 1e12, got " +
                       std::to_string(radiance) + " (beyond what float arithmetic keeps finite)");
  }
  for (size_t i = 0; i < scene.lights.size(); ++i) {
    const LightDesc& l = scene.lights[i];
    if (l.type == LightType::Spot && l.cone_falloff_deg > l.cone_angle_deg)
      throw InputError(file + ": lights." + std::to_string(i) + ".cone_falloff_deg: expected at most cone_angle_deg");
    if ((l.type == LightType::Spot || l.type == LightType::Directional) && glm::length(l.direction) < 1e-6f)
      throw InputError(file + ": lights." + std::to_string(i) + ".direction: expected a non-zero vector");
  }
  for (size_t i = 0; i < scene.surfaces.size(); ++i) {
    const SurfaceDesc& s = scene.surfaces[i];
    if (s.type == SurfaceType::Box && !(s.min.x < s.max.x && s.min.y < s.max.y && s.min.z < s.max.z))
      throw InputError(file + ": surfaces." + std::to_string(i) + ".max: expected every component greater than min's");
  }
  const CameraDesc& c = scene.camera;
  const Vec3 forward = c.look_at - c.position;
  if (glm::length(forward) < 1e-6f) throw InputError(file + ": camera.look_at: expected a point other than camera.position");
  if (glm::length(c.up) < limits::kMinDirectionLength)
    throw InputError(file + ": camera.up: expected a direction of length at least 1e-6, got " + std::to_string(glm::length(c.up)));
  if (glm::length(glm::cross(forward, c.up)) < 1e-6f * glm::length(forward) * glm::length(c.up))
    throw InputError(file + ": camera.up: expected a direction not parallel to the view direction");
  return scene;
}

SceneDesc loadSceneDesc(const std::string& path, const std::vector<std::string>& settings, const std::string& preset) {
  try {
    Json doc = readSceneJson(path);
    if (!preset.empty()) doc["strategy"] = Json{{"preset", preset}};
    for (const auto& s : settings) applySetting(doc, s, path + " (--set " + s.substr(0, 80) + (s.size() > 80 ? "..." : "") + ")");
    return parseSceneDesc(doc, path);
  } catch (const InputError&) {
    throw;
  } catch (const std::bad_alloc&) {
    throw InputError(path + ": out of memory while reading the scene");
  } catch (const std::exception& e) {
    // Whatever a library throws still names the file.
    throw InputError(path + ": " + e.what());
  }
}

Json sceneToJson(const SceneDesc& scene) {
  Json doc = Json::object();
  if (!scene.description.empty()) doc["description"] = scene.description;
  doc["camera"] = toJson(scene.camera);
  doc["display"] = toJson(scene.display);
  if (scene.display.autoExposure) doc["display"].erase("exposure");
  doc["render"] = toJson(scene.render);
  doc["strategy"] = toJson(scene.strategy);
  doc["volumes"] = Json::array();
  for (const auto& v : scene.volumes) doc["volumes"].push_back(toJson(v));
  doc["lights"] = Json::array();
  for (const auto& l : scene.lights) doc["lights"].push_back(toJson(l));
  doc["surfaces"] = Json::array();
  for (const auto& s : scene.surfaces) doc["surfaces"].push_back(toJson(s));
  return doc;
}

std::vector<std::string> emissionWarnings(const VolumeDesc& v) {
  std::vector<std::string> out;
  const EmissionDesc& e = v.emission;
  if (e.mode == EmissionMode::None) return out;
  if (!(e.intensity > 0.0f)) out.push_back("emission.intensity is 0: the volume emits nothing");
  if (e.mode == EmissionMode::Grid && isBlack(e.color)) out.push_back("emission.color is black: the volume emits nothing");
  if (e.units == EmissionUnits::Radiance && average(v.albedo) >= 1.0f)
    out.push_back("albedo 1 with emission.units \"radiance\": the source (1 - albedo) sigma_t Le is 0, the volume emits nothing "
                  "(use units \"per_length\" to emit whatever the albedo)");
  else if (e.units == EmissionUnits::Radiance && v.sigma_t_scale <= 0.0f)
    out.push_back("sigma_t_scale 0 with emission.units \"radiance\": nothing absorbs, so nothing emits (use units \"per_length\")");
  return out;
}

SceneDesc saveSceneDesc(const SceneDesc& scene, const std::string& path) {
  namespace fs = std::filesystem;
  SceneDesc saved = scene;
  saved.path = path;
  // The folders the relative volume paths are read from and written to. A bare file name ("fire.json")
  // has an empty parent, which fs::absolute refuses: the file's own absolute path has the folder.
  const fs::path oldBase = fs::absolute(scene.path.empty() ? fs::path("scene.json") : fs::path(scene.path)).parent_path();
  const fs::path newBase = fs::absolute(path).parent_path();
  for (auto& v : saved.volumes) {
    if (v.file.empty() || fs::path(v.file).is_absolute()) continue;
    const fs::path target = (oldBase / v.file).lexically_normal();
    const fs::path relative = target.lexically_relative(newBase.lexically_normal());
    v.file = relative.empty() ? target.string() : relative.string();
  }
  try {
    writeTextAtomically(path, sceneToJson(saved).dump(2) + "\n");
  } catch (const std::exception& e) {
    throw InputError(std::string(e.what()) + " (the scene file was not written)");
  }
  return saved;
}

}  // namespace candela
