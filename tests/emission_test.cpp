// Emission sampling (talk s.2.1; docs/method.md s.1-3): the Algorithm 2 pdf integrates to one over the
// sphere and matches a histogram of sampled directions (chi-square), from outside and inside the
// volume; the emission-aware majorant never drops below maj(mu_t) and follows its policy.
#include "integrator.h"
#include "stats.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <functional>

namespace candela {
namespace {

std::shared_ptr<Scene> torchOnly(const std::vector<std::string>& extra = {}) {
  std::vector<std::string> sets = {"strategy.preset=\"emission\"", "strategy.majorant.emission_term=true",
                                   "strategy.emission.light_sampling=true"};
  sets.insert(sets.end(), extra.begin(), extra.end());
  SceneDesc desc = test::loadScene("assets/scenes/torch-in-mist.json", sets);
  desc.volumes.resize(1);  // the flame alone
  return Scene::build(desc);
}

// Directions around x binned by (cos theta about `axis`, phi) over cos theta in [cosMin, 1]: the
// histogram of sample() against the integral of pdf() over each bin (a fine grid of directions per
// bin). Seen from outside, the cone around the direction to the volume holds all the mass.
void checkDirectionPdf(const std::function<bool(Rng&, Vec3&)>& sample, const std::function<float(const Vec3&)>& pdf, const Vec3& axis,
                       float cosMin, uint64_t seed) {
  constexpr int kCos = 40, kPhi = 40, kSamples = 300000, kSub = 8;
  Vec3 tx, ty;
  orthonormalBasis(axis, tx, ty);
  const double cosSpan = 1.0 - cosMin;
  std::vector<double> observed(kCos * kPhi, 0.0), expected(kCos * kPhi, 0.0);
  Rng rng(seed, 1);
  int drawn = 0;
  for (int i = 0; i < kSamples; ++i) {
    Vec3 w;
    if (!sample(rng, w)) continue;
    ++drawn;
    const float wz = glm::dot(w, axis);
    ASSERT_GE(wz, cosMin) << "a sampled direction outside the cone that bounds the volume";
    const int ci = std::min(kCos - 1, static_cast<int>((wz - cosMin) / cosSpan * kCos));
    float phi = std::atan2(glm::dot(w, ty), glm::dot(w, tx));
    if (phi < 0.0f) phi += 2.0f * kPi;
    const int pi = std::min(kPhi - 1, static_cast<int>(phi / (2.0f * kPi) * kPhi));
    observed[ci * kPhi + pi] += 1.0;
  }
  ASSERT_GT(drawn, kSamples * 0.99);
  double total = 0.0;
  const double dOmega = (cosSpan / kCos / kSub) * (2.0 * kPi / kPhi / kSub);
  for (int ci = 0; ci < kCos; ++ci)
    for (int pi = 0; pi < kPhi; ++pi)
      for (int a = 0; a < kSub; ++a)
        for (int b = 0; b < kSub; ++b) {
          const double z = cosMin + (ci + (a + 0.5) / kSub) * cosSpan / kCos;
          const double phi = (pi + (b + 0.5) / kSub) * 2.0 * kPi / kPhi;
          const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
          const Vec3 w = glm::normalize(static_cast<float>(r * std::cos(phi)) * tx + static_cast<float>(r * std::sin(phi)) * ty +
                                        static_cast<float>(z) * axis);
          const double p = pdf(w) * dOmega;
          expected[ci * kPhi + pi] += p;
          total += p;
        }
  EXPECT_NEAR(total, 1.0, 0.02) << "Algorithm 2's pdf must integrate to 1 over the sphere";
  double chi2 = 0.0, pooledObs = 0.0, pooledExp = 0.0;
  int dof = -1;
  for (size_t i = 0; i < observed.size(); ++i) {
    const double e = expected[i] * drawn;
    if (e < 10.0) {
      pooledObs += observed[i];
      pooledExp += e;
      continue;
    }
    chi2 += (observed[i] - e) * (observed[i] - e) / e;
    ++dof;
  }
  if (pooledExp > 10.0) chi2 += (pooledObs - pooledExp) * (pooledObs - pooledExp) / pooledExp, ++dof;
  ASSERT_GT(dof, 20);
  // The expected counts come from a numerical integral of a pdf with kinks at cell faces; allow for
  // its ~1% quadrature error on top of the sampling noise.
  double slack = 0.0;
  for (size_t i = 0; i < observed.size(); ++i) slack += std::pow(0.01 * expected[i] * drawn, 2.0) / std::max(1.0, expected[i] * drawn);
  std::printf("chi2 %.1f dof %d critical %.1f slack %.1f total %.4f\n", chi2, dof, test::chiSquareCritical(dof, 1e-4), slack, total);
  EXPECT_LT(chi2, test::chiSquareCritical(dof, 1e-4) + slack) << "dof " << dof;
}

void checkDirectionPdf(const EmissionLight& light, const Vec3& x, const Vec3& axis, float cosMin, uint64_t seed) {
  checkDirectionPdf([&](Rng& rng, Vec3& w) { return light.sample(x, rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform(), w); },
                    [&](const Vec3& w) { return light.pdf(x, w); }, axis, cosMin, seed);
}

TEST(EmissionLight, DirectionPdfMatchesSamplesFromOutside) {
  auto scene = torchOnly();
  ASSERT_EQ(scene->volumeLights().size(), 1u);
  const EmissionLight& light = *scene->volumeLights()[0];
  Vec3 lo, hi;
  light.medium().worldBounds(lo, hi);
  const Vec3 x(0.3f, 1.1f, 0.9f), centre = 0.5f * (lo + hi);
  const float radius = 0.5f * glm::length(hi - lo), distance = glm::length(centre - x);
  ASSERT_GT(distance, radius);
  checkDirectionPdf(light, x, (centre - x) / distance, std::sqrt(1.0f - radius * radius / (distance * distance)), 1);
}

TEST(EmissionLight, DirectionPdfMatchesSamplesFromInside) {
  auto scene = torchOnly({"strategy.emission.grid_cell_size=8"});
  checkDirectionPdf(*scene->volumeLights()[0], Vec3(0.0f, 1.2f, 0.0f), Vec3(0.0f, 0.0f, 1.0f), -1.0f, 2);
}

// Continuations toward emissive volumes (docs/method.md s.3b) draw from the volumes' densities mixed
// by the light sampler's pmf at x: with two flames and a sky, the mixture's pdf matches its samples.
TEST(EmissionLight, ContinuationTowardVolumesPdfMatchesSamples) {
  SceneDesc desc = test::loadScene("assets/scenes/torch-in-mist.json", {"strategy.preset=\"emission\""});
  desc.volumes.resize(1);
  desc.volumes.push_back(desc.volumes[0]);
  desc.volumes[1].name = "second flame";
  desc.volumes[1].transform.translate = Vec3(0.5f, 1.0f, 0.2f);
  auto scene = Scene::build(desc);
  ASSERT_EQ(scene->volumeLights().size(), 2u);
  const PathTracer tracer(*scene);
  const Vec3 x(0.0f, 1.2f, 0.0f);  // inside the first flame's bounds: every direction is possible
  float volumeShare = 0.0f;
  const float share = tracer.continuationShareTowardVolumes(x, volumeShare);
  ASSERT_GT(share, 0.0f);
  ASSERT_GT(volumeShare, 0.0f);
  ASSERT_LT(volumeShare, 1.0f) << "the sky keeps a share of the light samples";
  const int first = static_cast<int>(scene->lights().size());
  ASSERT_GT(scene->lightSampler().pmf(x, first + 1), 0.05f) << "both flames must matter";
  checkDirectionPdf([&](Rng& rng, Vec3& w) { return tracer.sampleVolumeDirection(x, volumeShare, rng, w); },
                    [&](const Vec3& w) { return tracer.volumeDirectionPdf(x, w, volumeShare); }, Vec3(0.0f, 0.0f, 1.0f), -1.0f, 3);
}

TEST(EmissionLight, CellProbabilitiesSumToOneAndFollowEnergy) {
  auto scene = torchOnly();
  const EmissionLight& light = *scene->volumeLights()[0];
  double sum = 0.0;
  for (size_t i = 0; i < light.layout().cellCount(); ++i) sum += light.cellProbability(static_cast<int>(i));
  EXPECT_NEAR(sum, 1.0, 1e-5);
  EXPECT_GT(light.power(), 0.0f);
  // A light-selection entry with power: volume lights compete with the environment.
  EXPECT_GT(scene->lightSampler().pmf(light.centroid(), static_cast<int>(scene->lights().size())), 0.5f);
}

TEST(EmissionLight, NonEmissiveVolumesAreNotLightsAndCostNothing) {
  SceneDesc desc = test::loadScene("assets/scenes/cloud.json", {"strategy.preset=\"emission\""});
  auto scene = Scene::build(desc);
  EXPECT_TRUE(scene->volumeLights().empty());
  EXPECT_FALSE(scene->hasEmissiveMedia());
  // The emission term leaves a non-emissive medium's majorant exactly maj(mu_t).
  SceneDesc plain = test::loadScene("assets/scenes/cloud.json", {"strategy.preset=\"conventional\""});
  auto conventional = Scene::build(plain);
  const Medium& a = *scene->mediaOwned()[0];
  const Medium& b = *conventional->mediaOwned()[0];
  for (size_t i = 0; i < a.majorantGrid().cellCount(); ++i) ASSERT_EQ(a.cellMajorant(static_cast<int>(i)), b.cellMajorant(static_cast<int>(i)));
}

TEST(EmissionMajorant, NeverBelowMajOfMuTAndFollowsThePolicy) {
  auto base = torchOnly({"strategy.majorant.emission_term=false"});
  const Medium& m0 = *base->mediaOwned()[0];
  float maxEmissionDriven = 0.0f;
  for (float k : {0.0f, 0.01f, 1.0f, 1e6f}) {
    for (float cap : {0.0f, 1.0f}) {
      StrategySettings s = base->strategy();
      s.majorant.emission_term = true;
      s.majorant.emission_weight = k;
      s.majorant.emission_cap = cap;
      auto scene = torchOnly();
      scene->setStrategy(s);
      const Medium& m = *scene->mediaOwned()[0];
      for (size_t i = 0; i < m.majorantGrid().cellCount(); ++i) {
        const float muT = m0.cellMajorant(static_cast<int>(i));
        const float muBar = m.cellMajorant(static_cast<int>(i));
        ASSERT_GE(muBar, muT);
        if (k == 0.0f) {
          ASSERT_EQ(muBar, muT);
        }
        // With the cap, an emission-driven rate never exceeds c / voxel_size.
        if (cap > 0.0f && muBar > muT) {
          ASSERT_LE(muBar, cap / m.voxelSize() * 1.0001f);
        }
        maxEmissionDriven = std::max(maxEmissionDriven, muBar / std::max(muT, 1e-6f));
      }
    }
  }
  EXPECT_GT(maxEmissionDriven, 2.0f) << "the emission term never raised the majorant";
}

TEST(EmissionMajorant, PolicyEditsRebuildOnlyWhatDependsOnThem) {
  auto scene = torchOnly();
  const Medium& m = *scene->mediaOwned()[0];
  const MajorantGrid* grid = &m.majorantGrid();
  const auto cells = grid->maxDensities();
  const EmissionLight* light = m.emissionLight();
  StrategySettings s = scene->strategy();
  s.majorant.emission_weight = 7.0f;
  scene->setStrategy(s);
  EXPECT_EQ(m.majorantGrid().maxDensities(), cells);
  EXPECT_EQ(m.emissionLight(), light) << "changing k must not rebuild the emission grid";
  s.emission.grid_cell_size = 8;
  scene->setStrategy(s);
  EXPECT_NE(m.emissionLight(), light);
  EXPECT_EQ(m.emissionLight()->cellSize(), 8);
}

// A relative emission weight k gives a ray through a thin emitter about k emission collisions, as
// through a dense one k per unit of absorption depth (medium.cpp: the radiance scale is what a ray
// gathers, Le (1 - exp(-tau_a))). Relative to Le alone, a thin emitter's rays got about k tau_a.
TEST(EmissionMajorant, ARelativeWeightGivesAThinEmittersRaysAboutKCollisions) {
  constexpr float k = 10.0f;
  for (float sigmaT : {0.05f, 0.5f, 5.0f}) {
    SceneDesc desc = test::loadScene("assets/scenes/test/emission-slab.json",
                                     {"strategy.preset=\"emission\"", "strategy.majorant.relative_weight=true",
                                      "strategy.majorant.emission_weight=" + std::to_string(k), "volumes.0.generator.size=[1,1,1]",
                                      "volumes.0.sigma_t_scale=" + std::to_string(sigmaT)});
    const auto scene = Scene::build(desc);
    const Medium& m = *scene->mediaOwned()[0];
    // A unit cube's mean chord is 2/3; the cells padding it stretch that a little.
    const float tau = m.emissionOpticalDepth();
    EXPECT_GT(tau, 0.8f * sigmaT * 2.0f / 3.0f) << "sigma_t " << sigmaT;
    EXPECT_LT(tau, 1.6f * sigmaT * 2.0f / 3.0f) << "sigma_t " << sigmaT;
    // Expected collisions on the centre ray through the cube (z from -1 to 1): the integral of mu_bar,
    // the emission-driven rate wherever it exceeds mu_t.
    double collisions = 0.0;
    constexpr int kSteps = 4000;
    for (int i = 0; i < kSteps; ++i) {
      const Vec3 p(0.0f, 0.0f, -1.0f + 2.0f * (i + 0.5f) / kSteps);
      const Vec3 index = Vec3(m.indexFromWorld() * glm::vec4(p, 1.0f));
      collisions += m.majorantAt(index) * (2.0 / kSteps);
    }
    const double expected = k * std::max(1.0, static_cast<double>(sigmaT));  // k, or k per unit of tau_a
    EXPECT_GT(collisions, 0.5 * expected) << "sigma_t " << sigmaT;
    EXPECT_LT(collisions, 2.5 * expected) << "sigma_t " << sigmaT;
  }
}

}  // namespace
}  // namespace candela
