// The stability suite (assets/scenes/stability/cases.json): where a method is known to be weak, every
// preset must still agree with conventional, and no NaN or Inf may reach the film.
//
// Power: each case prints the bias it can detect: the median over 2x2 regions and channels of the
// Bonferroni threshold times the combined standard error, relative to the mean (conventional at 4096
// spp, the others at 1024, 48x27 pixels). Measured: 0.1-0.9% for the thin fire, thick cloud, holes,
// invalid voxels, tiny grid and huge sparse field; 3-5% for the point light inside the medium and the
// probe-radius cases (god-rays); 8-19% for g = +-0.95 and the emission-weight cases (torch-in-mist),
// where conventional's fireflies dominate the variance. Those need far more conventional samples to
// catch a 2% bias; the closing note of the report issue says so.
#include "stability.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cstdio>

namespace candela {
namespace {

class Stability : public testing::TestWithParam<StabilityCase> {};

std::vector<StabilityCase> cases() { return loadStabilityCases(test::assetPath("assets/scenes/stability/cases.json")); }

TEST_P(Stability, EveryPresetAgreesWithConventionalAndTheFilmStaysFinite) {
  const StabilityCase& c = GetParam();
  // Conventional is cheap per sample and the noisier side in most cases: it gets 4x the samples.
  constexpr int kSpp = 1024;
  Film conventional;
  const StabilityResult base = runStability(c, "conventional", 4 * kSpp, nullptr, &conventional);
  EXPECT_EQ(base.rejected, 0u) << c.name << ": conventional";
  for (const char* preset : {"emission", "full", "equiangular"}) {
    const StabilityResult r = runStability(c, preset, kSpp, &conventional);
    std::printf("%-20s %-12s agree %-3s |z| %5.2f (threshold %4.2f)  detectable bias %5.2f%%  rejected %llu  rel. variance %8.3g  max sample %8.3g  %.1f s\n",
                c.name.c_str(), preset, r.agrees ? "yes" : "NO", r.maxAbsZ, r.threshold, 100.0 * r.detectableBias,
                static_cast<unsigned long long>(r.rejected), r.relativeVariance, r.maxSample, r.seconds);
    EXPECT_TRUE(r.agrees) << c.name << " " << preset << ": |z| " << r.maxAbsZ << " > " << r.threshold;
    EXPECT_EQ(r.rejected, 0u) << c.name << " " << preset;
  }
  if (c.name == "invalid-voxels") {
    ASSERT_FALSE(base.warnings.empty());
    EXPECT_NE(base.warnings.front().find("NaN, infinite or negative"), std::string::npos) << base.warnings.front();
  }
}

INSTANTIATE_TEST_SUITE_P(Cases, Stability, testing::ValuesIn(cases()),
                         [](const testing::TestParamInfo<StabilityCase>& info) {
                           std::string n = info.param.name;
                           for (char& ch : n)
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           return n;
                         });

}  // namespace
}  // namespace candela
