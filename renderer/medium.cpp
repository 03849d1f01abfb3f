#include "medium.h"

#include <glm/gtc/matrix_transform.hpp>

namespace candela {

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
  // A volume whose Le is zero everywhere is not an emitter and must cost nothing extra (METHOD.md s.0).
  emissive_ = aux_.valid() && desc.emission.intensity > 0.0f && albedoAverage_ < 1.0f &&
              !(desc.emission.mode == EmissionMode::Grid && isBlack(desc.emission.color));
  if (aux_.valid()) {
    auxFromDensityIndex_ = glm::inverse(aux_.worldFromIndex()) * density_.worldFromIndex();
    auxSameIndex_ = auxFromDensityIndex_ == Mat4(1.0f);
  }
  applyPolicy(MajorantPolicy{});
}

void Medium::worldBounds(Vec3& lo, Vec3& hi) const {
  lo = Vec3(kInfinity);
  hi = Vec3(-kInfinity);
  if (majorant_.empty()) return;
  const Vec3 a = majorant_.origin(), b = majorant_.domainMax();
  for (int c = 0; c < 8; ++c) {
    const Vec3 p((c & 1) ? b.x : a.x, (c & 2) ? b.y : a.y, (c & 4) ? b.z : a.z);
    const Vec3 w = Vec3(worldFromIndex_ * glm::vec4(p, 1.0f));
    lo = glm::min(lo, w);
    hi = glm::max(hi, w);
  }
}

void Medium::applyPolicy(const MajorantPolicy& policy) {
  const int cellSize = policy.structure == MajorantStructure::Grid ? policy.cell_size : 0;
  if (majorant_.empty() || builtStructure_ != policy.structure || builtCellSize_ != cellSize) {
    majorant_ = MajorantGrid(density_, policy.structure, policy.cell_size);
    builtStructure_ = policy.structure;
    builtCellSize_ = cellSize;
  }
  // Round up by a few ulps so float rounding in the trilinear lerp can never exceed the majorant.
  const float scale = desc_.sigma_t_scale * policy.safety_factor * (1.0f + 4e-7f);
  cellMajorant_.resize(majorant_.cellCount());
  for (size_t i = 0; i < cellMajorant_.size(); ++i) cellMajorant_[i] = majorant_.maxDensities()[i] * scale;
}

Medium::Sampler::Sampler(const Medium& m)
    : medium_(&m), density_(m.density_.sampler()), aux_(m.aux_.valid() ? m.aux_.sampler() : m.density_.sampler()) {}

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
  return e.color * (std::max(value, 0.0f) * e.intensity);
}

}  // namespace candela
