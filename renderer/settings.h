// Render and strategy settings: plain structs that serialise to JSON. The same structs drive the
// scene files, the CLI's --set flags, image metadata and (later) the viewer's panels.
//
// RenderSettings say *which* image (spp/time, path length): all strategies must converge to it.
// StrategySettings say *how* it is sampled: every preset must agree with `conventional`.
#pragma once

#include "fields.h"

#include <string>
#include <vector>

namespace candela {

enum class MajorantStructure { Global, Grid };
template <>
struct EnumNames<MajorantStructure> {
  static const std::vector<std::pair<MajorantStructure, const char*>>& get() {
    static const std::vector<std::pair<MajorantStructure, const char*>> v{{MajorantStructure::Global, "global"},
                                                                          {MajorantStructure::Grid, "grid"}};
    return v;
  }
};

// docs/method.md s.1: the majorant policy.
// mu_bar = max(maj(mu_t), min(k * maj(mu_a * lum(Le)), c / voxel_size)) when the emission term is on
// (talk s.2.1), else maj(mu_t). It never drops below maj(mu_t), so mu_n >= 0 always. The emission
// term is a sampling choice, not a bound: any mu_bar >= mu_t keeps every estimator unbiased.
struct MajorantPolicy {
  MajorantStructure structure = MajorantStructure::Grid;
  int cell_size = 8;             // voxels per majorant cell along each axis (grid structure)
  bool coarsen_thin = true;      // media that emit nothing: coarser cells where that costs less
  bool emission_term = false;    // raise mu_bar where mu_a * Le is large
  float emission_weight = 1.0f;  // k: collisions per unit length per unit of mu_a * lum(Le)
  bool relative_weight = false;  // k is dimensionless: relative to the emission a ray through each medium gathers
  float emission_cap = 1.0f;     // c: emission-driven rate capped at c collisions per voxel; 0 = no cap
  float safety_factor = 1.0f;    // multiplies every majorant; >= 1

  template <class V>
  void visit(V& v) {
    v.field("structure", structure, "global: one majorant for the whole volume; grid: one per coarse cell, walked by a 3D DDA");
    v.field("cell_size", cell_size, "Voxels per majorant cell along each axis (grid structure). Smaller is tighter but more DDA steps", Range{1, 4096});
    v.field("coarsen_thin", coarsen_thin,
            "Media that emit nothing get cells 2, 4, 8... times cell_size where the work model (work.h) says fewer DDA steps "
            "outweigh the extra null collisions: thin mist walks few large cells. Speed only; the image is unchanged");
    v.field("emission_term", emission_term, "Raise the majorant where emission is bright, so collisions (and emission gathering) concentrate there (talk 2.1)");
    v.field("emission_weight", emission_weight, "k: converts mu_a * lum(Le) into a collision rate; 0 turns the emission term off", Range{0.0, 1e9});
    v.field("relative_weight", relative_weight,
            "k relative to what a ray through each medium gathers, its absorption-weighted mean Le times 1 - exp(-tau_a) "
            "(dimensionless: a ray through a thin emitter gets about k emission collisions, a dense one k per unit of absorption "
            "depth), so one value fits any emission scale and density; off: k in units of 1 / radiance");
    v.field("emission_cap", emission_cap,
            "c: the emission-driven rate is capped at c / voxel size (collisions per voxel); 0 = the renderer's largest cap, "
            "1000 per voxel",
            Range{0.0, 1000.0});
    v.field("safety_factor", safety_factor, "Multiplies every majorant; keep 1 unless lookups can exceed the stored maxima", Range{1.0, 100.0});
  }
};

// Which ray segments gather their emission past the point where their tracked walk scatters
// (EmissionSettings::gather_past_scattering; docs/method.md s.2, "Emission past the scattering").
enum class PastScattering { Off, CameraRays, AllRays };
template <>
struct EnumNames<PastScattering> {
  static const std::vector<std::pair<PastScattering, const char*>>& get() {
    static const std::vector<std::pair<PastScattering, const char*>> v{
        {PastScattering::Off, "off"}, {PastScattering::CameraRays, "camera_rays"}, {PastScattering::AllRays, "all_rays"}};
    return v;
  }
};

// Emission sampling (talk s.2.1; docs/method.md s.2 and s.3).
struct EmissionSettings {
  bool gather_every_collision = false;  // P_a = P_n = 1: add mu_a Le / mu_bar at every collision
  bool light_sampling = false;          // emissive volumes are lights: NEE via the energy grid + MIS
  int grid_cell_size = 4;               // voxels per cell of the emission-energy-distribution grid
  // Share of the continuation directions at medium vertices drawn toward emissive volumes (their
  // energy-grid direction density) instead of from the phase function, scaled at each vertex by the
  // light sampler's share of those volumes there; one-sample MIS over the mixture (docs/method.md s.3b).
  float continuation_toward_volumes = 0.0f;
  // With gather_every_collision: a segment's emission by ratio tracking along the whole segment
  // (talk Algorithm 1), continued past the point where its tracked walk scatters, instead of only
  // up to it. A flame seen through a scattering medium is then no longer all or nothing per sample.
  PastScattering gather_past_scattering = PastScattering::Off;

