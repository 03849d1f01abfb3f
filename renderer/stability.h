// The stability suite (assets/scenes/stability/cases.json): scenes and settings where a method is
// known to be weak. For each case every preset is rendered and checked against `conventional`
// (region z-test, stats.h), and its rejected samples, relative variance and largest single sample
// (the firefly measure) are recorded. Used by the statistical tests and by `candela-cli report`.
#pragma once

#include "film.h"
#include "scene_desc.h"

#include <string>
#include <vector>

namespace candela {

// Regions per axis of the agreement test: few, large regions, so heavy-tailed estimators still have
// enough samples per region for the test to have power.
inline constexpr int kStabilityBlocks = 2;

struct StabilityCase {
  std::string name;
  std::string scenePath;                  // absolute
  std::string weakness;                   // what makes it hard, and for which method
  std::vector<std::string> sets;          // --set edits for every strategy
  std::vector<std::string> strategySets;  // edits under "strategy." for every preset but conventional
  int sppScale = 1;                       // heavy-tailed cases get more samples, so the test keeps its power
};

std::vector<StabilityCase> loadStabilityCases(const std::string& manifestPath);
// The case's scene under a preset, at `width` x `height` pixels.
SceneDesc stabilityScene(const StabilityCase& c, const std::string& preset);

struct StabilityResult {
  std::string caseName, preset;
  int spp = 0;
  double seconds = 0.0;
  bool agrees = true;          // with conventional (always true for conventional itself)
  double maxAbsZ = 0.0, threshold = 0.0;
  double detectableBias = 0.0; // median over region-channels with signal (>= 1/10 of the brightest) of threshold x combined standard error / mean
  uint64_t rejected = 0;       // NaN, Inf or negative samples kept off the film
  double relativeVariance = 0.0;  // mean over pixels of per-sample variance / mean^2 (where mean > 0)
  float maxSample = 0.0f;      // largest single sample: the firefly measure
  std::vector<std::string> warnings;
};

// Renders the case with `preset` at `spp` (seed differs from conventional's) and compares it with
// `conventional` (a film of the same case rendered with the conventional preset).
StabilityResult runStability(const StabilityCase& c, const std::string& preset, int spp, const Film* conventional, Film* out = nullptr,
                             int threads = 0);

}  // namespace candela
