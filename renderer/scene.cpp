#include "scene.h"

#include "input_limits.h"
#include "procedural.h"
#include "vdb_io.h"

#include <deque>
#include <filesystem>
#include "sequence.h"
#include <mutex>

namespace candela {

Camera::Camera(const CameraDesc& d) : width_(d.resolution.first), height_(d.resolution.second) {
  origin_ = d.position;
  forward_ = glm::normalize(d.look_at - d.position);
  right_ = glm::normalize(glm::cross(forward_, d.up));
  up_ = glm::cross(right_, forward_);
  tanHalf_ = std::tan(glm::radians(d.fov_y) * 0.5f);
  aspect_ = static_cast<float>(width_) / static_cast<float>(height_);
  fullWidth_ = static_cast<float>(width_), fullHeight_ = static_cast<float>(height_);
}

Ray Camera::generate(float x, float y) const {
  const float sx = (2.0f * (x + offsetX_) / fullWidth_ - 1.0f) * tanHalf_ * aspect_;
  const float sy = (1.0f - 2.0f * (y + offsetY_) / fullHeight_) * tanHalf_;
  return Ray{origin_, glm::normalize(forward_ + sx * right_ + sy * up_)};
}

Camera Camera::window(int x0, int y0, int w, int h) const {
  Camera c = *this;
  c.offsetX_ = offsetX_ + static_cast<float>(x0), c.offsetY_ = offsetY_ + static_cast<float>(y0);
  c.width_ = w, c.height_ = h;
  return c;
}

Scene::Scene(const SceneDesc& desc) : desc_(desc), camera_(desc.camera) {}

namespace {

// Grids loaded recently, keyed by file, grid names and modification time. Live edits of a volume's
// parameters rebuild the scene; this keeps them from re-reading and re-converting the VDB each time.
std::vector<LoadedGrid> loadGridsCached(const std::string& path, const std::vector<std::string>& names, const std::string& field) {
  static std::mutex mutex;
  static std::deque<std::pair<std::string, std::vector<LoadedGrid>>> cache;
  std::error_code ec;
  const auto stamp = std::filesystem::last_write_time(path, ec);
  std::string key = path + "|" + std::to_string(ec ? 0 : stamp.time_since_epoch().count());
  for (const auto& n : names) key += "|" + n;
  {
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& [k, grids] : cache)
      if (k == key) return grids;
  }
  std::vector<LoadedGrid> grids = loadVdbGrids(path, names, field);
  std::lock_guard<std::mutex> lock(mutex);
  cache.emplace_back(key, grids);
  if (cache.size() > 8) cache.pop_front();
  return grids;
}

}  // namespace

void prefetchSceneGrids(const SceneDesc& desc) {
  for (size_t i = 0; i < desc.volumes.size(); ++i) {
    const VolumeDesc& v = desc.volumes[i];
    if (v.has_generator) continue;
    const std::string path = volumeFilePath(desc, v, desc.render.frame);
    std::vector<std::string> names{v.density_grid};
    if (v.emission.mode == EmissionMode::Blackbody) names.push_back(v.temperature_grid);
    if (v.emission.mode == EmissionMode::Grid) names.push_back(v.emission_grid);
    loadGridsCached(path, names, "volumes." + std::to_string(i));
  }
}

// A medium the renderer can track (input_limits.h): finite world placement, voxels of a sane size,
// and no voxel so dense that tracking steps vanish below float precision. Checked before majorants
// (sized by the active box) are built.
void checkRepresentable(const Medium& m, const std::string& where, const StrategySettings& strategy) {
  const float voxel = m.voxelSize();
  if (!(voxel >= limits::kMinVoxelSize && voxel <= limits::kMaxVoxelSize))
    throw InputError(where + ".transform.scale: voxels end up " + std::to_string(voxel) +
                     " world units wide (the VDB's voxel size times the scale); expected between 1e-6 and 1e6");
  const Mat4& w = m.worldFromIndex();
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      if (!std::isfinite(w[i][j])) throw InputError(where + ".transform: the index-to-world transform is not finite");
  const MajorantGrid& grid = m.majorantGrid();
  if (grid.empty()) return;
  Vec3 lo, hi;
  m.worldBounds(lo, hi);
  if (maxComponent(glm::max(glm::abs(lo), glm::abs(hi))) > 10.0 * limits::kMaxCoordinate)
    throw InputError(where + ".transform: the volume reaches " + std::to_string(maxComponent(glm::max(glm::abs(lo), glm::abs(hi)))) +
                     " world units from the origin; expected within 1e7");
  float densest = 0.0f;
  for (float d : grid.maxDensities()) densest = std::max(densest, d);
  const double depth = static_cast<double>(densest) * m.sigmaTScale() * voxel;
  if (!(depth <= limits::kMaxOpticalDepthPerVoxel))
    throw InputError(where + ".sigma_t_scale: the densest voxel (" + std::to_string(densest) + " x sigma_t_scale " +
                     std::to_string(m.sigmaTScale()) + ") has an optical depth of " + std::to_string(depth) +
                     " per voxel; expected at most 1e4 (lower sigma_t_scale or the grid's values)");
  // The majorant grid at the finest cell size the strategy may ask for.
  const Vec3 extent = grid.cellExtent() * Vec3(grid.resolution());
  const double cells = static_cast<double>(extent.x) * extent.y * extent.z / std::pow(std::max(1, strategy.majorant.cell_size), 3);
  checkMemoryBudget(cells * 8.0, where, "the majorant grid at strategy.majorant.cell_size " + std::to_string(strategy.majorant.cell_size));
}

