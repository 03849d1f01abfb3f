#include "settings.h"

namespace candela {

const std::vector<std::string>& strategyPresetNames() {
  static const std::vector<std::string> names{"conventional", "emission", "full", "equiangular", "auto"};
  return names;
}

StrategySettings strategyPreset(const std::string& name, const std::string& origin) {
  StrategySettings s;
  s.preset = name;
  if (name == "conventional") return s;  // docs/method.md s.2, "conventional": the baseline
  // auto: conventional until Scene::build (or a strategy edit) decides (auto_strategy.h).
  if (name == "auto") return s;
  if (name == "emission" || name == "full" || name == "equiangular") {
    // Talk s.2.1: emission-aware majorant + emission at every collision + NEE toward emissive volumes.
    s.majorant.emission_term = true;
    s.majorant.emission_weight = 10.0f;  // the efficiency sweet spot measured on fire and torch-in-mist
    s.emission.gather_every_collision = true;
    s.emission.light_sampling = true;
    // Continuations aimed at the emissive volumes reach the glow a flame lights around it
    // (docs/method.md s.3b; measured in docs/performance.md, "Continuations toward emissive volumes").
    s.emission.continuation_toward_volumes = 0.25f;
    // A camera ray's emission by ratio tracking all the way through the flames, not only up to
    // where the ray scatters (docs/method.md s.2, "Emission past the scattering"): a flame seen through
    // smoke, mist or fog is then no longer all or nothing per sample. Per sample, against off
    // (docs/performance.md, "Emission past the scattering"): 9-32% less variance for 1-5% more work
    // on fire, torch-in-mist, torch-in-fog and shed-fire; on the rays after the camera ray it bought
    // nothing more.
    s.emission.gather_past_scattering = PastScattering::CameraRays;
    // Talk s.2.2: plus probe-guided distance sampling with MIS (the talk's Fig. 1 right), or the
    // equi-angular baseline in the same MIS slot.
    if (name == "full") {
      s.guiding.guide = DistanceGuide::Probes;
      // One vertex per guided segment: measured ahead of two balance-weighted vertices at equal
      // time on every report scene where guiding runs (docs/performance.md,
      // "Scattering sampling: one vertex per guided segment").
      s.guiding.combination = GuideCombination::OneSample;
      // The guided vertex on one segment in ten: a defensive share of the one-sample mixture. Its
      // density still bounds the MIS weight where tracking rarely scatters (dim smoke lit by a hot
      // core, mist beside shafts), while nine segments in ten cost what tracking costs. Against
      // q = 0.5, measured ahead by relMSE on every report scene where guiding runs and by MSE on all
      // but the sun shafts (docs/performance.md, "Scattering sampling: how often the guided vertex").
      s.guiding.guided_probability = 0.1f;
      // ...except in pixels whose light the probes predict is bright single scattering (sun shafts),
      // which get up to one in two: per sample 33-38% less MSE on the backlit god-rays scenes and 15%
      // on shed-fire, for 1.5% more work (docs/performance.md, "Bright pixels").
      s.guiding.bright_pixel_probability = 0.5f;
      // Those q are where a render starts. From 16 samples on, blocks of 8 x 8 pixels take the q
      // their own samples measure best, variance and relative variance per unit of work together
      // (camera_guides.h): a flame's pixels, whose noise is their emission, drop the guided vertex,
      // the dim mist around it keeps it. Per unit of work at 128-256 spp, against the predicted q
      // alone (relMSE / MSE): fire x1.17 / x0.99, torch-in-mist x1.06 / x1.02, god-rays x1.04 /
      // x1.02, god-rays-backlit x1.05 / x1.04, shed-fire x1.09 / x0.98, god-rays-dark x1.00 /
      // x1.02 (docs/performance.md, "Measured q").
      s.guiding.measured_pixel_probability = true;
      // Beyond the talk, which guides camera rays: the thin rays leaving a medium vertex get the
      // guided vertex too (on every such ray), where a sun shines or no volume emits. A camera vertex
      // in dim haze whose continuation crosses a thin sun shaft is then no longer a rare, bright
      // tracked sample: per unit of work x2.4 by relMSE and x1.8 by MSE on god-rays-dark, x1.6 / x1.5
      // on god-rays-backlit, x2.3 / x1.1 on shed-fire, level on the cloud, x0.97 on the side-lit
      // god-rays; flame-lit scenes are left as they were (docs/performance.md, "Guided continuations
      // in full").
      s.guiding.guided_segments = 2;
      s.guiding.secondary_rays = SecondaryRays::FromMediaUnlessFlameLit;
      s.guiding.secondary_probability = 1.0f;
      s.guiding.secondary_max_optical_depth = 0.5f;
    }
    if (name == "equiangular") s.guiding.guide = DistanceGuide::EquiAngular;
    return s;
  }
  std::string known;
  for (const auto& n : strategyPresetNames()) known += (known.empty() ? "" : ", ") + n;
  throw InputError(origin + ": expected a strategy preset (" + known + "), got \"" + name + "\"");
}

StrategySettings strategyFromJson(const Json& j, const std::string& file, const std::string& path) {
  if (!j.is_object()) throw InputError(file + ": " + path + ": expected an object, got " + shortJson(j));
  std::string preset = "conventional";
  if (j.contains("preset")) {
    if (!j["preset"].is_string()) throw InputError(file + ": " + path + ".preset: expected a string, got " + shortJson(j["preset"]));
    preset = j["preset"].get<std::string>();
  }
  StrategySettings s = strategyPreset(preset, file + ": " + path + ".preset");
  fromJson(j, s, file, path);
  return s;
}

}  // namespace candela
