// The auto strategy (auto_strategy.h): its scene rules build only what a scene needs, its decisions
// are the same for a seed whatever the thread count, and whatever it picks agrees with conventional
// on the report scenes (the stability suite holds it to the stability cases).
#include "auto_strategy.h"
#include "stats.h"
#include "test_support.h"

#include <tbb/global_control.h>

#include <gtest/gtest.h>

namespace candela {
namespace {

bool mentions(const AutoDecision& d, const std::string& text) {
  for (const auto& r : d.reasons)
    if (r.find(text) != std::string::npos) return true;
  return false;
}

TEST(AutoStrategy, ASceneWithoutEmissionBuildsNoEmissionStructures) {
  const auto scene = Scene::build(test::loadScene("assets/scenes/cloud.json", {"strategy.preset=\"auto\"", "camera.resolution=[64,36]"}));
  ASSERT_NE(scene->autoDecision(), nullptr);
  EXPECT_TRUE(mentions(*scene->autoDecision(), "no volume emits")) << scene->autoDecision()->summary();
  EXPECT_TRUE(scene->volumeLights().empty());
  EXPECT_FALSE(scene->strategy().majorant.emission_term);
  EXPECT_FALSE(scene->strategy().emission.gather_every_collision);
  EXPECT_EQ(scene->strategy().preset, "auto");
}

TEST(AutoStrategy, AThickCloudLearnsNoProbesAndSaysWhy) {
  // The report's cumulus ten times denser: most camera rays are far thicker than 4 optical depths.
  const auto scene = Scene::build(
      test::loadScene("assets/scenes/cloud.json", {"strategy.preset=\"auto\"", "camera.resolution=[64,36]", "volumes.0.sigma_t_scale=400"}));
  ASSERT_NE(scene->autoDecision(), nullptr);
  EXPECT_EQ(scene->probes(), nullptr) << scene->autoDecision()->summary();
  EXPECT_TRUE(mentions(*scene->autoDecision(), "no probes")) << scene->autoDecision()->summary();
  EXPECT_TRUE(scene->autoDecision()->pilot.empty());
}

TEST(AutoStrategy, EmissionMeansEmissionSamplingWithARelativeWeight) {
  const auto scene = Scene::build(test::loadScene("assets/scenes/fire.json", {"strategy.preset=\"auto\"", "camera.resolution=[48,48]"}));
  ASSERT_NE(scene->autoDecision(), nullptr);
  EXPECT_TRUE(scene->strategy().majorant.emission_term);
  EXPECT_TRUE(scene->strategy().majorant.relative_weight);
  EXPECT_TRUE(scene->strategy().emission.light_sampling);
  EXPECT_FALSE(scene->volumeLights().empty());
}

TEST(AutoStrategy, TheSameSeedGivesTheSameDecisionOnAnyThreadCount) {
  const SceneDesc desc = test::loadScene("assets/scenes/torch-in-mist.json", {"strategy.preset=\"auto\"", "camera.resolution=[96,54]"});
  std::string one, all;
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = Scene::build(desc)->autoDecision()->summary();
  }
  all = Scene::build(desc)->autoDecision()->summary();
  EXPECT_EQ(one, all);
  EXPECT_EQ(Scene::build(desc)->autoDecision()->summary(), all);
  EXPECT_NE(all.find("pilot"), std::string::npos) << all;
}

TEST(AutoStrategy, ChoosingAutoAgainRedecidesButTheSameDecisionDoesNot) {
  auto scene = Scene::build(test::loadScene("assets/scenes/fire.json", {"strategy.preset=\"auto\"", "camera.resolution=[48,48]"}));
  const StrategySettings decided = scene->strategy();
  scene->applyStrategy(strategyPreset("emission"));
  EXPECT_EQ(scene->autoDecision(), nullptr);
  scene->applyStrategy(strategyPreset("auto"));
  ASSERT_NE(scene->autoDecision(), nullptr);
  EXPECT_EQ(toJson(scene->strategy()), toJson(decided));
}

// Whatever auto picks converges to the conventional image on every report scene.
class AutoAgreement : public testing::TestWithParam<const char*> {};

TEST_P(AutoAgreement, AgreesWithConventional) {
  const std::string scene = std::string("assets/scenes/") + GetParam() + ".json";
  const std::vector<std::string> base{"camera.resolution=[24,14]", "render.max_depth=6"};
  std::vector<std::string> conv = base, autoSets = base;
  conv.push_back("strategy.preset=\"conventional\"");
  autoSets.push_back("strategy.preset=\"auto\"");
  autoSets.push_back("render.seed=77");
  const Film reference = test::render(test::loadScene(scene, conv), 4096);
  const SceneDesc autoDesc = test::loadScene(scene, autoSets);
  const Film film = test::render(autoDesc, 1024);
  const Agreement a = compareRenders(reference, film, 3, 2);
  EXPECT_TRUE(a.agree) << GetParam() << ": " << a.worst;
  EXPECT_EQ(film.rejectedSamples(), 0u);
}

INSTANTIATE_TEST_SUITE_P(ReportScenes, AutoAgreement,
                         testing::Values("torch-in-mist", "torch-in-fog", "fire", "god-rays", "god-rays-backlit", "god-rays-dark", "cloud"),
                         [](const testing::TestParamInfo<const char*>& info) {
                           std::string n = info.param;
                           for (char& c : n)
                             if (c == '-') c = '_';
                           return n;
                         });

}  // namespace
}  // namespace candela
