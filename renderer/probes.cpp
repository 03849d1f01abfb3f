#include "probes.h"

#include "integrator.h"
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
    if (!(m->albedoAverage() > 0.0f) || m->majorantGrid().empty()) continue;
    const MajorantGrid& grid = m->majorantGrid();
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
  const glm::ivec3 count = glm::max(glm::ivec3(glm::ceil(extent / set->spacing_)), glm::ivec3(1));
  std::vector<Vec3> centers;
  for (int z = 0; z < count.z; ++z)
    for (int y = 0; y < count.y; ++y)
      for (int x = 0; x < count.x; ++x) {
        const Vec3 p = lo + (Vec3(x, y, z) + 0.5f) * set->spacing_;
        if (mayScatterNear(scene, p, set->radius_)) centers.push_back(p);
      }
  set->placed_ = static_cast<int>(centers.size());

  // Learn in parallel; a probe not started before the deadline (or a cancel) is dropped.
  const PathTracer tracer(scene);
  const Vec3 camera = scene.desc().camera.position;
  const auto deadline = start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(settings.probe_budget_s));
  std::vector<float> weights(centers.size(), -1.0f), isotropic(centers.size(), 0.0f);
  tbb::parallel_for(size_t{0}, centers.size(), [&](size_t i) {
    if ((cancel && cancel->load()) || Clock::now() > deadline) return;
    Rng rng(hashCombine(scene.desc().render.seed, 0x9e0be5ULL), i);
    double sum = 0.0, sumIsotropic = 0.0;
    for (int s = 0; s < settings.probe_samples; ++s) {
      // y uniform in the ball of radius r around the probe.
      Vec3 y;
      do {
        y = Vec3(rng.uniform(), rng.uniform(), rng.uniform()) * 2.0f - 1.0f;
      } while (glm::dot(y, y) > 1.0f);
      y = centers[i] + y * set->radius_;
      const Scene::PointCoefficients c = scene.coefficientsAt(y);
      if (!(c.sigmaS > 0.0f)) continue;
      const float g = c.pick(scene, rng.uniform()).g();
      const Vec3 toCamera = camera - y;
      const float dist = glm::length(toCamera);
      if (!(dist > 0.0f)) continue;
      sum += c.sigmaS * luminance(tracer.inScattered(y, toCamera / dist, g, rng));
      sumIsotropic += c.sigmaS * luminance(tracer.inScattered(y, toCamera / dist, 0.0f, rng));
    }
    weights[i] = static_cast<float>(sum / settings.probe_samples);
    isotropic[i] = static_cast<float>(sumIsotropic / settings.probe_samples);
  });
  for (size_t i = 0; i < centers.size(); ++i)
    if (weights[i] >= 0.0f && std::isfinite(weights[i]) && std::isfinite(isotropic[i]))
      set->probes_.push_back({centers[i], weights[i], isotropic[i]});
  set->buildLookup(lo);
  set->seconds_ = std::chrono::duration<double>(Clock::now() - start).count();
  return set;
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

void ProbeSet::gatherKnots(const Ray& ray, float t0, float t1, bool cameraRay, std::vector<DistanceKnot>& knots) const {
  if (probes_.empty()) return;
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
      const Vec3 off = ray.at(t) - p.center;
      if (glm::dot(off, off) > r2 || t < t0 - radius_ || t > t1 + radius_) continue;
      knots.push_back({t, cameraRay ? p.weight : p.isotropicWeight});
    }
  }
}

}  // namespace candela
