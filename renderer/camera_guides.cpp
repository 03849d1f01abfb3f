#include "camera_guides.h"

#include "convergence.h"
#include "integrator.h"
#include "tracking.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace candela {

float CameraGuides::probabilityAt(const Scene& scene, int x, int y) const {
  const float base = scene.strategy().guiding.guided_probability;
  const float most = scene.strategy().guiding.bright_pixel_probability;
  if (!(most > base)) return base;
  return std::clamp(base * brightness(x, y), base, most);
}

void CameraGuides::refreshProbabilities(const Scene& scene) {
  for (int y = 0; y < height_; ++y)
    for (int x = 0; x < width_; ++x) {
      const size_t i = static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x);
      if (guides_[i].hasTable()) guides_[i].guidedProbability = probabilityAt(scene, x, y);
    }
}

bool CameraGuides::prepare(const Scene& scene, const PathTracer& tracer, const Camera& camera) {
  const GuidingSettings& g = scene.strategy().guiding;
  if (g.guide != DistanceGuide::Probes) return false;
  char identity[64];
  std::snprintf(identity, sizeof identity, "%p/%p/", static_cast<const void*>(&scene), static_cast<const void*>(tracer.probes()));
  // The tables depend on the camera, the probes and the guiding settings but q; each pixel's q is
  // refreshed without rebuilding them, so an edit of q (the viewer's slider) keeps the tables.
  GuidingSettings tableSettings = g;
  tableSettings.guided_probability = 0.0f;
  tableSettings.bright_pixel_probability = 0.0f;
  const std::string key = identity + toJson(scene.desc().camera).dump() + toJson(tableSettings).dump();
  const std::string probabilityKey = std::to_string(g.guided_probability) + ";" + std::to_string(g.bright_pixel_probability);
  measuring_ = measuresPixelProbability(g);
  if (key == key_) {
    if (probabilityKey != probabilityKey_) {
      probabilityKey_ = probabilityKey;
      refreshProbabilities(scene);
      resetMeasures();
    }
    return true;
  }
  key_ = key;
  probabilityKey_ = probabilityKey;
  ++builds_;
  width_ = camera.width();
  height_ = camera.height();
  const size_t pixels = static_cast<size_t>(width_) * static_cast<size_t>(height_);
  guides_.assign(pixels, CameraRayGuide{});
  std::vector<char> present(pixels, 0);  // while the tables are built: the pixels that keep one
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
      CameraRayGuide& stored = guides_[i];
      stored.n = v.n, stored.t0 = v.t0, stored.t1 = v.t1, stored.area = v.area, stored.uniformShare = v.uniformShare;
      // `data` points into the row below once it stops growing.
      offsets[static_cast<size_t>(y)][static_cast<size_t>(x)] = static_cast<uint32_t>(row.size());
      row.insert(row.end(), v.ts, v.ts + v.n);
      row.insert(row.end(), v.vs, v.vs + v.n);
      row.insert(row.end(), v.cdf, v.cdf + v.n);
      present[i] = 1;
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
    if (present[i] && predicted_[i] < dimThreshold_) present[i] = 0, ++dimPixels_;
  // The kept pixels' tables in their rows, which have stopped growing (a dim pixel's table stays in
  // its row, unused): from here a pixel has a table exactly where its entry points to one.
  bytes_ = 0;
  for (int y = 0; y < height_; ++y) {
    const std::vector<float>& row = rows_[static_cast<size_t>(y)];
    bytes_ += row.size() * sizeof(float);
    for (int x = 0; x < width_; ++x) {
      const size_t i = static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x);
      if (present[i]) guides_[i].data = row.data() + offsets[static_cast<size_t>(y)][static_cast<size_t>(x)];
    }
  }
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
      if (!guides_[i].hasTable()) continue;
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
  resetMeasures();
  return true;
}

void CameraGuides::resetMeasures() {
  measures_.clear();
  blocksX_ = (width_ + kMeasureBlock - 1) / kMeasureBlock;
  const int blocksY = (height_ + kMeasureBlock - 1) / kMeasureBlock;
  if (measuring_) measures_.resize(static_cast<size_t>(blocksX_) * static_cast<size_t>(blocksY));
  measuredSamples_ = 0;
  measuredCameraSamples_ = 0.0;
  measuredWork_ = 0.0;
  nextDecision_ = 16;
}

