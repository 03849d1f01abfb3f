// The equal-time comparison session, headless: interleaved slices give every pane the same time, the
// error series falls as spp rises, unbiased strategies agree with each other, bad references fail
// with a clear message.
#include "comparison_session.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

namespace candela {
namespace {

std::shared_ptr<const ComparisonFrame> waitUntilDone(ComparisonSession& session, double limit, double timeout = 60.0) {
  const auto start = std::chrono::steady_clock::now();
  while (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() < timeout) {
    auto f = session.latest();
    if (f && !f->panes.empty() && f->status.empty()) {
      bool done = true;
      for (const auto& p : f->panes) done = done && p.seconds >= limit;
      if (done) return f;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return nullptr;
}

TEST(Comparison, PanesGetEqualTimeAndTheirErrorFalls) {
  const SceneDesc desc = test::loadScene("assets/scenes/test/glow-box.json", {"camera.resolution=[64,36]"});
  Image reference;
  reference.width = 64;
  reference.height = 36;
  reference.rgb = test::render(desc, 512).meanImage();
  ComparisonSession session;
  session.start(desc, {{"conventional", strategyPreset("conventional")}, {"emission", strategyPreset("emission")}, {"full", strategyPreset("full")}},
                reference, 0, {}, 1.5);
  auto frame = waitUntilDone(session, 1.5);
  ASSERT_TRUE(frame);
  ASSERT_EQ(frame->panes.size(), 3u);
  double lo = 1e9, hi = 0.0, hiStart = 0.0;
  for (const auto& p : frame->panes) {
    lo = std::min(lo, p.seconds);
    if (p.seconds > hi) hi = p.seconds, hiStart = p.seconds - p.lastSlice;
    ASSERT_TRUE(p.film);
    EXPECT_GT(p.film->spp(), 0);
    ASSERT_GE(p.series.size(), 3u) << p.label;
    for (size_t i = 1; i < p.series.size(); ++i) EXPECT_GT(p.series[i].spp, p.series[i - 1].spp);
    EXPECT_LT(p.series.back().relmse, p.series.front().relmse) << p.label;
    EXPECT_GT(p.efficiency(), 0.0);
  }
  // Equal time to within one slice, as the scheduler guarantees on an idle or a busy machine: the
  // pane with the most time had no more than the least when its last pass began.
  EXPECT_LE(hiStart, lo + 1e-9) << lo << " .. " << hi << ", last pass began at " << hiStart;
  const std::string csv = comparisonCsv(*frame);
  EXPECT_NE(csv.find("pane,seconds,spp,mse,relmse,efficiency"), std::string::npos);
  EXPECT_NE(csv.find("\nfull,"), std::string::npos);
}

TEST(Comparison, UnbiasedStrategiesAgree) {
  const SceneDesc desc = test::loadScene("assets/scenes/test/slab.json", {"camera.resolution=[32,32]"});
  ComparisonSession session;
  session.start(desc, {{"conventional", strategyPreset("conventional")}, {"emission", strategyPreset("emission")}}, {}, 0, {}, 1.5);
  auto frame = waitUntilDone(session, 1.5);
  ASSERT_TRUE(frame);
  for (const auto& p : frame->panes) {
    EXPECT_TRUE(p.agreementTested) << p.label;
    EXPECT_TRUE(p.agreement.agree) << p.label << ": " << p.agreement.worst;
    ASSERT_FALSE(p.series.empty()) << "no reference: the pane's own error estimate";
    for (const auto& e : p.series) EXPECT_TRUE(e.estimated) << p.label;
  }
}

// Without a reference a pane's error is its own estimate, sample variance / spp: for an unbiased
// render that is its expected MSE, so it matches the error measured against a reference of many
// more samples (whose own error adds about spp / 4096 of the estimate).
TEST(Comparison, TheOwnErrorEstimateMatchesTheMeasuredError) {
  const SceneDesc desc = test::loadScene("assets/scenes/test/slab.json", {"camera.resolution=[32,32]"});
  SceneDesc refDesc = desc;
  refDesc.render.seed = 99;
  const std::vector<float> reference = test::render(refDesc, 4096).meanImage();
  ComparisonSession session;
  session.start(desc, {{"emission", strategyPreset("emission")}}, {}, 0, {}, 0.5);
  auto frame = waitUntilDone(session, 0.5);
  ASSERT_TRUE(frame);
  const PaneState& p = frame->panes[0];
  ASSERT_TRUE(p.film && !p.series.empty());
  const ErrorMetrics measured = imageError(p.film->meanImage(), reference);
  const ErrorSample& estimate = p.series.back();
  ASSERT_EQ(estimate.spp, p.film->spp());
  // The measured error holds the reference's own too: spp / 4096 of the pane's, both unbiased.
  const double withReference = 1.0 + estimate.spp / 4096.0;
  EXPECT_NEAR(estimate.mse * withReference / measured.mse, 1.0, 0.25) << "at " << estimate.spp << " spp";
  EXPECT_NEAR(estimate.relmse * withReference / measured.relmse, 1.0, 0.25) << "at " << estimate.spp << " spp";
}

// Titles in words; auto's names what it chose.
TEST(Comparison, PaneTitlesInWords) {
  PaneState p;
  p.label = "full";
  p.strategy = strategyPreset("full");
  EXPECT_EQ(paneTitle(p), "emission + scattering sampling");
  p.label = "full*";
  EXPECT_EQ(paneTitle(p), "emission + scattering sampling (edited)");
  p.label = "auto";
  p.strategy = strategyPreset("auto");
  EXPECT_EQ(paneTitle(p), "auto: choosing");
  p.preparing = false;
  p.autoChoice = "conventional, gathering";
  EXPECT_EQ(paneTitle(p), "auto: chose tracking only (gathering)");
}

// A biased pane is the odd one out: two independent renders of the slab agree with each other, and a
// render of a slightly different slab (standing in for a biased estimator) disagrees with both.
TEST(Comparison, ABiasedPaneIsTheOddOneOut) {
  const SceneDesc desc = test::loadScene("assets/scenes/test/slab.json", {"camera.resolution=[32,32]"});
  const Film a = test::render(desc, 128);
  SceneDesc other = desc;
  other.render.seed = 7;
  const Film b = test::render(other, 128);
  other.render.seed = 11;
  other.volumes[0].sigma_t_scale *= 1.3f;  // transmittance e^-1.3 against e^-1: about 7 standard errors per 4x4-pixel region at 128 spp
  const Film biased = test::render(other, 128);
  const auto fair = paneAgreement({&a, &b});
  EXPECT_TRUE(fair[0].agree && fair[1].agree) << fair[0].worst;
  const auto three = paneAgreement({&a, &b, &biased});
  EXPECT_TRUE(three[0].agree) << three[0].worst;
  EXPECT_TRUE(three[1].agree) << three[1].worst;
  EXPECT_FALSE(three[2].agree) << "the biased render must be flagged";
  EXPECT_NE(three[2].worst.find("pane "), std::string::npos);
  // Below the minimum spp nothing is tested.
  const Film few = test::render(desc, 4);
  EXPECT_EQ(paneAgreement({&few, &a})[0].tests, 0);
}

TEST(Comparison, AReferenceOfTheWrongSizeIsAClearError) {
  const SceneDesc desc = test::loadScene("assets/scenes/test/slab.json", {"camera.resolution=[32,32]"});
  Image reference;
  reference.width = 10;
  reference.height = 10;
  reference.rgb.assign(300, 0.5f);
  ComparisonSession session;
  session.start(desc, {{"conventional", strategyPreset("conventional")}}, reference);
  std::vector<std::string> messages;
  for (int i = 0; i < 2000 && messages.empty(); ++i) {
    messages = session.takeMessages();
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_FALSE(messages.empty());
  EXPECT_NE(messages.front().find("expected a 32x32 image, got 10x10"), std::string::npos) << messages.front();
}

}  // namespace
}  // namespace candela
