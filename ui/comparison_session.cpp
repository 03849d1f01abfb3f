#include "comparison_session.h"

#include "thread_priority.h"

#include <algorithm>
#include <chrono>
#include <sstream>

namespace candela {

ComparisonSession::ComparisonSession(RenderOptions options, bool yieldToUi) : options_(options) {
  worker_ = std::thread([this, yieldToUi] {
    if (yieldToUi) lowerThisThreadsPriority();  // the UI thread comes first (thread_priority.h)
    workerLoop();
  });
}

ComparisonSession::~ComparisonSession() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cancel_ = true;
  wake_.notify_all();
  worker_.join();
}

void ComparisonSession::start(const SceneDesc& scene, const std::vector<PaneSpec>& panes, Image reference, int referenceSpp,
                              const StrategySettings& referenceStrategy, double timeLimit) {
  auto r = std::make_unique<Request>();
  r->scene = scene;
  r->panes = panes;
  r->reference = std::move(reference);
  r->referenceSpp = referenceSpp;
  r->referenceStrategy = referenceStrategy;
  r->timeLimit = timeLimit;
  std::lock_guard<std::mutex> lock(mutex_);
  pending_ = std::move(r);
  cancel_ = true;
  wake_.notify_one();
}

std::shared_ptr<const ComparisonFrame> ComparisonSession::latest() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return latest_;
}

std::vector<std::string> ComparisonSession::takeMessages() {
  std::lock_guard<std::mutex> lock(mutex_);
  return std::exchange(messages_, {});
}

void ComparisonSession::publish(std::shared_ptr<ComparisonFrame> frame) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    frame->version = latest_ ? latest_->version + 1 : 1;
    latest_ = std::move(frame);
  }
  if (notify_) notify_();
}

void ComparisonSession::workerLoop() {
  using Clock = std::chrono::steady_clock;
  struct Pane {
    std::shared_ptr<Scene> scene;
    std::unique_ptr<ProgressiveRenderer> renderer;
    Film film;
    int passSpp = 1;
  };
  std::vector<Pane> panes;
  std::shared_ptr<ComparisonFrame> state;  // the working copy, published after each slice
  std::vector<float> reference;
  double timeLimit = 0.0;
  auto lastAgreement = Clock::now();

  for (;;) {
    std::unique_ptr<Request> request;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      auto allDone = [&] {
        if (panes.empty()) return true;
        if (timeLimit <= 0.0) return false;
        for (const auto& p : state->panes)
          if (p.seconds < timeLimit) return false;
        return true;
      };
      wake_.wait(lock, [&] { return stop_ || pending_ || !allDone(); });
      if (stop_) return;
      request = std::move(pending_);
      cancel_ = false;
    }
    if (request) {
      panes.clear();
      state = std::make_shared<ComparisonFrame>();
      state->width = request->scene.camera.resolution.first;
      state->height = request->scene.camera.resolution.second;
      // Every pane is listed at once, each saying it is being prepared until its scene is built.
      for (const auto& spec : request->panes) {
        PaneState s;
        s.label = spec.label;
        s.strategy = spec.strategy;
        state->panes.push_back(s);
      }
      state->status = "preparing the panes";
      publish(std::make_shared<ComparisonFrame>(*state));
      try {
        for (size_t i = 0; i < request->panes.size(); ++i) {
          SceneDesc desc = request->scene;
          desc.strategy = request->panes[i].strategy;
          Pane p;
          p.scene = Scene::build(desc);
          p.renderer = std::make_unique<ProgressiveRenderer>(p.scene, options_);
          panes.push_back(std::move(p));
          PaneState& s = state->panes[i];
          s.preparing = false;
          // auto's decision is charged to its pane's time, as bench and report charge it (not the
          // probes' learning, which no fixed preset is charged either), and its kept pilot samples
          // start the pane's image.
          if (const AutoDecision* d = panes.back().scene->autoDecision()) {
            s.seconds = d->chargedSeconds();
            s.autoChoice = d->label();
            s.autoSummary = d->summary();
            panes.back().film = continueFromPilot(*panes.back().scene, 0);
            if (panes.back().film.spp() > 0) s.film = std::make_shared<const Film>(panes.back().film);
          }
          publish(std::make_shared<ComparisonFrame>(*state));
        }
        reference.clear();
        const int w = state->width, h = state->height;
        if (!request->reference.rgb.empty()) {
          if (request->reference.width != w || request->reference.height != h)
            throw InputError("reference: expected a " + std::to_string(w) + "x" + std::to_string(h) + " image, got " +
                             std::to_string(request->reference.width) + "x" + std::to_string(request->reference.height));
          reference = request->reference.rgb;
        } else if (request->referenceSpp > 0) {
          state->status = "rendering the reference (" + std::to_string(request->referenceSpp) + " spp, " +
                          request->referenceStrategy.preset + "; cached for next time)";
          publish(std::make_shared<ComparisonFrame>(*state));
          reference = cachedReference(request->scene, request->referenceStrategy, request->referenceSpp, options_.threads).rgb;
        }
        state->hasReference = !reference.empty();
        if (state->hasReference) state->reference = std::make_shared<const std::vector<float>>(reference);
        state->status.clear();
        timeLimit = request->timeLimit;
      } catch (const std::exception& e) {
        std::lock_guard<std::mutex> lock(mutex_);
        messages_.push_back(std::string("comparison: ") + e.what());
        panes.clear();
        state->status = "failed";
        continue;
      }
      publish(std::make_shared<ComparisonFrame>(*state));
      lastAgreement = Clock::now();
      continue;
    }
    if (panes.empty()) continue;

    // The pane that has had the least time renders next: equal time at every moment, to one slice.
    size_t next = 0;
    for (size_t i = 1; i < panes.size(); ++i)
      if (state->panes[i].seconds < state->panes[next].seconds) next = i;
    Pane& pane = panes[next];
    PaneState& ps = state->panes[next];
    const auto start = Clock::now();
    if (!pane.renderer->renderPass(pane.film, pane.passSpp, &cancel_)) continue;
    const double slice = std::chrono::duration<double>(Clock::now() - start).count();
    ps.seconds += slice;
    ps.lastSlice = slice;
    // Slices of about 60 ms: short enough that the panes stay level, long enough to be efficient.
    if (slice < 0.03) pane.passSpp = std::min(pane.passSpp * 2, 1024);
    else if (slice > 0.12 && pane.passSpp > 1) pane.passSpp /= 2;
    ps.film = std::make_shared<const Film>(pane.film);
    if (!reference.empty()) {
      const ErrorMetrics e = imageError(pane.film.meanImage(), reference);
      ps.series.push_back({ps.seconds, pane.film.spp(), e.mse, e.relmse, false});
    } else if (pane.film.spp() >= 2) {
      // No reference: the render's own error estimate, its sample variance over its spp.
      const double n = pane.film.spp();
      ps.series.push_back({ps.seconds, pane.film.spp(), variancePerSample(pane.film) / n, relativeVariancePerSample(pane.film) / n, true});
    }
    // Agreement of region means, every second (it reads every film). Pairwise z-tests (unequal
    // variances) need enough samples for heavy-tailed estimators' standard errors to be honest, so
    // a pair is tested only from kAgreementMinSpp on. A pane is flagged when it disagrees with every
    // pane it was tested against: a biased strategy is the odd one out, the others still agree.
    if (panes.size() > 1 && std::chrono::duration<double>(Clock::now() - lastAgreement).count() > 1.0) {
      std::vector<const Film*> films;
      for (const auto& p : panes) films.push_back(&p.film);
      std::vector<std::string> labels;
      for (const auto& p : state->panes) labels.push_back(p.label);
      const auto results = paneAgreement(films, labels);
      for (size_t i = 0; i < panes.size(); ++i) {
        state->panes[i].agreement = results[i];
        state->panes[i].agreementTested = results[i].tests > 0;
      }
      lastAgreement = Clock::now();
    }
    publish(std::make_shared<ComparisonFrame>(*state));
  }
}

