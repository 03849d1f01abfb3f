#include "guide_inspector.h"

#include "atomic_file.h"

#include "camera_guides.h"
#include "integrator.h"
#include "phase.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace candela {

namespace {

// int f^2 / p dt / (int f dt)^2 over the tabulated points (infinite where p misses f's support).
double varianceFactor(const std::vector<double>& f, const std::vector<double>& p, double dt, double integral) {
  if (!(integral > 0.0)) return 0.0;
  double sum = 0.0;
  for (size_t i = 0; i < f.size(); ++i) {
    if (!(f[i] > 0.0)) continue;
    if (!(p[i] > 0.0)) return kInfinity;
    sum += f[i] * f[i] / p[i] * dt;
  }
  return sum / (integral * integral);
}

}  // namespace

GuideInspection inspectGuideAlongRay(const Scene& scene, const Ray& ray, int segment, const GuideInspectOptions& options) {
  GuideInspection r;
  r.ray = ray;
  r.segment = segment;
  const PathTracer tracer(scene);
  const float tEnd = tracer.nearestOccluder(ray);
  GuidedDistance guide;
  float tIn = 0.0f, tOut = 0.0f;
  const GuidingSettings& settings = scene.strategy().guiding;
  const bool hasDensity = tracer.guideFor(ray, tEnd, tIn, tOut, guide, segment > 0);
  const float maxDepth = segment > 0 ? settings.secondary_max_optical_depth : settings.max_optical_depth;
  const bool segmentGuided = segment < settings.guided_segments && (segment == 0 || guidedContinuationsApply(scene, settings));
  if (!hasDensity) {
    // Still show the ideal and tracked densities over the medium interval.
    if (!tracer.mediumInterval(ray, tEnd, tIn, tOut)) {
      r.note = "the ray misses every medium";
      return r;
    }
    std::vector<DistanceKnot> knots;
    if (settings.guide == DistanceGuide::Probes && scene.probes()) scene.probes()->gatherKnots(ray, tIn, tOut, knots);
    const bool lit = knotsCarryLight(knots);
    r.note = settings.guide == DistanceGuide::None ? "the strategy does not guide distances (guiding.guide = none)"
             : settings.guide == DistanceGuide::Probes && !lit && (!(maxDepth > 0.0f) || tracer.mediaOpticalDepth(ray) <= maxDepth)
                 ? "not guided: no probe along the ray carries light"
                 : segment > 0 ? "not guided: thicker than guiding.secondary_max_optical_depth" : "not guided: thicker than guiding.max_optical_depth";
  } else if (segment >= settings.guided_segments) {
    r.note = "not guided on this segment (guiding.guided_segments = " + std::to_string(settings.guided_segments) + "); the density shown is what it would be";
  } else if (!segmentGuided) {
    r.note = "not guided on this segment: volumes emit and no sun shines (guiding.secondary_rays = from_media_unless_flame_lit); the density "
             "shown is what it would be";
  }
  r.guided = hasDensity && segmentGuided;
  if (r.guided && segment == 0 && options.dim_pixel) {
    r.guided = false;
    r.note = "not guided: its probes predict less light than guiding.dim_pixel_floor x the image's mean; the density shown is what it would be";
  }
  if (settings.combination == GuideCombination::GuidedOnly) r.mixtureProbability = 1.0;
  if (settings.combination == GuideCombination::OneSample)
    r.mixtureProbability = options.guided_probability >= 0.0f ? options.guided_probability
                           : segment == 0                     ? settings.guided_probability
                                                              : settings.secondary_probability;
  if (!r.guided) r.mixtureProbability = 0.0;  // the strategy draws from the tracked density alone
  r.tIn = tIn;
  r.tOut = tOut;
  const int n = std::max(8, options.bins);
  const double dt = (static_cast<double>(tOut) - tIn) / n;
  const bool gather = scene.strategy().emission.gather_every_collision;
  r.t.resize(n);
  r.f.assign(n, 0.0), r.ideal.assign(n, 0.0), r.guidedPdf.assign(n, 0.0), r.trackedPdf.assign(n, 0.0), r.misPdf.assign(n, 0.0);
  r.transmittance.assign(n, 0.0), r.sigmaS.assign(n, 0.0), r.inScattered.assign(n, 0.0);

  // True transmittance and the gathering walk's scatter-only transmittance by midpoint quadrature
  // on 8 sub-steps per point (the grids are smooth at that scale: trilinear within a voxel).
  constexpr int kSub = 8;
  double tau = 0.0, tauScatter = 0.0;
  std::vector<double> scatterRate(n, 0.0), scatterTransmittance(n, 0.0);
  for (int i = 0; i < n; ++i) {
    const double a = tIn + i * dt;
    double tauMid = tau, tauScatterMid = tauScatter;
    for (int k = 0; k < kSub; ++k) {
      const double x = a + (k + 0.5) * dt / kSub;
      const Scene::PointCoefficients c = scene.coefficientsAt(ray.at(static_cast<float>(x)));
      const double rate = c.sigmaS + std::max(0.0f, c.muBar - c.sigmaT) > 0.0f
                              ? static_cast<double>(c.muBar) * c.sigmaS / (c.sigmaS + std::max(0.0f, c.muBar - c.sigmaT))
                              : 0.0;
      tau += c.sigmaT * dt / kSub;
      tauScatter += rate * dt / kSub;
      if (k == kSub / 2 - 1) tauMid = tau, tauScatterMid = tauScatter;
    }
    r.t[i] = a + 0.5 * dt;
    const Scene::PointCoefficients c = scene.coefficientsAt(ray.at(static_cast<float>(r.t[i])));
    r.sigmaS[i] = c.sigmaS;
    r.transmittance[i] = std::exp(-tauMid);
    const double sigmaN = std::max(0.0f, c.muBar - c.sigmaT);
    scatterRate[i] = c.sigmaS + sigmaN > 0.0 ? c.muBar * c.sigmaS / (c.sigmaS + sigmaN) : 0.0;
    scatterTransmittance[i] = std::exp(-tauScatterMid);
  }
  r.opticalDepth = tau;

  // The ideal source: phase-weighted direct light toward the ray's origin, by brute force.
  const Vec3 wo = -ray.direction;
  tbb::parallel_for(0, n, [&](int i) {
    if (!(r.sigmaS[i] > 0.0)) return;
    Rng rng(hashCombine(options.seed, 0x1a5bec7ULL), static_cast<uint64_t>(i));
    const Vec3 x = ray.at(static_cast<float>(r.t[i]));
    const Scene::PointCoefficients c = scene.coefficientsAt(x);
    double sum = 0.0;
    for (int s = 0; s < options.light_samples; ++s)
      sum += luminance(tracer.inScattered(x, wo, c.pick(scene, rng.uniform()).g(), rng));
    r.inScattered[i] = sum / std::max(1, options.light_samples);
    r.f[i] = r.sigmaS[i] * r.inScattered[i] * r.transmittance[i];
  });
  for (int i = 0; i < n; ++i) r.integral += r.f[i] * dt;
  for (int i = 0; i < n; ++i) {
    r.ideal[i] = r.integral > 0.0 ? r.f[i] / r.integral : 0.0;
    r.trackedPdf[i] = gather ? scatterRate[i] * scatterTransmittance[i] : r.sigmaS[i] * r.transmittance[i];
    r.guidedPdf[i] = hasDensity ? guide.pdf(static_cast<float>(r.t[i])) : 0.0;
    r.misPdf[i] = r.guided ? r.mixtureProbability * r.guidedPdf[i] + (1.0 - r.mixtureProbability) * r.trackedPdf[i] : r.trackedPdf[i];
  }
  if (hasDensity)
    for (const DistanceKnot& k : guide.knots) r.knots.push_back({k.t, guide.pdf(k.t)});
  r.varianceGuided = hasDensity ? varianceFactor(r.f, r.guidedPdf, dt, r.integral) : 0.0;
  r.varianceTracked = varianceFactor(r.f, r.trackedPdf, dt, r.integral);
  r.varianceMis = varianceFactor(r.f, r.misPdf, dt, r.integral);
  return r;
}