std::shared_ptr<Scene> Scene::build(const SceneDesc& desc, std::vector<std::string>* warnings,
                                    std::shared_ptr<const ProbeSet> servingProbes) {
  namespace fs = std::filesystem;
  if (desc.volumes.size() > static_cast<size_t>(kMaxMedia))
    throw InputError(desc.path + ": volumes: expected at most " + std::to_string(kMaxMedia) + " volumes");
  std::shared_ptr<Scene> scene(new Scene(desc));
  const fs::path base = desc.path.empty() ? fs::path(".") : fs::path(desc.path).parent_path();
  for (size_t i = 0; i < desc.volumes.size(); ++i) {
    const VolumeDesc& v = desc.volumes[i];
    const std::string field = "volumes." + std::to_string(i);
    std::string path;
    std::string density = v.density_grid, temperature = v.temperature_grid, emission = v.emission_grid;
    if (v.has_generator) {
      try {
        path = cachedGeneratedVolume(v.generator);
      } catch (const InputError& e) {
        throw InputError(desc.path + ": " + field + ".generator: " + e.what());
      }
      density = "density";
      const bool hasTemperature = v.generator.type == "torch" || v.generator.type == "plume" || v.generator.temperature > 0.0f;
      temperature = hasTemperature ? "temperature" : "";
      emission.clear();
      if (v.emission.mode == EmissionMode::Blackbody && !hasTemperature)
        throw InputError(desc.path + ": " + field + ".emission.mode: \"blackbody\" needs a temperature grid; generator \"" +
                         v.generator.type + "\" makes none (set generator.temperature > 0, or use a torch or plume)");
      if (v.emission.mode == EmissionMode::Grid)
        throw InputError(desc.path + ": " + field + ".emission.mode: generators make no emission grid; expected \"none\" or \"blackbody\"");
    } else {
      path = volumeFilePath(desc, v, desc.render.frame);  // fire.####.vdb: this scene's frame
    }
    std::vector<std::string> names{density};
    if (v.emission.mode == EmissionMode::Blackbody) names.push_back(temperature);
    if (v.emission.mode == EmissionMode::Grid) names.push_back(emission);
    std::vector<LoadedGrid> grids;
    try {
      grids = loadGridsCached(path, names, field);
    } catch (const InputError& e) {
      // Name the scene file too: the user edits that, and it says which volume asked for the VDB.
      throw InputError(desc.path + ": " + field + (v.has_generator ? ".generator" : ".file") + ": " + e.what());
    }
    for (const LoadedGrid& g : grids) {
      if (warnings && g.fromLevelSet)
        warnings->push_back(path + ": " + field + ": grid \"" + g.grid.name() +
                            "\" is a level set (a signed distance field): rendered as the fog volume it bounds, density 1 inside "
                            "the surface falling to 0 across the narrow band");
      if (warnings && g.sanitizedVoxels > 0)
        warnings->push_back(path + ": " + field + ": grid \"" + g.grid.name() + "\" had " + std::to_string(g.sanitizedVoxels) +
                            " NaN, infinite or negative values; they were set to 0");
    }
    VoxelGrid temperatureGrid, emissionGrid;
    if (v.emission.mode == EmissionMode::Blackbody) temperatureGrid = grids[1].grid;
    if (v.emission.mode == EmissionMode::Grid) emissionGrid = grids[1].grid;
    std::vector<LoadedGrid> color;
    if (v.emission.mode == EmissionMode::Grid && !v.color_grid.empty() && !v.has_generator) {
      try {
        color = loadVdbVectorGrid(path, v.color_grid, field + ".color_grid");
      } catch (const InputError& e) {
        throw InputError(desc.path + ": " + e.what());
      }
    }
    auto medium = std::make_unique<Medium>(v, grids[0].grid, temperatureGrid, emissionGrid);
    if (color.size() == 3) medium->setColorGrids(color[0].grid, color[1].grid, color[2].grid);
    checkRepresentable(*medium, desc.path + ": " + field, desc.strategy);
    if (medium->majorantGrid().empty() && warnings)
      warnings->push_back(path + ": " + field + ": grid \"" + density + "\" has no active voxels; the volume is empty");
    if (warnings)
      for (const std::string& w : emissionWarnings(v)) warnings->push_back(desc.path + ": " + field + ": " + w);
    // Per unit length the emission (a flame grid, or the temperature that drives blackbody) may reach
    // past the density grid; the renderer tracks the density grid's box only (docs/conventions.md).
    // The grids may have transforms of their own (a temperature at half the resolution): the
    // emission grid's extreme voxel centres are compared in the density grid's index space.
    // Only voxels above 0 emit (a temperature grid's ambient 0 around the fire does not).
    if (warnings && v.emission.units == EmissionUnits::PerLength && grids.size() > 1 && !grids[1].positiveBox.empty() &&
        !grids[0].grid.activeBox().empty()) {
      const IndexBox e = grids[1].positiveBox, d = grids[0].grid.activeBox();
      const Mat4 densityFromEmission = glm::inverse(grids[0].grid.worldFromIndex()) * grids[1].grid.worldFromIndex();
      bool outside = false;
      for (int c = 0; c < 8 && !outside; ++c) {
        const Vec3 p(densityFromEmission * glm::vec4(boxCorner(Vec3(e.min), Vec3(e.max), c), 1.0f));
        outside = glm::any(glm::lessThan(p, Vec3(d.min) - 0.5f)) || glm::any(glm::greaterThan(p, Vec3(d.max) + 0.5f));
      }
      if (outside)
        warnings->push_back(desc.path + ": " + field + ": the " + (v.emission.mode == EmissionMode::Grid ? "emission" : "temperature") +
                            " grid \"" + grids[1].grid.name() +
                            "\" reaches outside the density grid's bounding box; emission there is not rendered");
    }
    medium->setIndex(static_cast<int>(i));
    medium->applyStrategy(desc.strategy);
    scene->hasEmissiveMedia_ |= medium->emissive();
    scene->hasPerLengthEmission_ |= medium->emitsPerLength();
    scene->media_.push_back(std::move(medium));
  }
  for (const auto& m : scene->media_) scene->mediaView_.media.push_back(m.get());

  // Scene extent: the media, else the finite surfaces, else around the camera's target.
  Vec3 lo(kInfinity), hi(-kInfinity);
  for (const auto& m : scene->media_) {
    Vec3 a, b;
    m->worldBounds(a, b);
    lo = glm::min(lo, a);
    hi = glm::max(hi, b);
  }
  for (const auto& s : desc.surfaces) {
    if (s.type == SurfaceType::Box) lo = glm::min(lo, s.min), hi = glm::max(hi, s.max);
    if (s.type == SurfaceType::Sphere || s.type == SurfaceType::Cylinder) {
      lo = glm::min(lo, s.center - Vec3(s.radius));
      hi = glm::max(hi, s.center + Vec3(s.radius) + Vec3(0.0f, s.type == SurfaceType::Cylinder ? s.length : 0.0f, 0.0f));
    }
  }
  if (lo.x <= hi.x) {
    scene->boundsMin_ = lo, scene->boundsMax_ = hi;
    scene->center_ = 0.5f * (lo + hi);
    scene->radius_ = std::max(1e-3f, 0.5f * glm::length(hi - lo));
  } else {
    scene->center_ = desc.camera.look_at;
    scene->radius_ = std::max(1e-3f, glm::length(desc.camera.look_at - desc.camera.position));
  }
  for (const auto& l : desc.lights) {
    scene->lights_.emplace_back(l);
    scene->sunLit_ |= l.type == LightType::Directional && luminance(l.color) * l.intensity > 0.0f;
  }
  scene->buildLightSampler();
  // A light whose power float cannot hold would be dropped by the light sampler: an error instead.
  for (size_t i = 0; i < scene->lights_.size(); ++i)
    if (!std::isfinite(scene->lights_[i].power(scene->radius_)))
      throw InputError(desc.path + ": lights." + std::to_string(i) + ".intensity: the light's power is not finite at this scene size");
  for (size_t i = 0; i < scene->media_.size(); ++i)
    if (const EmissionLight* e = scene->media_[i]->emissionLight(); e && !std::isfinite(e->power()))
      throw InputError(desc.path + ": volumes." + std::to_string(i) + ".emission.intensity: the emitted power is not finite");
  // The film and its per-pixel tables, before any of them is allocated.
  const auto [width, height] = desc.camera.resolution;
  // Auto may choose probes; adaptive sampling keeps per-pixel figures (sample_allocation.h).
  const bool mayGuide = desc.strategy.guiding.guide != DistanceGuide::None || desc.strategy.preset == "auto";
  const bool adaptive = desc.strategy.adaptive_split > 1 || desc.strategy.preset == "auto";
  checkMemoryBudget(static_cast<double>(width) * height * ((mayGuide ? 320.0 : 64.0) + (adaptive ? 48.0 : 0.0)),
                    desc.path + ": camera.resolution", "an image of " + std::to_string(width) + " x " + std::to_string(height));
  scene->surfaces_ = std::make_unique<Surfaces>(desc.surfaces);
  if (desc.strategy.guiding.guide == DistanceGuide::Probes) {
    if (servingProbes) {
      std::atomic_store(&scene->probes_, servingProbes);
      scene->relearnProbesAsync();
    } else {
      scene->learnProbes();
      if (warnings && !scene->probes()->complete()) warnings->push_back(scene->probes()->incompleteWarning());
    }
  }
  // auto: rules and a pilot decide (after the scene is complete: the pilot renders it).
  if (needsAutoResolve(desc.strategy)) {
    scene->autoDecision_ = resolveAutoStrategy(*scene);
    if (warnings && scene->probes() && !scene->probes()->complete()) warnings->push_back(scene->probes()->incompleteWarning());
  }
  return scene;
}

