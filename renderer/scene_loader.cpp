#include "scene_desc.h"

#include <fstream>
#include <sstream>

namespace candela {

namespace {

template <class S>
std::vector<S> readList(const Json& doc, const char* key, const std::string& file) {
  std::vector<S> out;
  if (!doc.contains(key)) return out;
  const Json& list = doc[key];
  if (!list.is_array()) throw InputError(file + ": " + key + ": expected an array, got " + list.dump().substr(0, 60));
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
  if (v.emission.mode == EmissionMode::Blackbody && !v.has_generator && v.temperature_grid.empty())
    throw InputError(file + ": " + path + ".temperature_grid: expected a grid name, since emission.mode is \"blackbody\"");
  if (v.emission.mode == EmissionMode::Grid && !v.has_generator && v.emission_grid.empty())
    throw InputError(file + ": " + path + ".emission_grid: expected a grid name, since emission.mode is \"grid\"");
}

}  // namespace

Json readSceneJson(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open the scene file");
  std::stringstream ss;
  ss << in.rdbuf();
  try {
    return Json::parse(ss.str());
  } catch (const Json::parse_error& e) {
    throw InputError(path + ": not valid JSON (" + std::string(e.what()) + ")");
  }
}

SceneDesc parseSceneDesc(const Json& doc, const std::string& file) {
  if (!doc.is_object()) throw InputError(file + ": (top level): expected an object");
  static const char* known[] = {"camera", "render", "strategy", "volumes", "lights", "surfaces", "description"};
  for (auto it = doc.begin(); it != doc.end(); ++it) {
    bool ok = false;
    for (const char* k : known) ok |= it.key() == k;
    if (!ok)
      throw InputError(file + ": " + it.key() +
                       ": unknown field (expected one of: camera, render, strategy, volumes, lights, surfaces, description)");
  }
  if (doc.contains("description") && !doc["description"].is_string())
    throw InputError(file + ": description: expected a string");
  SceneDesc scene;
  scene.path = file;
  if (!doc.contains("camera")) throw InputError(file + ": camera: required field is missing");
  fromJson(doc["camera"], scene.camera, file, "camera");
  if (doc.contains("render")) fromJson(doc["render"], scene.render, file, "render");
  if (doc.contains("strategy")) scene.strategy = strategyFromJson(doc["strategy"], file, "strategy");
  scene.volumes = readList<VolumeDesc>(doc, "volumes", file);
  scene.lights = readList<LightDesc>(doc, "lights", file);
  scene.surfaces = readList<SurfaceDesc>(doc, "surfaces", file);
  for (size_t i = 0; i < scene.volumes.size(); ++i) checkVolume(scene.volumes[i], file, "volumes." + std::to_string(i));
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
  if (glm::length(glm::cross(forward, c.up)) < 1e-6f * glm::length(forward) * glm::length(c.up))
    throw InputError(file + ": camera.up: expected a direction not parallel to the view direction");
  return scene;
}

SceneDesc loadSceneDesc(const std::string& path, const std::vector<std::string>& settings, const std::string& preset) {
  Json doc = readSceneJson(path);
  if (!preset.empty()) doc["strategy"] = Json{{"preset", preset}};
  for (const auto& s : settings) applySetting(doc, s, path + " (--set " + s + ")");
  return parseSceneDesc(doc, path);
}

Json sceneToJson(const SceneDesc& scene) {
  Json doc = Json::object();
  doc["camera"] = toJson(scene.camera);
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

}  // namespace candela
