#include "camera_guides.h"

#include "integrator.h"
#include "tracking.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace candela {

float guidedProbabilityAt(const Scene& scene, int x, int y, int width, int height) {
  const GuidedRegions& regions = scene.guidedRegions();
  return regions.empty() ? scene.strategy().guiding.guided_probability : regions.at(x, y, width, height);
}

float CameraGuides::probabilityAt(const Scene& scene, int x, int y) const {
  const float base = guidedProbabilityAt(scene, x, y, width_, height_);
  const float most = scene.strategy().guiding.bright_pixel_probability;
  // q = 0 (auto's region map: tracking alone) stays 0: raising it would guide where the pilot
  // measured tracking ahead.
  if (!(base > 0.0f) || !(most > base)) return base;
  return std::clamp(base * brightness(x, y), base, most);
}

void CameraGuides::refreshProbabilities(const Scene& scene) {
  for (int y = 0; y < height_; ++y)
    for (int x = 0; x < width_; ++x) {
      const size_t i = static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x);
      if (present_[i]) guides_[i].guidedProbability = probabilityAt(scene, x, y);
    }
}

bool CameraGuides::prepare(const Scene& scene, const PathTracer& tracer, const Camera& camera) {
  const GuidingSettings& g = scene.strategy().guiding;
  if (g.guide != DistanceGuide::Probes) return false;
  char identity[64];
  std::snprintf(identity, sizeof identity, "%p/%p/", static_cast<const void*>(&scene), static_cast<const void*>(tracer.probes()));
  // The tables depend on the camera, the probes and the guiding settings but q; each pixel's q
  // (the settings' or auto's region map) is refreshed without rebuilding them, so auto's pilot
  // renders its q levels and region maps on tables built once.
  GuidingSettings tableSettings = g;
  tableSettings.guided_probability = 0.0f;
  tableSettings.bright_pixel_probability = 0.0f;
  const std::string key = identity + toJson(scene.desc().camera).dump() + toJson(tableSettings).dump();
  std::string probabilityKey = std::to_string(g.guided_probability) + ";" + std::to_string(g.bright_pixel_probability) + ";";
  for (float q : scene.guidedRegions().probability) probabilityKey += std::to_string(q) + ",";  // auto's region map
  if (key == key_) {
    if (probabilityKey != probabilityKey_) {
      probabilityKey_ = probabilityKey;
      refreshProbabilities(scene);
    }
    return true;
  }
  key_ = key;
  probabilityKey_ = probabilityKey;
  ++builds_;
  width_ = camera.width();
  height_ = camera.height();
  const size_t pixels = static_cast<size_t>(width_) * static_cast<size_t>(height_);
  guides_.assign(pixels, CameraRayGuide{0.0f, PiecewiseLinearView{}});
  present_.assign(pixels, 0);
  // Rows in parallel, each into its own buffer, which the row's views point into and which keeps its
  // capacity for the next rebuild. Copied into one flat array and freed, as they were, they made a
  // camera move's rebuild take 116 ms instead of 80 (docs/performance.md, "Camera-ray tables after
  // a camera move").
  rows_.resize(static_cast<size_t>(height_));
  std::vector<std::vector<uint32_t>> offsets(static_cast<size_t>(height_));
  predicted_.assign(pixels, 0.0f);
  std::vector<float> rayEnd(pixels, 0.0f);  // each centre ray's medium interval's end
  tbb::parallel_for(0, height_, [&](int y) {
    GuidedDistance guide;
    PiecewiseLinearDistance table;
    std::vector<float>& row = rows_[static_cast<size_t>(y)];
    row.clear();
    offsets[static_cast<size_t>(y)].assign(static_cast<size_t>(width_), 0);
    for (int x = 0; x < width_; ++x) {
      const Ray ray = camera.generate(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f);
      float tIn, tOut;
      const size_t i = static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x);
      if (!tracer.guideFor(ray, tracer.nearestOccluder(ray), tIn, tOut, guide)) continue;
      predicted_[i] = static_cast<float>(knotsIntegral(guide.knots, tIn, tOut));
      rayEnd[i] = tOut;
      table.build(tIn, tOut, guide.knots, g.floor);
      const PiecewiseLinearView v = table.view();
      PiecewiseLinearView& stored = guides_[i].view;
      stored = v;
      stored.ts = stored.vs = stored.cdf = nullptr;  // pointed into the row below, once it stops growing
      offsets[static_cast<size_t>(y)][static_cast<size_t>(x)] = static_cast<uint32_t>(row.size());
      row.insert(row.end(), v.ts, v.ts + v.n);
      row.insert(row.end(), v.vs, v.vs + v.n);
      row.insert(row.end(), v.cdf, v.cdf + v.n);
      present_[i] = 1;
    }
  });
  // Dim pixels are left to tracking (guiding.dim_pixel_floor): a choice by pixel, from the probes'
  // prediction for its centre ray, so MIS stays unbiased. Summed in pixel order: the same floor on
  // any thread count.
  double sum = 0.0;
  for (float v : predicted_) sum += v;
  dimThreshold_ = static_cast<float>(g.dim_pixel_floor * sum / static_cast<double>(std::max<size_t>(1, pixels)));
  dimPixels_ = 0;
  for (size_t i = 0; i < pixels; ++i)
    if (present_[i] && predicted_[i] < dimThreshold_) present_[i] = 0, guides_[i].guidedProbability = 0.0f, ++dimPixels_;
  // Bright pixels (guiding.bright_pixel_probability): the prediction over the mean, times its share
  // against the emission the centre ray may see. The share keeps a flame's pixels, whose light and
  // noise are their own emission, at the base q: raising it there only buys light samples of the
  // flame (fire: 4% more MSE per sample without it).
  // The bound is needed only where the prediction exceeds the mean: elsewhere the brightness is at
  // most 1 whatever the share, and q stays at its base (a camera move's rebuild on torch-in-mist
  // spent 15% of its time on bounds no q used).
  const double mean = sum / static_cast<double>(std::max<size_t>(1, pixels));
  const bool emits = scene.hasEmissiveMedia();
  brightness_.assign(pixels, 0.0f);
  if (mean > 0.0) tbb::parallel_for(0, height_, [&](int y) {
    for (int x = 0; x < width_; ++x) {
      const size_t i = static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x);
      if (!present_[i]) continue;
      const double relative = predicted_[i] / mean;
      double share = 1.0;
      if (emits && relative > 1.0) {
        const Ray ray = camera.generate(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f);
        const double bound = emissionBoundAlongRay(scene.media(), ray, rayEnd[i]);
        share = predicted_[i] / (predicted_[i] + bound);
        if (!std::isfinite(share)) share = 0.0;  // an unbounded emitter: not raised
      }
      brightness_[i] = static_cast<float>(relative * share);
    }
  });
  refreshProbabilities(scene);
  // The kept pixels' views into their rows (a dim pixel's table stays in its row, unused).
  bytes_ = 0;
  for (int y = 0; y < height_; ++y) {
    const std::vector<float>& row = rows_[static_cast<size_t>(y)];
    bytes_ += row.size() * sizeof(float);
    for (int x = 0; x < width_; ++x) {
      const size_t i = static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x);
      if (!present_[i]) continue;
      PiecewiseLinearView& v = guides_[i].view;
      const float* start = row.data() + offsets[static_cast<size_t>(y)][static_cast<size_t>(x)];
      v.ts = start;
      v.vs = start + v.n;
      v.cdf = start + 2 * v.n;
    }
  }
  return true;
}

}  // namespace candela
