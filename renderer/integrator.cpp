#include "integrator.h"

#include "phase.h"

#include <memory>

namespace candela {

namespace {

float surfaceOffset(const Vec3& p) { return 1e-4f * std::max(1.0f, maxComponent(glm::abs(p))); }

Vec3 sampleCosineHemisphere(Vec2 u) {
  const float r = std::sqrt(u.x);
  const float phi = 2.0f * kPi * u.y;
  return Vec3(r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0f, 1.0f - u.x)));
}

}  // namespace

PathTracer::PathTracer(const Scene& scene) : scene_(scene), probes_(scene.probes()) {
  // Equi-angular targets: point-like lights, and each emissive volume's emission centroid.
  for (const Light& l : scene.lights())
    if (l.hasPosition())
      equiAngularTargets_.push_back({l.desc().position, l.power(scene.radius())});
  for (const EmissionLight* v : scene.volumeLights()) equiAngularTargets_.push_back({v->centroid(), v->power()});
}

Rgb PathTracer::inScattered(const Vec3& p, const Vec3& wo, float g, Rng& rng) const {
  return directLight(p, wo, g, Vec3(0.0f), Rgb(0.0f), false, rng);
}

bool PathTracer::guideFor(const Ray& ray, float tEnd, float& tIn, float& tOut, GuidedDistance& out, bool secondary) const {
  const GuidingSettings& g = scene_.strategy().guiding;
  if (g.guide == DistanceGuide::None || !mediumInterval(ray, tEnd, tIn, tOut)) return false;
  // Thick rays are left to tracking, which scatters there reliably: the choice depends on the ray
  // alone (never on the walk), so MIS stays valid with the tracked technique alone on them.
  const float maxDepth = secondary ? g.secondary_max_optical_depth : g.max_optical_depth;
  if (maxDepth > 0.0f && majorantOpticalDepth(ray, tIn, tOut) > maxDepth) return false;
  if (g.guide == DistanceGuide::EquiAngular) {
    out.buildEquiAngular(ray, tIn, tOut, equiAngularTargets_);
  } else {
    out.knots.clear();
    if (probes_) probes_->gatherKnots(ray, tIn, tOut, out.knots);
    // A ray whose probes carry no light (it crosses the media's box where they are empty or
    // unlit) is left to tracking, as a thick one is: its guided density would be the floor alone,
    // a vertex drawn uniformly where no light scatters. Again a choice by the ray alone. On fire,
    // whose box is mostly empty around the flame, this cut full's work per sample by 2% for the
    // same variance (docs/performance.md, "Rays whose probes carry no light").
    if (!knotsCarryLight(out.knots)) return false;
    out.buildPiecewiseLinear(tIn, tOut, g.floor);
  }
  return true;
}

float PathTracer::mediaOpticalDepth(const Ray& ray) const {
  float tIn = 0.0f, tOut = 0.0f;
  if (!mediumInterval(ray, kInfinity, tIn, tOut)) return -1.0f;
  return majorantOpticalDepth(ray, tIn, tOut);
}

bool PathTracer::mediumInterval(const Ray& ray, float tEnd, float& tIn, float& tOut) const {
  tIn = kInfinity;
  tOut = 0.0f;
  for (const Medium* m : scene_.media().media) {
    const MajorantGrid& grid = m->majorantGrid();
    if (grid.empty()) continue;
    const Vec3 o = Vec3(m->indexFromWorld() * glm::vec4(ray.origin, 1.0f));
    const Vec3 d = Vec3(m->indexFromWorld() * glm::vec4(ray.direction, 0.0f));
    float a = 0.0f, b = tEnd;
    for (int axis = 0; axis < 3 && a <= b; ++axis) {
      const float lo = grid.origin()[axis], hi = grid.domainMax()[axis];
      if (d[axis] == 0.0f) {
        if (o[axis] < lo || o[axis] > hi) b = -1.0f;
        continue;
      }
      float t0 = (lo - o[axis]) / d[axis], t1 = (hi - o[axis]) / d[axis];
      if (t0 > t1) std::swap(t0, t1);
      a = std::max(a, t0);
      b = std::min(b, t1);
    }
    if (a < b) tIn = std::min(tIn, a), tOut = std::max(tOut, b);
  }
  return tIn < tOut;
}

float PathTracer::majorantOpticalDepth(const Ray& ray, float t0, float t1) const {
  float depth = 0.0f;
  for (const Medium* m : scene_.media().media) {
    const Vec3 o = Vec3(m->indexFromWorld() * glm::vec4(ray.origin, 1.0f));
    const Vec3 d = Vec3(m->indexFromWorld() * glm::vec4(ray.direction, 0.0f));
    MajorantDda dda(m->majorantGrid(), o, d, t0, t1);
    float a, b;
    int cell;
    while (dda.next(a, b, cell)) depth += m->majorantGrid().maxDensity(cell) * m->sigmaTScale() * (b - a);
  }
  return depth;
}

float PathTracer::guidedWeight(float r, float guidedProbability) const {
  const GuidingSettings& g = scene_.strategy().guiding;
  switch (g.combination) {
    case GuideCombination::Balance: return 1.0f / (1.0f + r);
    // One-sample MIS: p_g / (q p_g + (1 - q) p_t), the selection probability q included.
    case GuideCombination::OneSample: return 1.0f / (guidedProbability + (1.0f - guidedProbability) * r);
    case GuideCombination::Power: return std::isfinite(r * r) ? 1.0f / (1.0f + r * r) : 0.0f;
    case GuideCombination::Average: return 0.5f;
    case GuideCombination::GuidedOnly: return 1.0f;
  }
  return 0.0f;
}

