// Guided distance sampling is unbiased: `full` (probes + one-sample MIS), `equiangular`, probe guiding
// alone (guided_only, no tracked scattering), MIS off (the two techniques averaged), the power
// heuristic, a guided vertex that continues its own path, guiding on every segment, guided
// continuations from medium vertices only (the tracked vertex weighing nothing there; `full` has
// them on thin rays where a sun shines or no volume emits), the balance
// heuristic over both vertices and one-sample MIS in path mode all agree
// with `conventional` on god-rays (side-lit and backlit), torch-in-mist, cloud and a point light
// inside the medium, with the scattering medium's g = 0, 0.9 and -0.9 (docs/method.md s.5).
// The one-sample variants (full, continuations, dim pixels, bright pixels, measured q, path at q = 0.8) read the guided
// vertex's null collisions off the segment's tracked walk and draw fresh ones past its stop (s.4);
// the cloud, where guiding is forced onto thick rays, has most of its guided vertices past the stop.
// Power (checked by injecting a bias into the guided sample's weight in integrator.cpp): a 5% bias
// in the guided contribution fails point-in-mist (z up to 5.7 against a threshold of 4.1), where
// in-scattering from the guided segment dominates the pixels. On god-rays the floor and walls carry
// most of each pixel, so only larger biases in the guided part show there.
#include "stats.h"
#include "test_support.h"

#include <gtest/gtest.h>

