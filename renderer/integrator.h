// The volumetric path tracer. One tracking loop (tracking.h); this file decides what each
// collision does, by named pieces of the strategy:
// - event probabilities: conventional analog absorb / scatter / null with P = mu_a/mu_bar,
//   mu_s/mu_bar, mu_n/mu_bar and emission added at absorption (docs/method.md s.2, the talk's Fig. 1
//   left), or emission gathered at every collision with P_a = P_n = 1, absorption as a weight
//   (strategy.emission.gather_every_collision; talk 2.1);
// - majorant policy: the medium's per-cell mu_bar, optionally emission-aware (medium.cpp);
// - light sampler: lights and, with strategy.emission.light_sampling, emissive volumes by their
//   energy grid (Algorithm 2), all chosen by power; emission met along a phase/BSDF-sampled ray is
//   MIS-weighted against that (docs/method.md s.3);
// - distance sampler: with strategy.guiding, each guided ray segment also draws a guided distance
//   (probes or equi-angular) whose null collisions on [0, t] come from ratio tracking; it is
//   combined with the tracked scattering by MIS with p_guided = p_g(t) and
//   p_tracked = prod(P_null) * mu_bar(t) P_s(t) (docs/method.md s.4; Miller et al. 2019). Emission
//   along the ray is counted once, by the tracked walk. By default (guiding.guided_vertex = direct)
//   the guided vertex adds only its direct light and the tracked vertex carries the path.
// - direction sampler: HG at medium vertices, cosine at surfaces; with
//   strategy.emission.continuation_toward_volumes a medium vertex's continuation is a one-sample
//   mixture of HG and the emissive volumes' direction density, and every MIS weight against it uses
//   the mixture's pdf (docs/method.md s.3b).
// Scattering does next-event estimation (ratio-tracked transmittance, or Algorithm 1 toward
// emissive volumes), then samples HG; surfaces are diffuse.
//
// Path length: at most render.max_depth scattering/bounce vertices. The last vertex takes all its
// direct light by NEE (weight 1) and its continuation gathers only volume emission no light
// sampler covers, so every strategy computes exactly the same truncated image.
#pragma once

#include "distance_sampler.h"
#include "probes.h"
#include "scene.h"

namespace candela {

class CameraGuides;  // camera_guides.h: per-pixel camera-ray guide tables reused across passes

class PathTracer {
 public:
  explicit PathTracer(const Scene& scene);
  // Radiance arriving along the camera ray (scene-linear RGB). May be non-finite on a bug; the film
  // rejects and counts such samples.
  Rgb radiance(const Ray& cameraRay, Rng& rng) const;
  // The same, with the camera ray's guided density shared from `cameraGuide` (the table of the
  // ray's pixel and its q; null: built for the ray as usual).
  Rgb radiance(const Ray& cameraRay, const CameraRayGuide* cameraGuide, Rng& rng) const;
  // What the camera ray's scattering vertex did, for a pixel's measured q (camera_guides.h,
  // guiding.measured_pixel_probability). Under one-sample MIS the vertex, guided or tracked, adds
  // direct light D = f(t) / p_q(t), p_q = q p_g + (1 - q) p_t; with p_g and p_t at its distance, D
  // tells what any other q would have given there.
  struct CameraVertexRecord {
    bool table = false;        // the pixel has a guide table (its q may be 0)
    float q = 0.0f;            // the q this sample drew with
    float guidedPdf = 0.0f;    // p_g at the vertex's distance
    float trackedPdf = 0.0f;   // p_t at the vertex's distance (0: no vertex added light)
    Rgb direct{0.0f};          // D
    bool guidedDrawn = false;  // the guided vertex was drawn (guidedWork is its work)
    double guidedWork = 0.0;
  };
  // The same, filling `record` for the camera ray (a pixel with a cached table; `record` may be null).
  Rgb radiance(const Ray& cameraRay, const CameraRayGuide* cameraGuide, Rng& rng, CameraVertexRecord* record) const;

  // The guided distance density of a ray over its medium interval [tIn, tOut] as the strategy
  // builds it (probes or equi-angular), or false when the ray gets no guided sample (guiding off,
  // no medium, thicker than guiding.max_optical_depth, or for a ray after the camera ray
  // (`secondary`) guiding.secondary_max_optical_depth, or no probe along it carries light). For the
  // inspector and the camera cache.
  bool guideFor(const Ray& ray, float tEnd, float& tIn, float& tOut, GuidedDistance& out, bool secondary = false) const;
  // Optical depth of the majorant of mu_t along a whole ray through the media (no surfaces), or a
  // negative value when the ray misses every medium. For the auto strategy's scene rules.
  float mediaOpticalDepth(const Ray& ray) const;

  // Light scattered toward wo at a medium point with HG parameter g, by light sampling alone: the
  // phase-weighted direct light, emissive volumes included (one light chosen by the light sampler).
  Rgb inScattered(const Vec3& p, const Vec3& wo, float g, Rng& rng) const;
  // One sample of the luminance arriving at p from light `index` alone (the scene's lights, then
  // its emissive volumes), integrated over the light's solid angle with transmittance (ratio
  // tracking; Algorithm 1 toward emissive volumes) and no phase: E = int L T dw. Probes learn this.
  float unphasedIncident(const Vec3& p, int index, Rng& rng) const;

  // Solid-angle pdf of the volume-light technique producing direction w from x: the mixture
  // sum_m pmf_m p_m(w) over emissive volumes (Algorithm 2 for each).
  float volumeLightPdf(const Vec3& x, const Vec3& w) const;