float PathTracer::visibility(const Vec3& p, const Vec3& wi, float distance, int targetLight, Rng& rng) const {
  const float tMax = std::isfinite(distance) ? distance * (1.0f - 1e-4f) : kInfinity;
  const Ray ray{p, wi};
  if (scene_.surfaces().occluded(ray, tMax)) return 0.0f;
  // Sphere lights are opaque: a phase-sampled ray stops at them, so shadow rays must too.
  const auto& lights = scene_.lights();
  for (size_t i = 0; i < lights.size(); ++i)
    if (static_cast<int>(i) != targetLight && lights[i].type() == LightType::Sphere && std::isfinite(lights[i].intersect(ray, tMax)))
      return 0.0f;
  return ratioTrackingTransmittance(scene_.media(), ray, tMax, rng);
}

float PathTracer::nearestOccluder(const Ray& ray) const {
  float t = scene_.surfaces().intersect(ray, kInfinity).t;
  for (const Light& l : scene_.lights())
    if (l.type() == LightType::Sphere) t = std::min(t, l.intersect(ray, t));
  return t;
}

float PathTracer::volumeLightPdf(const Vec3& x, const Vec3& w) const {
  const auto& volumes = scene_.volumeLights();
  const int first = static_cast<int>(scene_.lights().size());
  float pdf = 0.0f;
  for (size_t m = 0; m < volumes.size(); ++m) {
    const float pmf = scene_.lightSampler().pmf(x, first + static_cast<int>(m));
    if (pmf > 0.0f) pdf += pmf * volumes[m]->pdf(x, w);
  }
  return pdf;
}

float PathTracer::continuationShareTowardVolumes(const Vec3& x, float& volumeShare) const {
  volumeShare = 0.0f;
  const EmissionSettings& e = scene_.strategy().emission;
  if (!(e.continuation_toward_volumes > 0.0f) || scene_.volumeLights().empty()) return 0.0f;
  const int first = static_cast<int>(scene_.lights().size());
  for (size_t m = 0; m < scene_.volumeLights().size(); ++m) volumeShare += scene_.lightSampler().pmf(x, first + static_cast<int>(m));
  // Scaled by the volumes' share of the light at x: where the sun or the sky outshines a flame, the
  // phase function keeps the continuations (measured: shed-fire's haze loses otherwise).
  return e.continuation_toward_volumes * std::min(1.0f, volumeShare);
}

float PathTracer::volumeDirectionPdf(const Vec3& x, const Vec3& w, float volumeShare) const {
  return volumeShare > 0.0f ? volumeLightPdf(x, w) / volumeShare : 0.0f;
}

bool PathTracer::sampleVolumeDirection(const Vec3& x, float volumeShare, Rng& rng, Vec3& wi) const {
  const auto& volumes = scene_.volumeLights();
  const int first = static_cast<int>(scene_.lights().size());
  float u = rng.uniform() * volumeShare;
  const float u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform();
  for (size_t m = 0; m < volumes.size(); ++m) {
    const float pmf = scene_.lightSampler().pmf(x, first + static_cast<int>(m));
    if (pmf > 0.0f && (u < pmf || m + 1 == volumes.size())) return volumes[m]->sample(x, u0, u1, u2, u3, wi);
    u -= pmf;
  }
  return false;
}

Rgb PathTracer::directLight(const Vec3& p, const Vec3& wo, float g, const Vec3& normal, const Rgb& albedo, bool useMis,
                            Rng& rng, float towardVolumes, float volumeShare) const {
  const LightSampler& sampler = scene_.lightSampler();
  if (sampler.empty()) return Rgb(0.0f);
  float pmf = 0.0f;
  const int index = sampler.sample(p, rng.uniform(), pmf);
  if (index < 0) return Rgb(0.0f);
  const bool onSurface = normal != Vec3(0.0f);
  auto scattering = [&](const Vec3& wi, Rgb& f, float& scatterPdf) {
    if (onSurface) {
      const float cosTheta = glm::dot(normal, wi);
      if (cosTheta <= 0.0f) return false;
      f = albedo * (kInvPi * cosTheta);
      scatterPdf = cosTheta * kInvPi;
    } else {
      scatterPdf = hgEval(wo, wi, g);
      f = Rgb(scatterPdf);
    }
    return true;
  };
  Rgb f;
  float scatterPdf;
  const size_t lightCount = scene_.lights().size();
  // The continuation this NEE competes with (MIS) is a mixture at medium vertices with continuations
  // toward emissive volumes (docs/method.md s.3b): its pdf, given the phase pdf and, when known, the
  // volume-light pdf of wi.
  const float share = useMis ? towardVolumes : 0.0f;
  auto continuationPdf = [&](const Vec3& wi, float phasePdf, float knownVolumeLightPdf) {
    if (!(share > 0.0f)) return phasePdf;
    const float lightPdf = knownVolumeLightPdf >= 0.0f ? knownVolumeLightPdf : volumeLightPdf(p, wi);
    return (1.0f - share) * phasePdf + share * lightPdf / volumeShare;
  };
  if (static_cast<size_t>(index) >= lightCount) {
    // An emissive volume (talk 2.1, Algorithm 2): a direction from its energy grid, the emission
    // integral along it by Algorithm 1, over the mixture pdf of all volume lights.
    const EmissionLight& volume = *scene_.volumeLights()[static_cast<size_t>(index) - lightCount];
    Vec3 wi;
    if (!volume.sample(p, rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform(), wi)) return Rgb(0.0f);
    if (!scattering(wi, f, scatterPdf)) return Rgb(0.0f);
    const float lightPdf = volumeLightPdf(p, wi);
    if (!(lightPdf > 0.0f)) return Rgb(0.0f);
    const Ray ray{p, wi};
    const Rgb emitted = emissionAlongRay(scene_.media(), ray, nearestOccluder(ray), rng);
    if (isBlack(emitted)) return Rgb(0.0f);
    const float weight = useMis ? powerHeuristic(lightPdf, continuationPdf(wi, scatterPdf, lightPdf)) : 1.0f;
    return f * emitted * (weight / lightPdf);
  }
  const Light& light = scene_.lights()[static_cast<size_t>(index)];
  LightSample ls;
  const Vec2 u(rng.uniform(), rng.uniform());
  if (!light.sample(p, u, ls) || isBlack(ls.radiance)) return Rgb(0.0f);
  if (!scattering(ls.wi, f, scatterPdf)) return Rgb(0.0f);
  const float tr = visibility(p, ls.wi, ls.distance, index, rng);
  if (tr <= 0.0f) return Rgb(0.0f);
  const float lightPdf = ls.pdf * pmf;
  const float weight = (ls.delta || !useMis) ? 1.0f : powerHeuristic(lightPdf, continuationPdf(ls.wi, scatterPdf, -1.0f));
  return f * ls.radiance * (tr * weight / lightPdf);
}