void CameraGuides::restart(const Scene& scene) {
  if (guides_.empty()) return;
  refreshProbabilities(scene);
  resetMeasures();
}

namespace {
double mixturePdf(double q, double guidedPdf, double trackedPdf) { return q * guidedPdf + (1.0 - q) * trackedPdf; }
}  // namespace

void CameraGuides::record(int x, int y, const PathTracer::CameraVertexRecord& vertex, const Rgb& sample, double share) {
  BlockMeasure& m = measures_[block(x, y)];
  m.samples += share;
  m.cameraSamples += 1.0;
  if (vertex.guidedDrawn) m.guided += 1.0, m.guidedWork += vertex.guidedWork;
  // No direct light: nothing changes with q (a non-finite sample the film rejects, and so does this).
  if (isBlack(vertex.direct) || !isFinite(vertex.direct) || !isFinite(sample)) return;
  const double q = vertex.q;
  const double drawn = mixturePdf(q, vertex.guidedPdf, vertex.trackedPdf);
  const double d[3] = {vertex.direct.r, vertex.direct.g, vertex.direct.b};
  const double r[3] = {sample.r - vertex.direct.r, sample.g - vertex.direct.g, sample.b - vertex.direct.b};
  for (size_t c = 0; c < kMeasuredProbabilities.size(); ++c) {
    const double other = kMeasuredProbabilities[c];
    const double pdf = mixturePdf(other, vertex.guidedPdf, vertex.trackedPdf);
    // A q' that could not have drawn this vertex (p_q' = 0) would lose its light: counted as a
    // huge second moment, so that q' is not chosen.
    const double ratio = pdf > 0.0 ? std::min(drawn / pdf, 1e6) : 1e6;
    // E[R D] under q': the vertex's technique reweighted from q to q'.
    const double technique = vertex.guidedDrawn ? (q > 0.0 ? other / q : 0.0) : (1.0 - other) / (1.0 - q);
    for (int ch = 0; ch < 3; ++ch)
      m.change[c][ch] += share * share * (d[ch] * d[ch] * (ratio - 1.0) + 2.0 * r[ch] * d[ch] * (ratio * technique - 1.0));
  }
}

std::vector<size_t> CameraGuides::pixelsByProbability() const {
  std::vector<size_t> counts(kMeasuredProbabilities.size() + 1, 0);
  for (size_t i = 0; i < guides_.size(); ++i) {
    if (!guides_[i].hasTable()) continue;
    const auto at = std::find(kMeasuredProbabilities.begin(), kMeasuredProbabilities.end(), guides_[i].guidedProbability);
    ++counts[static_cast<size_t>(at - kMeasuredProbabilities.begin())];
  }
  return counts;
}

double CameraGuides::measuredVarianceChange(size_t candidate) const {
  double change = 0.0;
  for (size_t b = 0; b < measures_.size(); ++b) {
    const BlockMeasure& m = measures_[b];
    const BlockRect r = blockRect(b);
    double pixels = 0.0;
    for (int y = r.y0; y < r.y1; ++y)
      for (int x = r.x0; x < r.x1; ++x) pixels += guides_[index(x, y)].hasTable() ? 1.0 : 0.0;
    if (!(m.samples > 0.0) || !(pixels > 0.0)) continue;
    for (int ch = 0; ch < 3; ++ch) change += m.change[candidate][ch] / (m.samples / pixels);
  }
  return change;
}