  template <class V>
  void visit(V& v) {
    v.field("gather_every_collision", gather_every_collision,
            "Gather emission at every tentative collision with absorption as a weight, instead of only at absorption events");
    v.field("light_sampling", light_sampling,
            "Treat emissive volumes as light sources: next-event estimation toward them, MIS with phase/BSDF sampling");
    v.field("grid_cell_size", grid_cell_size, "Voxels per cell of the emission-energy grid used to sample emissive volumes", Range{1, 4096});
    v.field("continuation_toward_volumes", continuation_toward_volumes,
            "Share of the paths' continuations at medium vertices aimed at emissive volumes (times the light sampler's share of "
            "them at the vertex), the rest by the phase function; the mixture's pdf weights both, so the image is unchanged. "
            "Reaches the glow that a flame lights in the medium around it. Needs light_sampling; 0: phase sampling only",
            Range{0.0, 0.9});
    v.field("gather_past_scattering", gather_past_scattering,
            "With gather_every_collision: which ray segments gather their emission along the whole segment by ratio tracking, "
            "continuing past the point where the path scatters (off, camera_rays, all_rays), instead of only up to it; a flame "
            "behind a scattering medium then stops being all or nothing per sample. The image is unchanged");
  }
};

enum class DistanceGuide { None, Probes, EquiAngular };
template <>
struct EnumNames<DistanceGuide> {
  static const std::vector<std::pair<DistanceGuide, const char*>>& get() {
    static const std::vector<std::pair<DistanceGuide, const char*>> v{
        {DistanceGuide::None, "none"}, {DistanceGuide::Probes, "probes"}, {DistanceGuide::EquiAngular, "equiangular"}};
    return v;
  }
};

// How the guided and the tracked scattering vertex of a guided segment combine (docs/method.md s.4).
// one_sample: one technique per segment, the guided one with probability guided_probability, its
// vertex weighted by the balance heuristic of the mixture (Veach's one-sample MIS): one NEE per
// segment instead of one for each technique.
enum class GuideCombination { Balance, Power, Average, GuidedOnly, OneSample };
template <>
struct EnumNames<GuideCombination> {
  static const std::vector<std::pair<GuideCombination, const char*>>& get() {
    static const std::vector<std::pair<GuideCombination, const char*>> v{{GuideCombination::Balance, "balance"},
                                                                        {GuideCombination::Power, "power"},
                                                                        {GuideCombination::Average, "average"},
                                                                        {GuideCombination::GuidedOnly, "guided_only"},
                                                                        {GuideCombination::OneSample, "one_sample"}};
    return v;
  }
};

// What the guided vertex estimates. direct: only its direct light (NEE), the tracked vertex alone
// continuing the path (the talk's "camera rays and direct illumination"); path: its direct light
// and a continuing path, both vertices weighted by MIS (docs/method.md s.4's simplest form).
enum class GuidedVertex { Direct, Path };
template <>
struct EnumNames<GuidedVertex> {
  static const std::vector<std::pair<GuidedVertex, const char*>>& get() {
    static const std::vector<std::pair<GuidedVertex, const char*>> v{{GuidedVertex::Direct, "direct"}, {GuidedVertex::Path, "path"}};
    return v;
  }
};

// Which rays after the camera ray get a guided sample when guided_segments > 1. from_media: only rays
// leaving a scattering vertex in a medium; rays leaving a surface are left to tracking. On
// god-rays-dark guiding the rays from surfaces too (most later rays: camera rays in thin haze mostly
// reach the ground) made the render 1.75x as long as from_media's for the same variance (docs/performance.md,
// "Guided continuations"). from_media_unless_flame_lit: as from_media, except in scenes where volumes
// emit and no sun (directional light) shines (guidedContinuationsApply in scene.h): there the
// continuations aimed at the emissive volumes (docs/method.md s.3b) already reach their glow, and a
// guided later vertex pays a light sample through the flame (torch-in-mist: x0.76 per unit of work).
enum class SecondaryRays { All, FromMedia, FromMediaUnlessFlameLit };
template <>
struct EnumNames<SecondaryRays> {
  static const std::vector<std::pair<SecondaryRays, const char*>>& get() {
    static const std::vector<std::pair<SecondaryRays, const char*>> v{{SecondaryRays::All, "all"},
                                                                      {SecondaryRays::FromMedia, "from_media"},
                                                                      {SecondaryRays::FromMediaUnlessFlameLit, "from_media_unless_flame_lit"}};
    return v;
  }
};

// Scattering (distance) sampling, talk s.2.2 and docs/method.md s.4: a guided distance sample per ray,
// combined with the tracked (transmittance-based) sample by MIS (Miller et al. 2019).
struct GuidingSettings {
  DistanceGuide guide = DistanceGuide::None;
  GuideCombination combination = GuideCombination::Balance;  // MIS heuristic, or MIS off
  float guided_probability = 0.5f;  // one_sample: probability that a segment uses the guided vertex
  GuidedVertex guided_vertex = GuidedVertex::Direct;
  int guided_segments = 1;        // 1: camera rays; 2: also the rays leaving the first vertex
  SecondaryRays secondary_rays = SecondaryRays::FromMedia;  // guided_segments > 1: which later rays
  // one_sample, guided_segments > 1: q on the rays after the camera ray. 1 (the guided vertex on
  // every such segment): the tracked vertex there is the rare event guiding exists to replace (a
  // vertex landing in a thin sun shaft), and the density is built whatever q is (docs/performance.md, "Guided
  // continuations").
  float secondary_probability = 1.0f;
  float floor = 0.1f;             // uniform share of the piecewise-linear density (full support)
  float probe_spacing = 0.0f;     // world units between probes; 0: 1/20 of the media's extent
  float probe_radius = 0.5f;      // radius of influence, in units of the spacing (0.5: spheres inscribed in lattice cells)
  int probe_samples = 32;         // light samples per probe when learning
  // Learning takes probe_samples per probe, always: the probes (and so the image) are the same on an
  // idle or a busy machine and on any thread count. The time cap is only a safety net; cutting
  // learning short makes the image depend on machine speed, so it is reported as a warning.
  float probe_time_cap_s = 120.0f;
  float max_optical_depth = 4.0f; // skip guiding on rays thicker than this (majorant of mu_t); 0: never skip
  // The same for the rays after the camera ray (guided_segments > 1). A continuation thicker than a
  // few tenths scatters near its start, where its tracked vertex is as good as a guided one, and
  // leaves most of its length unseen: on the side-lit god-rays guiding continuations up to 4 optical
  // depths cost 41% more work for 12% less variance, up to 0.5 they cost 3% per unit of work, while
  // god-rays-dark, god-rays-backlit and shed-fire keep their whole gain, which falls away below 0.35
  // (docs/performance.md, "Guided continuations in full").
  float secondary_max_optical_depth = 4.0f;
  // Camera rays of pixels whose probes predict less single-scattered light than this fraction of
  // the mean prediction over the image are left to tracking (camera_guides.h): on fire, 40% of the
  // guided pixels see next to nothing, and guiding them was 3.4% of the work for 6% of the relative
  // variance and none of the variance (docs/performance.md, "Dim pixels"). 0: guide every pixel whose probes
  // carry light.
  float dim_pixel_floor = 0.05f;
  // one_sample: the most q a pixel's camera rays get where the probes predict bright single
  // scattering that is the pixel's light (camera_guides.h): q = guided_probability x (the pixel's
  // prediction / the image's mean) x (its share against an upper bound of the emission along the
  // centre ray), clamped to [guided_probability, this]. A sun shaft gets the guided vertex on one
  // camera ray in two while dim mist keeps one in ten; a flame's pixels, whose light is their own
  // emission, are not raised (docs/performance.md, "Bright pixels"). At most guided_probability
  // (the struct's default 0): every pixel keeps guided_probability.
  float bright_pixel_probability = 0.0f;
  // one_sample, guided_vertex = direct: each pixel's camera-ray q measured instead of predicted
  // (camera_guides.h). After 16, 32, 64... samples the pixel takes, among 0, 0.05, 0.1, 0.2, 0.35
  // and 0.5 (at most the larger of the two settings above), the q whose variance x work its own
  // samples predict least: its camera vertex's direct light D = f / p_q, with p_g and p_t at the
  // vertex, says what any other q would have given there. Probes predict where single scattering
  // is; this measures whether it is the pixel's noise. A flame's pixels, whose noise is their own
  // emission, then spend nothing on guided vertices, while dim mist lit by it gets more.
  // Every pass is rendered with q fixed before it starts, so the image stays unbiased.
  bool measured_pixel_probability = false;

