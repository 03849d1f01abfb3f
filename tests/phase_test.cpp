// The HG sampler's directions follow its pdf (chi-square over a (cos theta, phi) histogram), and the
// pdf integrates to one.
#include "phase.h"
#include "rng.h"
#include "stats.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace candela {
namespace {

// P(cos theta <= c) for HG in this codebase's convention (integral of 2 pi hgPhase over [-1, c]).
double hgCosineCdf(double c, double g) {
  if (std::abs(g) < 1e-6) return 0.5 * (1.0 + c);
  return (1.0 - g * g) / (2.0 * g) * (1.0 / (1.0 - g) - 1.0 / std::sqrt(1.0 + g * g + 2.0 * g * c));
}

// The pdf itself integrates to one (midpoint rule over cos theta, fine enough for g = 0.95).
TEST(HgPhase, IntegratesToOne) {
  for (float g : {-0.95f, -0.3f, 0.0f, 0.5f, 0.95f}) {
    double total = 0.0;
    constexpr int kSteps = 200000;
    for (int i = 0; i < kSteps; ++i) total += 2.0 * kPi * hgPhase(static_cast<float>(-1.0 + (i + 0.5) * 2.0 / kSteps), g) * 2.0 / kSteps;
    EXPECT_NEAR(total, 1.0, 1e-3) << "g = " << g;
    EXPECT_NEAR(hgCosineCdf(1.0, g), 1.0, 1e-9);
  }
}

class HgSampling : public ::testing::TestWithParam<float> {};

TEST_P(HgSampling, HistogramMatchesPdf) {
  const float g = GetParam();
  const Vec3 wo = glm::normalize(Vec3(0.3f, -0.5f, 0.8f));
  Vec3 t, b;
  orthonormalBasis(wo, t, b);
  constexpr int kCos = 24, kPhi = 8, kSamples = 400000;
  std::vector<double> observed(kCos * kPhi, 0.0);
  Rng rng(42, static_cast<uint64_t>((g + 2.0f) * 1000));
  for (int i = 0; i < kSamples; ++i) {
    float pdf;
    const Vec3 wi = hgSample(wo, g, Vec2(rng.uniform(), rng.uniform()), pdf);
    ASSERT_NEAR(glm::length(wi), 1.0f, 1e-4f);
    ASSERT_NEAR(pdf, hgEval(wo, wi, g), 1e-3f * pdf + 1e-6f);
    const float c = glm::clamp(glm::dot(wi, wo), -1.0f, 1.0f);
    float phi = std::atan2(glm::dot(wi, b), glm::dot(wi, t));
    if (phi < 0.0f) phi += 2.0f * kPi;
    const int ci = std::min(kCos - 1, static_cast<int>((c + 1.0f) * 0.5f * kCos));
    const int pi = std::min(kPhi - 1, static_cast<int>(phi / (2.0f * kPi) * kPhi));
    observed[ci * kPhi + pi] += 1.0;
  }
  // Expected counts: integrate the pdf over each bin (midpoint rule on a fine sub-grid).
  double chi2 = 0.0, total = 0.0;
  int dof = -1;
  double pooledObs = 0.0, pooledExp = 0.0;
  for (int ci = 0; ci < kCos; ++ci) {
    // Probability of the cos-theta bin from the analytic CDF of HG, split evenly over phi bins.
    const double c0 = -1.0 + 2.0 * ci / kCos, c1 = -1.0 + 2.0 * (ci + 1) / kCos;
    const double binProb = (hgCosineCdf(c1, g) - hgCosineCdf(c0, g)) / kPhi;
    total += binProb * kPhi;
    for (int pi = 0; pi < kPhi; ++pi) {
      const double expected = binProb * kSamples;
      if (expected < 5.0) {
        pooledObs += observed[ci * kPhi + pi];
        pooledExp += expected;
        continue;
      }
      const double d = observed[ci * kPhi + pi] - expected;
      chi2 += d * d / expected;
      ++dof;
    }
  }
  if (pooledExp >= 5.0) {
    chi2 += (pooledObs - pooledExp) * (pooledObs - pooledExp) / pooledExp;
    ++dof;
  }
  EXPECT_NEAR(total, 1.0, 1e-9);
  EXPECT_LT(chi2, test::chiSquareCritical(dof, 1e-4)) << "g = " << g << ", dof = " << dof;
}

INSTANTIATE_TEST_SUITE_P(Anisotropies, HgSampling, ::testing::Values(-0.95f, -0.5f, 0.0f, 0.3f, 0.8f, 0.95f));

TEST(HgPhase, ForwardScatteringPeaksWhenLightContinuesStraight) {
  const Vec3 wo(0.0f, 0.0f, 1.0f);
  // g > 0: light arriving from -wo (travelling along wo) continues to the viewer: the peak.
  EXPECT_GT(hgEval(wo, -wo, 0.8f), hgEval(wo, wo, 0.8f));
  EXPECT_NEAR(hgEval(wo, Vec3(1, 0, 0), 0.0f), kInv4Pi, 1e-7f);
}

}  // namespace
}  // namespace candela
