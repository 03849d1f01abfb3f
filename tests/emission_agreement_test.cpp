// Emission sampling is unbiased: every setting converges to the conventional image (docs/method.md s.5).
// Each scene is rendered once with `conventional` and then with the emission preset and with each
// emission part on its own, with emission weights 0, 1 and huge, the cap on and off, global and grid
// majorants. Regions are compared by a Bonferroni-corrected z-test (alpha 1e-3 per comparison).
// Power (checked by injecting biases into integrator.cpp): a 2% bias in gathered emission fails the
// glow-box and closed-form slab tests; a 10% bias in the volume-NEE term alone (about 3% of the
// pixels it lights) fails glow-box, a large emitter lighting a scattering volume and a floor where
// conventional tracking is well-behaved. A 10% bias in the weight of upward continuations toward
// emissive volumes (docs/method.md s.3b) fails glow-box (per-unit-length) and torch-in-mist. A 10% bias in
// the emission gathered past the scattering (s.2) fails both glow-box tests on all rays. On fire and
// torch-in-mist conventional's estimate of a small bright flame is heavy-tailed, so those tests only
// catch gross (~10%+) biases at CI budgets.
#include "blackbody.h"
#include "stats.h"
#include "test_support.h"

#include <gtest/gtest.h>

namespace candela {
namespace {

struct Variant {
  const char* name;
  std::vector<std::string> settings;
};

const std::vector<Variant>& variants() {
  static const std::vector<Variant> v = {
      {"emission preset", {"strategy.preset=\"emission\""}},
      {"k=0", {"strategy.preset=\"emission\"", "strategy.majorant.emission_weight=0"}},
      {"k=huge, cap on", {"strategy.preset=\"emission\"", "strategy.majorant.emission_weight=1e6", "strategy.majorant.emission_cap=1"}},
      {"k=10, cap off", {"strategy.preset=\"emission\"", "strategy.majorant.emission_weight=10", "strategy.majorant.emission_cap=0"}},
      {"global majorant", {"strategy.preset=\"emission\"", "strategy.majorant.structure=\"global\""}},
      {"gathering only", {"strategy.emission.gather_every_collision=true"}},
      {"volume NEE only", {"strategy.emission.light_sampling=true", "strategy.emission.grid_cell_size=8"}},
      {"majorant term only", {"strategy.majorant.emission_term=true", "strategy.majorant.emission_weight=1e6"}},
      // docs/method.md s.3b: continuations aimed at the volumes, at the largest share and not at all.
      {"continuations toward volumes", {"strategy.emission.light_sampling=true", "strategy.emission.continuation_toward_volumes=0.9"}},
      {"emission preset, phase continuations", {"strategy.preset=\"emission\"", "strategy.emission.continuation_toward_volumes=0"}},
      // docs/method.md s.2, "Emission past the scattering": on every segment, and on camera rays
      // without light sampling (the continued estimate then carries all the emission).
      {"emission preset, past scattering on all rays", {"strategy.preset=\"emission\"", "strategy.emission.gather_past_scattering=\"all_rays\""}},
      {"gathering only, past scattering on camera rays",
       {"strategy.emission.gather_every_collision=true", "strategy.emission.gather_past_scattering=\"camera_rays\""}},
  };
  return v;
}

SceneDesc variantScene(const std::string& scene, const std::vector<std::string>& base, const std::vector<std::string>& extra,
                       uint32_t seed) {
  // Conventional unless the variant names a preset (the shipped scenes name auto).
  std::vector<std::string> sets = {"strategy.preset=\"conventional\""};
  sets.insert(sets.end(), base.begin(), base.end());
  sets.insert(sets.end(), extra.begin(), extra.end());
  sets.push_back("render.seed=" + std::to_string(seed));
  return test::loadScene(scene, sets);
}

// `referenceSpp` for conventional, `spp` for each variant: conventional's estimate of emission from a
// small bright flame is heavy-tailed (rare absorptions in the flame carry huge weights), so it needs
// many more samples before its standard error can be trusted.
void expectAgreement(const std::string& scene, const std::vector<std::string>& base, int referenceSpp, int spp, int blocksX,
                     int blocksY) {
  const Film reference = test::render(variantScene(scene, base, {}, 100), referenceSpp);
  uint32_t seed = 1;
  for (const Variant& v : variants()) {
    const Film film = test::render(variantScene(scene, base, v.settings, seed++), spp);
    const Agreement a = compareRenders(reference, film, blocksX, blocksY);
    EXPECT_TRUE(a.agree) << scene << ", " << v.name << ": " << a.worst;
    if (std::getenv("CANDELA_VERBOSE")) std::printf("%-20s max z %.2f (threshold %.2f) max rel %.4f\n", v.name, a.maxAbsZ, a.threshold, a.maxRelativeDifference);
    EXPECT_EQ(film.rejectedSamples(), 0u) << v.name;
  }
}

TEST(EmissionAgreement, GlowBox) { expectAgreement("assets/scenes/test/glow-box.json", {}, 16384, 4096, 4, 2); }

// Emission per unit length from an emitter that absorbs nothing (albedo 1): the analog walk gathers it
// at every collision, the others as usual; all agree.
TEST(EmissionAgreement, GlowBoxPerUnitLengthAlbedoOne) {
  expectAgreement("assets/scenes/test/glow-box.json", {"volumes.0.emission.units=\"per_length\"", "volumes.0.albedo=[1,1,1]"}, 16384, 4096,
                  4, 2);
}

TEST(EmissionAgreement, Fire) { expectAgreement("assets/scenes/fire.json", {"camera.resolution=[24,24]"}, 2048, 1024, 3, 3); }

TEST(EmissionAgreement, TorchInMist) {
  expectAgreement("assets/scenes/torch-in-mist.json", {"camera.resolution=[16,9]", "render.max_depth=4"}, 32768, 4096, 2, 1);
}

TEST(EmissionAgreement, EmissionSlabClosedForm) {
  const std::string scene = "assets/scenes/test/emission-slab.json";
  const Rgb le = blackbody()(1500.0f);
  uint32_t seed = 1;
  for (const Variant& v : variants()) {
    const SceneDesc desc = variantScene(scene, {}, v.settings, seed++);
    auto built = Scene::build(desc);
    const Film film = test::render(desc, 256);
    std::vector<Rgb> expected;
    const Camera& cam = built->camera();
    for (int by = 0; by < 4; ++by)
      for (int bx = 0; bx < 4; ++bx) {
        Rgb sum(0.0f);
        int n = 0;
        for (int y = by * cam.height() / 4; y < (by + 1) * cam.height() / 4; ++y)
          for (int x = bx * cam.width() / 4; x < (bx + 1) * cam.width() / 4; ++x, ++n)
            sum += le * (1.0f - std::exp(1.0f / cam.generate(x + 0.5f, y + 0.5f).direction.z));
        expected.push_back(sum / static_cast<float>(n));
      }
    const Agreement a = compareToExpected(film, 4, 4, expected);
    EXPECT_TRUE(a.agree) << v.name << ": " << a.worst;
    EXPECT_LT(a.maxRelativeDifference, 0.03) << v.name;
  }
}

}  // namespace
}  // namespace candela
