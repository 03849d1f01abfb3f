#include "convergence.h"

#include "atomic_file.h"

#include "procedural.h"
#include "renderer.h"
#include "rng.h"
#include "sequence.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace candela {

namespace {

struct ChartBox {
  double W, H, L, R, T, B;  // size and margins
};

// Decade grid lines (with minor lines), tick labels, the plot frame and axis titles of a log-log chart
// whose axes span 10^x0..10^x1 and 10^y0..10^y1.
void logLogFrame(std::ostringstream& s, const ChartBox& c, double x0, double x1, double y0, double y1, const std::string& xTitle,
                 const std::string& yTitle) {
  auto X = [&](double v) { return c.L + (std::log10(v) - x0) / (x1 - x0) * (c.W - c.L - c.R); };
  auto Y = [&](double v) { return c.H - c.B - (std::log10(v) - y0) / (y1 - y0) * (c.H - c.T - c.B); };
  for (double d = x0; d <= x1 + 1e-9; ++d) {
    for (int m = 1; m < 10 && d + std::log10(m) <= x1 + 1e-9; ++m) {
      const double x = X(std::pow(10.0, d) * m);
      s << "<line x1='" << x << "' y1='" << c.T << "' x2='" << x << "' y2='" << c.H - c.B << "' stroke='" << (m == 1 ? "#bbb" : "#eee") << "'/>\n";
    }
    s << "<text x='" << X(std::pow(10.0, d)) << "' y='" << c.H - c.B + 18 << "' text-anchor='middle'>1e" << d << "</text>\n";
  }
  for (double d = y0; d <= y1 + 1e-9; ++d) {
    for (int m = 1; m < 10 && d + std::log10(m) <= y1 + 1e-9; ++m) {
      const double y = Y(std::pow(10.0, d) * m);
      s << "<line x1='" << c.L << "' y1='" << y << "' x2='" << c.W - c.R << "' y2='" << y << "' stroke='" << (m == 1 ? "#bbb" : "#eee") << "'/>\n";
    }
    s << "<text x='" << c.L - 8 << "' y='" << Y(std::pow(10.0, d)) + 4 << "' text-anchor='end'>1e" << d << "</text>\n";
  }
  s << "<rect x='" << c.L << "' y='" << c.T << "' width='" << c.W - c.L - c.R << "' height='" << c.H - c.T - c.B
    << "' fill='none' stroke='black'/>\n"
    << "<text x='" << (c.L + c.W - c.R) / 2 << "' y='" << c.H - 18 << "' text-anchor='middle'>" << xTitle << "</text>\n"
    << "<text transform='translate(20," << (c.T + c.H - c.B) / 2 << ") rotate(-90)' text-anchor='middle'>" << yTitle << "</text>\n";
}

void legendEntry(std::ostringstream& s, const ChartBox& c, int row, const char* color, const std::string& label) {
  const double y = c.T + 20 + 22 * static_cast<double>(row);
  s << "<line x1='" << c.W - c.R + 15 << "' y1='" << y << "' x2='" << c.W - c.R + 40 << "' y2='" << y << "' stroke='" << color
    << "' stroke-width='3'/><text x='" << c.W - c.R + 46 << "' y='" << y + 4 << "'>" << label << "</text>\n";
}

void writeFile(const std::string& path, const std::string& text) { writeTextAtomically(path, text); }

// The unbiased variance of one sample from a film entry's sum and sum of squares over n >= 2 samples.
double sampleVariance(float sum, float sumSquares, int n) {
  const double m = static_cast<double>(sum) / n;
  return std::max(0.0, (static_cast<double>(sumSquares) / n - m * m) * n / (n - 1.0));
}
}  // namespace

const char* const kRelMseFormula =
    "relmse = mean over pixels and channels of (I - R)^2 / (R^2 + eps) with eps = (0.1 * mean(R))^2; "
    "mse = mean over pixels and channels of (I - R)^2; I the render, R the reference";