  template <class V>
  void visit(V& v) {
    v.field("guide", guide, "Guided distance sampler: none, probes (talk 2.2) or equiangular (Kulla and Fajardo 2012)");
    v.field("combination", combination,
            "How the guided and tracked samples combine: balance or power heuristic MIS (both vertices, two NEEs), average "
            "(MIS off), guided_only, or one_sample (one vertex per segment, chosen at random, balance-weighted)");
    v.field("guided_probability", guided_probability,
            "one_sample only: the probability that a guided segment uses the guided vertex rather than the tracked one",
            Range{0.01, 0.99});
    v.field("guided_vertex", guided_vertex,
            "direct: the guided vertex adds only its direct light and the tracked vertex continues the path; path: "
            "both vertices add direct light and a continuing path, weighted by MIS");
    v.field("guided_segments", guided_segments, "Path segments that get a guided sample: 1 camera rays, 2 also the rays from the first vertex", Range{1, 64});
    v.field("secondary_rays", secondary_rays,
            "guided_segments > 1: which rays after the camera ray get a guided sample: all, from_media (only rays leaving a "
            "scattering vertex in a medium; rays leaving a surface are left to tracking), or from_media_unless_flame_lit (as "
            "from_media, but none in scenes where volumes emit and no sun shines)");
    v.field("secondary_probability", secondary_probability,
            "one_sample, guided_segments > 1: the probability that a guided segment after the camera ray uses the guided vertex",
            Range{0.01, 1.0});
    v.field("floor", floor, "Uniform share of the guided density, so its support is complete", Range{1e-4, 1.0});
    v.field("probe_spacing", probe_spacing, "World units between probes (0: automatic, 1/20 of the media's extent)", Range{0.0, 1e6});
    // Capped at 2: beyond that every ray gathers thousands of overlapping probes (radius 10 measured
    // 250 s against 0.7 s for the same render in the stability suite), for no gain in the density.
    v.field("probe_radius", probe_radius, "Probe radius of influence, in units of the spacing (at most 2: larger only multiplies lookups)", Range{0.05, 2.0});
    v.field("probe_samples", probe_samples, "Light samples per probe when learning", Range{1, 1 << 20});
    v.field("probe_time_cap_s", probe_time_cap_s,
            "Safety net only: learning still running after this many seconds is cut, with a warning (the probes, and so the "
            "noise, then depend on machine speed)",
            Range{0.01, 3600.0});
    v.field("max_optical_depth", max_optical_depth,
            "Rays whose majorant optical depth exceeds this get no guided sample: tracking already scatters there (0: guide all)",
            Range{0.0, 1e6});
    v.field("secondary_max_optical_depth", secondary_max_optical_depth,
            "guided_segments > 1: rays after the camera ray whose majorant optical depth exceeds this get no guided sample (0: "
            "guide all)",
            Range{0.0, 1e6});
    v.field("dim_pixel_floor", dim_pixel_floor,
            "Camera rays of pixels whose probes predict less scattered light than this fraction of the image's mean "
            "prediction get no guided sample (0: guide every pixel whose probes carry light)",
            Range{0.0, 1e3});
    v.field("bright_pixel_probability", bright_pixel_probability,
            "one_sample: the most guided_probability a pixel's camera rays get where the probes predict more single-scattered "
            "light than the image's mean and more than the emission along the ray; q grows with both, from guided_probability up "
            "to this (at most guided_probability: off)",
            Range{0.0, 0.99});
    v.field("measured_pixel_probability", measured_pixel_probability,
            "one_sample, guided_vertex direct: after 16, 32, 64... samples each pixel's camera rays take the q (0 to the larger of "
            "guided_probability and bright_pixel_probability) whose variance x work the pixel's own samples predict least");
  }
};

// guiding.measured_pixel_probability takes effect under one-sample MIS with a direct guided vertex.
inline bool measuresPixelProbability(const GuidingSettings& g) {
  return g.measured_pixel_probability && g.combination == GuideCombination::OneSample && g.guided_vertex == GuidedVertex::Direct;
}

struct StrategySettings {
  std::string preset = "conventional";
  MajorantPolicy majorant;
  EmissionSettings emission;
  GuidingSettings guiding;
  int russian_roulette_depth = 3;  // scattering events before Russian roulette may end a path
  int adaptive_split = 1;          // most camera samples per film sample in a noisy block; 1: off