GuideInspection inspectGuide(const Scene& scene, int x, int y, const GuideInspectOptions& options) {
  const Ray camera = scene.camera().generate(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f);
  if (options.secondary_seed < 0) {
    GuideInspectOptions pixel = options;
    const bool chosen = pixel.guided_probability >= 0.0f;
    if (!chosen) pixel.guided_probability = scene.strategy().guiding.guided_probability;
    const GuidingSettings& g = scene.strategy().guiding;
    if (g.guide == DistanceGuide::Probes && (g.dim_pixel_floor > 0.0f || g.bright_pixel_probability > g.guided_probability) &&
        scene.probes()) {
      // The floor and a bright pixel's q are relative to the whole image's prediction: the render's
      // own pixel tables say.
      CameraGuides tables;
      const PathTracer tracer(scene);
      tables.prepare(scene, tracer, scene.camera());
      const CameraRayGuide* guide = tables.at(x, y);
      pixel.dim_pixel = !guide->hasTable() && tables.predictedLight(x, y) > 0.0f;
      if (!chosen && guide->hasTable()) pixel.guided_probability = guide->guidedProbability;
    }
    GuideInspection r = inspectGuideAlongRay(scene, camera, 0, pixel);
    if (!chosen && r.guided && measuresPixelProbability(g))
      r.note = "q shown is the probes' prediction; a render then sets the pixel's q from its own samples "
               "(guiding.measured_pixel_probability)";
    return r;
  }
  // A path chosen by the seed: a scattering distance on the camera ray from the tracked density
  // (conditioned on scattering), then a direction from the phase function there.
  GuideInspectOptions coarse = options;
  coarse.light_samples = 1;
  const GuideInspection first = inspectGuideAlongRay(scene, camera, 0, coarse);
  GuideInspection none;
  none.ray = camera;
  none.segment = 1;
  double total = 0.0;
  for (double p : first.trackedPdf) total += p;
  if (!(total > 0.0)) {
    none.note = "the camera ray never scatters: no secondary ray";
    return none;
  }
  Rng rng(static_cast<uint64_t>(options.secondary_seed), 0x5ec0dULL);
  double target = rng.uniform() * total;
  size_t i = 0;
  while (i + 1 < first.trackedPdf.size() && target >= first.trackedPdf[i]) target -= first.trackedPdf[i++];
  const Vec3 p = camera.at(static_cast<float>(first.t[i]));
  const Scene::PointCoefficients c = scene.coefficientsAt(p);
  float pdf;
  const Vec3 wi = hgSample(-camera.direction, c.pick(scene, rng.uniform()).g(), Vec2(rng.uniform(), rng.uniform()), pdf);
  return inspectGuideAlongRay(scene, Ray{p, wi}, 1, options);
}