float PathTracer::unphasedIncident(const Vec3& p, int index, Rng& rng) const {
  const size_t lightCount = scene_.lights().size();
  if (static_cast<size_t>(index) >= lightCount) {
    const EmissionLight& volume = *scene_.volumeLights()[static_cast<size_t>(index) - lightCount];
    Vec3 wi;
    if (!volume.sample(p, rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform(), wi)) return 0.0f;
    const float pdf = volume.pdf(p, wi);
    if (!(pdf > 0.0f)) return 0.0f;
    const Ray ray{p, wi};
    return luminance(emissionAlongRay(scene_.media(), ray, nearestOccluder(ray), rng)) / pdf;
  }
  const Light& light = scene_.lights()[static_cast<size_t>(index)];
  LightSample ls;
  if (!light.sample(p, Vec2(rng.uniform(), rng.uniform()), ls) || isBlack(ls.radiance) || !(ls.pdf > 0.0f)) return 0.0f;
  const float tr = visibility(p, ls.wi, ls.distance, index, rng);
  return tr > 0.0f ? luminance(ls.radiance) * tr / ls.pdf : 0.0f;
}

Rgb PathTracer::radiance(const Ray& cameraRay, Rng& rng) const { return radiance(cameraRay, nullptr, rng); }

Rgb PathTracer::radiance(const Ray& cameraRay, const CameraRayGuide* cameraGuide, Rng& rng) const {
  return radiance(cameraRay, cameraGuide, rng, nullptr);
}

Rgb PathTracer::radiance(const Ray& cameraRay, const CameraRayGuide* cameraGuide, Rng& rng, CameraVertexRecord* record) const {
  PathState state;
  state.ray = cameraRay;
  state.prevPos = cameraRay.origin;
  return trace(state, cameraGuide, rng, record);
}

bool PathTracer::scatterVertex(PathState& st, const Vec3& p, float g, Rgb& L, Rng& rng, float continueProbability,
                               float directWeight) const {
  const Scene& s = scene_;
  if (st.vertices >= s.render().max_depth) return false;
  ++st.vertices;
  const bool last = st.vertices == s.render().max_depth;
  const Vec3 wo = -st.ray.direction;
  // The continuation's mixture (docs/method.md s.3b), evaluated once for the vertex: the NEE's MIS
  // weights and the continuation below both use it.
  float volumeShare = 0.0f;
  const float towardVolumes = continuationShareTowardVolumes(p, volumeShare);
  // A zero MIS weight (the guided technique owns all direct light: guiding.combination =
  // guided_only) skips the NEE's rays entirely.
  if (directWeight > 0.0f)
    L += st.beta * directWeight * directLight(p, wo, g, Vec3(0.0f), Rgb(0.0f), !last, rng, towardVolumes, volumeShare);
  if (last) {
    // After the last vertex only volume emission that no light sampler covers is still missing.
    if (!s.hasEmissiveMedia() || !s.volumeLights().empty()) return false;
    st.lightsTaken = true;
  }
  if (continueProbability < 1.0f) {
    if (!(continueProbability > 0.0f) || rng.uniform() >= continueProbability) return false;
    st.beta /= continueProbability;
  }
  if (st.vertices >= s.strategy().russian_roulette_depth) {
    const float q = std::min(1.0f, maxComponent(st.beta));
    if (rng.uniform() >= q) return false;
    st.beta /= q;
  }
  // The continuation: HG sampling, or with continuation_toward_volumes a one-sample mixture of HG
  // and the emissive volumes' direction density, weighted by the mixture's pdf (docs/method.md s.3b).
  float pdf;
  Vec3 wi;
  if (towardVolumes > 0.0f && rng.uniform() < towardVolumes) {
    if (!sampleVolumeDirection(p, volumeShare, rng, wi)) return false;
    pdf = hgEval(wo, wi, g);
  } else {
    wi = hgSample(wo, g, Vec2(rng.uniform(), rng.uniform()), pdf);
  }
  st.prevVolumeLightPdf = -1.0f;
  if (towardVolumes > 0.0f) {
    st.prevVolumeLightPdf = volumeLightPdf(p, wi);
    const float mixture = (1.0f - towardVolumes) * pdf + towardVolumes * st.prevVolumeLightPdf / volumeShare;
    if (!(mixture > 0.0f)) return false;  // both densities underflowed: no finite weight to give
    st.beta *= pdf / mixture;
    pdf = mixture;
  }
  st.prevPdf = pdf;
  st.prevPos = p;
  st.ray = Ray{p, wi};
  st.fromMedium = true;
  ++st.segment;
  return true;
}