std::vector<Agreement> paneAgreement(const std::vector<const Film*>& films, const std::vector<std::string>& labels) {
  std::vector<Agreement> out(films.size());
  for (size_t i = 0; i < films.size(); ++i) {
    if (films[i]->spp() < kAgreementMinSpp) continue;
    Agreement& all = out[i];
    int partners = 0, disagreements = 0;
    for (size_t j = 0; j < films.size(); ++j) {
      if (j == i || films[j]->spp() < kAgreementMinSpp) continue;
      const Agreement a = compareRenders(*films[i], *films[j], 8, 8);
      ++partners;
      disagreements += a.agree ? 0 : 1;
      all.tests += a.tests;
      all.threshold = a.threshold;
      if (a.maxAbsZ >= all.maxAbsZ) {
        all.maxAbsZ = a.maxAbsZ;
        all.maxRelativeDifference = a.maxRelativeDifference;
        all.worst = (j < labels.size() ? "vs " + labels[j] : "pane " + std::to_string(j)) + ": " + a.worst;
      }
    }
    all.agree = partners == 0 || disagreements < partners;
  }
  return out;
}

std::string strategyInWords(const std::string& name) {
  const std::string base = name.substr(0, name.find(','));
  std::string words = base == "conventional" ? "tracking only"
                      : base == "emission"   ? "emission sampling"
                      : base == "full"       ? "emission + scattering sampling"
                      : base == "equiangular" ? "emission + equiangular sampling"
                                              : base;
  if (base != name) words += " (" + name.substr(name.find(',') + 2) + ")";
  return words;
}

std::string paneTitle(const PaneState& pane) {
  const bool edited = !pane.label.empty() && pane.label.back() == '*';
  if (pane.strategy.preset == "auto" && !edited)
    return pane.autoChoice.empty() ? std::string(pane.preparing ? "auto: choosing" : "auto")
                                   : "auto: chose " + strategyInWords(pane.autoChoice);
  return strategyInWords(pane.strategy.preset) + (edited ? " (edited)" : "");
}

std::string comparisonCsv(const ComparisonFrame& frame) {
  std::ostringstream out;
  out << "# relMSE = " << kRelMseFormula << "\n";
  if (!frame.hasReference) out << "# no reference: each pane's error is its own estimate, sample variance / spp\n";
  out << "pane,seconds,spp,mse,relmse,efficiency\n";
  for (const auto& p : frame.panes)
    for (const auto& s : p.series)
      out << p.label << ',' << s.seconds << ',' << s.spp << ',' << s.mse << ',' << s.relmse << ','
          << (s.relmse > 0.0 ? 1.0 / (s.relmse * s.seconds) : 0.0) << '\n';
  return out.str();
}

}  // namespace candela
