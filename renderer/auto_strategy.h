// The `auto` strategy: Candela chooses the sampling strategy for the scene, so artists need not know
// which preset, emission weight or guided depth suits their shot. Two steps:
// 1. Rules from the scene: emission sampling only when some volume emits (a scene without emission
//    never builds emission structures), with the emission weight relative to each medium's emission
//    scale; scattering (distance) sampling only when some volume scatters a light and enough camera
//    rays are thin enough for it to help (a thick cloud never learns probes).
// 2. Where volumes emit and either only they scatter or a sun shines too, full stands and runs
//    without a pilot: its gain there is in samples too rare for a pilot to see. Elsewhere a pilot:
//    the plain candidate and the guided camera vertex ("full") render a few samples per pixel of a
//    small image; equiangular follows only where full led in the image. Full measures each pixel
//    block's q itself (guiding.measured_pixel_probability), so no refinement of its q is a
//    candidate. Each one's variance per sample (the film's
//    sums of squares), relative to a mean image all candidates share and absolute, times its work
//    (work.h: counted, never timed)
//    gives two efficiencies; the candidate whose worse one, relative to the best candidate's, is
//    highest is kept (the report holds auto to the best preset by relMSE and by MSE) if it beats
//    the plain candidate by kAutoMargin on fresh samples after leading the pilot by
//    sqrt(kAutoMargin).
//    The same seed gives the same decision on any machine and thread count. An image small enough
//    is piloted as it is, on sample indices of its own per candidate, and the pilot's samples stay
//    in the image (AutoDecision::pilotFilm), but for the images that only measure (under a sun
//    the plain candidate's, a fresh round's second look at it included): the pilot then costs the
//    difference between the candidates it kept and the one it chose, and those images' work.
// Every candidate is an unbiased strategy: the choice changes the noise, never the image.
#pragma once

#include "settings.h"

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

namespace candela {

class Film;
class Scene;

struct AutoCandidate {
  std::string name;  // "emission", "conventional, gathering", "full", "equiangular"
  StrategySettings strategy;
  // The candidate the others must beat by kAutoMargin in the pilot (exactly one per list): the plain
  // one, or `full` where volumes emit and either only they scatter or a sun shines too, where it is
  // the only candidate (autoCandidates says why).
  bool standing = false;
};

struct AutoMeasurement {
  std::string name;
  // Per sample: the mean over pixels of variance / (shared mean^2 + eps), the shared mean being the
  // mean of every pilot image (the relMSE one sample per pixel would have), and the mean variance
  // (the MSE one sample per pixel would have).
  double relativeVariance = 0.0;
  double absoluteVariance = 0.0;
  double workPerSample = 0.0;  // WorkCounters::cost() per camera sample
  // 1 / (variance x workPerSample) by each figure, and the score that ranks the candidates: the
  // worse of the two, each relative to the best candidate's.
  double relativeEfficiency = 0.0, absoluteEfficiency = 0.0;
  double efficiency = 0.0;
};

struct AutoDecision {
  std::string chosen;  // the candidate's name ("emission", "full", "conventional, gathering", ...)
  // What the status bar, the report and the metadata show. (The candidates guide continuations as
  // the preset of the same name does, so the name alone says which settings ran.)
  std::string label() const { return chosen; }
  std::vector<std::string> reasons;        // the scene rules that decided the candidates
  std::vector<AutoMeasurement> pilot;      // empty when a single candidate needed no pilot
  double pilotWork = 0.0;                  // cost of the pilot in work units (ns on the calibration core)
  // Wall time of the rules, any probe learning and the pilot: reported, and charged to auto's time
  // in bench and report; never read to decide.
  double pilotSeconds = 0.0;
  // Of which learning probes for guided candidates: what a fixed guided preset also spends building
  // its scene, so bench and report charge auto only pilotSeconds - probeSeconds, as they charge no
  // preset its build.
  double probeSeconds = 0.0;
  // The time an equal-time comparison (bench, report, the viewer's panes) charges auto for deciding.
  double chargedSeconds() const { return std::max(0.0, pilotSeconds - probeSeconds); }
  int pilotWidth = 0, pilotHeight = 0, pilotSpp = 0;  // pilotSpp: per candidate image
  // Every kept pilot image's samples summed (all but a fresh round's second look at its rival and,
  // under a sun, the plain candidate's image: docs/method.md 4b), when the pilot rendered the image
  // itself (at most kPilotSamples pixels): sample indices 0 to pilotFilm->spp() - 1 of the scene's
  // seed, to be continued from (continueFromPilot). Null when the pilot rendered a reduced copy.
  std::shared_ptr<const Film> pilotFilm;
  std::string pilotView;  // the camera and render settings pilotFilm was rendered with (JSON)
  // One line: "auto chose emission: volumes emit; ...; pilot: emission 1.00, full 0.62".
  std::string summary() const;
};

// The emission weight auto uses, relative to each medium's emission scale (relative_weight): the
// value the per-sample sweep in docs/performance.md ("The auto strategy") puts within 5% of the best
// by relMSE and by MSE on fire, glow-box, torch-in-mist, torch-in-fog and a thin, bright flame.
inline constexpr float kAutoRelativeEmissionWeight = 10.0f;
// Camera samples per candidate image in the pilot (128 x 72 x 8): an image of at most this many
// pixels is piloted as it is, at 2-8 spp, and keeps the pilot's samples; a larger one is piloted on
// a copy of about 128 x 72 pixels at 8 spp.
inline constexpr double kPilotSamples = 128.0 * 72.0 * 8.0;
// How much more efficient than the plain candidate an elaborate one must be in the pilot.
inline constexpr double kAutoMargin = 1.2;
// Auto's StrategySettings::adaptive_split: the most camera samples per film sample in a block.
inline constexpr int kAutoSplit = 8;

// The settings `auto` starts from (before rules and pilot): conventional, named "auto".
StrategySettings autoBaseStrategy();
// True for settings that still need resolving (the preset "auto" as chosen, not yet decided).
bool needsAutoResolve(const StrategySettings& s);

// The candidates the scene rules leave, with the reasons.
std::vector<AutoCandidate> autoCandidates(const Scene& scene, std::vector<std::string>& reasons);

// Decides for `scene` (rules, then the pilot when more than one candidate remains), applies the
// choice with scene.setStrategy (preset stays "auto") and returns what it decided.
AutoDecision resolveAutoStrategy(Scene& scene);

// Auto's choice as settings an artist can take over: `running` (the scene's strategy once auto has
// decided, preset "auto") under the preset named after the chosen candidate ("conventional,
// gathering" is the conventional preset with gathering on), so that an edit to any of its fields
// starts from what auto chose and runs as edited, without deciding again. The viewer's Strategy
// panel shows auto's choice in its fields and applies an edit to them through this.
StrategySettings takeOverAutoChoice(const StrategySettings& running, const std::string& chosen);

// The film a render of `scene` starts from: the pilot's samples when auto piloted the image itself,
// the scene's camera still matches it and they do not exceed `maxSpp` (0: no limit, for a render to
// time); an empty film otherwise. Each sample's expectation is the pixel's value whichever candidate
// drew it and the renderer continues at the next sample index, so the image stays unbiased.
Film continueFromPilot(const Scene& scene, int maxSpp);

}  // namespace candela
