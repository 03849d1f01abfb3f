#include "film.h"

#include <algorithm>
#include <numeric>

namespace candela {

void Film::resize(int width, int height) {
  width_ = width;
  height_ = height;
  const size_t n = 3 * static_cast<size_t>(width) * height;
  sum_.assign(n, 0.0f);
  sumSq_.assign(n, 0.0f);
  rowRejected_.assign(static_cast<size_t>(height), 0);
  rowMax_.assign(static_cast<size_t>(height), 0.0f);
  maxSample_ = 0.0f;
  spp_ = 0;
  rejected_ = 0;
}

Rgb Film::mean(int x, int y) const {
  if (spp_ == 0) return Rgb(0.0f);
  const size_t i = 3 * (static_cast<size_t>(y) * width_ + x);
  return Rgb(sum_[i], sum_[i + 1], sum_[i + 2]) / static_cast<float>(spp_);
}

Image Film::image() const {
  Image out;
  out.width = width_;
  out.height = height_;
  out.rgb = meanImage();
  const size_t pixels = static_cast<size_t>(width_) * height_;
  out.channels["spp"].assign(pixels, static_cast<float>(spp_));
  if (spp_ >= 2) {
    const char* names[3] = {"variance.R", "variance.G", "variance.B"};
    for (int c = 0; c < 3; ++c) out.channels[names[c]].resize(pixels);
    for (int y = 0; y < height_; ++y)
      for (int x = 0; x < width_; ++x) {
        const Rgb se = standardError(x, y);
        for (int c = 0; c < 3; ++c) out.channels[names[c]][static_cast<size_t>(y) * width_ + x] = se[c] * se[c];
      }
  }
  return out;
}

Rgb Film::standardError(int x, int y) const {
  if (spp_ < 2) return Rgb(kInfinity);
  const size_t i = 3 * (static_cast<size_t>(y) * width_ + x);
  const float n = static_cast<float>(spp_);
  Rgb se;
  for (int c = 0; c < 3; ++c) {
    const float m = sum_[i + c] / n;
    const float var = std::max(0.0f, (sumSq_[i + c] / n - m * m) * n / (n - 1.0f));
    se[c] = std::sqrt(var / n);
  }
  return se;
}

std::vector<float> Film::meanImage() const {
  std::vector<float> out(sum_.size(), 0.0f);
  if (spp_ == 0) return out;
  const float inv = 1.0f / static_cast<float>(spp_);
  for (size_t i = 0; i < out.size(); ++i) out[i] = sum_[i] * inv;
  return out;
}

void Film::addPass(const Film& pass) {
  for (size_t i = 0; i < sum_.size(); ++i) {
    sum_[i] += pass.sum_[i];
    sumSq_[i] += pass.sumSq_[i];
  }
  spp_ += pass.spp_;
  maxSample_ = std::max(maxSample_, pass.maxSample_);
  for (float m : pass.rowMax_) maxSample_ = std::max(maxSample_, m);
  rejected_ += std::accumulate(pass.rowRejected_.begin(), pass.rowRejected_.end(), uint64_t{0}) + pass.rejected_;
}

}  // namespace candela
