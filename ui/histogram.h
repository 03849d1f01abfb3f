// The Display panel's histogram: display-referred values (after exposure, look and view transform)
// by luminance in even bins over [0, 1], with the share of pixels the screen clips: a channel at or
// past white, or every channel at black (what the clipping view paints red and blue).
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace candela {

struct DisplayHistogram {
  std::vector<float> counts;  // pixels per bin, darkest first
  size_t over = 0, under = 0, total = 0;
  double overShare() const { return total ? static_cast<double>(over) / static_cast<double>(total) : 0.0; }
  double underShare() const { return total ? static_cast<double>(under) / static_cast<double>(total) : 0.0; }
};

// `rgb`: interleaved display values (ColorPipeline::applyCpu's output).
inline DisplayHistogram displayHistogram(const std::vector<float>& rgb, int bins) {
  DisplayHistogram h;
  h.counts.assign(static_cast<size_t>(std::max(1, bins)), 0.0f);
  for (size_t i = 0; i + 2 < rgb.size(); i += 3) {
    const float r = rgb[i], g = rgb[i + 1], b = rgb[i + 2];
    ++h.total;
    if (r >= 1.0f || g >= 1.0f || b >= 1.0f) ++h.over;
    else if (r <= 0.0f && g <= 0.0f && b <= 0.0f) ++h.under;
    const float y = std::clamp(0.2126f * r + 0.7152f * g + 0.0722f * b, 0.0f, 1.0f);
    const size_t bin = std::min(h.counts.size() - 1, static_cast<size_t>(y * static_cast<float>(h.counts.size())));
    h.counts[bin] += 1.0f;
  }
  return h;
}

}  // namespace candela