Scene::PointCoefficients Scene::coefficientsAt(const Vec3& p) const {
  PointCoefficients c;
  for (size_t i = 0; i < media_.size(); ++i) {
    const Medium& m = *media_[i];
    const Vec3 idx = Vec3(m.indexFromWorld() * glm::vec4(p, 1.0f));
    const float sigmaT = Medium::Sampler(m).sigmaT(idx);
    c.shares[i] = sigmaT * m.albedoAverage();
    c.sigmaS += c.shares[i];
    c.sigmaT += sigmaT;
    c.muBar += m.majorantAt(idx);
  }
  return c;
}

const Medium& Scene::PointCoefficients::pick(const Scene& scene, float u) const {
  const auto& media = scene.mediaOwned();
  float x = u * sigmaS;
  for (size_t i = 0; i < media.size(); ++i) {
    if (x < shares[i]) return *media[i];
    x -= shares[i];
  }
  return *media.back();
}

void Scene::setStrategy(const StrategySettings& strategy) {
  cancelProbes_ = true;  // a background relearn reads the media being changed here
  waitForProbes();
  const GuidingSettings before = desc_.strategy.guiding;
  desc_.strategy = strategy;
  for (auto& m : media_) m->applyStrategy(strategy);
  buildLightSampler();
  const GuidingSettings& g = strategy.guiding;
  const bool probeSettingsChanged = before.probe_spacing != g.probe_spacing || before.probe_radius != g.probe_radius ||
                                    before.probe_samples != g.probe_samples || before.probe_time_cap_s != g.probe_time_cap_s;
  if (g.guide == DistanceGuide::Probes && (!probes() || probeSettingsChanged)) learnProbes();
}

