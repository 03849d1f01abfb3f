#include "integrator.h"

#include "phase.h"

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
    if (l.type() == LightType::Point || l.type() == LightType::Spot || l.type() == LightType::Sphere)
      equiAngularTargets_.push_back({l.desc().position, l.power(scene.radius())});
  for (const EmissionLight* v : scene.volumeLights()) equiAngularTargets_.push_back({v->centroid(), v->power()});
}

Rgb PathTracer::inScattered(const Vec3& p, const Vec3& wo, float g, Rng& rng) const {
  return directLight(p, wo, g, Vec3(0.0f), Rgb(0.0f), false, rng);
}

struct GuideDensity {
  bool piecewiseLinear = true;
  PiecewiseLinearDistance linear;
  EquiAngularDistance equiAngular;
  std::vector<DistanceKnot> knots;
  float sample(float u, float& pdf) const { return piecewiseLinear ? linear.sample(u, pdf) : equiAngular.sample(u, pdf); }
  float pdf(float t) const { return piecewiseLinear ? linear.pdf(t) : equiAngular.pdf(t); }
};

void PathTracer::buildGuide(const Ray& ray, float tIn, float tOut, GuideDensity& out) const {
  const GuidingSettings& g = scene_.strategy().guiding;
  out.piecewiseLinear = g.guide != DistanceGuide::EquiAngular;
  if (out.piecewiseLinear) {
    out.knots.clear();
    if (probes_) probes_->gatherKnots(ray, tIn, tOut, out.knots);
    out.linear.build(tIn, tOut, out.knots, g.floor);
  } else {
    out.equiAngular.build(ray, tIn, tOut, equiAngularTargets_);
  }
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

float PathTracer::guidedWeight(float r) const {
  switch (scene_.strategy().guiding.combination) {
    case GuideCombination::Balance: return 1.0f / (1.0f + r);
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
    const float pmf = scene_.lightSampler().pmf(first + static_cast<int>(m));
    if (pmf > 0.0f) pdf += pmf * volumes[m]->pdf(x, w);
  }
  return pdf;
}

Rgb PathTracer::directLight(const Vec3& p, const Vec3& wo, float g, const Vec3& normal, const Rgb& albedo, bool useMis,
                            Rng& rng) const {
  const LightSampler& sampler = scene_.lightSampler();
  if (sampler.empty()) return Rgb(0.0f);
  float pmf = 0.0f;
  const int index = sampler.sample(rng.uniform(), pmf);
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
    const float weight = useMis ? powerHeuristic(lightPdf, scatterPdf) : 1.0f;
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
  const float weight = (ls.delta || !useMis) ? 1.0f : powerHeuristic(lightPdf, scatterPdf);
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

Rgb PathTracer::radiance(const Ray& cameraRay, Rng& rng) const {
  PathState state;
  state.ray = cameraRay;
  state.prevPos = cameraRay.origin;
  return trace(state, rng);
}

bool PathTracer::scatterVertex(PathState& st, const Vec3& p, float g, Rgb& L, Rng& rng, float continueProbability,
                               float directWeight) const {
  const Scene& s = scene_;
  if (st.vertices >= s.render().max_depth) return false;
  ++st.vertices;
  const bool last = st.vertices == s.render().max_depth;
  const Vec3 wo = -st.ray.direction;
  L += st.beta * directWeight * directLight(p, wo, g, Vec3(0.0f), Rgb(0.0f), !last, rng);
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
  float pdf;
  const Vec3 wi = hgSample(wo, g, Vec2(rng.uniform(), rng.uniform()), pdf);
  st.prevPdf = pdf;
  st.prevPos = p;
  st.ray = Ray{p, wi};
  ++st.segment;
  return true;
}

namespace {
// The guided density of the segment being traced on this thread. Built before the tracked walk;
// the tracked weight and the guided sample read it before any recursion rebuilds it.
thread_local GuideDensity tlsGuide;
}  // namespace

Rgb PathTracer::guidedSample(const PathState& st, Rng& rng) const {
  const Scene& s = scene_;
  const bool gather = s.strategy().emission.gather_every_collision;
  float pdf = 0.0f;
  const float t = tlsGuide.sample(rng.uniform(), pdf);
  if (!(pdf > 0.0f)) return Rgb(0.0f);
  // Null collisions on [0, t) by ratio tracking, with exact products (no roulette): `ratio` is the
  // estimator's transmittance, `nullProbability` what the tracked technique would have paid.
  float ratio = 1.0f, nullProbability = 1.0f;
  trackCollisions(s.media(), st.ray, t, rng, [&](const Collision& c) {
    float sigmaS = 0.0f;
    for (int i = 0; i < c.count; ++i) sigmaS += c.sigmaT[i] * c.medium(i).albedoAverage();
    const float sigmaN = std::max(0.0f, c.muBar - c.sigmaTTotal);
    ratio *= sigmaN / c.muBar;
    nullProbability *= gather ? (sigmaS + sigmaN > 0.0f ? sigmaN / (sigmaS + sigmaN) : 0.0f) : sigmaN / c.muBar;
    return ratio > 0.0f;
  });
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
  const float weight = guidedWeight(nullProbability * scatterDensity / pdf);
  const float k = weight * ratio * sigmaS / pdf;
  if (!(k > 0.0f)) return Rgb(0.0f);
  const Medium& m = c.pick(s, rng.uniform());
  PathState g = st;
  g.beta = st.beta * k * (m.albedo() / m.albedoAverage());
  Rgb L(0.0f);
  const bool continuePath = s.strategy().guiding.guided_vertex == GuidedVertex::Path;
  if (scatterVertex(g, p, m.g(), L, rng, continuePath ? std::min(1.0f, k) : 0.0f) && continuePath) L += trace(g, rng);
  return L;
}

Rgb PathTracer::trace(PathState st, Rng& rng) const {
  const Scene& s = scene_;
  const StrategySettings& strategy = s.strategy();
  const auto& lights = s.lights();
  const int maxDepth = s.render().max_depth;
  const bool gather = strategy.emission.gather_every_collision;
  const bool emissive = s.hasEmissiveMedia();
  const bool volumeNee = !s.volumeLights().empty();
  const bool guiding = strategy.guiding.guide != DistanceGuide::None;
  const bool needTail = emissive && !volumeNee;
  GuideDensity& guide = tlsGuide;
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
        (volumeNee && st.prevPdf > 0.0f) ? powerHeuristic(st.prevPdf, volumeLightPdf(st.prevPos, ray.direction)) : 1.0f;

    // A guided distance sample for this segment (talk 2.2)? Its density must exist before the
    // tracked walk, whose scattering is weighted against it.
    float tIn = 0.0f, tOut = 0.0f;
    // Thick rays are left to tracking, which scatters there reliably: the choice depends on the ray
    // alone (never on the walk), so MIS stays valid with the tracked technique alone on them.
    const float maxDepthTau = strategy.guiding.max_optical_depth;
    const bool guided = guiding && st.segment < strategy.guiding.guided_segments && !st.lightsTaken && st.vertices < maxDepth &&
                        mediumInterval(ray, tEnd, tIn, tOut) &&
                        (maxDepthTau <= 0.0f || majorantOpticalDepth(ray, tIn, tOut) <= maxDepthTau);
    if (guided) buildGuide(ray, tIn, tOut, guide);
    PathState segmentStart;  // the guided sample starts from the segment's start, before the walk
    if (guided) segmentStart = st;

    enum class Event { None, Absorbed, Scattered } event = Event::None;
    Vec3 scatterPos(0.0f);
    float scatterG = 0.0f, scatterT = 0.0f;
    float nullProbability = 1.0f;  // prod of P_null over this walk's null collisions (for MIS)
    float scatterDensity = 0.0f;   // mu_bar(t) P_s(t) at the walk's scattering
    float walkWeight = 1.0f;       // product of absorption weights since the last roulette (gather mode)
    // The tracked scattering's MIS weight on a guided segment, applied to its NEE only
    // (guided_vertex = direct) or as its continuation's survival probability (path).
    float trackedDirect = 1.0f, trackedContinue = 1.0f;
    trackCollisions(s.media(), ray, tEnd, rng, [&](const Collision& c) {
      float sigmaA = 0.0f, sigmaS = 0.0f;
      for (int i = 0; i < c.count; ++i) {
        const float a = c.medium(i).albedoAverage();
        sigmaS += c.sigmaT[i] * a;
        sigmaA += c.sigmaT[i] * (1.0f - a);
      }
      const float sigmaN = std::max(0.0f, c.muBar - c.sigmaTTotal);
      const float u = rng.uniform();
      float pick;  // in [0, sigmaS) when the collision scatters
      if (gather) {
        // Talk 2.1 / METHOD.md s.2: P_a = 1, add mu_a Le / mu_bar; continue with absorption as a
        // weight, choosing scatter with P_s = mu_s / (mu_s + mu_n), both weighted 1 - mu_a / mu_bar.
        if (emissive) L += st.beta * c.emissionSource() * (emissionWeight / c.muBar);
        const float keep = (sigmaS + sigmaN) / c.muBar;
        if (!(keep > 0.0f)) {
          event = Event::Absorbed;
          return false;
        }
        st.beta *= keep;
        pick = u * (sigmaS + sigmaN);
        if (!(pick < sigmaS)) {
          if (guided) {
            // Guided segments skip the roulette: its survival probability would enter p_tracked.
            nullProbability *= sigmaN / (sigmaS + sigmaN);
            return true;
          }
          walkWeight *= keep;
          if (walkWeight < 0.1f) {
            // Roulette on the weight lost to absorption along this walk: unbiased, keeps it short.
            const float survive = walkWeight * 10.0f;
            if (rng.uniform() >= survive) {
              event = Event::Absorbed;
              return false;
            }
            st.beta /= survive;
            walkWeight = 1.0f;
          }
          return true;  // null collision
        }
        scatterDensity = c.muBar * sigmaS / (sigmaS + sigmaN);
      } else {
        // Conventional analog events.
        const float x = u * c.muBar;
        if (x < sigmaA) {
          // Absorption: E[beta * Le] with per-channel mu_a handled by the weight mu_a,rgb / mu_a,avg.
          if (emissive) L += st.beta * c.emissionSource() * (emissionWeight / sigmaA);
          event = Event::Absorbed;
          return false;
        }
        pick = x - sigmaA;
        if (!(pick < sigmaS)) {
          nullProbability *= sigmaN / c.muBar;
          return true;  // null collision: the weight mu_n / (P_n mu_bar) is exactly 1
        }
        scatterDensity = sigmaS;
      }
      // Scattering: pick the medium by its share of mu_s, weight its RGB albedo against the average.
      int chosen = c.count - 1;
      for (int i = 0; i < c.count; ++i) {
        const float si = c.sigmaT[i] * c.medium(i).albedoAverage();
        if (pick < si) {
          chosen = i;
          break;
        }
        pick -= si;
      }
      const Medium& m = c.medium(chosen);
      st.beta *= m.albedo() / m.albedoAverage();
      scatterG = m.g();
      scatterPos = c.p;
      scatterT = c.t;
      event = Event::Scattered;
      return false;
    });

    if (guided) {
      // MIS weight of the tracked scattering, then the guided sample from the segment's start.
      if (event == Event::Scattered) {
        // The tracked vertex's NEE carries its MIS weight w_t. In guided_vertex = path its
        // continuation survives with probability w_t (then unweighted): with the guided vertex doing
        // likewise, a guided segment continues about one path on average instead of two. In direct
        // mode the continuation is the tracked technique's alone, unweighted.
        const float pg = guide.pdf(scatterT);
        const float trackedWeight = pg > 0.0f ? 1.0f - guidedWeight(nullProbability * scatterDensity / pg) : 1.0f;
        if (strategy.guiding.guided_vertex == GuidedVertex::Path) {
          st.beta *= trackedWeight;
          trackedContinue = trackedWeight;
        } else {
          trackedDirect = trackedWeight;
        }
      }
      L += guidedSample(segmentStart, rng);
    }
    if (event == Event::Absorbed) break;

    if (event == Event::Scattered) {
      if (isBlack(st.beta) || !scatterVertex(st, scatterPos, scatterG, L, rng, trackedContinue, trackedDirect)) break;
      continue;
    }

    // The walk reached a light, a surface or infinity.
    if (lightHit >= 0) {
      if (!st.lightsTaken) {
        const Light& light = lights[static_cast<size_t>(lightHit)];
        const float w = st.prevPdf > 0.0f
                            ? powerHeuristic(st.prevPdf, s.lightSampler().pmf(lightHit) * light.pdf(st.prevPos, ray.direction))
                            : 1.0f;
        L += st.beta * light.emitted() * w;
      }
      break;
    }
    if (!hit.hit()) {
      if (!st.lightsTaken)
        for (size_t i = 0; i < lights.size(); ++i) {
          if (lights[i].type() != LightType::Environment) continue;
          const float w = st.prevPdf > 0.0f ? powerHeuristic(st.prevPdf, s.lightSampler().pmf(static_cast<int>(i)) * kInv4Pi) : 1.0f;
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
    st.prevPos = p;
    st.ray = Ray{p, wi};
    ++st.segment;
  }
  return L;
}

}  // namespace candela