std::vector<double> regionalRelativeVariance(const Film& film, int regionSize, int& regionsX, int& regionsY) {
  std::vector<double> out;
  const int w = film.width(), h = film.height(), n = film.spp();
  const int size = std::max(1, regionSize);
  regionsX = (w + size - 1) / size, regionsY = (h + size - 1) / size;
  if (n < 2) return out;
  const std::vector<float>& sum = film.sum();
  const std::vector<float>& sumSq = film.sumSquares();
  double imageMean = 0.0;
  for (float v : sum) imageMean += static_cast<double>(v) / n;
  imageMean /= std::max<size_t>(1, sum.size());
  const double eps = (0.1 * imageMean) * (0.1 * imageMean) + 1e-30;
  for (int ry = 0; ry < h; ry += size)
    for (int rx = 0; rx < w; rx += size) {
      // Per channel, as the relMSE is: a red flame's faint blue weighs as much as its red.
      double relative = 0.0;
      for (int ch = 0; ch < 3; ++ch) {
        double var = 0.0, mean = 0.0;
        int count = 0;
        for (int y = ry; y < std::min(h, ry + size); ++y)
          for (int x = rx; x < std::min(w, rx + size); ++x, ++count) {
            const size_t i = 3 * (static_cast<size_t>(y) * w + x) + ch;
            var += sampleVariance(sum[i], sumSq[i], n);
            mean += static_cast<double>(sum[i]) / n;
          }
        mean /= count;
        relative += (var / count) / (mean * mean + eps);
      }
      out.push_back(relative / 3.0);
    }
  return out;
}

double relativeVariancePerSample(const Film& film) {
  int rx = 0, ry = 0;
  const std::vector<double> regions = regionalRelativeVariance(film, 8, rx, ry);
  double total = 0.0;
  for (double v : regions) total += v;
  return regions.empty() ? 0.0 : total / static_cast<double>(regions.size());
}

double variancePerSample(const Film& film) {
  const int n = film.spp();
  if (n < 2) return 0.0;
  const std::vector<float>& sum = film.sum();
  const std::vector<float>& sumSq = film.sumSquares();
  double total = 0.0;
  for (size_t i = 0; i < sum.size(); ++i) total += sampleVariance(sum[i], sumSq[i], n);
  return sum.empty() ? 0.0 : total / static_cast<double>(sum.size());
}

PixelMoments pixelMoments(const Film& film) {
  PixelMoments m;
  const int n = film.spp();
  if (n < 2) return m;
  const std::vector<float>& sum = film.sum();
  const std::vector<float>& sumSq = film.sumSquares();
  m.mean.resize(sum.size());
  m.variance.resize(sum.size());
  for (size_t i = 0; i < sum.size(); ++i) {
    m.mean[i] = sum[i] / static_cast<float>(n);
    m.variance[i] = static_cast<float>(sampleVariance(sum[i], sumSq[i], n));
  }
  return m;
}

double relativeEpsilon(double meanValue) { return (0.1 * meanValue) * (0.1 * meanValue) + 1e-30; }

namespace {
// The relMSE's eps for a shared mean image.
double relativeEps(const std::vector<float>& mean) {
  double meanOfMean = 0.0;
  for (float v : mean) meanOfMean += v;
  return relativeEpsilon(meanOfMean / static_cast<double>(std::max<size_t>(1, mean.size())));
}
}  // namespace

double relativeVarianceAgainst(const std::vector<float>& variance, const std::vector<float>& mean) {
  if (variance.empty() || variance.size() != mean.size()) return 0.0;
  const double eps = relativeEps(mean);
  double total = 0.0;
  for (size_t i = 0; i < variance.size(); ++i) total += variance[i] / (static_cast<double>(mean[i]) * mean[i] + eps);
  return total / static_cast<double>(variance.size());
}

