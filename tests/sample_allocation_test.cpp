// Adaptive sampling by splitting (sample_allocation.h): the decision gives more camera samples to
// the blocks whose noise per unit of work is high and none where nothing is to be gained, and a
// split render agrees with an unsplit one, is the same on any thread count and counts its work.
#include "sample_allocation.h"

#include "auto_strategy.h"
#include "film.h"
#include "renderer.h"
#include "rng.h"
#include "stats.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <vector>

namespace candela {
namespace {

// A 64 x 32 film (8 x 4 blocks) of 4 samples per pixel whose figures the test writes itself:
// `value(block, sample, x, y)` gives each sample, `cost(block)` what each camera sample cost.
struct SyntheticFilm {
  static constexpr int kWidth = 64, kHeight = 32, kSamples = 4;
  Film film{kWidth, kHeight};
  AdaptiveSplit::Halves sumSquares{std::vector<float>(3 * kWidth * kHeight, 0.0f), std::vector<float>(3 * kWidth * kHeight, 0.0f)};
  AdaptiveSplit::Halves count{std::vector<float>(kWidth * kHeight, 0.0f), std::vector<float>(kWidth * kHeight, 0.0f)};
  std::vector<float> cost = std::vector<float>(kWidth * kHeight, 0.0f);

  template <class Value, class Cost>
  SyntheticFilm(Value value, Cost costOf) {
    for (int s = 0; s < kSamples; ++s) {
      Film pass(kWidth, kHeight);
      for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) {
          const int block = (y / AdaptiveSplit::kBlock) * (kWidth / AdaptiveSplit::kBlock) + x / AdaptiveSplit::kBlock;
          const float v = value(block, s, x, y);
          pass.addSample(x, y, Rgb(v));
          const size_t p = static_cast<size_t>(y) * kWidth + x;
          for (int c = 0; c < 3; ++c) sumSquares[s & 1][3 * p + c] += v * v;
          count[s & 1][p] += 1.0f;
          cost[p] += costOf(block);
        }
      pass.setPassSpp(1);
      film.addPass(pass);
    }
  }
  int splitAt(const SplitMap& m, int x, int y) const { return m.split.empty() ? 1 : m.split[static_cast<size_t>(y) * kWidth + x]; }
};

// Every pixel reads level(block) x (1 +- noise(block)), the sign alternating over pixels and samples.
template <class Level, class Noise>
auto plusMinusAround(Level level, Noise noise) {
  return [level, noise](int block, int s, int x, int y) { return level(block) * (1.0f + ((s + x + y) % 2 == 0 ? 1.0f : -1.0f) * noise(block)); };
}
// Every pixel reads 1 +- noise(block).
template <class Noise>
auto plusMinus(Noise noise) {
  return plusMinusAround([](int) { return 1.0f; }, noise);
}

TEST(AdaptiveSplit, TheNoisyBlockTakesMoreSamplesAndTheCalmOnesKeepOne) {
  // Block 21 (x 40-47, y 16-23) is noisy.
  const SyntheticFilm f(plusMinus([](int block) { return block == 21 ? 0.9f : 0.05f; }), [](int) { return 100.0f; });
  const SplitMap m = AdaptiveSplit::decide(f.film, f.sumSquares, f.count, f.cost, 8);
  ASSERT_FALSE(m.split.empty()) << m.summary();
  EXPECT_GT(f.splitAt(m, 43, 19), 1) << m.summary();
  EXPECT_EQ(f.splitAt(m, 0, 0), 1) << m.summary();
  EXPECT_EQ(f.splitAt(m, 63, 31), 1) << m.summary();
  EXPECT_GE(std::min(m.predictedMse, m.predictedRelMse), 1.1) << m.summary();
  EXPECT_NE(m.summary().find("camera sample per film sample"), std::string::npos) << m.summary();
}

TEST(AdaptiveSplit, ABlockWhoseSamplesCostMoreTakesFewer) {
  // Two equally noisy blocks, one four times as costly per sample: sqrt(variance / cost) gives it
  // half the samples of the other (or, where the near-best split of least work is kept, none).
  // Blocks 9 (x 8-15, y 8-15) and 13 (x 40-47, y 8-15) are noisy; 13's samples cost four times as much.
  const SyntheticFilm f(plusMinus([](int block) { return block == 9 || block == 13 ? 0.9f : 0.05f; }),
                       [](int block) { return block == 13 ? 400.0f : 100.0f; });
  const SplitMap m = AdaptiveSplit::decide(f.film, f.sumSquares, f.count, f.cost, 16);
  ASSERT_FALSE(m.split.empty()) << m.summary();
  EXPECT_GT(f.splitAt(m, 12, 12), f.splitAt(m, 44, 12)) << m.summary();
}

TEST(AdaptiveSplit, EvenNoiseGivesNoSplit) {
  const SyntheticFilm f(plusMinus([](int) { return 0.5f; }), [](int) { return 100.0f; });
  const SplitMap m = AdaptiveSplit::decide(f.film, f.sumSquares, f.count, f.cost, 8);
  EXPECT_TRUE(m.split.empty()) << m.summary();
  EXPECT_NE(m.summary().find("none"), std::string::npos);
}

TEST(AdaptiveSplit, RareBrightSamplesSpreadEvenlyGiveNoSplit) {
  // Every pixel alike: 1, and 1 sample in 20 reads 40 (a mist's rare bright paths). At 4 samples per
  // pixel some blocks drew more of them than others by chance; a split fitted to that would win on
  // the same samples and lose on the next ones. Cross-validated, it predicts nothing.
  const SyntheticFilm f(
      [](int, int s, int x, int y) {
        Rng rng(hashCombine(static_cast<uint64_t>(y * 64 + x), static_cast<uint64_t>(s)), 3);
        return rng.uniform() < 0.05f ? 40.0f : 1.0f;
      },
      [](int) { return 100.0f; });
  const SplitMap m = AdaptiveSplit::decide(f.film, f.sumSquares, f.count, f.cost, 8);
  EXPECT_TRUE(m.split.empty()) << m.summary();
}

TEST(AdaptiveSplit, ASmallBrightCoreSplitsForMseAlone) {
  // Block 21 (x 40-47, y 16-23) reads 20 +- 18, every other block 1 +- 0.9: any split loses a little
  // relMSE, and two camera samples in that one block halve most of the MSE. Its samples cost 40,
  // the others' 100, so that they add 1.3% to the work (kOneSidedWork).
  const SyntheticFilm f(plusMinusAround([](int block) { return block == 21 ? 20.0f : 1.0f; }, [](int) { return 0.9f; }),
                        [](int block) { return block == 21 ? 40.0f : 100.0f; });
  const SplitMap m = AdaptiveSplit::decide(f.film, f.sumSquares, f.count, f.cost, 8);
  ASSERT_FALSE(m.split.empty()) << m.summary();
  EXPECT_TRUE(m.oneSided);
  EXPECT_GT(f.splitAt(m, 43, 19), 1) << m.summary();
  EXPECT_EQ(f.splitAt(m, 0, 0), 1) << m.summary();
  EXPECT_GE(m.predictedMse, AdaptiveSplit::kOneSidedGain) << m.summary();
  EXPECT_GE(m.predictedRelMse, AdaptiveSplit::kOneSidedFloor) << m.summary();
  EXPECT_LT(m.predictedRelMse, AdaptiveSplit::kMinimumGain) << m.summary();
  EXPECT_DOUBLE_EQ(m.splitShare, 1.0 / 32.0) << m.summary();  // that block alone
  EXPECT_NE(m.summary().find("MSE alone"), std::string::npos) << m.summary();
}

TEST(AdaptiveSplit, ABrightRegionTooLargeForAOneMetricSplitKeepsOne) {
  // A quarter of the blocks read 20 +- 18, the others 1 +- 0.6: two camera samples in the bright
  // blocks predict far less MSE and about as much relMSE (x1.02), but cost 25% more work, more than
  // kOneSidedWork allows, which bounds what relMSE could lose if the prediction were wrong.
  const auto bright = [](int block) { return block % 4 == 1; };
  const SyntheticFilm f(plusMinusAround([=](int block) { return bright(block) ? 20.0f : 1.0f; }, [=](int block) { return bright(block) ? 0.9f : 0.6f; }),
                        [](int) { return 100.0f; });
  const SplitMap m = AdaptiveSplit::decide(f.film, f.sumSquares, f.count, f.cost, 8);
  EXPECT_TRUE(m.split.empty()) << m.summary();
}

TEST(AdaptiveSplit, SamplesWhoseSquaresOverflowGiveNoSplit) {
  const SyntheticFilm f([](int block, int s, int, int) { return block == 3 && s == 0 ? 1e30f : 1.0f; }, [](int) { return 100.0f; });
  const SplitMap m = AdaptiveSplit::decide(f.film, f.sumSquares, f.count, f.cost, 8);
  EXPECT_TRUE(m.split.empty()) << m.summary();
}

// Fire at 96 x 96: the flame's pixels are noisy and costly, the smoke's and the black background's
// calm, so the render splits.
SceneDesc splitFire(int split) {
  return test::loadScene("assets/scenes/fire.json", {"strategy.preset=\"emission\"", "camera.resolution=[96,96]", "render.max_depth=6",
                                                     "strategy.adaptive_split=" + std::to_string(split)});
}

TEST(AdaptiveSplit, ASplitRenderAgreesWithAnUnsplitOne) {
  auto scene = Scene::build(splitFire(8));
  ProgressiveRenderer renderer(scene, RenderOptions{0, 16});
  Film split;
  renderer.renderBudget(split, 256, 0.0, 4);
  const SplitMap* m = renderer.adaptiveSplit();
  ASSERT_NE(m, nullptr);
  ASSERT_FALSE(m->split.empty()) << m->summary();
  EXPECT_EQ(m->decidedAt, AdaptiveSplit::kFirstDecision);
  // Camera samples beyond one per film sample are counted as work.
  EXPECT_GT(renderer.work().samples, uint64_t{256} * 96 * 96) << m->summary();
  const Film plain = test::render(splitFire(1), 1024);
  const Agreement a = compareRenders(plain, split, 4, 4);
  EXPECT_TRUE(a.agree) << a.worst;
  EXPECT_EQ(split.rejectedSamples(), 0u);
}

TEST(AdaptiveSplit, TheSameSeedGivesTheSameImageOnAnyThreadCount) {
  auto scene = Scene::build(splitFire(8));
  ProgressiveRenderer oneThread(scene, RenderOptions{1, 16}), twoThreads(scene, RenderOptions{2, 16});
  Film one, two;
  oneThread.renderBudget(one, 12, 0.0, 4);
  twoThreads.renderBudget(two, 12, 0.0, 4);
  ASSERT_NE(oneThread.adaptiveSplit(), nullptr);
  ASSERT_FALSE(oneThread.adaptiveSplit()->split.empty()) << oneThread.adaptiveSplit()->summary();
  EXPECT_EQ(oneThread.adaptiveSplit()->split, twoThreads.adaptiveSplit()->split);
  EXPECT_EQ(one.sum(), two.sum());
  EXPECT_EQ(one.sumSquares(), two.sumSquares());
}

TEST(AdaptiveSplit, AFreshFilmStartsUnsplit) {
  // The same renderer, a second film: it measures afresh, so the same command gives the same image
  // whatever the renderer rendered before.
  auto scene = Scene::build(splitFire(8));
  ProgressiveRenderer renderer(scene, RenderOptions{0, 16});
  Film first, second;
  renderer.renderBudget(first, 12, 0.0, 4);
  ASSERT_NE(renderer.adaptiveSplit(), nullptr);
  ASSERT_FALSE(renderer.adaptiveSplit()->split.empty());
  renderer.renderBudget(second, 12, 0.0, 4);
  EXPECT_EQ(first.sum(), second.sum());
}

TEST(AdaptiveSplit, AutoSamplesAdaptivelyAndSaysSo) {
  auto scene = Scene::build(test::loadScene("assets/scenes/fire.json", {"strategy.preset=\"auto\"", "camera.resolution=[32,32]"}));
  ASSERT_NE(scene->autoDecision(), nullptr);
  EXPECT_EQ(scene->strategy().adaptive_split, kAutoSplit);
  EXPECT_NE(scene->autoDecision()->summary().find("adaptive sampling"), std::string::npos) << scene->autoDecision()->summary();
  // A preset does not.
  EXPECT_EQ(strategyPreset("full").adaptive_split, 1);
}

}  // namespace
}  // namespace candela