// What the tracked walk of one segment found.
struct PathTracer::SegmentWalk {
  enum class Event { None, Absorbed, Scattered } event = Event::None;
  Vec3 scatterPos{0.0f};
  float scatterG = 0.0f, scatterT = 0.0f;
  float nullProbability = 1.0f;  // prod of P_null over the walk's null collisions (for MIS)
  float scatterDensity = 0.0f;   // mu_bar(t) P_s(t) at the walk's scattering (for MIS)
  // The walk's tentative collisions cover (0, coveredT]: the segment's end when it went through,
  // else the last recorded collision, where it stopped (set when the walk keeps a record).
  float coveredT = 0.0f;
};

// One tentative collision of a guided segment's tracked walk: the guided sample reads its null
// collisions on [0, t) off these instead of walking them again (docs/method.md s.4).
struct PathTracer::WalkCollision {
  float t, sigmaS, sigmaN, muBar;
};

namespace {

// A collision's coefficients summed over the media overlapping it (albedo averages).
struct CollisionCoefficients {
  float sigmaA = 0.0f, sigmaS = 0.0f, sigmaN = 0.0f;
  explicit CollisionCoefficients(const Collision& c) {
    for (int i = 0; i < c.count; ++i) {
      const float a = c.medium(i).albedoAverage();
      sigmaS += c.sigmaT[i] * a;
      sigmaA += c.sigmaT[i] * (1.0f - a);
    }
    sigmaN = std::max(0.0f, c.muBar - c.sigmaTTotal);
  }
};

// What an event-probability rule made of a collision: keep walking, stop (absorbed), or scatter
// with `pick` in [0, mu_s) choosing the medium.
enum class Decision { Continue, Absorb, Scatter };

// Conventional analog events (docs/method.md s.2, the talk's Fig. 1 left): absorb / scatter / null
// with P = mu_a/mu_bar, mu_s/mu_bar, mu_n/mu_bar; emission is added only at absorption, E[beta Le]
// with the per-channel mu_a handled by the weight mu_a,rgb / mu_a,avg. A null collision's weight
// mu_n / (P_n mu_bar) is exactly 1. Per-unit-length emission (no mu_a to absorb it) is gathered at
// every collision, E / mu_bar.
Decision analogEvent(const Collision& c, const CollisionCoefficients& k, float u, bool emissive, bool perLength, float emissionWeight,
                     Rgb& beta, Rgb& L, float& nullProbability, float& scatterDensity, float& pick) {
  const float x = u * c.muBar;
  // Emission per unit length may sit where nothing absorbs: gathered at every collision instead.
  if (perLength) L += beta * c.emissionSourceOf(true) * (emissionWeight / c.muBar);
  if (x < k.sigmaA) {
    if (emissive) L += beta * c.emissionSourceOf(false) * (emissionWeight / k.sigmaA);
    return Decision::Absorb;
  }
  pick = x - k.sigmaA;
  if (!(pick < k.sigmaS)) {
    nullProbability *= k.sigmaN / c.muBar;
    return Decision::Continue;
  }
  scatterDensity = k.sigmaS;
  return Decision::Scatter;
}

// The gather walk's roulette (docs/method.md s.2): the weight lost to absorption since the last
// roulette, and once it falls below 0.1 a survival probability of 10x that weight. It depends on
// the collisions' coefficients alone, never on a random number, so a guided sample replays it
// exactly over its own null collisions to evaluate the tracked technique's pdf (s.4).
struct GatherRoulette {
  float walkWeight = 1.0f;
  // Folds in one null collision's kept share (mu_s + mu_n) / mu_bar; returns the survival
  // probability asked for there (1: no roulette).
  float survival(float keep) {
    walkWeight *= keep;
    if (!(walkWeight < 0.1f)) return 1.0f;
    const float survive = walkWeight * 10.0f;
    walkWeight = 1.0f;
    return survive;
  }
};

// Emission gathered at every collision (talk 2.1, docs/method.md s.2): P_a = 1, add mu_a Le / mu_bar;
// absorption becomes the weight 1 - mu_a / mu_bar, and the walk scatters with
// P_s = mu_s / (mu_s + mu_n), else continues, rouletted as GatherRoulette says (unbiased, keeps
// walks through a dense flame short). On guided segments the survival probabilities enter the
// tracked technique's pdf through nullProbability, as every other continuation probability does.
Decision gatherEvent(const Collision& c, const CollisionCoefficients& k, float u, bool emissive, float emissionWeight, bool guided,
                     Rgb& beta, Rgb& L, GatherRoulette& roulette, float& nullProbability, float& scatterDensity, float& pick, Rng& rng) {
  if (emissive) L += beta * c.emissionSource() * (emissionWeight / c.muBar);
  const float keep = (k.sigmaS + k.sigmaN) / c.muBar;
  if (!(keep > 0.0f)) return Decision::Absorb;
  beta *= keep;
  pick = u * (k.sigmaS + k.sigmaN);
  if (pick < k.sigmaS) {
    scatterDensity = c.muBar * k.sigmaS / (k.sigmaS + k.sigmaN);
    return Decision::Scatter;
  }
  const float survive = roulette.survival(keep);
  if (guided) nullProbability *= k.sigmaN / (k.sigmaS + k.sigmaN) * survive;
  if (survive < 1.0f) {
    if (rng.uniform() >= survive) return Decision::Absorb;
    beta /= survive;
  }
  return Decision::Continue;
}

// The scattering medium, chosen by its share of mu_s (pick in [0, mu_s)).
int scatteringMedium(const Collision& c, float pick) {
  for (int i = 0; i < c.count; ++i) {
    const float si = c.sigmaT[i] * c.medium(i).albedoAverage();
    if (pick < si) return i;
    pick -= si;
  }
  return c.count - 1;
}

}  // namespace

