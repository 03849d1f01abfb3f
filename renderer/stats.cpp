#include "stats.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace candela {

std::vector<RegionEstimate> regionEstimates(const Film& film, int blocksX, int blocksY) {
  std::vector<RegionEstimate> out;
  const int w = film.width(), h = film.height();
  const double n = film.spp();
  for (int by = 0; by < blocksY; ++by)
    for (int bx = 0; bx < blocksX; ++bx) {
      RegionEstimate r;
      r.x0 = bx * w / blocksX;
      r.x1 = (bx + 1) * w / blocksX;
      r.y0 = by * h / blocksY;
      r.y1 = (by + 1) * h / blocksY;
      const double pixels = static_cast<double>(r.x1 - r.x0) * (r.y1 - r.y0);
      double mean[3] = {0, 0, 0}, var[3] = {0, 0, 0};
      for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x) {
          const size_t i = 3 * (static_cast<size_t>(y) * w + x);
          for (int c = 0; c < 3; ++c) {
            const double m = film.sum()[i + c] / n;
            const double v = std::max(0.0, (film.sumSquares()[i + c] / n - m * m) * n / std::max(1.0, n - 1.0));
            mean[c] += m;
            var[c] += v / n;  // variance of this pixel's mean
          }
        }
      for (int c = 0; c < 3; ++c) {
        r.mean[c] = static_cast<float>(mean[c] / pixels);
        r.standardError[c] = static_cast<float>(std::sqrt(var[c]) / pixels);
      }
      out.push_back(r);
    }
  return out;
}

double normalTwoSidedThreshold(double p) {
  double lo = 0.0, hi = 40.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (std::erfc(mid / std::sqrt(2.0)) > p) lo = mid; else hi = mid;
  }
  return 0.5 * (lo + hi);
}

namespace {

Agreement compare(const std::vector<RegionEstimate>& a, const std::vector<Rgb>& b, const std::vector<Rgb>* seB, double alpha) {
  Agreement out;
  double brightest = 0.0;
  for (size_t r = 0; r < a.size(); ++r)
    for (int c = 0; c < 3; ++c) brightest = std::max({brightest, std::abs(static_cast<double>(a[r].mean[c])), std::abs(static_cast<double>(b[r][c]))});
  const double floor = 1e-3 * brightest;
  out.tests = static_cast<int>(a.size()) * 3;
  out.threshold = normalTwoSidedThreshold(alpha / out.tests);
  for (size_t r = 0; r < a.size(); ++r)
    for (int c = 0; c < 3; ++c) {
      const double diff = static_cast<double>(a[r].mean[c]) - b[r][c];
      const double se = std::hypot(std::hypot(static_cast<double>(a[r].standardError[c]), seB ? static_cast<double>((*seB)[r][c]) : 0.0), floor);
      const double z = se > 0.0 ? std::abs(diff) / se : (std::abs(diff) > 0.0 ? 1e30 : 0.0);
      const double scale = std::max(std::abs(static_cast<double>(a[r].mean[c])), std::abs(static_cast<double>(b[r][c])));
      if (scale > 0.0) out.maxRelativeDifference = std::max(out.maxRelativeDifference, std::abs(diff) / scale);
      if (z > out.maxAbsZ) {
        out.maxAbsZ = z;
        std::ostringstream os;
        os << "region " << r << " [" << a[r].x0 << "," << a[r].x1 << ")x[" << a[r].y0 << "," << a[r].y1 << ") channel " << c
           << ": " << a[r].mean[c] << " +- " << a[r].standardError[c] << " vs " << b[r][c];
        if (seB) os << " +- " << (*seB)[r][c];
        os << " (z = " << z << ")";
        out.worst = os.str();
      }
    }
  out.agree = out.maxAbsZ <= out.threshold;
  return out;
}

}  // namespace

Agreement compareRenders(const Film& a, const Film& b, int blocksX, int blocksY, double alpha) {
  const auto ra = regionEstimates(a, blocksX, blocksY);
  const auto rb = regionEstimates(b, blocksX, blocksY);
  std::vector<Rgb> means, ses;
  for (const auto& r : rb) means.push_back(r.mean), ses.push_back(r.standardError);
  return compare(ra, means, &ses, alpha);
}

Agreement compareToEstimates(const Film& film, int blocksX, int blocksY, const std::vector<RegionEstimate>& expected, double alpha) {
  std::vector<Rgb> means, ses;
  for (const auto& r : expected) means.push_back(r.mean), ses.push_back(r.standardError);
  return compare(regionEstimates(film, blocksX, blocksY), means, &ses, alpha);
}

Agreement compareToExpected(const Film& film, int blocksX, int blocksY, const std::vector<Rgb>& expected, double alpha) {
  return compare(regionEstimates(film, blocksX, blocksY), expected, nullptr, alpha);
}

}  // namespace candela
