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

Rgb PathTracer::radiance(const Ray& cameraRay, Rng& rng) const {
  const Scene& s = scene_;
  const int maxDepth = s.render().max_depth;
  const int rrDepth = s.strategy().russian_roulette_depth;
  const auto& lights = s.lights();
  Ray ray = cameraRay;
  Rgb L(0.0f), beta(1.0f);
  int vertices = 0;           // scattering and bounce events so far
  bool lightsTaken = false;   // the last vertex already took all direct light by NEE
  float prevPdf = 0.0f;       // solid-angle pdf of the direction that made `ray` (0: camera ray)
  Vec3 prevPos = ray.origin;
  const bool gather = s.strategy().emission.gather_every_collision;
  const bool emissive = s.hasEmissiveMedia();
  const bool volumeNee = !s.volumeLights().empty();
  // After the last vertex's NEE, a continuation is needed only to gather volume emission that no
  // light sampler covers.
  const bool needTail = emissive && !volumeNee;

  for (;;) {
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
        (volumeNee && prevPdf > 0.0f) ? powerHeuristic(prevPdf, volumeLightPdf(prevPos, ray.direction)) : 1.0f;

    enum class Event { None, Absorbed, Scattered } event = Event::None;
    Vec3 scatterPos(0.0f);
    float scatterG = 0.0f;
    float walkWeight = 1.0f;  // product of absorption weights since the last roulette (gather mode)
    trackCollisions(s.media(), ray, tEnd, rng, [&](const Collision& c) {
      float sigmaA = 0.0f, sigmaS = 0.0f;
      for (int i = 0; i < c.count; ++i) {
        const float a = c.medium(i).albedoAverage();
        sigmaS += c.sigmaT[i] * a;
        sigmaA += c.sigmaT[i] * (1.0f - a);
      }
      const float u = rng.uniform();
      float pick;  // in [0, sigmaS) when the collision scatters
      if (gather) {
        // Talk 2.1 / METHOD.md s.2: P_a = 1, add mu_a Le / mu_bar; continue with absorption as a
        // weight, choosing scatter with P_s = mu_s / (mu_s + mu_n), both weighted 1 - mu_a / mu_bar.
        if (emissive) L += beta * c.emissionSource() * (emissionWeight / c.muBar);
        const float sigmaN = std::max(0.0f, c.muBar - c.sigmaTTotal);
        const float keep = (sigmaS + sigmaN) / c.muBar;
        if (!(keep > 0.0f)) {
          event = Event::Absorbed;
          return false;
        }
        beta *= keep;
        walkWeight *= keep;
        pick = u * (sigmaS + sigmaN);
        if (!(pick < sigmaS)) {
          if (walkWeight < 0.1f) {
            // Roulette on the weight lost to absorption along this walk: unbiased, keeps it short.
            const float survive = walkWeight * 10.0f;
            if (rng.uniform() >= survive) {
              event = Event::Absorbed;
              return false;
            }
            beta /= survive;
            walkWeight = 1.0f;
          }
          return true;  // null collision
        }
      } else {
        // Conventional analog events.
        const float x = u * c.muBar;
        if (x < sigmaA) {
          // Absorption: E[beta * Le] with per-channel mu_a handled by the weight mu_a,rgb / mu_a,avg.
          if (emissive) L += beta * c.emissionSource() * (emissionWeight / sigmaA);
          event = Event::Absorbed;
          return false;
        }
        pick = x - sigmaA;
        if (!(pick < sigmaS)) return true;  // null collision: the weight mu_n / (P_n mu_bar) is exactly 1
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
      beta *= m.albedo() / m.albedoAverage();
      scatterG = m.g();
      scatterPos = c.p;
      event = Event::Scattered;
      return false;
    });
    if (event == Event::Absorbed) break;

    if (event == Event::Scattered) {
      if (vertices >= maxDepth) break;
      ++vertices;
      const bool last = vertices == maxDepth;
      const Vec3 wo = -ray.direction;
      L += beta * directLight(scatterPos, wo, scatterG, Vec3(0.0f), Rgb(0.0f), !last, rng);
      if (last) {
        if (!needTail) break;
        lightsTaken = true;
      }
      if (vertices >= rrDepth) {
        const float q = std::min(1.0f, maxComponent(beta));
        if (rng.uniform() >= q) break;
        beta /= q;
      }
      float pdf;
      const Vec3 wi = hgSample(wo, scatterG, Vec2(rng.uniform(), rng.uniform()), pdf);
      prevPdf = pdf;
      prevPos = scatterPos;
      ray = Ray{scatterPos, wi};
      continue;
    }

    // The walk reached a light, a surface or infinity.
    if (lightHit >= 0) {
      if (!lightsTaken) {
        const Light& light = lights[static_cast<size_t>(lightHit)];
        const float w = prevPdf > 0.0f
                            ? powerHeuristic(prevPdf, s.lightSampler().pmf(lightHit) * light.pdf(prevPos, ray.direction))
                            : 1.0f;
        L += beta * light.emitted() * w;
      }
      break;
    }
    if (!hit.hit()) {
      if (!lightsTaken)
        for (size_t i = 0; i < lights.size(); ++i) {
          if (lights[i].type() != LightType::Environment) continue;
          const float w = prevPdf > 0.0f ? powerHeuristic(prevPdf, s.lightSampler().pmf(static_cast<int>(i)) * kInv4Pi) : 1.0f;
          L += beta * lights[i].emitted() * w;
        }
      break;
    }
    // Diffuse surface.
    if (vertices >= maxDepth) break;
    ++vertices;
    const bool last = vertices == maxDepth;
    const Vec3 n = glm::dot(hit.normal, ray.direction) < 0.0f ? hit.normal : -hit.normal;
    const Vec3 hitPos = ray.at(hit.t);
    const Vec3 p = hitPos + n * surfaceOffset(hitPos);
    L += beta * directLight(p, -ray.direction, 0.0f, n, hit.albedo, !last, rng);
    if (last) {
      if (!needTail) break;
      lightsTaken = true;
    }
    if (vertices >= rrDepth) {
      const float q = std::min(1.0f, maxComponent(beta * hit.albedo));
      if (rng.uniform() >= q) break;
      beta /= q;
    }
    const Vec3 local = sampleCosineHemisphere(Vec2(rng.uniform(), rng.uniform()));
    const Vec3 wi = toWorld(local, n);
    beta *= hit.albedo;
    prevPdf = local.z * kInvPi;
    prevPos = p;
    ray = Ray{p, wi};
  }
  return L;
}

}  // namespace candela