PathTracer::SegmentWalk PathTracer::walkSegment(PathState& st, float tEnd, bool guided, std::vector<WalkCollision>* record, float emissionWeight,
                                                Rgb& L, Rng& rng) const {
  const EmissionSettings& e = scene_.strategy().emission;
  const bool gather = e.gather_every_collision;
  const bool emissive = scene_.hasEmissiveMedia();
  const bool perLength = scene_.hasPerLengthEmission();
  // Emission past the scattering (docs/method.md s.2): the segment's emission by ratio tracking over
  // the same collisions, L += beta_0 w S / mu_bar with w the running product of mu_n / mu_bar, an
  // estimate of int T S dt by itself (talk Algorithm 1). Where the tracked walk scatters or is
  // absorbed, this estimate walks on to the last point where a medium may emit, so the emission
  // behind the scattering point is no longer lost to this sample and made up by others.
  const bool pastScattering = gather && emissive &&
                              (e.gather_past_scattering == PastScattering::AllRays ||
                               (e.gather_past_scattering == PastScattering::CameraRays && st.segment == 0));
  const Rgb emissionBeta = st.beta * emissionWeight;  // the segment's throughput before the walk
  float emissionRatio = 1.0f;
  bool trackedDone = false;  // the tracked walk ended; only the emission estimate walks on
  float emissionEnd = 0.0f;  // where it may stop: past it no medium emits
  if (record) record->clear();
  SegmentWalk walk;
  GatherRoulette roulette;
  const bool through = trackCollisions(scene_.media(), st.ray, tEnd, rng, [&](const Collision& c) {
    if (pastScattering && emissionRatio > 0.0f) {
      if (trackedDone && c.t > emissionEnd) return false;
      L += emissionBeta * c.emissionSource() * (emissionRatio / c.muBar);
      emissionRatio *= std::max(0.0f, 1.0f - c.sigmaTTotal / c.muBar);
      rouletteSmallWeight(emissionRatio, rng);
    }
    if (trackedDone) return emissionRatio > 0.0f;
    const CollisionCoefficients k(c);
    if (record) record->push_back({c.t, k.sigmaS, k.sigmaN, c.muBar});
    const float u = rng.uniform();
    float pick = 0.0f;
    const Decision d = gather ? gatherEvent(c, k, u, emissive && !pastScattering, emissionWeight, guided, st.beta, L, roulette,
                                            walk.nullProbability, walk.scatterDensity, pick, rng)
                              : analogEvent(c, k, u, emissive, perLength, emissionWeight, st.beta, L, walk.nullProbability, walk.scatterDensity,
                                            pick);
    if (d == Decision::Continue) return true;
    if (d == Decision::Absorb) {
      walk.event = SegmentWalk::Event::Absorbed;
    } else {
      // Scattering: weight the chosen medium's RGB albedo against the average used to pick it.
      const Medium& m = c.medium(scatteringMedium(c, pick));
      st.beta *= m.albedo() / m.albedoAverage();
      walk.scatterG = m.g();
      walk.scatterPos = c.p;
      walk.scatterT = c.t;
      walk.event = SegmentWalk::Event::Scattered;
    }
    if (!pastScattering || !(emissionRatio > 0.0f)) return false;
    // The emission estimate walks on only as far as a medium may emit.
    emissionEnd = c.t + lastEmissionAlongRay(scene_.media(), Ray{c.p, st.ray.direction}, tEnd - c.t);
    trackedDone = true;
    return emissionEnd > c.t;
  });
  if (record) walk.coveredT = through && !trackedDone ? tEnd : record->back().t;
  return walk;
}

