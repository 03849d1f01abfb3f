#include "probes.h"

#include "work.h"

#include "integrator.h"
#include "input_limits.h"
#include "phase.h"
#include "scene.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>

namespace candela {

namespace {

// Can any medium scatter near p (within r)? Checks the majorant cells at p and 6 points around it.
bool mayScatterNear(const Scene& scene, const Vec3& p, float r) {
  static const Vec3 offsets[7] = {{0, 0, 0}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const auto& m : scene.mediaOwned()) {
    if (!(m->albedoAverage() > 0.0f) || m->occupancyGrid().empty()) continue;
    const MajorantGrid& grid = m->occupancyGrid();
    for (const Vec3& o : offsets) {
      const Vec3 idx = Vec3(m->indexFromWorld() * glm::vec4(p + o * r, 1.0f));
      const Vec3 c = (idx - grid.origin()) / grid.cellExtent();
      if (glm::any(glm::lessThan(c, Vec3(0.0f))) || glm::any(glm::greaterThanEqual(c, Vec3(grid.resolution())))) continue;
      const glm::ivec3 cell(c);
      if (grid.maxDensity(grid.cellIndex(cell.x, cell.y, cell.z)) > 0.0f) return true;
    }
  }
  return false;
}

}  // namespace

Vec3 uniformInBall(const Vec3& center, float radius, Rng& rng) {
  Vec3 y;
  do {
    y = Vec3(rng.uniform(), rng.uniform(), rng.uniform()) * 2.0f - 1.0f;
  } while (glm::dot(y, y) > 1.0f);
  return center + y * radius;
}

std::shared_ptr<const ProbeSet> ProbeSet::learn(const Scene& scene, const GuidingSettings& settings, const std::atomic<bool>* cancel) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  auto set = std::make_shared<ProbeSet>();
  Vec3 lo(kInfinity), hi(-kInfinity);
  for (const auto& m : scene.mediaOwned()) {
    Vec3 a, b;
    m->worldBounds(a, b);
    lo = glm::min(lo, a);
    hi = glm::max(hi, b);
  }
  if (!(lo.x <= hi.x)) return set;
  const Vec3 extent = hi - lo;
  set->spacing_ = settings.probe_spacing > 0.0f ? settings.probe_spacing : std::max({extent.x, extent.y, extent.z}) / 20.0f;
  set->radius_ = settings.probe_radius * set->spacing_;
  // The lattice is bounded before any allocation: a tiny spacing over a large volume would
  // otherwise take minutes and gigabytes (input_limits.h).
  const Vec3 cells = glm::ceil(extent / set->spacing_);
  const double lattice = static_cast<double>(cells.x) * cells.y * cells.z;
  if (!(lattice <= limits::kMaxProbes))
    throw InputError(scene.desc().path + ": strategy.guiding.probe_spacing: " + std::to_string(set->spacing_) + " gives a lattice of " +
                     std::to_string(lattice) + " probes over the volumes' extent; expected at most 4e6 (raise the spacing, or 0: automatic)");
  const glm::ivec3 count = glm::max(glm::ivec3(cells), glm::ivec3(1));
  std::vector<Vec3> centers;
  for (int z = 0; z < count.z; ++z)
    for (int y = 0; y < count.y; ++y)
      for (int x = 0; x < count.x; ++x) {
        const Vec3 p = lo + (Vec3(x, y, z) + 0.5f) * set->spacing_;
        if (mayScatterNear(scene, p, set->radius_)) centers.push_back(p);
      }
  set->placed_ = static_cast<int>(centers.size());

