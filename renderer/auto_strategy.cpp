#include "auto_strategy.h"

#include "convergence.h"
#include "integrator.h"
#include "renderer.h"
#include "scene.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

namespace candela {

std::string AutoDecision::summary() const {
  std::string s = "auto chose " + label();
  for (size_t i = 0; i < reasons.size(); ++i) s += (i == 0 ? ": " : "; ") + reasons[i];
  if (!pilot.empty()) {
    s += "; pilot (" + std::to_string(pilotWidth) + "x" + std::to_string(pilotHeight) + ", " + std::to_string(pilotSpp) + " spp each" +
         (pilotFilm ? ", " + std::to_string(pilotFilm->spp()) + " spp kept in the image" : std::string()) + ") score";
    for (const auto& m : pilot) {
      char buf[96];
      std::snprintf(buf, sizeof(buf), " %s %.2f,", m.name.c_str(), m.efficiency);
      s += buf;
    }
    s.pop_back();
  }
  return s;
}

StrategySettings autoBaseStrategy() {
  StrategySettings s = strategyPreset("conventional");
  s.preset = "auto";
  return s;
}

namespace {
std::string viewKey(const Scene& scene) { return toJson(scene.desc().camera).dump() + toJson(scene.render()).dump(); }
}  // namespace

Film continueFromPilot(const Scene& scene, int maxSpp) {
  const AutoDecision* d = scene.autoDecision();
  if (!d || !d->pilotFilm || d->pilotView != viewKey(scene) || (maxSpp > 0 && d->pilotFilm->spp() > maxSpp)) return Film();
  return *d->pilotFilm;
}

StrategySettings takeOverAutoChoice(const StrategySettings& running, const std::string& chosen) {
  StrategySettings s = running;
  const std::string preset = chosen.substr(0, chosen.find(','));
  const auto& names = strategyPresetNames();
  s.preset = std::find(names.begin(), names.end(), preset) != names.end() ? preset : "conventional";
  return s;
}

bool needsAutoResolve(const StrategySettings& s) { return s.preset == "auto" && toJson(s) == toJson(autoBaseStrategy()); }

namespace {

StrategySettings named(const char* preset) {
  StrategySettings s = strategyPreset(preset);
  s.preset = "auto";
  return s;
}

// A margin as the decision lines print it: "20%" for kAutoMargin.
std::string marginPercent(double margin = kAutoMargin) { return std::to_string(static_cast<int>(std::lround(100.0 * (margin - 1.0)))) + "%"; }

// The share of camera rays (a 32 x 18 grid over the image) that cross a medium with a majorant
// optical depth of at most `maxDepth`, among those that cross one at all.
double thinRayShare(const Scene& scene, float maxDepth) {
  PathTracer tracer(scene);
  const Camera& cam = scene.camera();
  int crossing = 0, thin = 0;
  for (int j = 0; j < 18; ++j)
    for (int i = 0; i < 32; ++i) {
      const Ray r = cam.generate((i + 0.5f) * cam.width() / 32.0f, (j + 0.5f) * cam.height() / 18.0f);
      const float depth = tracer.mediaOpticalDepth(r);
      if (depth < 0.0f) continue;
      ++crossing;
      if (depth <= maxDepth) ++thin;
    }
  return crossing ? static_cast<double>(thin) / crossing : 0.0;
}

}  // namespace

std::vector<AutoCandidate> autoCandidates(const Scene& scene, std::vector<std::string>& reasons) {
  std::vector<AutoCandidate> out;
  const bool emissive = scene.hasEmissiveMedia();
  StrategySettings base = named(emissive ? "emission" : "conventional");
  if (emissive) {
    base.majorant.relative_weight = true;
    base.majorant.emission_weight = kAutoRelativeEmissionWeight;
    reasons.push_back("volumes emit: emission sampling on (relative emission weight " + std::to_string(kAutoRelativeEmissionWeight).substr(0, 4) +
                      ")");
  } else {
    // Absorption weighted at every collision instead of ending the path (docs/method.md s.2): no
    // emission structure, and measured at or above the analog walk on every report scene without
    // emission (docs/performance.md, "The auto strategy").
    base.emission.gather_every_collision = true;
    reasons.push_back("no volume emits: no emission sampling, absorption weighted at every collision");
  }
  out.push_back({emissive ? "emission" : "conventional, gathering", base, true});

  bool scatters = false;
  for (const Medium* m : scene.media().media) scatters |= m->albedoAverage() > 0.0f;
  const bool lit = !scene.lights().empty() || !scene.volumeLights().empty() || emissive;
  if (!scatters || !lit) {
    reasons.push_back(scatters ? "no lights: no scattering sampling" : "no volume scatters: no scattering sampling");
    return out;
  }
  const float maxDepth = base.guiding.max_optical_depth;
  const double share = thinRayShare(scene, maxDepth);
  char why[256];
  if (share < 0.5) {
    std::snprintf(why, sizeof(why), "%.0f%% of camera rays through the media are thinner than %.0f optical depths: no probes", 100.0 * share,
                  maxDepth);
    reasons.push_back(why);
    return out;
  }
  std::snprintf(why, sizeof(why), "%.0f%% of camera rays are thin enough for scattering sampling", 100.0 * share);
  reasons.push_back(why);
  // The guided candidates, like the plain one, weight absorption at every collision (as the full
  // and equiangular presets do in any scene). With the analog walk auto's full trailed the full
  // preset by 15-20% relMSE at equal spp on god-rays-backlit and god-rays-dark.
  StrategySettings full = base;
  const StrategySettings fullPreset = strategyPreset("full");
  full.guiding = fullPreset.guiding;
  const bool sunLit = scene.sunLit();
  // Guided continuations (the thin rays leaving a medium vertex guided too) come with the preset
  // (settings.cpp, guiding.secondary_rays = from_media_unless_flame_lit): where a sun shines or no
  // volume emits. Where a camera vertex in dim haze continues into a thin sun shaft, the tracked
  // vertex there is a rare, bright sample that the pilot's few samples per pixel seldom draw, so
  // they are a rule, not a candidate. Where volumes emit and no sun makes shafts, the guided
  // vertex's light sample of the emissive volumes made them cost 14-29% more time for the same MSE
  // (torch-in-mist, torch-in-fog, fire), and the continuations aimed at the volumes (docs/method.md
  // s.3b) already reach their glow (docs/performance.md, "Guided continuations").
  if (guidedContinuationsApply(scene, full.guiding))
    reasons.push_back(std::string(sunLit ? "a sun shines into the media" : "no volume emits") +
                      ": guided candidates guide the thin rays leaving a medium vertex too");
  out.push_back({"full", full});
  // Where volumes emit, full (the guided vertex on one camera segment in ten) stands and runs
  // without a pilot, unless the flames light a medium that emits nothing and is too thick for
  // single scattering to make its glow (below). Its gain is in rare tracked vertices (dim smoke
  // scattering a hot core's light, haze beside a sun's shafts) whose weight the guided density
  // bounds: an 8-spp pilot seldom draws them (fire: emission 0.20 against full 0.18 per sample at 8
  // spp, 1.19 against 0.62 at 64; shed-fire's region map x0.74 of emission by relMSE in the pilot,
  // x2.15 of the best preset in the bench), while nine seeds of the bench at 8 s put full x1.35
  // ahead of emission by relMSE and x0.94 by MSE on fire.
  // Where a medium that emits nothing scatters the flames' light and no sun shines into it (a torch
  // in mist or fog), it depends on how thin the medium is. Where most camera rays cross less than
  // one optical depth (torch-in-mist: 97%), single scattering makes the halo, which is what the
  // guided vertex samples, and full stands: once the adaptive split has taken the flame core's MSE,
  // which both share, relMSE ranks them, and over nine seeds auto read x0.97 of each seed's better
  // preset by relMSE with full and x0.92 with emission (docs/performance.md, "A split for one
  // metric"). Where they cross more (torch-in-fog: none; glow-box: 27%), tracking alone scatters
  // often, full read x0.91 of emission by relMSE with the same split, and the plain candidate
  // stands, as the pilot says.
  bool plainScatterer = false;
  for (const Medium* m : scene.media().media) plainScatterer |= !m->emissive() && m->albedoAverage() > 0.0f;
  const bool flamesLightAPlainMedium = emissive && plainScatterer && !sunLit;
  const double singleScatteringShare = flamesLightAPlainMedium ? thinRayShare(scene, 1.0f) : 0.0;
  if (flamesLightAPlainMedium && singleScatteringShare < 0.5) {
    std::snprintf(why, sizeof(why),
                  "the volumes light a medium that emits nothing, no sun shines, and %.0f%% of camera rays cross less than one optical depth: "
                  "emission stands", 100.0 * singleScatteringShare);
    reasons.push_back(why);
  } else if (emissive) {
    // Where full stands, the pilot only ever risked overturning it: it chose full on all 18 seeds of
    // fire, shed-fire and thin-bright-fire and on every emissive stability case, and without its q
    // refinements (below) its 2-spp images put emission ahead of full on shed-fire (seed 1: x1.40,
    // relMSE x1.91), where full is x2.9 ahead by relative variance per sample. So full runs at once
    // and the render keeps the pilot's time (0.2-1.0 s of the bench's 8 s; docs/performance.md,
    // "No pilot where full stands").
    out.erase(out.begin());
    out.front().standing = true;
    std::string where = sunLit ? "volumes emit under a sun" : "only the emitting volumes scatter";
    if (flamesLightAPlainMedium) {
      std::snprintf(why, sizeof(why), "the volumes light a thin medium that emits nothing (%.0f%% of camera rays cross less than one optical depth)",
                    100.0 * singleScatteringShare);
      where = why;
    }
    reasons.push_back(where + ": full stands, no pilot (the pilot cannot see its gain, in samples too rare for a few per pixel)");
    return out;
  }
  // Full measures each pixel block's q from its own samples (guiding.measured_pixel_probability, as
  // the preset does): from 16 samples per pixel on it takes 0 to 0.5 per block itself. The pilot's
  // refinements of q (the guided vertex on one camera segment in two, a map of q by region) would
  // differ from it in the first 16 samples only, and cost up to 1.6 s of torch-in-fog's 8 s, so they
  // are no candidates (docs/performance.md, "No pilot where full stands"). Deeper guiding
  // (guided_segments 8) is none either: per sample at 320x180 it cost 2.9x full's work on
  // god-rays-dark for 1.3x less variance, 2.4x on shed-fire for 1.1x, and it never came within 0.3
  // of the best in a pilot.
  reasons.push_back("full measures each pixel block's q from its own samples: no q refinements piloted");
  // Equi-angular sampling aims at a point: a point, spot or sphere light, or an emissive volume's
  // emission centroid (PathTracer's targets). Without one its slot holds a uniform density over the
  // ray's medium interval, which on the god-rays scenes measured x0.55-0.70 of conventional by
  // relMSE per unit of work, so it can never be the candidate that is nowhere far behind; on a
  // 48 x 27 god-rays its 10-thousand-sample pilot still put it ahead on one seed in eight, at x0.75
  // of conventional (docs/performance.md, "Auto against conventional on the stability cases").
  bool aimable = emissive;
  for (const Light& l : scene.lights()) aimable |= l.hasPosition();
  if (!aimable) {
    reasons.push_back("no point, spot or sphere light and no emissive volume: equiangular has nothing to aim at, no candidate");
    return out;
  }
  StrategySettings equi = base;
  equi.guiding.guide = DistanceGuide::EquiAngular;
  out.push_back({"equiangular", equi});
  return out;
}

namespace {
AutoDecision decide(Scene& scene);

// Each measurement's efficiencies 1 / (variance x work) by the relative and the absolute figure,
// and its score: the worse of the two, each relative to the best of `ms`.
void scoreAgainstEachOther(std::vector<AutoMeasurement>& ms) {
  double bestRelative = 0.0, bestAbsolute = 0.0;
  for (AutoMeasurement& m : ms) {
    m.relativeEfficiency = 1.0 / std::max(1e-30, m.relativeVariance * m.workPerSample);
    m.absoluteEfficiency = 1.0 / std::max(1e-30, m.absoluteVariance * m.workPerSample);
    bestRelative = std::max(bestRelative, m.relativeEfficiency);
    bestAbsolute = std::max(bestAbsolute, m.absoluteEfficiency);
  }
  for (AutoMeasurement& m : ms) m.efficiency = std::min(m.relativeEfficiency / bestRelative, m.absoluteEfficiency / bestAbsolute);
}
}  // namespace

AutoDecision resolveAutoStrategy(Scene& scene) {
  const auto start = std::chrono::steady_clock::now();
  AutoDecision d = decide(scene);
  // Whatever it chose, auto samples adaptively: blocks whose noise per unit of work is high take
  // up to kAutoSplit camera samples per film sample, decided by the render's own samples
  // (sample_allocation.h; docs/performance.md, "Adaptive sampling by splitting").
  scene.setAdaptiveSplit(kAutoSplit);
  d.reasons.push_back("adaptive sampling: up to " + std::to_string(kAutoSplit) +
                      " camera samples per film sample where a block's noise per unit of work calls for them (from 4 camera samples per pixel)");
  d.pilotSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return d;
}

namespace {

AutoDecision decide(Scene& scene) {
  AutoDecision d;
  std::vector<AutoCandidate> candidates = autoCandidates(scene, d.reasons);
  if (candidates.size() == 1) {
    d.chosen = candidates[0].name;
    scene.setStrategy(candidates[0].strategy);
    return d;
  }
  // The pilot renders about kPilotSamples camera samples per candidate image. An image of at most
  // that many pixels is rendered as it is, at 2-8 spp, and every candidate's samples stay in it
  // (d.pilotFilm): each pilot image draws its own range of sample indices, so the images are
  // independent of each other and of the passes that follow, and each sample is an unbiased
  // estimate of its pixel whichever candidate drew it (the choice depends on earlier samples only),
  // so at a fixed spp the image's expectation is unchanged. A larger image is piloted on a copy of
  // about 128 x 72 pixels at 8 spp whose samples are discarded: kept, they would cost the first image
  // seconds in the viewer, and the pilot is a small share of a render that size needs.
  const CameraDesc full = scene.desc().camera;
  const double pixels = static_cast<double>(full.resolution.first) * full.resolution.second;
  CameraDesc pilotCamera = full;
  d.pilotSpp = std::clamp(static_cast<int>(std::lround(kPilotSamples / pixels)), 2, 8);
  const bool keep = pixels <= kPilotSamples;
  if (!keep) {
    const double scale = std::sqrt(kPilotSamples / 8.0 / pixels);
    pilotCamera.resolution = {std::max(8, static_cast<int>(std::lround(full.resolution.first * scale))),
                              std::max(8, static_cast<int>(std::lround(full.resolution.second * scale)))};
    d.pilotSpp = 8;
    scene.setCamera(pilotCamera);
  }
  d.pilotWidth = pilotCamera.resolution.first, d.pilotHeight = pilotCamera.resolution.second;
  Film kept = keep ? Film(full.resolution.first, full.resolution.second) : Film();  // every pilot image's samples
  int nextSample = 0;  // the first sample index of the next pilot image
  // Every pilot image's per-pixel moments. The mean of all their means is the one normaliser of the
  // relative figure (candidates render the same image, so it is a reference they share, as the
  // relMSE's reference is): a candidate's own noisy mean would normalise its bright outliers away.
  std::vector<PixelMoments> images;  // parallel to d.pilot
  std::vector<float> sharedMean;  // the running mean of every pilot image's mean
  int sharedCount = 0;
  auto share = [&](const PixelMoments& pm) {
    if (pm.mean.empty()) return;
    if (sharedMean.empty()) sharedMean.assign(pm.mean.size(), 0.0f);
    ++sharedCount;
    for (size_t i = 0; i < pm.mean.size(); ++i) sharedMean[i] += (pm.mean[i] - sharedMean[i]) / static_cast<float>(sharedCount);
  };
  // One renderer for every pilot image: they share its camera-ray guide tables, which a new q does
  // not rebuild (camera_guides.h).
  ProgressiveRenderer renderer(std::shared_ptr<const Scene>(&scene, [](const Scene*) {}), RenderOptions{0, 16});
  // Renders one candidate's pilot image on the next range of sample indices (independent of every
  // other pilot image) and measures it. The per-pixel moments go to `moments`. An image that only
  // measures (!keepSamples: the plain candidate's images under a sun, its first and the fresh
  // round's second look at it) renders from indices the image never uses, so the kept ones stay 0 to
  // kept.spp() - 1, where the render continues.
  int nextUnkeptSample = 1 << 28;
  auto measure = [&](const AutoCandidate& c, PixelMoments& moments, bool keepSamples = true) {
    const bool hadProbes = scene.probes() != nullptr;
    scene.setStrategy(c.strategy);
    if (!hadProbes && scene.probes()) d.probeSeconds += scene.probes()->learnSeconds();
    int& first = keepSamples ? nextSample : nextUnkeptSample;
    renderer.setFirstSample(first);
    first += d.pilotSpp;
    const WorkCounters before = renderer.work();
    Film film;
    renderer.renderBudget(film, d.pilotSpp, 0.0, d.pilotSpp);
    const WorkCounters work = renderer.work() - before;
    if (keep && keepSamples) kept.addPass(film);
    moments = pixelMoments(film);
    share(moments);
    AutoMeasurement m;
    m.name = c.name;
    m.absoluteVariance = variancePerSample(film);
    m.workPerSample = work.cost() / std::max<double>(1.0, static_cast<double>(work.samples));
    d.pilotWork += work.cost();
    return m;
  };
  // Scores measurements against each other: per metric (relMSE-like against the shared mean image,
  // MSE-like) the efficiency 1 / (variance x work) relative to the best of them, and as the score the
  // worse of the two. The report holds auto to the best preset by both metrics; where they disagree
  // (fire: full ahead by relMSE; shed-fire: full ahead by MSE, emission by relMSE) the candidate
  // that is nowhere far behind wins.
  auto score = [&](std::vector<AutoMeasurement>& ms, const std::vector<const PixelMoments*>& moments) {
    for (size_t i = 0; i < ms.size(); ++i) ms[i].relativeVariance = relativeVarianceAgainst(moments[i]->variance, sharedMean);
    scoreAgainstEachOther(ms);
  };
  auto scorePilot = [&] {
    std::vector<const PixelMoments*> ptrs;
    for (const PixelMoments& pm : images) ptrs.push_back(&pm);
    score(d.pilot, ptrs);
  };
  // First the plain candidate and the guided camera vertex ("full"); equiangular follows only where
  // full was ahead of the plain candidate in the whole image. Over the report scenes it never came
  // within 10% of the best where full was behind, and skipping it halves the pilot there.
  size_t fullIndex = candidates.size();
  for (size_t i = 0; i < candidates.size(); ++i)
    if (candidates[i].name == "full") fullIndex = i;
  std::vector<AutoCandidate> refinements;
  images.reserve(candidates.size() + 3);
  // Under a sun the plain candidate's images only measure (the fresh round's look at it too): where
  // a sun shines into the media the guided candidates either win by far, the plain candidate's
  // variance per sample by MSE 4-6 times theirs (god-rays-dark, god-rays-backlit), or lose by a few
  // percent (god-rays), so its kept samples cost the first far more than dropping them costs the
  // second (docs/performance.md, "The pilot's second look at the rival"). A rule of the scene,
  // fixed before any sample is drawn: the kept samples stay unbiased (docs/method.md 4b).
  const bool keepPlain = !scene.sunLit();
  if (keep && !keepPlain) d.reasons.push_back("a sun shines into the media: the plain candidate's pilot image only measures");
  for (size_t i = 0; i < candidates.size(); ++i) {
    if (i != 0 && i != fullIndex) {
      refinements.push_back(candidates[i]);
      continue;
    }
    d.pilot.push_back(measure(candidates[i], images.emplace_back(), i != 0 || keepPlain));
  }
  candidates.erase(std::remove_if(candidates.begin() + 1, candidates.end(), [](const AutoCandidate& c) { return c.name != "full"; }),
                   candidates.end());
  fullIndex = candidates.size() > 1 ? 1 : candidates.size();
  if (fullIndex < candidates.size()) {
    scorePilot();
    if (d.pilot[fullIndex].efficiency > d.pilot[0].efficiency) {
      for (const AutoCandidate& c : refinements) {
        candidates.push_back(c);
        d.pilot.push_back(measure(c, images.emplace_back()));
      }
    } else {
      std::string line = "full behind " + candidates[0].name + " in the first round";
      std::string names;
      for (const AutoCandidate& c : refinements) names += (names.empty() ? "" : " and ") + c.name;
      if (!names.empty()) line += ": " + names + " not tried";
      d.reasons.push_back(line);
    }
  }
  scorePilot();
  // The best-scoring candidate, but only when it beats the standing one (the plain candidate: where
  // full stands there is no pilot) by kAutoMargin: the pilot's variances and the work model are
  // estimates, and a near tie is not worth a change. The full margin is asked of the fresh round
  // below, on twice the samples. Of this first 8-spp round the challengers need only half of it
  // (the square root): asked the whole, it turned full down on one seed in eight of god-rays-dark
  // (x1.12 in the pilot), where fresh seeds measure full x1.3-1.8 ahead and the bench x1.6 by MSE.
  size_t standing = 0;
  for (size_t i = 0; i < candidates.size(); ++i)
    if (candidates[i].standing) standing = i;
  double best = 0.0;
  size_t chosen = standing;
  for (size_t i = 0; i < d.pilot.size(); ++i)
    if (d.pilot[i].efficiency > best) best = d.pilot[i].efficiency, chosen = i;
  const std::string margin = marginPercent();
  const double pilotMargin = std::sqrt(kAutoMargin);
  if (chosen != standing && best < pilotMargin * d.pilot[standing].efficiency) {
    chosen = standing;
    d.reasons.push_back("no candidate beat " + candidates[standing].name + " by " + marginPercent(pilotMargin) + " in the pilot");
  } else if (chosen != standing) {
    // The winner's curse: the best of several noisy estimates is an optimistic one (8 spp see a
    // heavy-tailed candidate's rare large samples only by luck; on torch-in-mist the pilot's ratio of
    // full to emission ranged from 0.5 to 1.8 over seeds). So the winner is measured again on images
    // of two fresh sample ranges, its rival once more, and the winner is kept only if the fresh
    // estimates still score it kAutoMargin ahead of the rival's (both rounds pooled).
    auto confirm = [&](size_t challenger, size_t rival) {
      PixelMoments freshImage, freshImage2, rivalImage;
      const AutoMeasurement fresh = measure(candidates[challenger], freshImage);
      const AutoMeasurement fresh2 = measure(candidates[challenger], freshImage2);
      // The rival is the plain candidate, and its second image is kept where its first is: without
      // a sun, where the plain candidate mostly keeps its place (torch-in-fog: the fresh round
      // turned full down on every seed, and a dropped look cost 2 of the image's 100 samples per
      // pixel). Under a sun it only measures, as the first does: kept, it would add the samples of
      // the candidate about to lose (on god-rays-dark, at 5 times full's variance per sample, 4 of
      // the pilot's 14 samples per pixel instead of 2). Either is a rule fixed before any sample is
      // drawn, so the kept samples stay unbiased (docs/method.md 4b).
      const AutoMeasurement rivalAgain = measure(candidates[rival], rivalImage, rival == 0 && keepPlain);
      // Pooled per candidate: the mean of its images' variances (against the shared mean) and work.
      std::vector<AutoMeasurement> pair{fresh, fresh2, d.pilot[rival], rivalAgain};
      score(pair, {&freshImage, &freshImage2, &images[rival], &rivalImage});
      std::vector<AutoMeasurement> pooled(2);
      for (int k = 0; k < 2; ++k) {
        const AutoMeasurement &a = pair[2 * k], &b = pair[2 * k + 1];
        pooled[k].absoluteVariance = 0.5 * (a.absoluteVariance + b.absoluteVariance);
        pooled[k].relativeVariance = 0.5 * (a.relativeVariance + b.relativeVariance);
        pooled[k].workPerSample = 0.5 * (a.workPerSample + b.workPerSample);
      }
      scoreAgainstEachOther(pooled);
      const double ratio = pooled[0].efficiency / std::max(1e-30, pooled[1].efficiency);
      char why[240];
      std::snprintf(why, sizeof(why), "%s measured again on fresh samples: x%.2f %s (relMSE x%.2f, MSE x%.2f)", candidates[challenger].name.c_str(),
                    ratio, candidates[rival].name.c_str(), pooled[0].relativeEfficiency / pooled[1].relativeEfficiency,
                    pooled[0].absoluteEfficiency / pooled[1].absoluteEfficiency);
      d.reasons.push_back(why);
      if (ratio >= kAutoMargin) return true;
      d.reasons.push_back("not " + margin + " ahead: " + candidates[rival].name);
      return false;
    };
    if (!confirm(chosen, standing)) chosen = standing;
  }
  d.chosen = candidates[chosen].name;
  if (keep) d.pilotFilm = std::make_shared<const Film>(std::move(kept)), d.pilotView = viewKey(scene);
  else scene.setCamera(full);
  scene.setStrategy(candidates[chosen].strategy);
  return d;
}

}  // namespace

}  // namespace candela
