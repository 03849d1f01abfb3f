#include "stability.h"

#include "renderer.h"
#include "scene.h"
#include "stats.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>

namespace candela {

std::vector<StabilityCase> loadStabilityCases(const std::string& manifestPath) {
  std::ifstream in(manifestPath);
  if (!in) throw InputError(manifestPath + ": cannot open the stability manifest");
  Json doc;
  try {
    doc = Json::parse(in);
  } catch (const std::exception& e) {
    throw InputError(manifestPath + ": not valid JSON (" + e.what() + ")");
  }
  if (!doc.contains("cases") || !doc["cases"].is_array()) throw InputError(manifestPath + ": cases: expected an array");
  const auto base = std::filesystem::path(manifestPath).parent_path();
  std::vector<StabilityCase> cases;
  for (size_t i = 0; i < doc["cases"].size(); ++i) {
    const Json& j = doc["cases"][i];
    const std::string field = "cases." + std::to_string(i);
    if (!j.contains("name") || !j.contains("scene")) throw InputError(manifestPath + ": " + field + ": expected \"name\" and \"scene\"");
    StabilityCase c;
    c.name = j["name"].get<std::string>();
    c.scenePath = (base / j["scene"].get<std::string>()).lexically_normal().string();
    c.weakness = j.value("weakness", "");
    if (j.contains("sets")) c.sets = j["sets"].get<std::vector<std::string>>();
    if (j.contains("strategy_sets")) c.strategySets = j["strategy_sets"].get<std::vector<std::string>>();
    c.sppScale = j.value("spp_scale", 1);
    if (c.sppScale < 1 || c.sppScale > 1024) throw InputError(manifestPath + ": " + field + ".spp_scale: expected an integer in [1, 1024]");
    cases.push_back(c);
  }
  return cases;
}

SceneDesc stabilityScene(const StabilityCase& c, const std::string& preset) {
  std::vector<std::string> sets = c.sets;
  if (preset != "conventional")
    for (const auto& s : c.strategySets) sets.push_back("strategy." + s);
  return loadSceneDesc(c.scenePath, sets, preset);
}

StabilityResult runStability(const StabilityCase& c, const std::string& preset, int spp, const Film* conventional, Film* out, int threads) {
  StabilityResult r;
  r.caseName = c.name;
  r.preset = preset;
  r.spp = spp;
  SceneDesc desc = stabilityScene(c, preset);
  // Independent streams: conventional keeps the scene's seed, the other presets use another.
  if (preset != "conventional") desc.render.seed += 1000;
  const auto start = std::chrono::steady_clock::now();
  auto scene = Scene::build(desc, &r.warnings);
  ProgressiveRenderer renderer(scene, RenderOptions{threads, 16});
  Film film;
  renderer.renderBudget(film, spp, 0.0, std::min(spp, 64));
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.rejected = film.rejectedSamples();
  r.maxSample = film.maxSample();
  double rv = 0.0;
  int counted = 0;
  for (int y = 0; y < film.height(); ++y)
    for (int x = 0; x < film.width(); ++x) {
      const Rgb m = film.mean(x, y), se = film.standardError(x, y);
      const float lum = (m.r + m.g + m.b) / 3.0f;
      if (lum <= 0.0f) continue;
      const float seLum = (se.r + se.g + se.b) / 3.0f;
      rv += static_cast<double>(seLum) * seLum * film.spp() / (static_cast<double>(lum) * lum);  // per-sample variance / mean^2
      ++counted;
    }
  r.relativeVariance = counted ? rv / counted : 0.0;
  if (conventional && preset != "conventional") {
    const Agreement a = compareRenders(film, *conventional, kStabilityBlocks, kStabilityBlocks);
    r.agrees = a.agree;
    r.maxAbsZ = a.maxAbsZ;
    r.threshold = a.threshold;
    const auto ra = regionEstimates(film, kStabilityBlocks, kStabilityBlocks), rb = regionEstimates(*conventional, kStabilityBlocks, kStabilityBlocks);
    // Over the region-channels that carry signal (at least a tenth of the brightest): a bias in a
    // channel that is nearly black (the blue of a flame) is neither visible nor meaningful.
    double brightest = 0.0;
    for (size_t i = 0; i < ra.size(); ++i)
      for (int ch = 0; ch < 3; ++ch) brightest = std::max(brightest, 0.5 * (ra[i].mean[ch] + rb[i].mean[ch]));
    std::vector<double> detectable;
    for (size_t i = 0; i < ra.size(); ++i)
      for (int ch = 0; ch < 3; ++ch) {
        const double m = 0.5 * (ra[i].mean[ch] + rb[i].mean[ch]);
        if (m <= 0.1 * brightest || m <= 0.0) continue;
        const double s = std::sqrt(double(ra[i].standardError[ch]) * ra[i].standardError[ch] + double(rb[i].standardError[ch]) * rb[i].standardError[ch]);
        detectable.push_back(a.threshold * s / m);
      }
    if (!detectable.empty()) {
      std::nth_element(detectable.begin(), detectable.begin() + detectable.size() / 2, detectable.end());
      r.detectableBias = detectable[detectable.size() / 2];
    }
  }
  if (out) *out = std::move(film);
  return r;
}

}  // namespace candela