  // Each light's direction for the phase applied at lookup (ProbeLight).
  for (const Light& l : scene.lights()) {
    ProbeLight pl;
    switch (l.type()) {
      case LightType::Directional: {
        LightSample ls;
        if (l.sample(scene.center(), Vec2(0.5f), ls)) pl = {ProbeLight::Kind::Direction, ls.wi};
        break;
      }
      case LightType::Point:
      case LightType::Spot:
      case LightType::Sphere: pl = {ProbeLight::Kind::Position, l.desc().position}; break;
      case LightType::Environment: break;
    }
    set->lights_.push_back(pl);
  }
  for (const EmissionLight* v : scene.volumeLights()) set->lights_.push_back({ProbeLight::Kind::Position, v->centroid()});
  const size_t lightCount = set->lights_.size();

  // Learn in parallel, every probe with the same sample count and its own random stream, so the set
  // is the same whatever the thread count or machine load. A probe not started before the safety
  // cap (or a cancel) is dropped; complete() then says so and callers warn.
  const PathTracer tracer(scene);
  const auto deadline = start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(settings.probe_time_cap_s));
  std::vector<float> weights(centers.size() * lightCount, 0.0f), gs(centers.size(), 0.0f);
  std::vector<char> learned(centers.size(), 0);
  tbb::parallel_for(size_t{0}, centers.size(), [&](size_t i) {
    if ((cancel && cancel->load()) || Clock::now() > deadline) return;
    Rng rng(hashCombine(scene.desc().render.seed, 0x9e0be5ULL), i);
    std::vector<double> sums(lightCount, 0.0);
    double sigmaSSum = 0.0, gSum = 0.0;
    for (int s = 0; s < settings.probe_samples; ++s) {
      const Vec3 y = uniformInBall(centers[i], set->radius_, rng);
      const Scene::PointCoefficients c = scene.coefficientsAt(y);
      if (!(c.sigmaS > 0.0f)) continue;
      sigmaSSum += c.sigmaS;
      gSum += c.sigmaS * c.pick(scene, rng.uniform()).g();
      for (size_t l = 0; l < lightCount; ++l) sums[l] += c.sigmaS * tracer.unphasedIncident(y, static_cast<int>(l), rng);
    }
    bool finite = true;
    for (size_t l = 0; l < lightCount; ++l) {
      const float u = static_cast<float>(sums[l] / settings.probe_samples);
      finite = finite && std::isfinite(u);
      weights[i * lightCount + l] = std::max(0.0f, u);
    }
    gs[i] = sigmaSSum > 0.0 ? static_cast<float>(gSum / sigmaSSum) : 0.0f;
    learned[i] = finite;
  });
  for (size_t i = 0; i < centers.size(); ++i) {
    if (!learned[i]) continue;
    set->probes_.push_back({centers[i], gs[i]});
    set->weights_.insert(set->weights_.end(), weights.begin() + static_cast<std::ptrdiff_t>(i * lightCount),
                         weights.begin() + static_cast<std::ptrdiff_t>((i + 1) * lightCount));
  }
  set->buildLookup(lo);
  set->seconds_ = std::chrono::duration<double>(Clock::now() - start).count();
  return set;
}

std::string ProbeSet::incompleteWarning() const {
  if (complete()) return {};
  return "strategy.guiding.probe_time_cap_s: probe learning was cut by its safety cap after " + std::to_string(seconds_) + " s (" +
         std::to_string(probes_.size()) + " of " + std::to_string(placed_) +
         " probes learned): the noise of this render now depends on machine speed; raise the cap or lower "
         "strategy.guiding.probe_samples";
}

