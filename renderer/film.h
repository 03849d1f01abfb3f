// Float32 accumulation film: per pixel the sum and the sum of squares of the samples (RGB), so the
// variance of each pixel's mean is known. Samples with NaN, Inf or negative values are rejected and
// counted; they contribute zero but still count as samples, so the estimate stays normalised.
#pragma once

#include "image_io.h"

#include "core.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace candela {

class Film {
 public:
  Film() = default;
  Film(int width, int height) { resize(width, height); }
  void resize(int width, int height);

  int width() const { return width_; }
  int height() const { return height_; }
  int spp() const { return spp_; }                     // samples per pixel accumulated
  uint64_t rejectedSamples() const { return rejected_; }
  // A warning when more than 1 in 10,000 samples were rejected (NaN, Inf or negative: the pixels
  // there read darker than they are); empty otherwise. The CLI and the viewer show it.
  std::string rejectedSamplesWarning() const {
    const double total = static_cast<double>(spp_) * width_ * height_;
    if (rejected_ == 0 || !(static_cast<double>(rejected_) > 1e-4 * total)) return {};
    char buf[200];
    std::snprintf(buf, sizeof buf, "%llu of %.0f samples (%.2g%%) were NaN, infinite or negative and were rejected: the image is darker than it should be",
                  static_cast<unsigned long long>(rejected_), total, 100.0 * static_cast<double>(rejected_) / total);
    return buf;
  }
  // The largest single accepted sample (any channel): the firefly measure of the stability suite.
  float maxSample() const { return maxSample_; }

  Rgb mean(int x, int y) const;
  // Standard error of the pixel mean, per channel.
  Rgb standardError(int x, int y) const;
  // The whole image as interleaved RGB means.
  std::vector<float> meanImage() const;
  // The mean as an Image with the layers a compositor expects: "variance.R/G/B" (the variance of each
  // pixel's mean, the squared standard error; from 2 spp) and "spp".
  Image image() const;

  const std::vector<float>& sum() const { return sum_; }
  const std::vector<float>& sumSquares() const { return sumSq_; }

  // Adds a finished pass of `spp` samples per pixel (the renderer's pass buffer).
  void addPass(const Film& pass);
  // What the film accepts: finite, non-negative values.
  static bool acceptable(const Rgb& value) { return isFinite(value) && value.r >= 0.0f && value.g >= 0.0f && value.b >= 0.0f; }
  // Counts a rejected sample of row y that is not added on its own (a split pixel's sub-sample).
  void countRejected(int y) { ++rejectedLocal(y); }
  // Adds one sample to pixel (x, y) of a pass buffer; returns false (and counts it) if rejected.
  bool addSample(int x, int y, const Rgb& value) {
    const size_t i = 3 * (static_cast<size_t>(y) * width_ + x);
    if (!acceptable(value)) {
      ++rejectedLocal(y);
      return false;
    }
    float& rowMax = rowMax_[static_cast<size_t>(y)];
    rowMax = std::max(rowMax, std::max(value.r, std::max(value.g, value.b)));
    sum_[i] += value.r;
    sum_[i + 1] += value.g;
    sum_[i + 2] += value.b;
    sumSq_[i] += value.r * value.r;
    sumSq_[i + 1] += value.g * value.g;
    sumSq_[i + 2] += value.b * value.b;
    return true;
  }
  void setPassSpp(int spp) { spp_ = spp; }

 private:
  // Per-row counters so parallel tiles never share a counter (rows of a tile belong to one task).
  uint64_t& rejectedLocal(int y) { return rowRejected_[static_cast<size_t>(y)]; }
  int width_ = 0, height_ = 0, spp_ = 0;
  uint64_t rejected_ = 0;
  float maxSample_ = 0.0f;
  std::vector<float> rowMax_;
  std::vector<float> sum_, sumSq_;
  std::vector<uint64_t> rowRejected_;
};

}  // namespace candela
