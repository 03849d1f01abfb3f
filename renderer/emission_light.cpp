#include "emission_light.h"

#include "medium.h"

#include <tbb/parallel_for.h>

#include <algorithm>

namespace candela {

EmissionLight::EmissionLight(const Medium& medium, int cellSize) : medium_(&medium), cellSize_(std::max(1, cellSize)) {
  if (!medium.emissive()) return;
  const VoxelGrid& density = medium.densityGrid();
  layout_ = CoarseGrid::over(density, cellSize_);
  if (layout_.empty()) return;
  const Mat4& m = medium.worldFromIndex();
  const float voxelVolume = std::abs(glm::determinant(glm::mat3(m)));
  cellVolume_ = voxelVolume * layout_.cellExtent.x * layout_.cellExtent.y * layout_.cellExtent.z;

  // Energy per cell: the sum over voxel centres inside it of the source's luminance * voxel volume.
  const IndexBox box = density.activeBox();
  const int depth = box.max.z - box.min.z + 1;
  const int slabs = std::max(1, std::min(16, depth));
  std::vector<std::vector<double>> partial(static_cast<size_t>(slabs), std::vector<double>(layout_.cellCount(), 0.0));
  tbb::parallel_for(0, slabs, [&](int s) {
    Medium::Sampler sampler(medium);
    std::vector<double>& out = partial[static_cast<size_t>(s)];
    for (int z = box.min.z + depth * s / slabs; z < box.min.z + depth * (s + 1) / slabs; ++z)
      for (int y = box.min.y; y <= box.max.y; ++y)
        for (int x = box.min.x; x <= box.max.x; ++x) {
          // mu_a lum(Le) in radiance units, lum(E) per unit length (also where the density is 0).
          const float source = sampler.sourceLuminanceAtVoxel(x, y, z);
          if (!(source > 0.0f)) continue;
          const glm::ivec3 c = glm::clamp(glm::ivec3(glm::floor((Vec3(x, y, z) - layout_.origin) / layout_.cellExtent)),
                                          glm::ivec3(0), layout_.res - 1);
          out[static_cast<size_t>(layout_.cellIndex(c.x, c.y, c.z))] += static_cast<double>(source) * voxelVolume;
        }
  });
  std::vector<double> energy(layout_.cellCount(), 0.0);
  for (const auto& p : partial)
    for (size_t i = 0; i < energy.size(); ++i) energy[i] += p[i];
  double total = 0.0;
  for (double e : energy) total += e;
  if (!(total > 0.0)) return;
  power_ = static_cast<float>(4.0 * kPi * total);
  cellPdf_.assign(energy.size(), 0.0f);
  double acc = 0.0;
  for (size_t i = 0; i < energy.size(); ++i) {
    if (energy[i] <= 0.0) continue;
    cellPdf_[i] = static_cast<float>(energy[i] / total);
    acc += energy[i] / total;
    cellOf_.push_back(static_cast<int>(i));
    const Vec3 centre = layout_.origin + (Vec3(layout_.cellCoords(static_cast<int>(i))) + 0.5f) * layout_.cellExtent;
    centroid_ += static_cast<float>(energy[i] / total) * Vec3(medium.worldFromIndex() * glm::vec4(centre, 1.0f));
    cdf_.push_back(static_cast<float>(acc));
  }
  cdf_.back() = 1.0f;
  // The emission's spread about its centroid (energy-weighted mean squared distance, each cell's own
  // extent included): the light-selection estimate treats the volume as a source that size.
  const Vec3 cellDiagonal = glm::mat3(m) * layout_.cellExtent;
  double spread2 = glm::dot(cellDiagonal, cellDiagonal) / 12.0;
  for (int cell : cellOf_) {
    const Vec3 centre = layout_.origin + (Vec3(layout_.cellCoords(cell)) + 0.5f) * layout_.cellExtent;
    const Vec3 d = Vec3(m * glm::vec4(centre, 1.0f)) - centroid_;
    spread2 += static_cast<double>(cellPdf_[static_cast<size_t>(cell)]) * glm::dot(d, d);
  }
  spread2_ = static_cast<float>(spread2);
}

LightImportance EmissionLight::importance() const {
  LightImportance out;
  out.intensity = power_ / (4.0f * kPi);  // an isotropic source of that power
  out.position = centroid_;
  out.spread2 = spread2_;
  return out;
}

bool EmissionLight::sample(const Vec3& x, float u0, float u1, float u2, float u3, Vec3& wi) const {
  if (cdf_.empty()) return false;
  const size_t k = static_cast<size_t>(std::min<std::ptrdiff_t>(std::upper_bound(cdf_.begin(), cdf_.end(), u0) - cdf_.begin(),
                                                                 static_cast<std::ptrdiff_t>(cdf_.size()) - 1));
  const Vec3 cell(layout_.cellCoords(cellOf_[k]));
  const Vec3 indexPoint = layout_.origin + (cell + Vec3(u1, u2, u3)) * layout_.cellExtent;
  const Vec3 y = Vec3(medium_->worldFromIndex() * glm::vec4(indexPoint, 1.0f));
  const Vec3 d = y - x;
  const float len = glm::length(d);
  if (!(len > 1e-7f)) return false;
  wi = d / len;
  return true;
}

float EmissionLight::pdf(const Vec3& x, const Vec3& w) const {
  if (cdf_.empty()) return 0.0f;
  const Mat4& ifw = medium_->indexFromWorld();
  const Vec3 o = Vec3(ifw * glm::vec4(x, 1.0f));
  const Vec3 d = Vec3(ifw * glm::vec4(w, 0.0f));
  MajorantDda dda(layout_, o, d, 0.0f, kInfinity);
  float t0, t1;
  int cell;
  double p = 0.0;
  while (dda.next(t0, t1, cell)) {
    const float pv = cellPdf_[static_cast<size_t>(cell)];
    if (pv > 0.0f) p += static_cast<double>(pv) * (static_cast<double>(t1) * t1 * t1 - static_cast<double>(t0) * t0 * t0) / 3.0;
  }
  return static_cast<float>(p / cellVolume_);
}

}  // namespace candela