void Scene::applyStrategy(const StrategySettings& strategy) {
  // The preset "auto" as chosen decides again, unless it is what this scene already decided.
  const bool sameAsDecided = autoDecision_ && toJson(strategy) == toJson(desc_.strategy);
  if (needsAutoResolve(strategy) && !sameAsDecided) {
    autoDecision_ = resolveAutoStrategy(*this);
    return;
  }
  if (strategy.preset != "auto") autoDecision_.reset();
  setStrategy(strategy);
}

void Scene::learnProbes() {
  waitForProbes();
  std::atomic_store(&probes_, ProbeSet::learn(*this, desc_.strategy.guiding));
}

void Scene::relearnProbesAsync() {
  cancelProbes_ = true;
  waitForProbes();
  cancelProbes_ = false;
  probeThread_ = std::thread([this] {
    auto fresh = ProbeSet::learn(*this, desc_.strategy.guiding, &cancelProbes_);
    if (!cancelProbes_) std::atomic_store(&probes_, fresh);
  });
}

void Scene::waitForProbes() {
  if (probeThread_.joinable()) probeThread_.join();
}

void Scene::setCamera(const CameraDesc& camera) {
  // Probes hold no camera-dependent term (the phase is applied per ray: probes.h), so they stay.
  desc_.camera = camera;
  camera_ = Camera(camera);
}

Scene::~Scene() {
  cancelProbes_ = true;
  waitForProbes();
}

void Scene::buildLightSampler() {
  // Lights and emissive volumes compete by their estimated fluence at the shading point (talk 2.1:
  // emissive volumes are lights).
  std::vector<LightImportance> importance;
  for (const Light& l : lights_) importance.push_back(l.importance());
  volumeLights_.clear();
  for (const auto& m : media_)
    if (const EmissionLight* e = m->emissionLight(); e && !e->empty()) {
      volumeLights_.push_back(e);
      importance.push_back(e->importance());
    }
  lightSampler_ = LightSampler(std::move(importance));
}

}  // namespace candela