void ProbeSet::buildLookup(const Vec3& latticeOrigin) {
  cellStart_.clear();
  cellProbes_.clear();
  if (probes_.empty()) return;
  // Lookup cells coincide with the probe lattice's cells (shifted to cover the spheres), so with a
  // radius of at most half the spacing each probe lives in exactly one cell: its own.
  Vec3 lo(kInfinity), hi(-kInfinity);
  for (const auto& p : probes_) lo = glm::min(lo, p.center), hi = glm::max(hi, p.center);
  lo = latticeOrigin + glm::floor((lo - radius_ - latticeOrigin) / spacing_) * spacing_;
  hi += radius_;
  lookup_.origin = lo;
  lookup_.cellExtent = Vec3(spacing_);
  lookup_.res = glm::max(glm::ivec3(glm::ceil((hi - lo) / spacing_)), glm::ivec3(1));
  std::vector<std::vector<uint32_t>> lists(lookup_.cellCount());
  for (uint32_t i = 0; i < probes_.size(); ++i) {
    // Shrunk by a hair: a sphere touching a cell face at one point cannot be crossed there.
    const float r = radius_ * (1.0f - 1e-4f);
    const glm::ivec3 a = glm::clamp(glm::ivec3(glm::floor((probes_[i].center - r - lo) / spacing_)), glm::ivec3(0), lookup_.res - 1);
    const glm::ivec3 b = glm::clamp(glm::ivec3(glm::floor((probes_[i].center + r - lo) / spacing_)), glm::ivec3(0), lookup_.res - 1);
    for (int z = a.z; z <= b.z; ++z)
      for (int y = a.y; y <= b.y; ++y)
        for (int x = a.x; x <= b.x; ++x) lists[static_cast<size_t>(lookup_.cellIndex(x, y, z))].push_back(i);
  }
  cellStart_.push_back(0);
  for (const auto& l : lists) {
    cellProbes_.insert(cellProbes_.end(), l.begin(), l.end());
    cellStart_.push_back(static_cast<uint32_t>(cellProbes_.size()));
  }
}

float ProbeSet::weight(size_t probe, const Vec3& wo, const Vec3& x) const {
  const float g = probes_[probe].g;
  const float* u = &weights_[probe * lights_.size()];
  float s = 0.0f;
  for (size_t l = 0; l < lights_.size(); ++l) {
    if (!(u[l] > 0.0f)) continue;
    const ProbeLight& light = lights_[l];
    switch (light.kind) {
      case ProbeLight::Kind::Direction: s += u[l] * hgEval(wo, light.v, g); break;
      case ProbeLight::Kind::Position: {
        const Vec3 d = light.v - x;
        const float len = glm::length(d);
        s += u[l] * (len > 0.0f ? hgEval(wo, d / len, g) : kInv4Pi);
        break;
      }
      case ProbeLight::Kind::Diffuse: s += u[l] * kInv4Pi; break;
    }
  }
  return s;
}

void ProbeSet::gatherKnots(const Ray& ray, float t0, float t1, std::vector<DistanceKnot>& knots) const {
  // No lights (and no emission): no probe has a weight, and the guide is its uniform floor.
  if (probes_.empty() || lights_.empty()) return;
  // A probe overlaps several cells; per-thread stamps keep one knot per probe in O(1).
  thread_local std::vector<uint32_t> stamps;
  thread_local uint32_t query = 0;
  if (stamps.size() < probes_.size()) stamps.assign(probes_.size(), 0);
  if (++query == 0) {
    std::fill(stamps.begin(), stamps.end(), 0);
    query = 1;
  }
  MajorantDda dda(lookup_, ray.origin, ray.direction, std::max(0.0f, t0 - radius_), t1 + radius_);
  float c0, c1;
  int cell;
  const float r2 = radius_ * radius_;
  while (dda.next(c0, c1, cell)) {
    for (uint32_t k = cellStart_[static_cast<size_t>(cell)]; k < cellStart_[static_cast<size_t>(cell) + 1]; ++k) {
      const uint32_t index = cellProbes_[k];
      if (stamps[index] == query) continue;
      stamps[index] = query;
      const Probe& p = probes_[index];
      const float t = glm::dot(p.center - ray.origin, ray.direction);
      const Vec3 x = ray.at(t);
      const Vec3 off = x - p.center;
      if (glm::dot(off, off) > r2 || t < t0 - radius_ || t > t1 + radius_) continue;
      knots.push_back({t, weight(index, -ray.direction, x)});
      ++threadWork().knots;
    }
  }
}

}  // namespace candela