  // Continuations toward emissive volumes (strategy.emission.continuation_toward_volumes;
  // docs/method.md s.3b): the share of a medium vertex's continuations drawn toward them at x (0 when
  // off), the direction density of that technique (Algorithm 2's densities mixed by the light
  // sampler's pmf of each volume at x, normalised), and a sample of it. `volumeShare` receives the
  // light sampler's total pmf of the volumes at x.
  float continuationShareTowardVolumes(const Vec3& x, float& volumeShare) const;
  float volumeDirectionPdf(const Vec3& x, const Vec3& w, float volumeShare) const;
  bool sampleVolumeDirection(const Vec3& x, float volumeShare, Rng& rng, Vec3& wi) const;

  // The part of [0, tEnd] where some medium may be non-zero; false when there is none.
  bool mediumInterval(const Ray& ray, float tEnd, float& tIn, float& tOut) const;
  // The probe set this tracer samples (null without probe guiding).
  const ProbeSet* probes() const { return probes_.get(); }
  // Distance to the nearest surface or (opaque) sphere light along a ray; infinity when none.
  float nearestOccluder(const Ray& ray) const;

 private:
  struct PathState {
    Ray ray;
    Rgb beta{1.0f};
    int vertices = 0;          // scattering and bounce events so far
    int segment = 0;           // index of `ray` along the path (0: the camera ray)
    bool lightsTaken = false;  // the last vertex already took all direct light by NEE
    float prevPdf = 0.0f;      // solid-angle pdf of the direction that made `ray` (0: camera ray)
    float prevVolumeLightPdf = -1.0f;  // volumeLightPdf(prevPos, ray.direction) when already known, else < 0
    Vec3 prevPos{0.0f};
    bool fromMedium = false;   // `ray` leaves a scattering vertex in a medium (not a surface or the camera)
  };
  struct SegmentWalk;  // what the tracked walk of one segment found (integrator.cpp)
  struct WalkCollision;  // one tentative collision of a guided segment's tracked walk (integrator.cpp)
  class SegmentScratch;  // a path's reused per-segment buffers (integrator.cpp)

  // Follows a path from its current ray to the end; returns the radiance it gathers. The camera
  // ray's guided density comes from `cameraGuide` when given.
  Rgb trace(PathState state, const CameraRayGuide* cameraGuide, Rng& rng, CameraVertexRecord* record = nullptr) const;
  // The tracked walk along one segment (docs/method.md s.2): the one tracking loop with the strategy's
  // event probabilities (analogEvent or gatherEvent) as its collision callback. Adds emission to L.
  // On a guided segment the walk also replays the tracked pdf's null factors, and `record`, when
  // given, receives its tentative collisions for the segment's guided sample.
  SegmentWalk walkSegment(PathState& state, float tEnd, bool guided, std::vector<WalkCollision>* record, float emissionWeight, Rgb& L,
                          Rng& rng) const;
  // Distance-sampler choice for one segment: whether it gets a guided sample, and its density.
  bool prepareGuide(const PathState& state, float tEnd, const CameraRayGuide* cameraGuide, GuidedDistance& guide) const;
  // A medium scattering vertex at p: NEE, Russian roulette, HG sampling of the next ray. Returns
  // false when the path ends there. The NEE is scaled by `directWeight` (an MIS weight on guided
  // segments); the continuation (not the NEE) survives with probability `continueProbability`
  // first (used to spend about one continuation per guided segment in guided_vertex = path).
  bool scatterVertex(PathState& state, const Vec3& p, float g, Rgb& L, Rng& rng, float continueProbability = 1.0f,
                     float directWeight = 1.0f) const;
  // The guided distance sample of one ray segment (docs/method.md s.4), drawn from `guide`: its
  // vertex's direct light, and with guided_vertex = path also the path continuing from it. `walked`,
  // when given, holds the segment's tracked walk's collisions over (0, walkedT], which it reuses;
  // without it the sample walks its own null collisions from the segment's start. tEnd: where the
  // segment ends (a surface or infinity).
  // `densities`, when given, receives p_g and p_t at the drawn distance (left alone when the sample
  // adds nothing).
  Rgb guidedSample(const PathState& state, float tEnd, const GuidedDistance& guide, const std::vector<WalkCollision>* walked,
                   float walkedT, Rng& rng, float* densities = nullptr) const;
  // Optical depth of maj(mu_t) along a ray over [t0, t1] (no lookups: majorant cells only).
  float majorantOpticalDepth(const Ray& ray, float t0, float t1) const;
  // MIS weight of the guided technique given r = p_tracked / p_guided.
  float guidedWeight(float r, float guidedProbability) const;

  // Direct light at a vertex by one light sample. With useMis its weight is MIS against the vertex's
  // continuation: BSDF or HG sampling, or at a medium vertex the mixture with share `towardVolumes`
  // toward the emissive volumes (their light-sampler share `volumeShare`; scatterVertex computes both).
  Rgb directLight(const Vec3& p, const Vec3& wo, float g, const Vec3& normal, const Rgb& albedo, bool useMis, Rng& rng,
                  float towardVolumes = 0.0f, float volumeShare = 0.0f) const;
  float visibility(const Vec3& p, const Vec3& wi, float distance, int targetLight, Rng& rng) const;

  const Scene& scene_;
  std::shared_ptr<const ProbeSet> probes_;  // the set serving this tracer (swapped sets never disturb it)
  std::vector<EquiAngularTarget> equiAngularTargets_;
};

}  // namespace candela
