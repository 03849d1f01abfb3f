// The stability suite (assets/scenes/stability/cases.json): where a method is known to be weak, every
// preset must still agree with conventional, and no NaN or Inf may reach the film.
//
// Power: each comparison computes the bias it can detect: the median, over the 2x2 regions and
// channels that carry signal, of the Bonferroni threshold (alpha 1e-3) times the combined standard
// error, relative to the mean. Conventional renders 4x the samples of the others (4096 against 1024
// spp at 48x27 or 48x48 pixels; heavy-tailed cases scale both by their spp_scale). Measured: at most
// 1.7% for every case and preset (0.06% thin fire ... 1.7% probe radius) and the test asserts < 2%,
// with one exception it asserts and explains: a point light inside the medium with the emission
// preset (no equi-angular sampling). Its next-event estimate has infinite variance (1/d^2 at the
// light with transmittance-proportional distances), so its standard error does not shrink as
// 1/sqrt(N): 4.8% at 1024 spp, 4.5% at 6144. That is the failure this case exists to show;
// equi-angular sampling (equiangular 1.7-1.9%) removes it. The `full` preset shares it: its
// probe-guided vertex is drawn on one camera segment in ten (one-sample MIS), and on the other nine
// the tracked vertex takes that same next-event estimate. Its detectable bias moves with the random
// stream, 1.6-2.4% (its variance per sample over seeds 1-12 at 48x27: 0.09 to 23), as auto's does
// when it chooses emission. Equi-angular sampling removes the singularity from the camera ray's
// vertex only (guided_segments = 1): the vertices after it take the same next-event estimate, so
// its detectable bias moves with the stream too, less: 1.7% with random sub-pixel positions, 2.3%
// with the stratified ones, which draw different random numbers (its variance per sample over seeds
// 1-6 at 96x54, 512 spp: 11-45 before, 9-50 after). It is held to 4%, the others to 6%.

#include "stability.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <ostream>

namespace candela {
namespace {

class Stability : public testing::TestWithParam<StabilityCase> {};

}  // namespace

// gtest prints a parameter in test listings: the case's name, not its bytes.
void PrintTo(const StabilityCase& c, std::ostream* os) { *os << c.name; }

namespace {

std::vector<StabilityCase> cases() { return loadStabilityCases(test::assetPath("assets/scenes/stability/cases.json")); }

TEST_P(Stability, EveryPresetAgreesWithConventionalAndTheFilmStaysFinite) {
  const StabilityCase& c = GetParam();
  // Conventional is cheap per sample and the noisier side in most cases: it gets 4x the samples.
  constexpr int kSpp = 1024;
  Film conventional;
  const int spp = kSpp * c.sppScale;
  const StabilityResult base = runStability(c, "conventional", 4 * spp, nullptr, &conventional);
  EXPECT_EQ(base.rejected, 0u) << c.name << ": conventional";
  for (const char* preset : {"emission", "full", "equiangular", "auto"}) {
    const StabilityResult r = runStability(c, preset, spp, &conventional);
    std::printf("%-20s %-12s agree %-3s |z| %5.2f (threshold %4.2f)  detectable bias %5.2f%%  rejected %llu  rel. variance %8.3g  max sample %8.3g  %.1f s\n",
                c.name.c_str(), preset, r.agrees ? "yes" : "NO", r.maxAbsZ, r.threshold, 100.0 * r.detectableBias,
                static_cast<unsigned long long>(r.rejected), r.relativeVariance, r.maxSample, r.seconds);
    EXPECT_TRUE(r.agrees) << c.name << " " << preset << ": |z| " << r.maxAbsZ << " > " << r.threshold;
    // auto may choose emission there too; full keeps the tracked vertex on nine segments in ten.
    const std::string p = preset;
    const bool pointLight = c.name == "point-light-inside";
    const bool infiniteVariance = pointLight && (p == "emission" || p == "full" || p == "auto");
    const double power = infiniteVariance ? 0.06 : pointLight && p == "equiangular" ? 0.04 : 0.02;
    EXPECT_LT(r.detectableBias, power) << c.name << " " << preset << ": the test lacks the power to catch a " << 100.0 * power << "% bias";
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
