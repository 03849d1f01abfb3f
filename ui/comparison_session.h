// Equal-time comparison of sampling strategies (the talk's Fig. 1, live): 1 to 4 panes over the
// same scene and camera, each with its own strategy settings. One worker interleaves time slices of
// about 60 ms with the same thread count, always giving the next slice to the pane with the least
// render time, so at any moment the panes have had the same CPU time to within one slice. With a
// reference image each pane gets an error-versus-time series (MSE, relMSE) against it; without one,
// the series is each pane's own estimate (its pixels' sample variance over spp: the MSE of an
// unbiased render, docs/method.md s.5). Every pane's region means are tested against the others'
// (a biased strategy shows as disagreeing).
// No GL: the viewer draws it, tests drive it headless.
#pragma once

#include "convergence.h"
#include "film.h"
#include "renderer.h"
#include "scene.h"
#include "stats.h"

#include <atomic>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace candela {

// Samples per pixel both panes need before their region means are compared.
inline constexpr int kAgreementMinSpp = 64;

struct PaneSpec {
  std::string label;  // shown on the pane and in the chart (usually the preset name)
  StrategySettings strategy;
};

struct ErrorSample {
  double seconds = 0.0;
  int spp = 0;
  double mse = 0.0;
  double relmse = 0.0;
  bool estimated = false;  // from the pane's own variance (no reference)
};

struct PaneState {
  std::string label;
  StrategySettings strategy;
  bool preparing = true;             // its scene is being built (auto: deciding) and it has no image
  std::string autoChoice;            // auto's pane: the candidate it chose ("full", ...); empty otherwise
  std::string autoSummary;           // auto's pane: its decision in one line (AutoDecision::summary)
  std::shared_ptr<const Film> film;  // null until the first pass
  double seconds = 0.0;              // render time this pane has had (auto's pilot included)
  double lastSlice = 0.0;            // duration of its latest pass (equal time holds to one slice)
  std::vector<ErrorSample> series;   // with a reference: one sample per pass
  Agreement agreement;               // against every other pane (agree only if all agree)
  bool agreementTested = false;
  double efficiency() const {        // 1 / (relMSE x time) at the newest sample
    return series.empty() || series.back().relmse <= 0.0 ? 0.0 : 1.0 / (series.back().relmse * series.back().seconds);
  }
};

struct ComparisonFrame {
  uint64_t version = 0;
  std::vector<PaneState> panes;
  int width = 0, height = 0;
  bool hasReference = false;
  std::shared_ptr<const std::vector<float>> reference;  // interleaved RGB, the panes' size
  std::string status;  // "preparing", "rendering the reference (N spp)", "" while comparing
};

class ComparisonSession {
 public:
  // `yieldToUi`: as RenderSession's.
  explicit ComparisonSession(RenderOptions options = {}, bool yieldToUi = false);
  ~ComparisonSession();
  ComparisonSession(const ComparisonSession&) = delete;
  ComparisonSession& operator=(const ComparisonSession&) = delete;

  // Starts (or restarts) the comparison: builds one scene per pane, then renders. `reference` may be
  // empty; `referenceSpp` > 0 instead renders one first with `referenceStrategy` (cached on disk by
  // scene and settings hash, see cachedReference). `timeLimit` > 0 stops every pane at that time.
  void start(const SceneDesc& scene, const std::vector<PaneSpec>& panes, Image reference = {}, int referenceSpp = 0,
             const StrategySettings& referenceStrategy = {}, double timeLimit = 0.0);
  std::shared_ptr<const ComparisonFrame> latest() const;
  std::vector<std::string> takeMessages();
  void setNotify(std::function<void()> notify) { notify_ = std::move(notify); }

 private:
  void workerLoop();
  void publish(std::shared_ptr<ComparisonFrame> frame);

  RenderOptions options_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  struct Request {
    SceneDesc scene;
    std::vector<PaneSpec> panes;
    Image reference;
    int referenceSpp = 0;
    StrategySettings referenceStrategy;
    double timeLimit = 0.0;
  };
  std::unique_ptr<Request> pending_;
  std::atomic<bool> cancel_{false};
  std::shared_ptr<const ComparisonFrame> latest_;
  std::vector<std::string> messages_;
  std::function<void()> notify_;
  std::thread worker_;
};

// Each film's region means tested against every other film's (z-test with each side's own
// standard error: Welch's test at these sample sizes), from kAgreementMinSpp on. A film is flagged
// (agree = false) when it disagrees with every film it was tested against: a biased strategy is the
// odd one out and the others still agree. `worst` reads "vs LABEL: region ..." (or "pane J: ..."
// without labels).
std::vector<Agreement> paneAgreement(const std::vector<const Film*>& films, const std::vector<std::string>& labels = {});

// A pane's title in an artist's words: what its strategy does, and for auto what it chose
// ("auto: chose emission + scattering sampling"). An edited preset's label ends in "*".
std::string paneTitle(const PaneState& pane);
// What a preset (or auto's candidate, "conventional, gathering" included) samples, in words.
std::string strategyInWords(const std::string& presetOrCandidate);

// The error series of every pane as CSV: pane,seconds,spp,mse,relmse,efficiency.
std::string comparisonCsv(const ComparisonFrame& frame);

}  // namespace candela