namespace candela {
namespace {

struct Case {
  const char* scene;
  int mistIndex;  // the volume whose g is varied
  std::vector<std::string> base;
  int referenceSpp, spp, blocksX, blocksY;
};

const std::vector<std::pair<const char*, std::vector<std::string>>>& variants() {
  static const std::vector<std::pair<const char*, std::vector<std::string>>> v = {
      {"full", {"strategy.preset=\"full\""}},
      {"equiangular", {"strategy.preset=\"equiangular\""}},
      {"guided only", {"strategy.preset=\"full\"", "strategy.guiding.combination=\"guided_only\""}},
      {"MIS off (average)", {"strategy.preset=\"full\"", "strategy.guiding.combination=\"average\""}},
      {"power heuristic, 2 segments",
       {"strategy.preset=\"full\"", "strategy.guiding.combination=\"power\"", "strategy.guiding.guided_segments=2"}},
      // The guided vertex continues a path too (docs/method.md s.4's simplest form) instead of adding only
      // its direct light; and direct-light guiding on every segment of the path.
      {"guided vertex continues (path)", {"strategy.preset=\"full\"", "strategy.guiding.guided_vertex=\"path\""}},
      {"every segment guided", {"strategy.preset=\"full\"", "strategy.guiding.guided_segments=64", "strategy.guiding.secondary_rays=\"all\""}},
      // Guided continuations: the rays leaving a medium vertex guided too, their guided vertex on
      // every such segment (secondary_probability 1: the tracked vertex there weighs nothing). The
      // preset `full` has them on rays up to 0.5 optical depths where no flame alone lights the
      // scene (the first variant); here on every such ray up to 4, in every scene.
      {"continuations from media, q 1",
       {"strategy.preset=\"full\"", "strategy.guiding.secondary_rays=\"from_media\"", "strategy.guiding.secondary_max_optical_depth=4"}},
      // One-sample MIS: one vertex per guided segment, picked at random (guided with probability q).
      {"balance MIS (two vertices)", {"strategy.preset=\"full\"", "strategy.guiding.combination=\"balance\""}},
      // Pixels left to tracking by the probes' prediction (a floor at the image's mean leaves about
      // half of them): a choice by pixel, so the image keeps its expectation.
      {"dim pixels unguided, floor 1", {"strategy.preset=\"full\"", "strategy.guiding.dim_pixel_floor=1"}},
      // q raised by pixel from 0.05 up to 0.99 where the probes predict bright single scattering
      // (camera_guides.h): again a choice by pixel.
      {"bright pixels, q 0.05 to 0.99",
       {"strategy.preset=\"full\"", "strategy.guiding.guided_probability=0.05", "strategy.guiding.bright_pixel_probability=0.99",
        "strategy.guiding.measured_pixel_probability=false"}},
      // q measured by blocks of pixels from 16 samples on (camera_guides.h), here starting from
      // bright pixels' q up to 0.99: a choice made between passes from passes already rendered.
      // (`full` measures too.)
      {"measured q, from bright pixels up to 0.99",
       {"strategy.preset=\"full\"", "strategy.guiding.guided_probability=0.05", "strategy.guiding.bright_pixel_probability=0.99"}},
      {"one-sample MIS, path, q = 0.8",
       {"strategy.preset=\"full\"", "strategy.guiding.combination=\"one_sample\"", "strategy.guiding.guided_vertex=\"path\"",
        "strategy.guiding.guided_probability=0.8"}},
  };
  return v;
}

class GuidingAgreement : public ::testing::TestWithParam<std::tuple<int, const char*>> {};

TEST_P(GuidingAgreement, EveryGuidedVariantAgreesWithConventional) {
  static const std::vector<Case> cases = {
      {"assets/scenes/god-rays.json", 0, {"camera.resolution=[24,12]", "render.max_depth=4"}, 4096, 1024, 4, 2},
      {"assets/scenes/test/point-in-mist.json", 0, {"camera.resolution=[24,12]"}, 16384, 4096, 4, 2},
      // Guiding forced on every ray of the thick cloud (by default it skips rays thicker than 4).
      {"assets/scenes/cloud.json", 0, {"camera.resolution=[24,12]", "render.max_depth=16", "strategy.guiding.max_optical_depth=0"}, 1024, 256, 4, 2},
      {"assets/scenes/torch-in-mist.json", 1, {"camera.resolution=[16,9]", "render.max_depth=4"}, 32768, 2048, 2, 1},
      {"assets/scenes/god-rays-backlit.json", 0, {"camera.resolution=[24,12]", "render.max_depth=4"}, 4096, 1024, 4, 2},
  };
  const Case& c = cases[static_cast<size_t>(std::get<0>(GetParam()))];
  const std::string g = std::get<1>(GetParam());
  auto desc = [&](const std::vector<std::string>& extra, uint32_t seed) {
    // Conventional unless the variant names a preset (the shipped scenes name auto).
    std::vector<std::string> sets = {"strategy.preset=\"conventional\""};
    sets.insert(sets.end(), c.base.begin(), c.base.end());
    sets.push_back("volumes." + std::to_string(c.mistIndex) + ".g=" + g);
    sets.insert(sets.end(), extra.begin(), extra.end());
    sets.push_back("render.seed=" + std::to_string(seed));
    return test::loadScene(c.scene, sets);
  };
  const Film reference = test::render(desc({}, 100), c.referenceSpp);
  uint32_t seed = 1;
  for (const auto& [name, settings] : variants()) {
    const Film film = test::render(desc(settings, seed++), c.spp);
    const Agreement a = compareRenders(reference, film, c.blocksX, c.blocksY);
    EXPECT_TRUE(a.agree) << c.scene << ", g = " << g << ", " << name << ": " << a.worst;
    EXPECT_EQ(film.rejectedSamples(), 0u) << name;
    if (std::getenv("CANDELA_VERBOSE"))
      std::printf("%s g=%s %-28s max z %.2f (threshold %.2f)\n", c.scene, g.c_str(), name, a.maxAbsZ, a.threshold);
  }
}

std::string caseName(const ::testing::TestParamInfo<std::tuple<int, const char*>>& info) {
  static const char* names[] = {"GodRays", "PointInMist", "Cloud", "TorchInMist", "GodRaysBacklit"};
  std::string g = std::get<1>(info.param);
  for (char& ch : g) ch = ch == '-' ? 'm' : ch == '.' ? 'p' : ch;
  return std::string(names[std::get<0>(info.param)]) + "_g" + g;
}

INSTANTIATE_TEST_SUITE_P(ScenesAndAnisotropies, GuidingAgreement,
                         ::testing::Combine(::testing::Values(0, 1, 2, 3, 4), ::testing::Values("0", "0.9", "-0.9")), caseName);

}  // namespace
}  // namespace candela
