// The guide inspector: along one ray (a pixel's camera ray, or a secondary ray of a chosen path),
// the distance densities a strategy samples against the ideal one, and how much variance each
// leaves (docs/method.md, "Scattering distance sampling"). For engineers asking why a guided
// density loses, and for the viewer's Ctrl+click chart.
//
// Tabulated on `bins` points over the ray's medium interval [tIn, tOut]:
// - ideal:   f(t) = mu_s(t) L_s(t) T(t), the single-scattering source the distance sample should
//            follow. L_s is the phase-weighted direct light toward the ray's origin, by brute force
//            (light_samples light samples per point, the renderer's own light sampler); T is the
//            true transmittance by fine quadrature of mu_t.
// - guided:  p_g(t), the strategy's guided density (probe knots or equi-angular), normalised.
// - tracked: the density of the tracked walk's scattering distance: mu_s T for analog events;
//            with emission gathering (P_s = mu_s / (mu_s + mu_n)) s' exp(-int s'), s' = mu_bar P_s.
//            It integrates to the probability of scattering before tOut (less than 1).
// - mis:     the mixture the strategy's MIS draws from: q p_g + (1 - q) p_t under one-sample MIS
//            (guiding.combination = one_sample), q the ray's guided probability
//            (guiding.guided_probability on camera rays, raised in bright pixels by
//            guiding.bright_pixel_probability (camera_guides.h), guiding.secondary_probability
//            on later ones); p_g alone for guided_only;
//            (p_g + p_t) / 2 when each technique draws one sample (balance, power, average).
// Variance factor of a density p: V = int f^2 / p dt / (int f dt)^2. 1 is perfect importance
// sampling; V - 1 is the relative variance of the one-sample estimator f / p (for the tracked
// density, whose mass is below 1, V counts its pass-through samples as zeros).
#pragma once

#include "distance_sampler.h"
#include "scene.h"

#include <string>
#include <vector>

namespace candela {

struct GuideInspectOptions {
  int bins = 256;              // points along the ray
  int light_samples = 256;     // light samples per point for the ideal curve
  int secondary_seed = -1;     // >= 0: inspect the secondary ray of a path chosen by this seed
  // The one-sample q of the mixture; < 0: the strategy's for the ray's segment (inspectGuide puts
  // the pixel's there for its camera ray).
  float guided_probability = -1.0f;
  // The pixel is left to tracking by guiding.dim_pixel_floor (inspectGuide finds out for its camera ray).
  bool dim_pixel = false;
  uint64_t seed = 1;
};

struct GuideInspection {
  Ray ray;
  int segment = 0;                // 0: the camera ray; 1: the secondary ray
  float tIn = 0.0f, tOut = 0.0f;  // the ray's medium interval (empty: the ray misses every medium)
  bool guided = false;            // the strategy would draw a guided sample on this ray
  double mixtureProbability = 0.5;  // the guided technique's share in misPdf (q under one-sample MIS; 0 unguided)
  std::string note;               // why not, when it would not
  double opticalDepth = 0.0;      // int mu_t over [tIn, tOut]
  std::vector<double> t, f, ideal, guidedPdf, trackedPdf, misPdf, transmittance, sigmaS, inScattered;
  std::vector<DistanceKnot> knots;  // the probe knots, value scaled to the guided pdf's units
  double integral = 0.0;            // int f dt
  double varianceGuided = 0.0, varianceTracked = 0.0, varianceMis = 0.0;
};

// Inspects the ray through the centre of pixel (x, y) of the scene's camera (or, with
// secondary_seed, the ray leaving a scattering vertex of that camera ray drawn by the tracked
// density and the phase function with that seed).
GuideInspection inspectGuide(const Scene& scene, int x, int y, const GuideInspectOptions& options);
// The same for any ray (`segment` says which path segment it stands for: 0 camera, 1+ later).
GuideInspection inspectGuideAlongRay(const Scene& scene, const Ray& ray, int segment, const GuideInspectOptions& options);

// CSV (one row per point, the knots after) and an SVG chart of the four densities with the knots.
void writeInspectionCsv(const std::string& path, const GuideInspection& inspection);
void writeInspectionSvg(const std::string& path, const GuideInspection& inspection, const std::string& title);
// One line per technique: "guided V = ..., tracked V = ..., mis V = ...".
std::string inspectionSummary(const GuideInspection& inspection);

}  // namespace candela