bool PathTracer::prepareGuide(const PathState& st, float tEnd, const CameraRayGuide* cameraGuide, GuidedDistance& guide) const {
  const GuidingSettings& g = scene_.strategy().guiding;
  if (g.guide == DistanceGuide::None || st.segment >= g.guided_segments || st.lightsTaken || st.vertices >= scene_.render().max_depth)
    return false;
  // Later rays by their origin alone (a choice by path prefix, never by this segment's walk): from
  // surfaces they are left to tracking under from_media, and every one of them in a flame-lit scene
  // under from_media_unless_flame_lit (a choice by scene).
  if (st.segment > 0 && ((g.secondary_rays != SecondaryRays::All && !st.fromMedium) || !guidedContinuationsApply(scene_, g))) return false;
  const bool cached = st.segment == 0 && cameraGuide;
  if (cached) {
    if (!cameraGuide->hasTable()) return false;
    // The pixel's table lies in memory no other camera ray touches this pass: fetching all of it
    // while the walk runs takes the cache misses off the scattering's pdf (docs/performance.md,
    // "Camera-ray tables in the cache"), which a pixel whose q is measured evaluates even at q = 0.
    cameraGuide->prefetchTable();
    // A pixel whose q is 0 (its block measured tracking alone ahead) gets no guided sample: a
    // choice by pixel alone, so the tracked technique alone is unbiased there.
    if (!(cameraGuide->guidedProbability > 0.0f)) return false;
  }
  ++threadWork().guides;  // an interval, a majorant walk for the thickness test, a table (a pixel's cached one: a lookup)
  guide.guidedProbability = cached ? cameraGuide->guidedProbability : st.segment > 0 ? g.secondary_probability : g.guided_probability;
  if (cached) {
    // The pixel's cached table (camera_guides.h), over its centre ray's medium interval: a choice by
    // pixel, as the thickness test made once for that ray is.
    guide.share(cameraGuide->view());
    return true;
  }
  float tIn = 0.0f, tOut = 0.0f;
  return guideFor(st.ray, tEnd, tIn, tOut, guide, st.segment > 0);
}

Rgb PathTracer::guidedSample(const PathState& st, float tEnd, const GuidedDistance& guide, const std::vector<WalkCollision>* walked,
                             float walkedT, Rng& rng, float* densities) const {
  ++threadWork().guided;
  const Scene& s = scene_;
  const bool gather = s.strategy().emission.gather_every_collision;
  float pdf = 0.0f;
  const float t = guide.sample(rng.uniform(), pdf);
  // A pixel's shared table spans its centre ray's interval: a jittered ray may end sooner, at a
  // surface, and no light scatters there on this segment.
  if (!(pdf > 0.0f) || !(t < tEnd)) return Rgb(0.0f);
  // Null collisions on [0, t) by ratio tracking, with exact products (no roulette): `ratio` is the
  // estimator's transmittance, `nullProbability` what the tracked technique would have paid.
  float ratio = 1.0f, nullProbability = 1.0f;
  GatherRoulette roulette;  // replayed, not drawn: the tracked walk's survival probabilities
  auto nullCollision = [&](float sigmaS, float sigmaN, float muBar) {
    ratio *= sigmaN / muBar;
    if (gather) {
      const float kept = sigmaS + sigmaN;
      nullProbability *= kept > 0.0f ? sigmaN / kept * roulette.survival(kept / muBar) : 0.0f;
    } else {
      nullProbability *= sigmaN / muBar;
    }
    return ratio > 0.0f;
  };
  // The segment's tracked walk already drew tentative collisions at rate mu_bar over (0, walkedT]:
  // those before t are this sample's, and past walkedT (where the walk stopped) fresh ones continue
  // the same Poisson process, which is memoryless. The collisions on [0, t) are thus distributed as
  // a walk of their own would draw them, independently of t, so the guided estimate keeps its
  // expectation; it only becomes correlated with the tracked one. On fire this removed most of a
  // guided vertex's cost, the re-walk of the camera ray (docs/performance.md, "The guided vertex
  // reuses the tracked walk's collisions").
  if (walked) {
    for (const WalkCollision& c : *walked) {
      if (!(c.t < t)) break;
      if (!nullCollision(c.sigmaS, c.sigmaN, c.muBar)) return Rgb(0.0f);
    }
  } else {
    walkedT = 0.0f;  // no walk to share: a walk of its own from the segment's start
  }
  if (t > walkedT) {
    const Ray rest{st.ray.at(walkedT), st.ray.direction};
    trackCollisions(s.media(), rest, t - walkedT, rng, [&](const Collision& c) {
      const CollisionCoefficients k(c);
      return nullCollision(k.sigmaS, k.sigmaN, c.muBar);
    });
  }
  if (!(ratio > 0.0f)) return Rgb(0.0f);
  // The scattering vertex at t.
  const Vec3 p = st.ray.at(t);
  const Scene::PointCoefficients c = s.coefficientsAt(p);
  const float sigmaS = c.sigmaS, sigmaT = c.sigmaT, muBar = c.muBar;
  if (!(sigmaS > 0.0f)) return Rgb(0.0f);
  const float sigmaN = std::max(0.0f, muBar - sigmaT);
  const float scatterDensity = gather ? muBar * sigmaS / (sigmaS + sigmaN) : sigmaS;
  // The vertex's NEE always uses its MIS-weighted throughput k = w_g T_hat mu_s / p_g (that is where
  // guiding pays off in thin media). In guided_vertex = path only the continuation is rouletted, with
  // probability min(1, k); in direct mode there is none (the tracked vertex carries the path).
  if (densities) densities[0] = pdf, densities[1] = nullProbability * scatterDensity;
  const float weight = guidedWeight(nullProbability * scatterDensity / pdf, guide.guidedProbability);
  const float k = weight * ratio * sigmaS / pdf;
  if (!(k > 0.0f)) return Rgb(0.0f);
  const Medium& m = c.pick(s, rng.uniform());
  PathState g = st;
  g.beta = st.beta * k * (m.albedo() / m.albedoAverage());
  Rgb L(0.0f);
  const bool continuePath = s.strategy().guiding.guided_vertex == GuidedVertex::Path;
  if (scatterVertex(g, p, m.g(), L, rng, continuePath ? std::min(1.0f, k) : 0.0f) && continuePath) L += trace(g, nullptr, rng);
  return L;
}