ErrorMetrics imageError(const std::vector<float>& image, const std::vector<float>& reference) {
  ErrorMetrics e;
  if (image.size() != reference.size() || image.empty()) return {NAN, NAN};
  double refMean = 0.0;
  for (float r : reference) refMean += r;
  refMean /= static_cast<double>(reference.size());
  const double eps = std::max(1e-12, (0.1 * refMean) * (0.1 * refMean));
  for (size_t i = 0; i < image.size(); ++i) {
    const double d = static_cast<double>(image[i]) - reference[i];
    e.mse += d * d;
    e.relmse += d * d / (static_cast<double>(reference[i]) * reference[i] + eps);
  }
  e.mse /= static_cast<double>(image.size());
  e.relmse /= static_cast<double>(image.size());
  return e;
}

std::vector<float> errorFalseColour(const std::vector<float>& image, const std::vector<float>& reference, bool relative) {
  static const float ramp[6][3] = {{0, 0, 0}, {0.1f, 0.2f, 0.9f}, {0.1f, 0.8f, 0.3f}, {0.95f, 0.9f, 0.1f}, {0.95f, 0.15f, 0.1f}, {1, 1, 1}};
  double mean = 0.0;
  for (float v : reference) mean += v;
  mean = std::max(1e-12, mean / std::max<size_t>(1, reference.size()));
  const double eps = 0.01 * mean * mean;  // (0.1 mean)^2, as in relMSE
  std::vector<float> out(image.size(), 0.0f);
  for (size_t p = 0; p + 2 < image.size() && p + 2 < reference.size(); p += 3) {
    double e = 0.0;
    for (int c = 0; c < 3; ++c) {
      const double d = std::abs(double(image[p + c]) - reference[p + c]);
      e += relative ? d / std::sqrt(double(reference[p + c]) * reference[p + c] + eps) : d / mean;
    }
    const float t = std::clamp(static_cast<float>((std::log10(std::max(1e-6, e / 3.0)) + 2.0) / 3.0), 0.0f, 1.0f) * 5.0f;
    const int k = std::min(4, static_cast<int>(t));
    const float f = t - k;
    for (int c = 0; c < 3; ++c) out[p + c] = ramp[k][c] * (1 - f) + ramp[k + 1][c] * f;
  }
  return out;
}

