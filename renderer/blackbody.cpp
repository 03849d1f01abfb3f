#include "blackbody.h"

#include <cmath>

namespace candela {

namespace {

double lobe(double lambda, double mu, double s1, double s2) {
  const double s = lambda < mu ? s1 : s2;
  const double t = (lambda - mu) / s;
  return std::exp(-0.5 * t * t);
}

// CIE 1931 2-degree colour matching functions, multi-lobe Gaussian fit (Wyman et al. 2013).
void cie(double nm, double& x, double& y, double& z) {
  x = 1.056 * lobe(nm, 599.8, 37.9, 31.0) + 0.362 * lobe(nm, 442.0, 16.0, 26.7) - 0.065 * lobe(nm, 501.1, 20.4, 26.2);
  y = 0.821 * lobe(nm, 568.8, 46.9, 40.5) + 0.286 * lobe(nm, 530.9, 16.3, 31.1);
  z = 1.217 * lobe(nm, 437.0, 11.8, 36.0) + 0.681 * lobe(nm, 459.0, 26.0, 13.8);
}

// Unnormalised XYZ of a blackbody.
void planckXyz(double kelvin, double& X, double& Y, double& Z) {
  X = Y = Z = 0.0;
  if (kelvin <= 0.0) return;
  constexpr double h = 6.62607015e-34, c = 2.99792458e8, k = 1.380649e-23;
  for (double nm = 360.0; nm <= 830.0; nm += 2.0) {
    const double l = nm * 1e-9;
    const double radiance = 2.0 * h * c * c / (l * l * l * l * l) / std::expm1(h * c / (l * k * kelvin));
    double x, y, z;
    cie(nm, x, y, z);
    X += radiance * x;
    Y += radiance * y;
    Z += radiance * z;
  }
}

}  // namespace

Rgb blackbodyExact(float kelvin) {
  static const double norm = [] {
    double X, Y, Z;
    planckXyz(1500.0, X, Y, Z);
    return 1.0 / Y;
  }();
  double X, Y, Z;
  planckXyz(kelvin, X, Y, Z);
  X *= norm;
  Y *= norm;
  Z *= norm;
  // XYZ (D65) to linear Rec.709; the deep-red end falls slightly outside the gamut, so clamp.
  const double r = 3.2406 * X - 1.5372 * Y - 0.4986 * Z;
  const double g = -0.9689 * X + 1.8758 * Y + 0.0415 * Z;
  const double b = 0.0557 * X - 0.2040 * Y + 1.0570 * Z;
  return Rgb(static_cast<float>(std::max(0.0, r)), static_cast<float>(std::max(0.0, g)), static_cast<float>(std::max(0.0, b)));
}

BlackbodyTable::BlackbodyTable() : table_(kEntries) {
  for (int i = 0; i < kEntries; ++i) table_[static_cast<size_t>(i)] = blackbodyExact(kMaxKelvin * static_cast<float>(i) / (kEntries - 1));
}

const BlackbodyTable& blackbody() {
  static const BlackbodyTable table;
  return table;
}

}  // namespace candela
