// The auto strategy (auto_strategy.h): its scene rules build only what a scene needs, its decisions
// are the same for a seed whatever the thread count, and whatever it picks agrees with conventional
// on the report scenes (the stability suite holds it to the stability cases).
#include "auto_strategy.h"
#include "camera_guides.h"
#include "integrator.h"
#include "renderer.h"
#include "stats.h"
#include "test_support.h"

#include <tbb/global_control.h>

#include <gtest/gtest.h>

#include <algorithm>

namespace candela {
namespace {

// gtest names from scene names: "god-rays-dark" -> "god_rays_dark".
std::string sceneTestName(const testing::TestParamInfo<const char*>& info) {
  std::string n = info.param;
  for (char& c : n)
    if (c == '-') c = '_';
  return n;
}

bool mentions(const std::vector<std::string>& reasons, const std::string& text) {
  for (const auto& r : reasons)
    if (r.find(text) != std::string::npos) return true;
  return false;
}
bool mentions(const AutoDecision& d, const std::string& text) { return mentions(d.reasons, text); }

TEST(AutoStrategy, ASceneWithoutEmissionBuildsNoEmissionStructures) {
  const auto scene = Scene::build(test::loadScene("assets/scenes/cloud.json", {"strategy.preset=\"auto\"", "camera.resolution=[64,36]"}));
  ASSERT_NE(scene->autoDecision(), nullptr);
  EXPECT_TRUE(mentions(*scene->autoDecision(), "no volume emits")) << scene->autoDecision()->summary();
  EXPECT_TRUE(scene->volumeLights().empty());
  EXPECT_FALSE(scene->strategy().majorant.emission_term);
  // Weighting absorption at every collision builds nothing; it is the walk auto uses everywhere.
  EXPECT_TRUE(scene->strategy().emission.gather_every_collision);
  EXPECT_FALSE(scene->strategy().emission.light_sampling);
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
  const SceneDesc desc = test::loadScene("assets/scenes/torch-in-fog.json", {"strategy.preset=\"auto\"", "camera.resolution=[96,54]"});
  std::string one, all;
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = Scene::build(desc)->autoDecision()->summary();
  }
  all = Scene::build(desc)->autoDecision()->summary();
  EXPECT_EQ(one, all);
  EXPECT_EQ(Scene::build(desc)->autoDecision()->summary(), all);
  EXPECT_NE(all.find("; pilot ("), std::string::npos) << all;  // a pilot ran
}

// The frequent guided vertex (q = 0.5) and equiangular refine the guided camera vertex: the pilot
// renders equiangular only when full was ahead of the plain candidate and the scene has a point to
// aim it at (the god-rays scenes, lit by a sun and a sky, have none), the frequent guided vertex
// also when full was ahead in some region, and it says what it skipped.
TEST(AutoStrategy, RefinementsOfGuidingArePilotedOnlyWhereFullIsAhead) {
  for (const char* name : {"torch-in-fog", "god-rays-dark", "god-rays"}) {
    const bool aimable = std::string(name) == "torch-in-fog";
    const auto scene = Scene::build(test::loadScene(std::string("assets/scenes/") + name + ".json",
                                                    {"strategy.preset=\"auto\"", "camera.resolution=[96,54]"}));
    const AutoDecision* d = scene->autoDecision();
    ASSERT_NE(d, nullptr);
    ASSERT_GE(d->pilot.size(), 2u) << d->summary();
    ASSERT_EQ(d->pilot[1].name, "full") << d->summary();
    bool equiangular = false, qRefinement = false;
    for (const auto& m : d->pilot) equiangular |= m.name == "equiangular", qRefinement |= m.name.rfind("full, ", 0) == 0;
    // The first round's verdict, as the decision states it. (The scores in d->pilot are those of the
    // last round, against every candidate and a mean image they all share, so two candidates'
    // order there need not be the first round's.)
    const bool fullBehind = mentions(*d, "full behind ");
    EXPECT_EQ(equiangular, aimable && !fullBehind) << name << ": " << d->summary();
    EXPECT_EQ(mentions(*d, "equiangular not tried"), aimable && fullBehind) << name << ": " << d->summary();
    EXPECT_EQ(mentions(*d, "equiangular has nothing to aim at"), !aimable) << name << ": " << d->summary();
    // Full measures each pixel block's q from its own samples: its q refinements (one camera segment
    // in two, the region map) would differ from it in the first 16 samples only.
    EXPECT_FALSE(qRefinement) << name << ": " << d->summary();
    EXPECT_TRUE(mentions(*d, "no q refinements piloted")) << name << ": " << d->summary();
  }
}

// Where full stands (volumes emit, and only they scatter, a sun shines too, or the medium they light
// is thin) it runs without a pilot: the pilot's few samples per pixel cannot see its gain.
TEST(AutoStrategy, WhereFullStandsItRunsWithoutAPilot) {
  for (const char* name : {"fire", "shed-fire", "torch-in-mist"}) {
    const auto scene = Scene::build(test::loadScene(std::string("assets/scenes/") + name + ".json",
                                                    {"strategy.preset=\"auto\"", "camera.resolution=[48,27]"}));
    const AutoDecision* d = scene->autoDecision();
    ASSERT_NE(d, nullptr);
    EXPECT_EQ(d->chosen, "full") << name;
    EXPECT_TRUE(d->pilot.empty()) << name << ": " << d->summary();
    EXPECT_EQ(d->pilotFilm, nullptr) << name;
    EXPECT_TRUE(mentions(*d, "full stands, no pilot")) << name << ": " << d->summary();
    EXPECT_EQ(scene->strategy().guiding.guide, DistanceGuide::Probes) << name;
    EXPECT_TRUE(scene->strategy().majorant.relative_weight) << name;
  }
}

// Exactly one candidate stands (the one the others must beat by the margin): full where volumes emit
// and only they scatter (fire's smoke), a sun shines too (shed-fire) or the medium that emits nothing
// they light is thin (torch-in-mist: most camera rays cross less than one optical depth), the plain
// candidate where that medium is denser (torch-in-fog) and where nothing emits; and the decision says
// which stands.
TEST(AutoStrategy, TheStandingCandidateFollowsWhatScattersTheLight) {
  for (const auto& [name, expected] : std::vector<std::pair<const char*, const char*>>{{"torch-in-mist", "full"},
                                                                                      {"torch-in-fog", "emission"},
                                                                                      {"fire", "full"},
                                                                                      {"shed-fire", "full"},
                                                                                      {"god-rays-dark", "conventional, gathering"}}) {
    const auto scene = Scene::build(test::loadScene(std::string("assets/scenes/") + name + ".json", {"camera.resolution=[32,18]"}));
    std::vector<std::string> reasons;
    const std::vector<AutoCandidate> candidates = autoCandidates(*scene, reasons);
    int standing = 0;
    std::string standingName;
    for (const AutoCandidate& c : candidates)
      if (c.standing) ++standing, standingName = c.name;
    EXPECT_EQ(standing, 1) << name;
    EXPECT_EQ(standingName, expected) << name;
    std::string all;
    for (const std::string& r : reasons) all += r + "; ";
    const std::string said = std::string(expected) == "conventional, gathering" ? "" : std::string(expected) + " stands";
    if (said.empty()) {
      EXPECT_EQ(all.find("stands"), std::string::npos) << name << ": " << all;  // nothing emits: the pilot's plain rule
    } else {
      EXPECT_NE(all.find(said), std::string::npos) << name << ": " << all;
    }
  }
  const auto scene = Scene::build(test::loadScene("assets/scenes/fire.json", {"strategy.preset=\"auto\"", "camera.resolution=[48,48]"}));
  const AutoDecision* d = scene->autoDecision();
  ASSERT_NE(d, nullptr);
  EXPECT_TRUE(mentions(*d, "full stands")) << d->summary();
  if (d->chosen == "full") {
    EXPECT_EQ(scene->strategy().guiding.guide, DistanceGuide::Probes) << d->summary();
  }
}

// Guided continuations (the thin rays leaving a medium vertex guided too) where shafts of a sun or
// no emission make them pay: shed-fire's sun beside its campfire, god-rays-dark; not where flames
// are the only concentrated light (torch-in-mist, fire), whose glow the continuations aimed at the
// volumes reach and whose light samples make a guided later vertex dear. The guided candidates
// have them as the preset `full` does, so "auto chose full" names the settings that ran.
TEST(AutoStrategy, GuidedContinuationsWhereASunOrNoEmissionMakesShafts) {
  for (const auto& [name, continued] : std::vector<std::pair<const char*, bool>>{
           {"shed-fire", true}, {"god-rays-dark", true}, {"torch-in-mist", false}, {"fire", false}}) {
    const auto scene = Scene::build(test::loadScene(std::string("assets/scenes/") + name + ".json", {"camera.resolution=[32,18]"}));
    EXPECT_EQ(guidedContinuationsApply(*scene, strategyPreset("full").guiding), continued) << name;
    std::vector<std::string> reasons;
    const std::vector<AutoCandidate> candidates = autoCandidates(*scene, reasons);
    int guided = 0;
    for (const AutoCandidate& c : candidates) {
      if (c.strategy.guiding.guide != DistanceGuide::Probes) continue;
      ++guided;
      EXPECT_EQ(guidedContinuationsApply(*scene, c.strategy.guiding), continued) << name << ": " << c.name;
      GuidingSettings preset = strategyPreset("full").guiding;
      preset.guided_probability = c.strategy.guiding.guided_probability;  // "full, guided_probability 0.5"
      EXPECT_EQ(toJson(c.strategy.guiding).dump(), toJson(preset).dump()) << name << ": " << c.name;
    }
    EXPECT_GE(guided, 1) << name;
    EXPECT_EQ(mentions(reasons, "guide the thin rays leaving a medium vertex"), continued) << name;
  }
}

// What auto shows (status bar, report, metadata) begins "auto chose NAME", NAME being the
// candidate: the settings of the preset of that name, its q changed where the name says so.
TEST(AutoStrategy, ItsLabelIsTheCandidatesName) {
  for (const char* name : {"god-rays-dark", "torch-in-mist"}) {
    const auto scene = Scene::build(
        test::loadScene(std::string("assets/scenes/") + name + ".json", {"strategy.preset=\"auto\"", "camera.resolution=[32,18]"}));
    const AutoDecision* d = scene->autoDecision();
    ASSERT_NE(d, nullptr) << name;
    EXPECT_EQ(d->label(), d->chosen) << name;
    EXPECT_EQ(d->summary().rfind("auto chose " + d->label(), 0), 0u) << d->summary();
  }
}

// Every candidate, guided or not, weights absorption at every collision as the full preset does,
// in a scene without emission too.
TEST(AutoStrategy, EveryCandidateGathersAtEveryCollision) {
  const auto scene = Scene::build(test::loadScene("assets/scenes/god-rays-dark.json", {"camera.resolution=[32,18]"}));
  std::vector<std::string> reasons;
  const std::vector<AutoCandidate> candidates = autoCandidates(*scene, reasons);
  ASSERT_GE(candidates.size(), 2u);
  EXPECT_EQ(candidates[0].strategy.guiding.guide, DistanceGuide::None);
  EXPECT_FALSE(candidates[0].strategy.majorant.emission_term);
  for (size_t i = 0; i < candidates.size(); ++i) {
    EXPECT_TRUE(candidates[i].strategy.emission.gather_every_collision) << candidates[i].name;
    if (i > 0) {
      EXPECT_NE(candidates[i].strategy.guiding.guide, DistanceGuide::None) << candidates[i].name;
    }
  }
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

// The Strategy panel shows auto's choice in its fields; an edit to one of them takes the choice over:
// the preset named after the candidate, every other field as auto set it, run as edited with no new
// decision, and saved and loaded unchanged.
TEST(AutoStrategy, AnEditTakesAutosChoiceOverAsItsPreset) {
  for (const auto& [name, preset] : {std::pair<const char*, const char*>{"torch-in-mist", "full"}, {"cloud", "conventional"}}) {
    auto scene = Scene::build(
        test::loadScene(std::string("assets/scenes/") + name + ".json", {"strategy.preset=\"auto\"", "camera.resolution=[32,18]"}));
    ASSERT_NE(scene->autoDecision(), nullptr) << name;
    const StrategySettings running = scene->strategy();
    StrategySettings taken = takeOverAutoChoice(running, scene->autoDecision()->chosen);
    EXPECT_EQ(taken.preset, preset) << name;
    EXPECT_FALSE(needsAutoResolve(taken)) << name;
    Json sameFields = toJson(taken);
    sameFields["preset"] = "auto";
    EXPECT_EQ(sameFields, toJson(running)) << name;
    EXPECT_EQ(toJson(strategyFromJson(toJson(taken), "session.json", "strategy")), toJson(taken)) << name;

    taken.russian_roulette_depth = running.russian_roulette_depth + 2;
    scene->applyStrategy(taken);
    EXPECT_EQ(scene->autoDecision(), nullptr) << name;
    EXPECT_EQ(toJson(scene->strategy()), toJson(taken)) << name;
    EXPECT_EQ(scene->strategy().adaptive_split, running.adaptive_split) << name;
  }
}

// An image no larger than the pilot's sample count is piloted as it is, and the pilot's samples
// start the render: they are the scene seed's first sample indices, the render continues after them,
// and they are used only for the view they were rendered for and only where they do not exceed the
// spp asked for. A larger image is piloted on a reduced copy and starts empty.
TEST(AutoStrategy, ThePilotsSamplesStartTheImageOfTheViewTheyWereRenderedFor) {
  auto scene = Scene::build(test::loadScene("assets/scenes/god-rays-dark.json", {"strategy.preset=\"auto\"", "camera.resolution=[96,54]"}));
  const AutoDecision* d = scene->autoDecision();
  ASSERT_NE(d, nullptr);
  ASSERT_NE(d->pilotFilm, nullptr) << d->summary();
  EXPECT_EQ(d->pilotWidth, 96);
  EXPECT_EQ(d->pilotSpp, 8);
  // Each fresh round ("measured again": against full, then against the standing candidate) renders
  // three more images: the challenger's two and a second look at its rival, the plain candidate.
  // Under god-rays-dark's sun the plain candidate's images only measure, the first and the second
  // look; without a sun every image is kept.
  const auto reasonsWith = [](const AutoDecision& decision, const char* text) {
    return static_cast<int>(std::count_if(decision.reasons.begin(), decision.reasons.end(),
                                          [&](const std::string& r) { return r.find(text) != std::string::npos; }));
  };
  const int rounds = reasonsWith(*d, "measured again");
  ASSERT_GT(rounds, 0) << d->summary();
  ASSERT_EQ(reasonsWith(*d, "the plain candidate's pilot image only measures"), 1) << d->summary();
  const int images = static_cast<int>(d->pilot.size()) - 1 + 2 * rounds;
  EXPECT_EQ(d->pilotFilm->spp(), images * d->pilotSpp) << d->summary();
  EXPECT_NE(d->summary().find(std::to_string(d->pilotFilm->spp()) + " spp kept in the image"), std::string::npos) << d->summary();
  const int kept = d->pilotFilm->spp();
  {
    // Without a sun the plain candidate's images stay, the fresh round's look at it too (torch-in-fog).
    const auto unlit =
        Scene::build(test::loadScene("assets/scenes/torch-in-fog.json", {"strategy.preset=\"auto\"", "camera.resolution=[96,54]"}));
    const AutoDecision* u = unlit->autoDecision();
    ASSERT_NE(u, nullptr);
    ASSERT_NE(u->pilotFilm, nullptr) << u->summary();
    EXPECT_EQ(reasonsWith(*u, "only measures"), 0) << u->summary();
    EXPECT_EQ(u->pilotFilm->spp(), (static_cast<int>(u->pilot.size()) + 3 * reasonsWith(*u, "measured again")) * u->pilotSpp)
        << u->summary();
  }
  EXPECT_EQ(continueFromPilot(*scene, 0).spp(), kept);
  EXPECT_EQ(continueFromPilot(*scene, kept).spp(), kept);
  EXPECT_EQ(continueFromPilot(*scene, kept - 1).spp(), 0) << "more samples than asked for";

  // The render continues at sample index `kept`: the same as the pilot's sums plus a separate render
  // of those indices.
  Film continued = continueFromPilot(*scene, 0);
  ProgressiveRenderer renderer(scene, RenderOptions{0, 16});
  renderer.renderPass(continued, 2);
  RenderOptions after{0, 16};
  after.firstSample = kept;
  ProgressiveRenderer separate(scene, after);
  Film next;
  separate.renderPass(next, 2);
  Film expected = *d->pilotFilm;
  expected.addPass(next);
  ASSERT_EQ(continued.spp(), kept + 2);
  EXPECT_EQ(continued.sum(), expected.sum());
  Film fromZero;
  ProgressiveRenderer(scene, RenderOptions{0, 16}).renderPass(fromZero, 2);
  EXPECT_NE(fromZero.sum(), next.sum()) << "the continuation draws new sample indices";

  CameraDesc moved = scene->desc().camera;
  moved.position.x += 0.1f;
  scene->setCamera(moved);
  EXPECT_EQ(continueFromPilot(*scene, 0).spp(), 0) << "the pilot's samples belong to the view they were rendered for";

  const auto large =
      Scene::build(test::loadScene("assets/scenes/torch-in-fog.json", {"strategy.preset=\"auto\"", "camera.resolution=[400,240]"}));
  ASSERT_NE(large->autoDecision(), nullptr);
  ASSERT_FALSE(large->autoDecision()->pilot.empty()) << large->autoDecision()->summary();
  EXPECT_EQ(large->autoDecision()->pilotFilm, nullptr) << large->autoDecision()->summary();
  EXPECT_LT(large->autoDecision()->pilotWidth, 400);
  EXPECT_EQ(continueFromPilot(*large, 0).spp(), 0);
  EXPECT_EQ(large->camera().width(), 400) << "the camera is restored after a reduced pilot";
}

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
  const Film film = test::render(autoDesc, 1024);  // the pilot's samples (of every candidate) included
  const Agreement a = compareRenders(reference, film, 3, 2);
  EXPECT_TRUE(a.agree) << GetParam() << ": " << a.worst;
  EXPECT_EQ(film.rejectedSamples(), 0u);
}

INSTANTIATE_TEST_SUITE_P(ReportScenes, AutoAgreement,
                         testing::Values("torch-in-mist", "torch-in-fog", "fire", "god-rays", "god-rays-backlit", "god-rays-dark", "cloud", "shed-fire"),
                         sceneTestName);

}  // namespace
}  // namespace candela