std::string inspectionSummary(const GuideInspection& r) {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "segment %d, medium [%.4g, %.4g], optical depth %.3g, int f = %.4g; variance factor int f^2/p / (int f)^2: guided %.4g, "
                "tracked %.4g, mis (guided share %.3g) %.4g%s%s",
                r.segment, r.tIn, r.tOut, r.opticalDepth, r.integral, r.varianceGuided, r.varianceTracked, r.mixtureProbability, r.varianceMis,
                r.note.empty() ? "" : "; ", r.note.c_str());
  return buf;
}

void writeInspectionCsv(const std::string& path, const GuideInspection& r) {
  std::ostringstream out;
  out << "# " << inspectionSummary(r) << "\n";
  out << "# ray origin " << r.ray.origin.x << " " << r.ray.origin.y << " " << r.ray.origin.z << ", direction " << r.ray.direction.x << " "
      << r.ray.direction.y << " " << r.ray.direction.z << "\n";
  out << "t,ideal_pdf,guided_pdf,tracked_pdf,mis_pdf,f,transmittance,sigma_s,in_scattered\n";
  for (size_t i = 0; i < r.t.size(); ++i)
    out << r.t[i] << "," << r.ideal[i] << "," << r.guidedPdf[i] << "," << r.trackedPdf[i] << "," << r.misPdf[i] << "," << r.f[i] << ","
        << r.transmittance[i] << "," << r.sigmaS[i] << "," << r.inScattered[i] << "\n";
  out << "\nknot_t,knot_guided_pdf\n";
  for (const auto& k : r.knots) out << k.t << "," << k.value << "\n";
  writeTextAtomically(path, out.str());
}

