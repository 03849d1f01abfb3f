// Scattering (distance) sampling, talk s.2.2 / METHOD.md s.4: the piecewise-linear sampler matches
// its pdf (chi-square, including zero- and one-knot cases), the equi-angular sampler matches its
// pdf, probes are placed and learned within budget, and a background relearn swaps a new set in
// while the old one keeps serving.
#include "distance_sampler.h"
#include "stats.h"
#include "test_support.h"

#include <gtest/gtest.h>

namespace candela {
namespace {

// Histogram of `sample` over [t0, t1] against the integral of `pdf` per bin (Simpson's rule on a
// fine grid); also checks that the returned pdf equals pdf(t) and integrates to 1.
template <class Dist>
void checkDistance(const Dist& dist, float t0, float t1, uint64_t seed) {
  constexpr int kBins = 64, kSamples = 200000, kSub = 64;
  std::vector<double> observed(kBins, 0.0);
  Rng rng(seed, 3);
  for (int i = 0; i < kSamples; ++i) {
    float pdf;
    const float t = dist.sample(rng.uniform(), pdf);
    ASSERT_GE(t, t0);
    ASSERT_LE(t, t1);
    ASSERT_NEAR(pdf, dist.pdf(t), 1e-4f * pdf + 1e-6f);
    observed[std::min(kBins - 1, static_cast<int>((t - t0) / (t1 - t0) * kBins))] += 1.0;
  }
  double chi2 = 0.0, total = 0.0;
  int dof = -1;
  const double h = (t1 - t0) / kBins / kSub;
  for (int b = 0; b < kBins; ++b) {
    double p = 0.0;
    for (int s = 0; s < kSub; ++s) {
      const double a = t0 + (b * kSub + s) * h;
      p += h / 6.0 * (dist.pdf(static_cast<float>(a)) + 4.0 * dist.pdf(static_cast<float>(a + 0.5 * h)) + dist.pdf(static_cast<float>(a + h)));
    }
    total += p;
    const double e = p * kSamples;
    if (e < 5.0) continue;
    chi2 += (observed[b] - e) * (observed[b] - e) / e;
    ++dof;
  }
  EXPECT_NEAR(total, 1.0, 2e-3);
  EXPECT_LT(chi2, test::chiSquareCritical(std::max(dof, 1), 1e-4)) << "dof " << dof;
}

TEST(PiecewiseLinear, MatchesItsPdfForManyKnots) {
  std::vector<DistanceKnot> knots = {{2.5f, 1.0f}, {1.2f, 0.2f}, {3.0f, 4.0f}, {3.1f, 0.0f}, {4.5f, 2.0f}, {-1.0f, 3.0f}, {9.0f, 1.0f}};
  PiecewiseLinearDistance d;
  d.build(1.0f, 6.0f, knots, 0.1f);
  checkDistance(d, 1.0f, 6.0f, 1);
}

TEST(PiecewiseLinear, ZeroKnotsIsUniform) {
  std::vector<DistanceKnot> knots;
  PiecewiseLinearDistance d;
  d.build(0.5f, 2.5f, knots, 0.1f);
  EXPECT_FLOAT_EQ(d.pdf(1.0f), 0.5f);
  checkDistance(d, 0.5f, 2.5f, 2);
}

TEST(PiecewiseLinear, OneKnotIsFlatAndAllZeroKnotsFallBackToUniform) {
  std::vector<DistanceKnot> one = {{1.7f, 3.0f}};
  PiecewiseLinearDistance d;
  d.build(0.0f, 4.0f, one, 0.2f);
  EXPECT_NEAR(d.pdf(0.3f), 0.25f, 1e-6f);
  checkDistance(d, 0.0f, 4.0f, 3);
  std::vector<DistanceKnot> zeros = {{1.0f, 0.0f}, {2.0f, 0.0f}};
  d.build(0.0f, 4.0f, zeros, 0.2f);
  EXPECT_NEAR(d.pdf(3.0f), 0.25f, 1e-6f);
  checkDistance(d, 0.0f, 4.0f, 4);
}

TEST(PiecewiseLinear, FloorKeepsTheSupportComplete) {
  std::vector<DistanceKnot> knots = {{1.0f, 0.0f}, {2.0f, 5.0f}, {3.0f, 0.0f}};
  PiecewiseLinearDistance d;
  d.build(0.0f, 10.0f, knots, 0.05f);
  EXPECT_NEAR(d.pdf(8.0f), 0.005f, 1e-6f);  // where the knots say 0, the floor remains
  checkDistance(d, 0.0f, 10.0f, 5);
}

TEST(EquiAngular, MatchesItsPdfForOneAndSeveralLights) {
  const Ray ray{Vec3(0.0f), glm::normalize(Vec3(1.0f, 0.2f, 0.0f))};
  EquiAngularDistance d;
  d.build(ray, 0.5f, 8.0f, {{Vec3(3.0f, 1.5f, 0.4f), 1.0f}});
  checkDistance(d, 0.5f, 8.0f, 6);
  d.build(ray, 0.5f, 8.0f, {{Vec3(3.0f, 1.5f, 0.4f), 1.0f}, {Vec3(6.0f, 1.21f, 0.05f), 3.0f}, {Vec3(-2.0f, 0.0f, 1.0f), 0.5f}});
  checkDistance(d, 0.5f, 8.0f, 7);
  d.build(ray, 0.5f, 8.0f, {});
  checkDistance(d, 0.5f, 8.0f, 8);
}

TEST(Probes, PlacedOverTheMediumAndLearnedWithinBudget) {
  auto scene = Scene::build(test::loadScene("assets/scenes/god-rays.json", {"strategy.preset=\"full\""}));
  auto probes = scene->probes();
  ASSERT_TRUE(probes);
  EXPECT_GT(probes->placed(), 100);
  EXPECT_TRUE(probes->complete());
  int lit = 0;
  for (const auto& p : probes->probes()) lit += p.weight > 0.0f;
  EXPECT_GT(lit, probes->placed() / 4) << "most probes under the slats should see the sun";
  // A tiny budget drops probes instead of overrunning.
  StrategySettings s = scene->strategy();
  s.guiding.probe_budget_s = 0.01f;
  s.guiding.probe_samples = 100000;
  scene->setStrategy(s);
  EXPECT_FALSE(scene->probes()->complete());
  EXPECT_LT(scene->probes()->learnSeconds(), 1.0);
}

// Both weights estimate E[mu_s L T / p] times a phase: with g = 0 the phase toward the camera is
// isotropic too, so over all probes the two sums agree (independent light samples: within noise);
// with g = 0.85 seen side-on they must not (the phase toward the camera is 0.2x isotropic there).
TEST(Probes, IsotropicWeightMatchesTheCameraWeightWhenThePhaseIsIsotropic) {
  auto sums = [](const std::string& g) {
    auto scene = Scene::build(test::loadScene("assets/scenes/god-rays.json", {"strategy.preset=\"full\"", "volumes.0.g=" + g}));
    double camera = 0.0, isotropic = 0.0;
    for (const auto& p : scene->probes()->probes()) camera += p.weight, isotropic += p.isotropicWeight;
    return std::make_pair(camera, isotropic);
  };
  const auto [camera0, isotropic0] = sums("0");
  ASSERT_GT(camera0, 0.0);
  EXPECT_NEAR(isotropic0 / camera0, 1.0, 0.03);
  const auto [camera85, isotropic85] = sums("0.85");
  EXPECT_LT(camera85 / isotropic85, 0.6);
}

TEST(Probes, BackgroundRelearnKeepsTheOldSetServingUntilTheNewOneIsReady) {
  auto scene = Scene::build(test::loadScene("assets/scenes/god-rays.json", {"strategy.preset=\"full\"", "camera.resolution=[16,9]"}));
  const auto before = scene->probes();
  CameraDesc moved = scene->desc().camera;
  moved.position += Vec3(1.0f, 0.0f, 0.0f);
  scene->setCamera(moved);  // relearns on a background thread
  // Rendering goes on meanwhile with whichever set is current.
  ProgressiveRenderer renderer(scene, RenderOptions{1, 8});
  Film film;
  EXPECT_TRUE(renderer.renderPass(film, 1));
  scene->waitForProbes();
  const auto after = scene->probes();
  EXPECT_NE(before, after);
  EXPECT_EQ(before->placed(), after->placed());
  EXPECT_EQ(before.use_count(), 1) << "the scene let go of the old set; whoever still holds it keeps it alive";
  EXPECT_FALSE(before->probes().empty());
}

// A live volume edit rebuilds the scene: the previous probes serve at once while the new ones learn.
TEST(Probes, RebuiltSceneServesThePreviousProbesUntilItsOwnAreLearned) {
  const SceneDesc desc = test::loadScene("assets/scenes/god-rays.json", {"strategy.preset=\"full\"", "camera.resolution=[16,9]"});
  auto first = Scene::build(desc);
  const auto serving = first->probes();
  SceneDesc edited = desc;
  edited.volumes[0].sigma_t_scale *= 2.0f;
  auto rebuilt = Scene::build(edited, nullptr, serving);
  ProgressiveRenderer renderer(rebuilt, RenderOptions{1, 8});
  Film film;
  EXPECT_TRUE(renderer.renderPass(film, 1));
  rebuilt->waitForProbes();
  EXPECT_NE(rebuilt->probes(), serving);
  EXPECT_EQ(rebuilt->probes()->placed(), serving->placed());
}

}  // namespace
}  // namespace candela