// A segment's guided density and its tracked walk's collisions, reused by the next path this
// thread traces at the same recursion level (a continuing guided vertex traces its own path one
// level down). Their vectors keep their capacity, so a path whose secondary segments build
// densities from probe knots (guided_segments > 1) allocates nothing once warm: fresh densities per
// path spent about a tenth of such a render in malloc and free. Every use rebuilds them
// (prepareGuide, walkSegment) before reading them, so nothing carries from one path to the next but
// capacity.
class PathTracer::SegmentScratch {
 public:
  SegmentScratch() {
    Pool& pool = threadPool();
    if (pool.depth == pool.buffers.size()) pool.buffers.push_back(std::make_unique<Buffers>());
    buffers_ = pool.buffers[pool.depth++].get();
  }
  ~SegmentScratch() { --threadPool().depth; }
  SegmentScratch(const SegmentScratch&) = delete;
  SegmentScratch& operator=(const SegmentScratch&) = delete;
  GuidedDistance& guide() { return buffers_->guide; }
  std::vector<WalkCollision>& walked() { return buffers_->walked; }

 private:
  struct Buffers {
    GuidedDistance guide;
    std::vector<WalkCollision> walked;
  };
  struct Pool {
    std::vector<std::unique_ptr<Buffers>> buffers;
    size_t depth = 0;
  };
  static Pool& threadPool() {
    thread_local Pool pool;
    return pool;
  }
  Buffers* buffers_ = nullptr;
};