bool CameraGuides::passFinished(const Scene& scene, const Film& film, int spp, double passWork, double cameraSamples) {
  if (!measuring_ || measures_.empty()) return false;
  measuredSamples_ += spp;
  measuredCameraSamples_ += cameraSamples;
  measuredWork_ += passWork;
  if (measuredCameraSamples_ < nextDecision_) return false;
  nextDecision_ = 2.0 * measuredCameraSamples_;
  const GuidingSettings& g = scene.strategy().guiding;
  const double most = std::max(g.guided_probability, g.bright_pixel_probability);
  // The image's variance per sample, its relative variance (the relMSE's, per channel, eps = (0.1 x
  // the mean image's mean)^2) and its work per sample: a block's q' is weighed by how much it
  // changes the logarithms of variance x work and relative variance x work, summed (the product of
  // the two efficiencies), so a block may give up a little of one for more of the other. Balanced
  // instead (the blocks weighing the two so that the worse fell least short of its best) the
  // choices measured x0.98-1.01 of these by each metric per unit of work on every report scene
  // (docs/performance.md, "Measured q balanced between the metrics"). A block that drew no guided
  // vertex (q was 0) prices one at the image's mean. All summed in a fixed order: the same on any
  // thread count.
  const double filmSpp = std::max(1, film.spp());
  const std::vector<float>& sum = film.sum();
  const std::vector<float>& sumSquares = film.sumSquares();
  double meanOfMean = 0.0;
  for (float v : sum) meanOfMean += v / filmSpp;
  meanOfMean /= static_cast<double>(std::max<size_t>(1, sum.size()));
  const double eps = relativeEpsilon(meanOfMean);
  auto pixelVariance = [&](size_t i) { return std::max(0.0, sumSquares[i] / filmSpp - (sum[i] / filmSpp) * (sum[i] / filmSpp)); };
  auto inverseSquare = [&](size_t i) { return 1.0 / ((sum[i] / filmSpp) * (sum[i] / filmSpp) + eps); };
  double variance = 0.0, relative = 0.0, work = measuredWork_, guidedWork = 0.0, guided = 0.0;
  for (size_t i = 0; i < sum.size(); ++i) variance += pixelVariance(i), relative += pixelVariance(i) * inverseSquare(i);
  for (const BlockMeasure& m : measures_) guidedWork += m.guidedWork, guided += m.guided;
  if (!(guided > 0.0) || !(variance > 0.0) || !(relative > 0.0) || !(work > 0.0)) return false;
  work /= measuredSamples_;  // per sample, summed over pixels
  const double meanGuidedWork = guidedWork / guided;
  tbb::parallel_for(0, static_cast<int>(measures_.size()), [&](int b) {
    const BlockMeasure& m = measures_[static_cast<size_t>(b)];
    const BlockRect r = blockRect(static_cast<size_t>(b));
    // Per channel, the measured pixels' variance-weighted mean of 1 / (mean^2 + eps), which turns a
    // change of variance into one of relative variance.
    double pixels = 0.0;
    double blockVariance[3] = {0.0, 0.0, 0.0}, blockRelative[3] = {0.0, 0.0, 0.0}, blockInverse[3] = {0.0, 0.0, 0.0};
    for (int y = r.y0; y < r.y1; ++y)
      for (int x = r.x0; x < r.x1; ++x) {
        if (!guides_[index(x, y)].hasTable()) continue;  // no table: no q to measure
        const size_t i = index(x, y);
        pixels += 1.0;
        for (int ch = 0; ch < 3; ++ch) {
          const size_t k = 3 * i + static_cast<size_t>(ch);
          blockVariance[ch] += pixelVariance(k), blockRelative[ch] += pixelVariance(k) * inverseSquare(k), blockInverse[ch] += inverseSquare(k);
        }
      }
    if (!(pixels > 0.0) || !(m.cameraSamples >= 8.0 * pixels) || !(m.samples >= 2.0 * pixels)) return;
    const double perPixel = m.samples / pixels;  // samples per pixel: the sums become per sample, summed over pixels
    const double perGuided = m.guided > 0.0 ? m.guidedWork / m.guided : meanGuidedWork;
    float best = kMeasuredProbabilities[0];
    double bestScore = std::numeric_limits<double>::infinity();
    for (size_t c = 0; c < kMeasuredProbabilities.size(); ++c) {
      const double q = kMeasuredProbabilities[c];
      if (q > most + 1e-6) continue;
      // Guided work per film sample: q per camera sample, of which a split pixel draws k per film sample.
      const double cameraPerFilm = m.cameraSamples / m.samples;
      double score = 2.0 * (q * perGuided * pixels * cameraPerFilm - m.guidedWork / perPixel) / work;
      for (int ch = 0; ch < 3; ++ch) {
        const double change = m.change[c][ch] / perPixel;
        const double toRelative = blockVariance[ch] > 0.0 ? blockRelative[ch] / blockVariance[ch] : blockInverse[ch] / pixels;
        score += change / variance + change * toRelative / relative;
      }
      if (score < bestScore) bestScore = score, best = static_cast<float>(q);
    }
    for (int y = r.y0; y < r.y1; ++y)
      for (int x = r.x0; x < r.x1; ++x)
        if (guides_[index(x, y)].hasTable()) guides_[index(x, y)].guidedProbability = best;
  });
  ++measuredDecisions_;
  return true;
}

}  // namespace candela