  template <class V>
  void visit(V& v) {
    v.field("preset", preset,
            "Named starting point for the settings below (auto, conventional, emission, full, equiangular). auto chooses from "
            "the scene and a short pilot render, and says what it chose");
    v.object("majorant", majorant, "How the majorant (the collision rate of null-collision tracking) is built");
    v.object("emission", emission, "Emission sampling: gathering at every collision and emissive volumes as lights");
    v.object("guiding", guiding, "Scattering distance sampling: probe guiding or equi-angular, with MIS");
    v.field("russian_roulette_depth", russian_roulette_depth, "Scattering events before Russian roulette may end a path (unbiased)", Range{0, 100000});
    v.field("adaptive_split", adaptive_split,
            "Adaptive sampling: after the first 4 samples per pixel, each 8 x 8 block renders up to this many camera samples "
            "per film sample, as many as its measured noise per unit of work calls for, and the film keeps their mean. "
            "The image is unchanged; 1: every pixel one",
            Range{1, 16});
  }
};

// Names of the strategy presets, in the order the CLI lists them.
const std::vector<std::string>& strategyPresetNames();
// The settings of a preset; throws InputError naming `origin` for an unknown name.
StrategySettings strategyPreset(const std::string& name, const std::string& origin = "strategy preset");
// Reads a "strategy" object: the preset's settings first, then the object's own fields on top.
StrategySettings strategyFromJson(const Json& j, const std::string& file, const std::string& path);

struct RenderSettings {
  int spp = 64;          // samples per pixel for a batch render
  float time_s = 0.0f;   // when > 0, render until this many seconds have passed instead of spp
  uint32_t seed = 1;
  int max_depth = 32;    // most scattering or bounce events on a path
  int frame = 1;         // substituted into volume file patterns (fire.####.vdb)

  template <class V>
  void visit(V& v) {
    v.field("spp", spp, "Samples per pixel of a batch render", Range{1, 1 << 24});
    v.field("time_s", time_s, "Render for this many seconds instead (0: use spp)", Range{0.0, 1e7});
    v.field("seed", seed, "Random seed; a seed and spp give the same image on any thread count");
    v.field("max_depth", max_depth, "Most scattering or surface-bounce events on a path", Range{0, 100000});
    v.field("frame", frame, "Frame number put into volume file patterns: fire.####.vdb, fire_$F4.vdb, fire.%04d.vdb", Range{-1000000, 1000000});
  }
};

}  // namespace candela
