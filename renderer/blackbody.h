// Blackbody emission colour: Planck's law integrated against the CIE 1931 observer (the analytic
// fit of Wyman, Sloan and Shirley 2013), converted to linear Rec.709, tabulated for the hot loop.
#pragma once

#include "core.h"

#include <vector>

namespace candela {

// Radiance of a blackbody at `kelvin`, in linear Rec.709, scaled so that 1500 K has luminance 1.
// Below ~500 K it is effectively black; it grows steeply with temperature as physics says.
Rgb blackbodyExact(float kelvin);

class BlackbodyTable {
 public:
  BlackbodyTable();
  Rgb operator()(float kelvin) const {
    if (!(kelvin > 0.0f)) return Rgb(0.0f);
    const float x = std::min(kelvin, kMaxKelvin) * (static_cast<float>(kEntries - 1) / kMaxKelvin);
    const int i = std::min(static_cast<int>(x), kEntries - 2);
    const float f = x - static_cast<float>(i);
    return table_[static_cast<size_t>(i)] * (1.0f - f) + table_[static_cast<size_t>(i) + 1] * f;
  }
  static constexpr float kMaxKelvin = 12000.0f;
  static constexpr int kEntries = 4096;

 private:
  std::vector<Rgb> table_;
};

const BlackbodyTable& blackbody();

}  // namespace candela
