// Checks a viewer screenshot against the CLI's render of the same scene (used by the GUI test):
//   display_compare GUI.png GUI.exr CLI.exr SPP
// - the PNG carries the scene, the strategy settings as JSON, the display settings and spp;
// - the viewer's scene-linear EXR matches the CLI's (same seed and spp: the same samples);
// - the PNG is a rendered volume (not black, not uniform) and matches the CLI's EXR after the same
//   OCIO display transform run on the CPU, to within 8-bit quantisation and GPU/CPU rounding.
#include "color_pipeline.h"
#include "image_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

using namespace candela;

namespace {
int failures = 0;
void check(bool ok, const std::string& what) {
  std::printf("%s: %s\n", ok ? "ok  " : "FAIL", what.c_str());
  if (!ok) ++failures;
}
}  // namespace

int main(int argc, char** argv) {
  // display_compare --metadata IMAGE.png KEY: prints one metadata value (for the scripted GUI tests).
  if (argc == 4 && std::string(argv[1]) == "--metadata") {
    try {
      const DisplayImage image = readDisplayPng(argv[2]);
      auto it = image.metadata.find(argv[3]);
      if (it == image.metadata.end()) return 1;
      std::printf("%s\n", it->second.c_str());
      return 0;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s\n", e.what());
      return 1;
    }
  }
  // display_compare --halves IMAGE.png: mean 8-bit level of the left and right halves and of the
  // whole image, and how many distinct levels it holds (a rendered image, not a flat colour).
  if (argc == 3 && std::string(argv[1]) == "--halves") {
    try {
      const DisplayImage image = readDisplayPng(argv[2]);
      double left = 0.0, right = 0.0;
      std::map<int, int> levels;
      for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x)
          for (int c = 0; c < 3; ++c) {
            const int v = image.rgb8[3 * (static_cast<size_t>(y) * image.width + x) + c];
            (x < image.width / 2 ? left : right) += v;
            ++levels[v];
          }
      const double n = 1.5 * image.width * image.height;
      std::printf("left %.2f right %.2f mean %.2f levels %zu\n", left / n, right / n, 0.5 * (left + right) / n, levels.size());
      return 0;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s\n", e.what());
      return 1;
    }
  }
  // display_compare --same-exr A.exr B.exr: the two scene-linear images hold the same samples: equal
  // to float rounding (passes sized by time group the same samples differently, so sums round
  // differently in the last bits).
  if (argc == 4 && std::string(argv[1]) == "--same-exr") {
    try {
      const Image a = readExr(argv[2]), b = readExr(argv[3]);
      check(a.width == b.width && a.height == b.height, "same size");
      double worst = 0.0;
      bool same = a.rgb.size() == b.rgb.size();
      for (size_t i = 0; i < std::min(a.rgb.size(), b.rgb.size()); ++i) {
        const double d = std::abs(static_cast<double>(a.rgb[i]) - b.rgb[i]);
        worst = std::max(worst, d);
        same = same && d <= 1e-5 * std::max(1.0, std::abs(static_cast<double>(a.rgb[i])));
      }
      check(same, "the same pixels to float rounding (largest difference " + std::to_string(worst) + ")");
      return failures ? 1 : 0;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s\n", e.what());
      return 1;
    }
  }
  // display_compare --figure FIG.png FIG.csv PANES: the scripted comparison figure has PANES labelled
  // panes with rendered content, equal time shares (to one pass), and a CSV whose spp rises and whose
  // error falls for every pane.
  if (argc == 5 && std::string(argv[1]) == "--figure") {
    try {
      const DisplayImage fig = readDisplayPng(argv[2]);
      const int expected = std::stoi(argv[4]);
      const Json panes = Json::parse(fig.metadata.at("panes"));
      check(static_cast<int>(panes.size()) == expected, "the figure has " + std::to_string(panes.size()) + " panes");
      double lo = 1e30, hi = 0.0, hiStart = 0.0;
      for (const auto& p : panes) {
        lo = std::min(lo, p.at("seconds").get<double>());
        if (p.at("seconds").get<double>() > hi) {
          hi = p.at("seconds").get<double>();
          hiStart = hi - p.at("last_slice_seconds").get<double>();
        }
        check(p.at("spp").get<int>() > 0 && !p.at("label").get<std::string>().empty(),
              "pane " + p.at("label").get<std::string>() + ": " + std::to_string(p.at("spp").get<int>()) + " spp, " +
                  std::to_string(p.at("seconds").get<double>()) + " s");
      }
      // Equal time as the scheduler guarantees it on any machine, idle or busy: the pane with the
      // most time had no more than the least when its last pass began (equal to one pass).
      check(hiStart <= lo + 1e-6, "time shares equal to one pass (" + std::to_string(lo) + " .. " + std::to_string(hi) +
                                      " s, the last pass began at " + std::to_string(hiStart) + " s)");
      // Each pane of the figure (row by row in its grid) shows a rendered image: not black, not
      // uniform (below the label band).
      int columns = 0, rows = 0;
      check(std::sscanf(fig.metadata.at("grid").c_str(), "%dx%d", &columns, &rows) == 2 && columns > 0 && rows > 0 && columns * rows >= expected,
            "the figure's grid " + fig.metadata.at("grid") + " holds " + std::to_string(expected) + " panes");
      const int cellW = fig.width / columns, cellH = fig.height / rows;
      for (int k = 0; k < expected; ++k) {
        double sum = 0.0, sumSq = 0.0;
        int n = 0;
        const int x0 = (k % columns) * cellW, y0 = (k / columns) * cellH;
        for (int y = y0 + cellH / 3; y < y0 + cellH; ++y)
          for (int x = x0 + 4; x < x0 + cellW - 4; ++x)
            for (int c = 0; c < 3; ++c) {
              const double v = fig.rgb8[3 * (static_cast<size_t>(y) * fig.width + x) + c];
              sum += v, sumSq += v * v, ++n;
            }
        const double mean = sum / n, sd = std::sqrt(std::max(0.0, sumSq / n - mean * mean));
        check(mean > 0.5 && sd > 2.0, "pane " + std::to_string(k) + " strip: mean " + std::to_string(mean) + ", std. dev. " + std::to_string(sd));
      }
      std::ifstream csv(argv[3]);
      std::string line;
      std::map<std::string, std::vector<std::pair<int, double>>> series;
      while (std::getline(csv, line)) {
        if (line.empty() || line[0] == '#' || line.rfind("pane,", 0) == 0) continue;
        std::stringstream ss(line);
        std::string label, seconds, spp, mse, relmse;
        std::getline(ss, label, ',');
        std::getline(ss, seconds, ',');
        std::getline(ss, spp, ',');
        std::getline(ss, mse, ',');
        std::getline(ss, relmse, ',');
        series[label].push_back({std::stoi(spp), std::stod(relmse)});
      }
      check(static_cast<int>(series.size()) == expected, "the CSV has a series per pane");
      for (const auto& [label, points] : series) {
        bool rising = points.size() >= 2;
        for (size_t i = 1; i < points.size(); ++i) rising = rising && points[i].first > points[i - 1].first;
        check(rising, label + ": spp rises over " + std::to_string(points.size()) + " samples");
        check(points.size() >= 2 && points.back().second < points.front().second,
              label + ": relMSE falls from " + std::to_string(points.front().second) + " to " + std::to_string(points.back().second));
      }
    } catch (const std::exception& e) {
      std::printf("FAIL: %s\n", e.what());
      return 1;
    }
    return failures ? 1 : 0;
  }
  if (argc != 5) {
    std::fprintf(stderr, "usage: display_compare GUI.png GUI.exr CLI.exr SPP\n");
    return 2;
  }
  try {
    const DisplayImage gui = readDisplayPng(argv[1]);
    const Image guiExr = readExr(argv[2]);
    const Image cli = readExr(argv[3]);
    const int spp = std::stoi(argv[4]);

    // Metadata.
    for (const char* key : {"scene", "strategy", "settings", "display", "spp", "time_s"})
      check(gui.metadata.count(key) == 1, std::string("PNG metadata has ") + key);
    if (failures) return 1;
    check(gui.metadata.at("spp") == std::to_string(spp), "PNG metadata spp = " + gui.metadata.at("spp"));
    const Json strategy = Json::parse(gui.metadata.at("strategy"));
    check(strategy.contains("majorant") && strategy.contains("guiding"), "strategy metadata is the full settings JSON");
    check(guiExr.metadata.count("strategy") == 1, "EXR metadata has the strategy");

    // Same samples as the CLI.
    check(gui.width == cli.width && gui.height == cli.height && guiExr.width == cli.width, "sizes match the CLI render");
    if (failures) return 1;
    double worst = 0.0;
    for (size_t i = 0; i < cli.rgb.size(); ++i)
      worst = std::max(worst, std::abs(static_cast<double>(guiExr.rgb[i]) - cli.rgb[i]) / std::max(1e-3, static_cast<double>(cli.rgb[i])));
    check(worst < 1e-3, "scene-linear EXR equals the CLI's (worst relative difference " + std::to_string(worst) + ")");

    // A rendered volume.
    double mean = 0.0, meanSq = 0.0;
    for (uint8_t v : gui.rgb8) mean += v, meanSq += double(v) * v;
    mean /= gui.rgb8.size();
    const double stddev = std::sqrt(std::max(0.0, meanSq / gui.rgb8.size() - mean * mean));
    check(mean > 1.0, "not black (mean " + std::to_string(mean) + " of 255)");
    check(stddev > 3.0, "not uniform (std. dev. " + std::to_string(stddev) + ")");

    // The GPU display pass against OCIO's CPU processor with the same settings.
    const ColorPipeline colors = ColorPipeline::load(gui.metadata.count("ocio_config") ? gui.metadata.at("ocio_config") : "");
    DisplaySettings display;
    fromJson(Json::parse(gui.metadata.at("display")), display, argv[1], "display");
    std::vector<float> expected = cli.rgb;
    colors.applyCpu(display, expected);
    std::vector<int> diffs(expected.size());
    double meanDiff = 0.0;
    for (size_t i = 0; i < expected.size(); ++i) {
      diffs[i] = std::abs(int(toDisplayByte(expected[i])) - int(gui.rgb8[i]));
      meanDiff += diffs[i];
    }
    meanDiff /= diffs.size();
    std::sort(diffs.begin(), diffs.end());
    const int p999 = diffs[diffs.size() * 999 / 1000];
    check(meanDiff < 0.5, "PNG matches the CLI render through the same display transform (mean |diff| " + std::to_string(meanDiff) + " of 255)");
    check(p999 <= 3, "99.9th percentile |diff| " + std::to_string(p999) + " <= 3 of 255 (max " + std::to_string(diffs.back()) + ")");
  } catch (const std::exception& e) {
    std::printf("FAIL: %s\n", e.what());
    return 1;
  }
  return failures ? 1 : 0;
}