Rgb PathTracer::trace(PathState st, const CameraRayGuide* cameraGuide, Rng& rng, CameraVertexRecord* record) const {
  const Scene& s = scene_;
  const StrategySettings& strategy = s.strategy();
  const auto& lights = s.lights();
  const int maxDepth = s.render().max_depth;
  const bool volumeNee = !s.volumeLights().empty();
  const bool needTail = s.hasEmissiveMedia() && !volumeNee;
  SegmentScratch scratch;  // this path's segment buffers (a continuing guided vertex traces its own)
  GuidedDistance& guide = scratch.guide();
  Rgb L(0.0f);

  for (;;) {
    const Ray ray = st.ray;
    SurfaceHit hit = s.surfaces().intersect(ray, kInfinity);
    float tEnd = hit.t;
    int lightHit = -1;
    for (size_t i = 0; i < lights.size(); ++i) {
      if (lights[i].type() != LightType::Sphere) continue;
      const float t = lights[i].intersect(ray, tEnd);
      if (t < tEnd) tEnd = t, lightHit = static_cast<int>(i);
    }

    // Emission met along a phase/BSDF-sampled ray competes with NEE toward emissive volumes.
    const float emissionWeight =
        (volumeNee && st.prevPdf > 0.0f)
            ? powerHeuristic(st.prevPdf, st.prevVolumeLightPdf >= 0.0f ? st.prevVolumeLightPdf : volumeLightPdf(st.prevPos, ray.direction))
            : 1.0f;

    // A guided distance sample for this segment (talk 2.2)? Its density must exist before the
    // tracked walk, whose scattering is weighted against it; the guided sample starts from the
    // segment's start, before the walk changes the state.
    const bool guided = prepareGuide(st, tEnd, cameraGuide, guide);
    const PathState segmentStart = guided ? st : PathState{};
    // The camera ray of a pixel whose q is measured (camera_guides.h): its vertex is recorded, and
    // where the pixel's q is 0 the walk still keeps p_t (a product it otherwise skips), so that
    // the pixel can learn what guiding would give it.
    CameraVertexRecord* const rec =
        record && st.segment == 0 && cameraGuide && cameraGuide->hasTable() && strategy.guiding.combination == GuideCombination::OneSample
            ? record
            : nullptr;
    if (rec) rec->table = true, rec->q = guided ? guide.guidedProbability : 0.0f;
    // With one-sample MIS the guided vertex reads its null collisions off the tracked walk's
    // (guidedSample). With two vertices per segment (balance, power, average) it draws its own: both
    // vertices' light samples estimate the same in-scattering, and on shared collisions they err
    // together (equiangular on point-in-mist: 20% less work, 40-75% more variance per sample).
    // One-sample MIS picks its vertex before the walk, so only a segment whose guided vertex is
    // drawn keeps the walk's collisions.
    const bool oneSample = strategy.guiding.combination == GuideCombination::OneSample;
    const bool guidedPicked = guided && (!oneSample || rng.uniform() < guide.guidedProbability);
    const bool shareWalk = guidedPicked && oneSample;
    const SegmentWalk walk = walkSegment(st, tEnd, guided || rec, shareWalk ? &scratch.walked() : nullptr, emissionWeight, L, rng);
    // The tracked vertex's p_g and p_t, evaluated once: its MIS weight on a guided segment needs
    // them unless one-sample MIS picked the guided vertex (the tracked one then counts for
    // nothing), and a measured pixel records them (where its q is 0 the segment has no guide, and
    // the pixel's table is the same density).
    const bool scattered = walk.event == SegmentWalk::Event::Scattered;
    const bool trackedCounts = scattered && !(oneSample && guidedPicked);
    const float scatterGuidedPdf =
        trackedCounts && guided ? guide.pdf(walk.scatterT) : trackedCounts && rec ? cameraGuide->view().pdf(walk.scatterT) : 0.0f;
    const float scatterTrackedPdf = walk.nullProbability * walk.scatterDensity;
    if (rec && trackedCounts) rec->guidedPdf = scatterGuidedPdf, rec->trackedPdf = scatterTrackedPdf;

    // The tracked scattering's MIS weight on a guided segment (docs/method.md s.4): on its NEE only in
    // guided_vertex = direct (the continuation is the tracked technique's alone, unweighted), or
    // as its continuation's survival probability in path mode, where the guided vertex does
    // likewise so that a guided segment continues about one path on average instead of two.
    // With one-sample MIS only one of the two vertices counts: the guided one with probability q.
    float trackedDirect = 1.0f, trackedContinue = 1.0f;
    if (guided) {
      const float q = guide.guidedProbability;
      if (scattered) {
        const float pg = scatterGuidedPdf, pt = scatterTrackedPdf;
        // One-sample MIS: p_t / (q p_g + (1 - q) p_t) when the tracked vertex was picked, else nothing.
        const float trackedWeight = oneSample   ? (guidedPicked ? 0.0f : pt / (q * pg + (1.0f - q) * pt))
                                    : pg > 0.0f ? 1.0f - guidedWeight(pt / pg, q)
                                                : 1.0f;
        if (strategy.guiding.guided_vertex == GuidedVertex::Path) {
          st.beta *= trackedWeight;
          trackedContinue = trackedWeight;
        } else {
          trackedDirect = trackedWeight;
        }
      }
      if (guidedPicked) {
        const double workBefore = rec ? threadWork().cost() : 0.0;
        float densities[2] = {0.0f, 0.0f};
        const Rgb direct = guidedSample(segmentStart, tEnd, guide, shareWalk ? &scratch.walked() : nullptr, walk.coveredT, rng,
                                        rec ? densities : nullptr);
        L += direct;
        if (rec) {
          rec->guidedDrawn = true;
          rec->guidedWork = threadWork().cost() - workBefore;
          rec->guidedPdf = densities[0], rec->trackedPdf = densities[1], rec->direct = direct;
        }
      }
    }
    if (walk.event == SegmentWalk::Event::Absorbed) break;

    if (scattered) {
      if (isBlack(st.beta)) break;
      const Rgb before = L;
      const bool continues = scatterVertex(st, walk.scatterPos, walk.scatterG, L, rng, trackedContinue, trackedDirect);
      if (rec && !guidedPicked) rec->direct = L - before;
      if (!continues) break;
      continue;
    }

    // The walk reached a light, a surface or infinity.
    if (lightHit >= 0) {
      if (!st.lightsTaken) {
        const Light& light = lights[static_cast<size_t>(lightHit)];
        const float w = st.prevPdf > 0.0f
                            ? powerHeuristic(st.prevPdf, s.lightSampler().pmf(st.prevPos, lightHit) * light.pdf(st.prevPos, ray.direction))
                            : 1.0f;
        L += st.beta * light.emitted() * w;
      }
      break;
    }
    if (!hit.hit()) {
      if (!st.lightsTaken)
        for (size_t i = 0; i < lights.size(); ++i) {
          if (lights[i].type() != LightType::Environment) continue;
          const float w = st.prevPdf > 0.0f ? powerHeuristic(st.prevPdf, s.lightSampler().pmf(st.prevPos, static_cast<int>(i)) * kInv4Pi) : 1.0f;
          L += st.beta * lights[i].emitted() * w;
        }
      break;
    }
    // Diffuse surface.
    if (st.vertices >= maxDepth) break;
    ++st.vertices;
    const bool last = st.vertices == maxDepth;
    const Vec3 n = glm::dot(hit.normal, ray.direction) < 0.0f ? hit.normal : -hit.normal;
    const Vec3 hitPos = ray.at(hit.t);
    const Vec3 p = hitPos + n * surfaceOffset(hitPos);
    L += st.beta * directLight(p, -ray.direction, 0.0f, n, hit.albedo, !last, rng);
    if (last) {
      if (!needTail) break;
      st.lightsTaken = true;
    }
    if (st.vertices >= strategy.russian_roulette_depth) {
      const float q = std::min(1.0f, maxComponent(st.beta * hit.albedo));
      if (rng.uniform() >= q) break;
      st.beta /= q;
    }
    const Vec3 local = sampleCosineHemisphere(Vec2(rng.uniform(), rng.uniform()));
    const Vec3 wi = toWorld(local, n);
    st.beta *= hit.albedo;
    st.prevPdf = local.z * kInvPi;
    st.prevVolumeLightPdf = -1.0f;
    st.prevPos = p;
    st.ray = Ray{p, wi};
    st.fromMedium = false;
    ++st.segment;
  }
  return L;
}

}  // namespace candela
