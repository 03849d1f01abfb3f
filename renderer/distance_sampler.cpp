#include "distance_sampler.h"

#include <algorithm>

namespace candela {

void PiecewiseLinearDistance::build(float t0, float t1, std::vector<DistanceKnot>& knots, float floor) {
  t0_ = t0;
  t1_ = std::max(t1, t0 + 1e-7f);
  ts_.clear();
  vs_.clear();
  cdf_.clear();
  area_ = 0.0f;
  uniformShare_ = 1.0f;
  for (auto& k : knots) k.t = std::clamp(k.t, t0_, t1_);
  // Knots arrive nearly sorted (gathered along the ray): insertion sort is close to linear.
  for (size_t i = 1; i < knots.size(); ++i)
    for (size_t j = i; j > 0 && knots[j].t < knots[j - 1].t; --j) std::swap(knots[j], knots[j - 1]);
  if (knots.empty()) return;
  // Segment ends: t0, the knots, t1; flat beyond the outer knots.
  ts_.push_back(t0_);
  vs_.push_back(std::max(0.0f, knots.front().value));
  for (const auto& k : knots) {
    ts_.push_back(k.t);
    vs_.push_back(std::max(0.0f, k.value));
  }
  ts_.push_back(t1_);
  vs_.push_back(std::max(0.0f, knots.back().value));
  cdf_.push_back(0.0f);
  for (size_t i = 0; i + 1 < ts_.size(); ++i) {
    area_ += 0.5f * (vs_[i] + vs_[i + 1]) * (ts_[i + 1] - ts_[i]);
    cdf_.push_back(area_);
  }
  if (area_ > 0.0f && std::isfinite(area_)) uniformShare_ = floor;
}

float PiecewiseLinearView::linear(float t) const {
  if (t < t0 || t > t1 || n == 0) return 0.0f;
  const uint32_t i = static_cast<uint32_t>(std::upper_bound(ts, ts + n, t) - ts);
  if (i == 0) return vs[0];
  if (i >= n) return vs[n - 1];
  const float dt = ts[i] - ts[i - 1];
  const float f = dt > 0.0f ? (t - ts[i - 1]) / dt : 0.0f;
  return vs[i - 1] + f * (vs[i] - vs[i - 1]);
}

float PiecewiseLinearView::pdf(float t) const {
  if (t < t0 || t > t1) return 0.0f;
  const float uniform = uniformShare / (t1 - t0);
  if (uniformShare >= 1.0f) return uniform;
  return uniform + (1.0f - uniformShare) * linear(t) / area;
}

float PiecewiseLinearView::sample(float u, float& pdfOut) const {
  float t;
  if (u < uniformShare) {
    t = t0 + (u / uniformShare) * (t1 - t0);
  } else {
    const float target = (u - uniformShare) / (1.0f - uniformShare) * area;
    uint32_t i = static_cast<uint32_t>(std::upper_bound(cdf, cdf + n, target) - cdf);
    i = std::clamp<uint32_t>(i, 1, n - 1);  // segment i-1 spans [ts[i-1], ts[i]]
    while (i + 1 < n && cdf[i] == cdf[i - 1]) ++i;  // skip zero-area segments
    const float a = target - cdf[i - 1];
    const float v0 = vs[i - 1], v1 = vs[i], dt = ts[i] - ts[i - 1];
    const float slope = dt > 0.0f ? (v1 - v0) / dt : 0.0f;
    // Solve v0 x + slope x^2 / 2 = a for x in [0, dt] (stable form of the quadratic root).
    const float disc = std::max(0.0f, v0 * v0 + 2.0f * slope * a);
    const float denom = v0 + std::sqrt(disc);
    const float x = denom > 0.0f ? 2.0f * a / denom : 0.0f;
    t = ts[i - 1] + std::clamp(x, 0.0f, dt);
  }
  t = std::clamp(t, t0, t1);
  pdfOut = pdf(t);
  return t;
}

void EquiAngularDistance::build(const Ray& ray, float t0, float t1, const std::vector<EquiAngularTarget>& targets) {
  t0_ = t0;
  t1_ = std::max(t1, t0 + 1e-7f);
  lobes_.clear();
  float total = 0.0f;
  for (const auto& target : targets) {
    if (!(target.weight > 0.0f)) continue;
    Lobe l;
    l.delta = glm::dot(target.point - ray.origin, ray.direction);
    // A point on the ray itself would make the density singular; keep a tiny distance.
    l.d = std::max(glm::length(ray.at(l.delta) - target.point), 1e-4f * (t1_ - t0_));
    l.theta0 = std::atan((t0_ - l.delta) / l.d);
    l.theta1 = std::atan((t1_ - l.delta) / l.d);
    if (!(l.theta1 > l.theta0)) continue;
    l.weight = target.weight;
    total += l.weight;
    lobes_.push_back(l);
  }
  for (auto& l : lobes_) l.weight /= total;
}

float EquiAngularDistance::pdf(float t) const {
  if (t < t0_ || t > t1_) return 0.0f;
  if (lobes_.empty()) return 1.0f / (t1_ - t0_);
  float p = 0.0f;
  for (const auto& l : lobes_) {
    const float x = t - l.delta;
    p += l.weight * l.d / ((l.theta1 - l.theta0) * (l.d * l.d + x * x));
  }
  return p;
}

float EquiAngularDistance::sample(float u, float& pdfOut) const {
  float t;
  if (lobes_.empty()) {
    t = t0_ + u * (t1_ - t0_);
  } else {
    size_t k = 0;
    while (k + 1 < lobes_.size() && u >= lobes_[k].weight) u -= lobes_[k++].weight;
    const Lobe& l = lobes_[k];
    const float v = std::clamp(u / l.weight, 0.0f, 1.0f);
    t = l.delta + l.d * std::tan(l.theta0 + v * (l.theta1 - l.theta0));
  }
  t = std::clamp(t, t0_, t1_);
  pdfOut = pdf(t);
  return t;
}

void GuidedDistance::buildPiecewiseLinear(float t0, float t1, float floor) {
  kind_ = Kind::Linear;
  linear_.build(t0, t1, knots, floor);
}

void GuidedDistance::buildEquiAngular(const Ray& ray, float t0, float t1, const std::vector<EquiAngularTarget>& targets) {
  kind_ = Kind::EquiAngular;
  equiAngular_.build(ray, t0, t1, targets);
}

float GuidedDistance::sample(float u, float& pdf) const {
  switch (kind_) {
    case Kind::Linear: return linear_.sample(u, pdf);
    case Kind::EquiAngular: return equiAngular_.sample(u, pdf);
    case Kind::Shared: return shared_.sample(u, pdf);
  }
  pdf = 0.0f;
  return 0.0f;
}

float GuidedDistance::pdf(float t) const {
  switch (kind_) {
    case Kind::Linear: return linear_.pdf(t);
    case Kind::EquiAngular: return equiAngular_.pdf(t);
    case Kind::Shared: return shared_.pdf(t);
  }
  return 0.0f;
}

}  // namespace candela
