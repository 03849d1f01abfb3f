// Error-versus-time measurement (the CLI's bench command): error metrics against a reference,
// cached high-spp references, and the convergence CSV and SVG chart.
#pragma once

#include "film.h"

#include "image_io.h"
#include "scene_desc.h"

#include <string>
#include <vector>

namespace candela {

struct ErrorMetrics {
  double mse = 0.0;
  double relmse = 0.0;
};

// mse    = mean over pixels and channels of (I - R)^2
// relmse = mean over pixels and channels of (I - R)^2 / (R^2 + eps), eps = (0.01 * mean(R))^2 ... see kRelMseFormula
extern const char* const kRelMseFormula;
ErrorMetrics imageError(const std::vector<float>& image, const std::vector<float>& reference);
// A render's own noise figure, no reference needed. Per square region of `regionSize` pixels and per
// channel: the mean over its pixels of one sample's variance (the film's sums of squares) over the
// region's mean^2 + eps, eps as the relMSE's from the image mean; averaged over the channels. Pooling the mean over a region
// keeps a pixel that caught a rare bright sample from normalising its own variance away. Row-major,
// regionsX x regionsY; empty below 2 spp. The auto strategy's pilot ranks candidates by it.
std::vector<double> regionalRelativeVariance(const Film& film, int regionSize, int& regionsX, int& regionsY);
// Its mean over 8 x 8-pixel regions: about the relMSE one sample per pixel would have (relMSE x spp
// of a converged render). 0 below 2 spp.
double relativeVariancePerSample(const Film& film);
// The mean over pixels and channels of one sample's variance: the MSE one sample per pixel would
// have (MSE x spp of a converged render), the absolute counterpart of the figure above. 0 below 2 spp.
double variancePerSample(const Film& film);
// Per pixel and channel, interleaved as the film: the mean and one sample's variance (from 2 spp;
// empty below). The auto strategy's pilot normalises several candidates' variances by one shared
// mean image, as the relMSE normalises by one reference.
struct PixelMoments {
  std::vector<float> mean, variance;
};
PixelMoments pixelMoments(const Film& film);
// The relMSE's eps for an image whose mean over pixels and channels is `meanValue`: (0.1 x it)^2.
double relativeEpsilon(double meanValue);
// The relMSE one sample per pixel would have if `mean` were the reference: the mean over pixels and
// channels of variance / (mean^2 + eps), eps as the relMSE's.
double relativeVarianceAgainst(const std::vector<float>& variance, const std::vector<float>& mean);
// An error map for display: per pixel, averaged over channels, |I - R| / mean(R) (absolute) or
// |I - R| / sqrt(R^2 + eps) with the relMSE's eps (relative), in false colour on a log scale from
// 0.01 (black) through blue, green, yellow, red to 10 (white). Interleaved RGB in [0, 1].
std::vector<float> errorFalseColour(const std::vector<float>& image, const std::vector<float>& reference, bool relative);

// A stable hash of everything that decides the expected image (camera, scene content, render
// settings but spp/time), plus `extra` (reference strategy and spp). A volume file counts by what
// identifies its content (its canonical path, size and modification time at the scene's frame), not by
// its name in the scene: another file of the same name, or a file written again, is another image.
std::string sceneContentHash(const SceneDesc& scene, const std::string& extra);

// The reference for a scene: loaded from the cache or rendered with `strategy` at `spp` and cached
// under cacheDirectory()/references. `log` receives progress lines.
Image cachedReference(const SceneDesc& scene, const StrategySettings& strategy, int spp, int threads, std::string* cachePath = nullptr);

struct ConvergencePoint {
  std::string strategy;
  double budgetSeconds = 0.0;
  double seconds = 0.0;
  int spp = 0;
  double mse = 0.0;
  double relmse = 0.0;
  uint64_t rejected = 0;
  // Counted work (work.h: calibrated nanoseconds on one core, never the clock), auto's pilot included:
  // efficiency by work, 1 / (relMSE x work), ranks strategies without the clock's noise.
  double work = 0.0;
};

// Efficiency 1 / (relMSE x time) versus a swept parameter, one line per strategy; x is logarithmic
// over the positive values, and a value of 0 is drawn as a dashed horizontal line per strategy.
struct SweepPoint {
  std::string strategy;
  double value = 0.0;
  double efficiency = 0.0;
  std::string note;  // drawn beside the point (e.g. probe count and learning time)
};
void writeSweepSvg(const std::string& path, const std::vector<SweepPoint>& points, const std::string& title, const std::string& xLabel);

void writeConvergenceCsv(const std::string& path, const std::vector<ConvergencePoint>& points, const std::string& comment);
// Error versus time on log-log axes, one line per strategy.
void writeConvergenceSvg(const std::string& path, const std::vector<ConvergencePoint>& points, const std::string& title);

}  // namespace candela