void writeInspectionSvg(const std::string& path, const GuideInspection& r, const std::string& title) {
  const int W = 900, H = 440, left = 70, right = 20, top = 40, bottom = 110;
  double yMax = 0.0;
  for (size_t i = 0; i < r.t.size(); ++i) yMax = std::max({yMax, r.ideal[i], r.guidedPdf[i], r.trackedPdf[i], r.misPdf[i]});
  if (!(yMax > 0.0)) yMax = 1.0;
  yMax *= 1.05;
  const double x0 = r.tIn, x1 = std::max(r.tOut, r.tIn + 1e-6f);
  auto X = [&](double t) { return left + (t - x0) / (x1 - x0) * (W - left - right); };
  auto Y = [&](double v) { return top + (1.0 - std::min(v, yMax) / yMax) * (H - top - bottom); };
  std::ostringstream s;
  s << "<svg xmlns='http://www.w3.org/2000/svg' width='" << W << "' height='" << H << "' font-family='sans-serif' font-size='12'>\n"
    << "<rect width='100%' height='100%' fill='white'/>\n"
    << "<text x='" << left << "' y='22' font-size='14'>" << title << "</text>\n";
  for (int k = 0; k <= 5; ++k) {
    const double v = yMax * k / 5.0, t = x0 + (x1 - x0) * k / 5.0;
    char label[32];
    s << "<line x1='" << left << "' x2='" << W - right << "' y1='" << Y(v) << "' y2='" << Y(v) << "' stroke='#ddd'/>\n";
    std::snprintf(label, sizeof label, "%.3g", v);
    s << "<text x='" << left - 6 << "' y='" << Y(v) + 4 << "' text-anchor='end'>" << label << "</text>\n";
    std::snprintf(label, sizeof label, "%.3g", t);
    s << "<text x='" << X(t) << "' y='" << H - bottom + 16 << "' text-anchor='middle'>" << label << "</text>\n";
  }
  s << "<text x='" << (W + left) / 2 << "' y='" << H - bottom + 34 << "' text-anchor='middle'>distance t along the ray</text>\n";
  s << "<text x='16' y='" << (top + H - bottom) / 2 << "' transform='rotate(-90 16 " << (top + H - bottom) / 2
    << ")' text-anchor='middle'>density (1/length)</text>\n";
  auto line = [&](const std::vector<double>& v, const char* colour, const char* dash) {
    s << "<polyline fill='none' stroke='" << colour << "' stroke-width='2'" << dash << " points='";
    for (size_t i = 0; i < r.t.size(); ++i) s << X(r.t[i]) << "," << Y(v[i]) << " ";
    s << "'/>\n";
  };
  line(r.ideal, "#111", "");
  line(r.trackedPdf, "#2a7fd4", "");
  if (r.guided || !r.knots.empty() || r.varianceGuided > 0.0) line(r.guidedPdf, "#e07b2a", "");
  line(r.misPdf, "#3aa655", " stroke-dasharray='6,4'");
  for (const auto& k : r.knots) s << "<circle cx='" << X(k.t) << "' cy='" << Y(k.value) << "' r='3' fill='#e07b2a'/>\n";
  char legend[4][160];
  std::snprintf(legend[0], sizeof legend[0], "ideal mu_s L_s T (normalised), int f = %.4g", r.integral);
  std::snprintf(legend[1], sizeof legend[1], "guided (probe knots as dots): V = %.4g", r.varianceGuided);
  std::snprintf(legend[2], sizeof legend[2], "tracked: V = %.4g (optical depth %.3g)", r.varianceTracked, r.opticalDepth);
  std::snprintf(legend[3], sizeof legend[3], "MIS mixture (guided share %.3g): V = %.4g", r.mixtureProbability, r.varianceMis);
  const char* colours[4] = {"#111", "#e07b2a", "#2a7fd4", "#3aa655"};
  for (int k = 0; k < 4; ++k) {
    const int y = H - bottom + 54 + (k % 2) * 18, x = left + (k / 2) * 400;
    s << "<rect x='" << x << "' y='" << y - 9 << "' width='14' height='4' fill='" << colours[k] << "'/>\n"
      << "<text x='" << x + 20 << "' y='" << y - 3 << "'>" << legend[k] << "</text>\n";
  }
  s << "<text x='" << left << "' y='" << H - 8 << "' fill='#555'>V = int f^2/p / (int f)^2 (1 is perfect). " << r.note << "</text>\n";
  s << "</svg>\n";
  writeTextAtomically(path, s.str());
}

}  // namespace candela