std::string sceneContentHash(const SceneDesc& scene, const std::string& extra) {
  Json doc = sceneToJson(scene);
  doc.erase("strategy");
  doc.erase("display");  // how it is shown, not what is rendered
  doc.erase("description");
  doc["render"].erase("spp");
  doc["render"].erase("time_s");
  for (size_t i = 0; i < scene.volumes.size(); ++i) {
    const VolumeDesc& volume = scene.volumes[i];
    if (volume.has_generator || volume.file.empty()) continue;
    namespace fs = std::filesystem;
    const fs::path file = volumeFilePath(scene, volume, scene.render.frame);
    std::error_code error;
    const fs::path canonical = fs::weakly_canonical(fs::absolute(file, error), error);
    const auto size = fs::file_size(canonical, error);
    const auto modified = fs::last_write_time(canonical, error);
    doc["volumes"][i]["file"] = error ? file.string()
                                      : canonical.string() + "|" + std::to_string(size) + "|" +
                                            std::to_string(modified.time_since_epoch().count());
  }
  const std::string text = doc.dump() + "|" + extra;
  uint64_t h = 0xcafef00dULL;
  for (char c : text) h = hashCombine(h, static_cast<uint64_t>(static_cast<unsigned char>(c)));
  char buf[32];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

Image cachedReference(const SceneDesc& scene, const StrategySettings& strategy, int spp, int threads, std::string* cachePath) {
  namespace fs = std::filesystem;
  // One reference for every render seed: a bench over seeds 1-3 renders it once, not three times.
  // It is rendered with a seed of its own, so it shares no samples with the renders it judges
  // (unless one of them asks for seed 0x5eed).
  SceneDesc keyed = scene;
  keyed.render.seed = 0;
  const std::string key = sceneContentHash(keyed, "reference-v2 spp=" + std::to_string(spp) + " " + toJson(strategy).dump());
  const fs::path dir = fs::path(cacheDirectory()) / "references";
  const fs::path path = dir / (key + ".exr");
  if (cachePath) *cachePath = path.string();
  if (fs::exists(path)) return readExr(path.string());
  SceneDesc desc = scene;
  desc.strategy = strategy;
  desc.render.seed = 0x5eedu;
  auto built = Scene::build(desc);
  ProgressiveRenderer renderer(built, RenderOptions{threads, 32});
  Film film;
  const double seconds = renderer.renderBudget(film, spp, 0.0, std::max(1, std::min(spp, 16)));
  Image image;
  image.width = film.width();
  image.height = film.height();
  image.rgb = film.meanImage();
  image.metadata["scene"] = scene.path;
  image.metadata["strategy"] = toJson(strategy).dump();
  image.metadata["spp"] = std::to_string(film.spp());
  image.metadata["seconds"] = std::to_string(seconds);
  fs::create_directories(dir);
  const fs::path tmp = dir / (key + ".tmp.exr");
  writeExr(tmp.string(), image);
  fs::rename(tmp, path);
  return image;
}

void writeConvergenceCsv(const std::string& path, const std::vector<ConvergencePoint>& points, const std::string& comment) {
  std::ostringstream out;
  out << "# " << kRelMseFormula << "\n";
  if (!comment.empty()) out << "# " << comment << "\n";
  out << "strategy,budget_s,time_s,spp,mse,relmse,rejected\n";
  for (const auto& p : points)
    out << p.strategy << ',' << p.budgetSeconds << ',' << p.seconds << ',' << p.spp << ',' << p.mse << ',' << p.relmse << ','
        << p.rejected << '\n';
  writeTextAtomically(path, out.str());
}

void writeConvergenceSvg(const std::string& path, const std::vector<ConvergencePoint>& points, const std::string& title) {
  std::map<std::string, std::vector<const ConvergencePoint*>> series;
  std::vector<std::string> order;
  double tMin = 1e30, tMax = -1e30, eMin = 1e30, eMax = -1e30;
  for (const auto& p : points) {
    if (!(p.relmse > 0.0) || !(p.seconds > 0.0) || !std::isfinite(p.relmse)) continue;
    if (!series.count(p.strategy)) order.push_back(p.strategy);
    series[p.strategy].push_back(&p);
    tMin = std::min(tMin, p.seconds), tMax = std::max(tMax, p.seconds);
    eMin = std::min(eMin, p.relmse), eMax = std::max(eMax, p.relmse);
  }
  if (order.empty()) tMin = 0.1, tMax = 1, eMin = 0.01, eMax = 1;
  const double lt0 = std::floor(std::log10(tMin)), lt1 = std::max(lt0 + 1, std::ceil(std::log10(tMax)));
  const double le0 = std::floor(std::log10(eMin)), le1 = std::max(le0 + 1, std::ceil(std::log10(eMax)));
  const double W = 720, H = 480, L = 80, R = 180, T = 50, B = 60;
  auto X = [&](double t) { return L + (std::log10(t) - lt0) / (lt1 - lt0) * (W - L - R); };
  auto Y = [&](double e) { return H - B - (std::log10(e) - le0) / (le1 - le0) * (H - T - B); };
  static const char* colors[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf"};
  std::ostringstream s;
  s << "<svg xmlns='http://www.w3.org/2000/svg' width='" << W << "' height='" << H << "' font-family='sans-serif' font-size='12'>\n"
    << "<rect width='100%' height='100%' fill='white'/>\n"
    << "<text x='" << W / 2 << "' y='24' text-anchor='middle' font-size='15'>" << title << "</text>\n";
  logLogFrame(s, {W, H, L, R, T, B}, lt0, lt1, le0, le1, "render time (s, log)", "relMSE (log)");
  for (size_t i = 0; i < order.size(); ++i) {
    auto& pts = series[order[i]];
    std::sort(pts.begin(), pts.end(), [](auto* a, auto* b) { return a->seconds < b->seconds; });
    const char* c = colors[i % 8];
    s << "<polyline fill='none' stroke='" << c << "' stroke-width='2' points='";
    for (auto* p : pts) s << X(p->seconds) << ',' << Y(p->relmse) << ' ';
    s << "'/>\n";
    for (auto* p : pts) s << "<circle cx='" << X(p->seconds) << "' cy='" << Y(p->relmse) << "' r='3.5' fill='" << c << "'/>\n";
    legendEntry(s, {W, H, L, R, T, B}, static_cast<int>(i), c, order[i]);
  }
  s << "</svg>\n";
  writeFile(path, s.str());
}

void writeSweepSvg(const std::string& path, const std::vector<SweepPoint>& points, const std::string& title, const std::string& xLabel) {
  std::vector<std::string> order;
  double xMin = 1e30, xMax = -1e30, yMin = 1e30, yMax = -1e30;
  for (const auto& p : points) {
    if (std::find(order.begin(), order.end(), p.strategy) == order.end()) order.push_back(p.strategy);
    if (!(p.efficiency > 0.0) || !std::isfinite(p.efficiency)) continue;
    yMin = std::min(yMin, p.efficiency), yMax = std::max(yMax, p.efficiency);
    if (p.value > 0.0) xMin = std::min(xMin, p.value), xMax = std::max(xMax, p.value);
  }
  if (xMin > xMax) xMin = 0.1, xMax = 10;
  if (yMin > yMax) yMin = 0.1, yMax = 10;
  const double lx0 = std::floor(std::log10(xMin)), lx1 = std::max(lx0 + 1, std::ceil(std::log10(xMax)));
  const double ly0 = std::floor(std::log10(yMin)), ly1 = std::max(ly0 + 1, std::ceil(std::log10(yMax)));
  const double W = 720, H = 480, L = 80, R = 190, T = 50, B = 60;
  auto X = [&](double v) { return L + (std::log10(v) - lx0) / (lx1 - lx0) * (W - L - R); };
  auto Y = [&](double e) { return H - B - (std::log10(e) - ly0) / (ly1 - ly0) * (H - T - B); };
  static const char* colors[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b"};
  std::ostringstream s;
  s << "<svg xmlns='http://www.w3.org/2000/svg' width='" << W << "' height='" << H << "' font-family='sans-serif' font-size='12'>\n"
    << "<rect width='100%' height='100%' fill='white'/>\n"
    << "<text x='" << W / 2 << "' y='24' text-anchor='middle' font-size='15'>" << title << "</text>\n";
  logLogFrame(s, {W, H, L, R, T, B}, lx0, lx1, ly0, ly1, xLabel + " (log)", "efficiency 1/(relMSE x time) (log)");
  for (size_t i = 0; i < order.size(); ++i) {
    const char* c = colors[i % 6];
    std::vector<const SweepPoint*> pts;
    for (const auto& p : points)
      if (p.strategy == order[i] && p.efficiency > 0.0 && std::isfinite(p.efficiency)) pts.push_back(&p);
    std::sort(pts.begin(), pts.end(), [](auto* a, auto* b) { return a->value < b->value; });
    s << "<polyline fill='none' stroke='" << c << "' stroke-width='2' points='";
    for (auto* p : pts)
      if (p->value > 0.0) s << X(p->value) << ',' << Y(p->efficiency) << ' ';
    s << "'/>\n";
    for (auto* p : pts) {
      if (p->value > 0.0) {
        s << "<circle cx='" << X(p->value) << "' cy='" << Y(p->efficiency) << "' r='3.5' fill='" << c << "'/>\n";
        if (!p->note.empty())
          s << "<text x='" << X(p->value) + 6 << "' y='" << Y(p->efficiency) - 8 << "' font-size='10' fill='" << c << "'>" << p->note
            << "</text>\n";
      } else {
        s << "<line x1='" << L << "' y1='" << Y(p->efficiency) << "' x2='" << W - R << "' y2='" << Y(p->efficiency) << "' stroke='" << c
          << "' stroke-dasharray='6,4'/><text x='" << L + 6 << "' y='" << Y(p->efficiency) - 5 << "' fill='" << c << "'>" << xLabel
          << " = 0</text>\n";
      }
    }
    legendEntry(s, {W, H, L, R, T, B}, static_cast<int>(i), c, order[i]);
  }
  s << "</svg>\n";
  writeFile(path, s.str());
}

}  // namespace candela
