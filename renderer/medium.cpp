#include "medium.h"

#include <glm/gtc/matrix_transform.hpp>

#include "work.h"

#include <algorithm>
#include <utility>

namespace candela {

namespace {

// How many times cell_size a medium's majorant cells should be (1, 2, 4, ...): the factor with the
// least expected work per unit length of a ray, by the work model (work.h). A ray crosses about 1.5
// cell planes per cell length (the mean of |dx| + |dy| + |dz| over directions), each a DDA segment,
// and meets the cell's majorant times its length in (null) collisions; the mean majorant over the
// cells stands for the cells a ray crosses. Coarser cells trade segments for collisions, which only
// pays in thin media: in a cloud, fine cells keep the null collisions few (measured: the cloud
// scene's work rose 12% at 2x cells, which the model called 3% cheaper).
// Returns the factor and leaves the coarsened grid in `chosen` (untouched when the factor is 1).
int coarsenForWork(const MajorantGrid& fine, float cellSize, float collisionsPerUnitDensity, MajorantGrid& chosen) {
  // Work per voxel length of ray.
  auto work = [&](const MajorantGrid& grid, int factor) {
    double mean = 0.0;
    for (float m : grid.maxDensities()) mean += m;
    mean /= static_cast<double>(std::max<size_t>(1, grid.cellCount()));
    return WorkCost::kSegment * 1.5 / (cellSize * factor) + WorkCost::kCollision * mean * collisionsPerUnitDensity;
  };
  int best = 1;
  double bestWork = work(fine, 1);
  for (int factor = 2, cells = static_cast<int>(fine.cellCount()); cells > 1; factor *= 2) {
    MajorantGrid grid = fine.coarsened(factor);
    cells = static_cast<int>(grid.cellCount());
    // A coarser grid must save a tenth: the work model's fits are good to about 20%, and a cloud's
    // dense core, where its walks end, holds more collisions than the mean says.
    if (const double w = work(grid, factor); w < 0.9 * bestWork) bestWork = w, best = factor, chosen = std::move(grid);
  }
  return best;
}

// The mean chord of the cells of `layout` whose value is positive, in world units (cells of
// `voxelSize` x cellExtent): 4 V / S (Cauchy's formula), S the area of their faces toward cells that
// are not, or the domain's edge. 0 when no cell is.
double meanChordOfCells(const CoarseGrid& layout, float voxelSize, const std::vector<float>& values) {
  const auto positive = [&](int x, int y, int z) {
    return x >= 0 && y >= 0 && z >= 0 && x < layout.res.x && y < layout.res.y && z < layout.res.z &&
           values[static_cast<size_t>(layout.cellIndex(x, y, z))] > 0.0f;
  };
  const Vec3 e = layout.cellExtent * voxelSize;
  double area = 0.0;
  size_t cells = 0;
  for (int z = 0; z < layout.res.z; ++z)
    for (int y = 0; y < layout.res.y; ++y)
      for (int x = 0; x < layout.res.x; ++x) {
        if (!positive(x, y, z)) continue;
        ++cells;
        area += e.y * e.z * (!positive(x - 1, y, z) + !positive(x + 1, y, z)) + e.x * e.z * (!positive(x, y - 1, z) + !positive(x, y + 1, z)) +
                e.x * e.y * (!positive(x, y, z - 1) + !positive(x, y, z + 1));
      }
  return area > 0.0 ? 4.0 * static_cast<double>(cells) * e.x * e.y * e.z / area : 0.0;
}

}  // namespace

Mat4 transformMatrix(const TransformDesc& t) {
  Mat4 m = glm::translate(Mat4(1.0f), t.translate);
  m = glm::rotate(m, glm::radians(t.rotate_deg.z), Vec3(0, 0, 1));
  m = glm::rotate(m, glm::radians(t.rotate_deg.y), Vec3(0, 1, 0));
  m = glm::rotate(m, glm::radians(t.rotate_deg.x), Vec3(1, 0, 0));
  return glm::scale(m, t.scale);
}

Medium::Medium(const VolumeDesc& desc, VoxelGrid density, VoxelGrid temperature, VoxelGrid emission)
    : desc_(desc), density_(std::move(density)) {
  worldFromIndex_ = transformMatrix(desc.transform) * density_.worldFromIndex();
  indexFromWorld_ = glm::inverse(worldFromIndex_);
  albedo_ = desc.albedo;
  albedoAverage_ = average(albedo_);
  if (desc.emission.mode == EmissionMode::Blackbody) aux_ = std::move(temperature);
  if (desc.emission.mode == EmissionMode::Grid) aux_ = std::move(emission);
  // A volume whose source is zero everywhere is not an emitter and must cost nothing extra
  // (docs/method.md s.0). In radiance units an albedo of 1 leaves no absorption, hence no source.
  perLength_ = desc.emission.units == EmissionUnits::PerLength;
  emissive_ = aux_.valid() && desc.emission.intensity > 0.0f && (perLength_ || albedoAverage_ < 1.0f) &&
              !(desc.emission.mode == EmissionMode::Grid && isBlack(desc.emission.color));
  if (aux_.valid()) {
    auxFromDensityIndex_ = glm::inverse(aux_.worldFromIndex()) * density_.worldFromIndex();
    auxSameIndex_ = auxFromDensityIndex_ == Mat4(1.0f);
  }
  voxelSize_ = std::cbrt(std::abs(glm::determinant(glm::mat3(worldFromIndex_))));
  applyStrategy(StrategySettings{});
}

void Medium::worldBounds(Vec3& lo, Vec3& hi) const {
  lo = Vec3(kInfinity);
  hi = Vec3(-kInfinity);
  if (majorant_.empty()) return;
  const Vec3 a = majorant_.origin(), b = majorant_.domainMax();
  for (int c = 0; c < 8; ++c) {
    const Vec3 w = Vec3(worldFromIndex_ * glm::vec4(boxCorner(a, b, c), 1.0f));
    lo = glm::min(lo, w);
    hi = glm::max(hi, w);
  }
}

void Medium::applyStrategy(const StrategySettings& strategy) {
  const MajorantPolicy& policy = strategy.majorant;
  const int cellSize = policy.structure == MajorantStructure::Grid ? policy.cell_size : 0;
  // Coarser cells for media that emit nothing: an emitter keeps the asked-for cells, which also
  // shape its emission-aware majorant and emission maxima (the variance of the emission estimate).
  const bool coarsen = policy.coarsen_thin && policy.structure == MajorantStructure::Grid && !emissive_;
  // The coarsening weighs collisions, so a new safety factor decides it again.
  if (majorant_.empty() || builtStructure_ != policy.structure || builtCellSize_ != cellSize || builtCoarsen_ != coarsen ||
      (coarsen && builtSafetyFactor_ != policy.safety_factor)) {
    majorant_ = MajorantGrid(density_, policy.structure, policy.cell_size);
    occupancy_ = MajorantGrid();
    coarsening_ = 1;
    if (coarsen) {
      // Collisions per voxel length per unit of stored density.
      const float perDensity = desc_.sigma_t_scale * policy.safety_factor * voxelSize_;
      MajorantGrid coarse;
      coarsening_ = coarsenForWork(majorant_, static_cast<float>(policy.cell_size), perDensity, coarse);
      if (coarsening_ > 1) occupancy_ = std::exchange(majorant_, std::move(coarse));
    }
    builtStructure_ = policy.structure;
    builtCellSize_ = cellSize;
    builtCoarsen_ = coarsen;
    builtSafetyFactor_ = policy.safety_factor;
    emissionMaxima_.clear();
    radianceScale_ = 0.0f;
  }
  const bool emissionTerm = policy.emission_term && policy.emission_weight > 0.0f && emissive_;
  // Per unit length, emission may sit where mu_t is 0: the majorant needs its maxima whatever the policy.
  if ((emissionTerm || emitsPerLength()) && emissionMaxima_.empty()) {
    emissionMaxima_ = footprintMaxima(majorant_.layout(), density_.activeBox(), [this] {
      return [sampler = Sampler(*this)](int x, int y, int z) { return sampler.sourceLuminanceAtVoxel(x, y, z); };
    });
    // 1% of the mean positive maximum; 1 when no voxel centre emits (the source may still, between
    // a dense voxel with no emission and an emitting one with no density).
    double sum = 0.0;
    size_t positive = 0;
    for (float m : emissionMaxima_)
      if (m > 0.0f) sum += m, ++positive;
    emissionFloor_ = positive ? static_cast<float>(0.01 * sum / static_cast<double>(positive)) : 1.0f;
  }
  if (strategy.emission.light_sampling && emissive_) {
    if (!emissionLight_ || emissionLight_->cellSize() != strategy.emission.grid_cell_size)
      emissionLight_ = std::make_unique<EmissionLight>(*this, strategy.emission.grid_cell_size);
  } else {
    emissionLight_.reset();
  }
  // mu_bar = max(maj(mu_t), min(k * maj(mu_a lum(Le)), c / voxel_size)); rounded up by a few ulps so
  // float rounding in the trilinear lerp can never exceed maj(mu_t).
  const float scale = desc_.sigma_t_scale * policy.safety_factor * (1.0f + 4e-7f);
  // The radiance scale: the mean Le over the emitting cells, weighted by their absorption (the sum of
  // the cells' source maxima over the sum of their mu_a maxima), or per unit length the mean E over
  // emitting cells times a voxel. A mean, not the peak: a flame whose few hottest voxels outshine the
  // rest by 30x still gets collisions where most of its light comes from.
  if (!emissionMaxima_.empty() && radianceScale_ == 0.0f) {
    const float absorption = desc_.sigma_t_scale * (1.0f - albedoAverage_);
    double source = 0.0, weight = 0.0;
    size_t emitting = 0;
    for (size_t i = 0; i < emissionMaxima_.size(); ++i) {
      if (!(emissionMaxima_[i] > 0.0f)) continue;
      source += emissionMaxima_[i];
      weight += perLength_ ? 1.0 / voxelSize_ : static_cast<double>(majorant_.maxDensities()[i]) * absorption;
      ++emitting;
    }
    radianceScale_ = weight > 0.0 ? static_cast<float>(source / weight) : 0.0f;
    // What a ray through the emitter gathers is Le (1 - exp(-tau_a)), not Le: a thin emitter's rays
    // see a small part of its Le, and a weight relative to Le alone gave them well under one
    // emission collision each (thin-bright-fire, tau_a 0.02: 7x the relative variance of raw k = 10).
    // So a relative k is about the number of emission collisions on a ray through a thin emitter, and
    // k per unit of absorption depth in a dense one. tau_a: the emitting cells' mean mu_a bound times
    // their mean chord, 4 V / S (Cauchy's formula; S counts the faces between emitting and other cells).
    emissionDepth_ = 0.0f;
    if (!perLength_ && weight > 0.0) {
      const double chord = meanChordOfCells(majorant_.layout(), voxelSize_, emissionMaxima_);
      emissionDepth_ = static_cast<float>(weight / static_cast<double>(emitting) * chord);
      radianceScale_ *= static_cast<float>(-std::expm1(-static_cast<double>(emissionDepth_)));
    }
  }
  const float emissionScale = policy.relative_weight ? (radianceScale_ > 0.0f ? policy.emission_weight / radianceScale_ : 0.0f)
                                                     : policy.emission_weight;
  // Capped even at c = 0: past about 1000 collisions per voxel a walk would not end (input_limits.h).
  const float cap = (policy.emission_cap > 0.0f ? policy.emission_cap : 1000.0f) / voxelSize_;
  cellMajorant_.resize(majorant_.cellCount());
  transmittanceMajorant_.resize(majorant_.cellCount());
  for (size_t i = 0; i < cellMajorant_.size(); ++i) {
    float muBar = majorant_.maxDensities()[i] * scale;
    transmittanceMajorant_[i] = muBar;
    if (emissionTerm) muBar = std::max(muBar, std::min(emissionMaxima_[i] * emissionScale, cap));
    // Emission per unit length where nothing extinguishes: collisions at rate min(maj(E), c / voxel)
    // so the emission is gathered (any mu_bar > 0 there keeps it unbiased; this one is cheap).
    if (!(muBar > 0.0f) && emitsPerLength() && emissionMaxima_[i] > 0.0f) muBar = std::min(emissionMaxima_[i], cap);
    cellMajorant_[i] = muBar;
  }
}

void Medium::setColorGrids(VoxelGrid r, VoxelGrid g, VoxelGrid b) {
  colorR_ = std::move(r), colorG_ = std::move(g), colorB_ = std::move(b);
  colorFromDensityIndex_ = glm::inverse(colorR_.worldFromIndex()) * density_.worldFromIndex();
  // The emission maxima, light and scale were built with a uniform colour: the next applyStrategy
  // rebuilds them.
  emissionMaxima_.clear();
  radianceScale_ = 0.0f;
  emissionLight_.reset();
}

Medium::Sampler::Sampler(const Medium& m)
    : medium_(&m),
      density_(m.density_.sampler()),
      aux_(m.aux_.valid() ? m.aux_.sampler() : m.density_.sampler()) {
  if (m.colorR_.valid()) color_ = ColorSamplers{m.colorR_.sampler(), m.colorG_.sampler(), m.colorB_.sampler()};
}

float Medium::Sampler::sourceLuminanceAtVoxel(int x, int y, int z) const {
  const Medium& m = *medium_;
  if (!m.emissive_) return 0.0f;
  if (m.perLength_) return luminance(emission(Vec3(x, y, z)));
  const float d = density_.voxel(x, y, z);
  return d > 0.0f ? d * m.desc_.sigma_t_scale * (1.0f - m.albedoAverage_) * luminance(emission(Vec3(x, y, z))) : 0.0f;
}

Rgb Medium::Sampler::emission(const Vec3& indexPos) const {
  const Medium& m = *medium_;
  if (!m.emissive_) return Rgb(0.0f);
  const Vec3 p = m.auxSameIndex_ ? indexPos : Vec3(m.auxFromDensityIndex_ * glm::vec4(indexPos, 1.0f));
  const float value = aux_.trilinear(p);
  const EmissionDesc& e = m.desc_.emission;
  if (e.mode == EmissionMode::Blackbody) {
    if (!(value > 0.0f)) return Rgb(0.0f);
    return blackbody()(value * e.temperature_scale + e.temperature_offset) * e.intensity;
  }
  Rgb color = e.color;
  if (color_) {
    // Cd at the point, clamped to [0, 1e6] per channel (a colour, not a light).
    const Vec3 q = Vec3(m.colorFromDensityIndex_ * glm::vec4(indexPos, 1.0f));
    color *= Rgb(std::clamp(color_->r.trilinear(q), 0.0f, 1e6f), std::clamp(color_->g.trilinear(q), 0.0f, 1e6f),
                 std::clamp(color_->b.trilinear(q), 0.0f, 1e6f));
  }
  return color * (std::max(value, 0.0f) * e.intensity);
}

}  // namespace candela
