// Light selection (renderer/lights.h): the probability of each light depends on the shading point
// (its estimated fluence there, with a defensive uniform share). Unit tests of the sampler, and a
// superposition test: a scene rendered with all its lights agrees with the sum of renders lit by
// one light each, where no selection happens at all.
#include "emission_light.h"
#include "lights.h"
#include "renderer.h"
#include "scene.h"
#include "stats.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace candela;

namespace {

std::vector<LightImportance> mixedLights() {
  std::vector<LightImportance> lights(4);
  lights[0].intensity = 1.0f;  // a point light at the origin
  lights[1].atInfinity = true, lights[1].fluence = 0.5f;  // a sky
  lights[2].intensity = 0.0f;  // dark: never picked
  lights[3].intensity = 20.0f, lights[3].position = Vec3(5.0f, 0.0f, 0.0f), lights[3].spread2 = 0.25f;  // a flame
  return lights;
}

}  // namespace

TEST(LightSelection, ProbabilitiesSumToOneKeepTheDefensiveShareAndNeverPickADarkLight) {
  const LightSampler sampler(mixedLights());
  ASSERT_FALSE(sampler.empty());
  for (const Vec3 p : {Vec3(0.1f, 0.0f, 0.0f), Vec3(4.5f, 0.2f, 0.0f), Vec3(100.0f, 50.0f, -30.0f), Vec3(5.0f, 0.0f, 0.0f)}) {
    float sum = 0.0f;
    for (int i = 0; i < sampler.size(); ++i) {
      const float pmf = sampler.pmf(p, i);
      sum += pmf;
      if (i == 2) EXPECT_EQ(pmf, 0.0f);
      else EXPECT_GE(pmf, LightSampler::kDefensiveShare / 3.0f - 1e-6f) << "light " << i;
    }
    EXPECT_NEAR(sum, 1.0f, 1e-5f);
  }
}

TEST(LightSelection, NearLightsGetTheSamplesAndFarOnesLeaveThemToTheSky) {
  const LightSampler sampler(mixedLights());
  // Beside the flame, the flame; beside the point light, the point light; far from both, the sky.
  EXPECT_GT(sampler.pmf(Vec3(4.6f, 0.0f, 0.0f), 3), 0.75f);
  EXPECT_GT(sampler.pmf(Vec3(0.05f, 0.0f, 0.0f), 0), 0.75f);
  EXPECT_GT(sampler.pmf(Vec3(100.0f, 0.0f, 0.0f), 1), 0.75f);
}

TEST(LightSelection, SampledFrequenciesMatchThePmf) {
  const LightSampler sampler(mixedLights());
  const Vec3 p(2.0f, 1.0f, 0.0f);
  const int n = 200000;
  std::vector<int> count(static_cast<size_t>(sampler.size()), 0);
  Rng rng(7, 0);
  for (int k = 0; k < n; ++k) {
    float pmf = 0.0f;
    const int i = sampler.sample(p, rng.uniform(), pmf);
    ASSERT_GE(i, 0);
    EXPECT_FLOAT_EQ(pmf, sampler.pmf(p, i));
    ++count[static_cast<size_t>(i)];
  }
  double chi2 = 0.0;
  int dof = -1;
  for (int i = 0; i < sampler.size(); ++i) {
    const double expected = n * static_cast<double>(sampler.pmf(p, i));
    if (expected == 0.0) {
      EXPECT_EQ(count[static_cast<size_t>(i)], 0);
      continue;
    }
    chi2 += (count[static_cast<size_t>(i)] - expected) * (count[static_cast<size_t>(i)] - expected) / expected;
    ++dof;
  }
  EXPECT_LT(chi2, test::chiSquareCritical(dof, 1e-4));
}

TEST(LightSelection, AnEmptyOrAllDarkSamplerPicksNothing) {
  float pmf = 1.0f;
  EXPECT_EQ(LightSampler().sample(Vec3(0.0f), 0.5f, pmf), -1);
  EXPECT_EQ(pmf, 0.0f);
  std::vector<LightImportance> dark(2);
  const LightSampler sampler(dark);
  EXPECT_TRUE(sampler.empty());
  EXPECT_EQ(sampler.sample(Vec3(0.0f), 0.5f, pmf), -1);
  EXPECT_EQ(sampler.pmf(Vec3(0.0f), 0), 0.0f);
}

// The case that motivated it: torch-in-mist's faint night sky, weighed by its power over the whole
// scene, took 87% of the light samples; beside the torch the flame now takes most of them.
TEST(LightSelection, BesideTheTorchTheFlameTakesMostSamples) {
  auto scene = Scene::build(test::loadScene("assets/scenes/torch-in-mist.json", {"strategy.preset=\"emission\""}));
  ASSERT_EQ(scene->volumeLights().size(), 1u);
  const int flame = static_cast<int>(scene->lights().size());
  const Vec3 nearFlame = scene->volumeLights()[0]->centroid() + Vec3(0.5f, 0.0f, 0.0f);
  EXPECT_GT(scene->lightSampler().pmf(nearFlame, flame), 0.75f);
}

// Unbiasedness of the point-dependent selection: light adds up. The scene lit by everything agrees
// with the sum of renders lit by each light alone (one light: nothing to select).
class LightsAddUp : public ::testing::TestWithParam<const char*> {};

TEST_P(LightsAddUp, AllLightsAgreeWithTheSumOfEachLightAlone) {
  const std::string path = std::string("assets/scenes/") + GetParam() + ".json";
  const std::vector<std::string> common{"camera.resolution=[48,27]", "strategy.preset=\"emission\"", "render.max_depth=4"};
  const SceneDesc all = test::loadScene(path, common);
  const int spp = 512;
  const int blocksX = 4, blocksY = 3;
  // One render per light source: each scene light alone, then each emissive volume alone.
  std::vector<SceneDesc> parts;
  for (size_t i = 0; i < all.lights.size(); ++i) {
    SceneDesc d = all;
    d.lights = {all.lights[i]};
    for (auto& v : d.volumes) v.emission.intensity = 0.0f;
    parts.push_back(d);
  }
  for (size_t v = 0; v < all.volumes.size(); ++v) {
    if (all.volumes[v].emission.mode == EmissionMode::None) continue;
    SceneDesc d = all;
    d.lights.clear();
    for (size_t o = 0; o < d.volumes.size(); ++o)
      if (o != v) d.volumes[o].emission.intensity = 0.0f;
    parts.push_back(d);
  }
  ASSERT_GE(parts.size(), 2u) << "a superposition test needs at least two lights";
  std::vector<RegionEstimate> sum;
  uint32_t seed = 100;
  for (SceneDesc& d : parts) {
    d.render.seed = seed++;
    const auto regions = regionEstimates(test::render(d, spp), blocksX, blocksY);
    if (sum.empty()) {
      sum = regions;
      continue;
    }
    for (size_t r = 0; r < sum.size(); ++r)
      for (int c = 0; c < 3; ++c) {
        sum[r].mean[c] += regions[r].mean[c];
        sum[r].standardError[c] = std::hypot(sum[r].standardError[c], regions[r].standardError[c]);
      }
  }
  const Agreement a = compareToEstimates(test::render(all, spp), blocksX, blocksY, sum);
  EXPECT_TRUE(a.agree) << a.worst;
}

INSTANTIATE_TEST_SUITE_P(Scenes, LightsAddUp, ::testing::Values("torch-in-mist", "shed-fire"));
