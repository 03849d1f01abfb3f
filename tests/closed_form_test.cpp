// Closed forms (docs/method.md s.5): transmittance through a homogeneous slab and a linear density ramp
// (ratio tracking and delta tracking, every majorant policy); an emission-only slab
// L = Le (1 - exp(-tau)); and a white furnace that must return the environment radiance exactly.
#include "blackbody.h"
#include "stats.h"
#include "test_support.h"
#include "tracking.h"

#include <gtest/gtest.h>

namespace candela {
namespace {

struct Estimate {
  double mean = 0.0, standardError = 0.0;
};

// Mean and standard error of ratio-tracking and delta-tracking (escape probability) estimates.
void estimateTransmittance(const Scene& scene, const Ray& ray, float distance, Estimate& ratio, Estimate& delta) {
  constexpr int kRuns = 40000;
  Rng rng(11, 5);
  double s = 0, s2 = 0, escapes = 0;
  for (int i = 0; i < kRuns; ++i) {
    const double t = ratioTrackingTransmittance(scene.media(), ray, distance, rng);
    s += t;
    s2 += t * t;
    const bool escaped = trackCollisions(scene.media(), ray, distance, rng, [&](const Collision& c) {
      return rng.uniform() * c.muBar >= c.sigmaTTotal;  // real collision (any kind) stops the walk
    });
    escapes += escaped ? 1.0 : 0.0;
  }
  ratio.mean = s / kRuns;
  ratio.standardError = std::sqrt(std::max(0.0, s2 / kRuns - ratio.mean * ratio.mean) / kRuns);
  delta.mean = escapes / kRuns;
  delta.standardError = std::sqrt(delta.mean * (1.0 - delta.mean) / kRuns);
}

const std::vector<std::string> kPolicies[] = {
    {"strategy.majorant.structure=\"global\""},
    {"strategy.majorant.structure=\"grid\"", "strategy.majorant.cell_size=1", "strategy.majorant.coarsen_thin=false"},
    {"strategy.majorant.structure=\"grid\"", "strategy.majorant.cell_size=8", "strategy.majorant.coarsen_thin=false"},
    {"strategy.majorant.structure=\"grid\"", "strategy.majorant.cell_size=1", "strategy.majorant.coarsen_thin=true"},
    {"strategy.majorant.safety_factor=3.0"},
};

TEST(ClosedForm, HomogeneousSlabTransmittance) {
  for (const auto& policy : kPolicies) {
    auto scene = Scene::build(test::loadScene("assets/scenes/test/slab.json", policy));
    // Straight through the slab along -z: optical depth sigma_t * density * thickness = 2 * 1 * 0.5.
    const Ray ray{Vec3(0.1f, -0.2f, 3.0f), Vec3(0.0f, 0.0f, -1.0f)};
    Estimate ratio, delta;
    estimateTransmittance(*scene, ray, 10.0f, ratio, delta);
    const double expected = std::exp(-1.0);
    EXPECT_NEAR(ratio.mean, expected, 5.0 * ratio.standardError + 1e-4) << policy[0];
    EXPECT_NEAR(delta.mean, expected, 5.0 * delta.standardError + 1e-4) << policy[0];
    // Stopping inside the slab, a quarter of the way through: tau = 0.25.
    estimateTransmittance(*scene, ray, 3.0f - 0.125f, ratio, delta);
    EXPECT_NEAR(ratio.mean, std::exp(-0.25), 5.0 * ratio.standardError + 1e-4);
    EXPECT_NEAR(delta.mean, std::exp(-0.25), 5.0 * delta.standardError + 1e-4);
  }
}

TEST(ClosedForm, LinearRampTransmittance) {
  // density rises linearly from 0 at voxel 0 to `value` at voxel 63 along x: tau(s) = k s^2 / 2.
  SceneDesc desc = test::loadScene("assets/scenes/test/slab.json");
  VolumeDesc& v = desc.volumes[0];
  v.generator.type = "ramp";
  v.generator.resolution = 64;
  v.generator.size = Vec3(2.0f, 1.0f, 1.0f);
  v.generator.value = 1.0f;
  v.sigma_t_scale = 3.0f;
  for (const auto& policy : kPolicies) {
    desc.strategy.majorant = MajorantPolicy{};
    SceneDesc edited = parseSceneDesc([&] {
      Json doc = sceneToJson(desc);
      for (const auto& s : policy) applySetting(doc, s, "test");
      return doc;
    }(), "ramp");
    auto scene = Scene::build(edited);
    const float voxel = 2.0f / 64.0f;
    const float x0 = -1.0f + 0.5f * voxel;       // centre of voxel 0, where the ramp starts
    const float yz = -0.5f + 16.5f * voxel;      // a voxel centre in y and z: no interpolation across
    const Ray ray{Vec3(x0 - 0.3f, yz, yz), Vec3(1.0f, 0.0f, 0.0f)};
    const float slope = 3.0f * 1.0f / (63.0f * voxel);  // sigma_t per world unit, per world unit
    for (float s : {0.5f, 1.0f, 1.5f, 1.9f}) {
      Estimate ratio, delta;
      estimateTransmittance(*scene, ray, 0.3f + s, ratio, delta);
      const double expected = std::exp(-0.5 * slope * s * s);
      EXPECT_NEAR(ratio.mean, expected, 5.0 * ratio.standardError + 1e-4) << "s = " << s << " " << policy[0];
      EXPECT_NEAR(delta.mean, expected, 5.0 * delta.standardError + 1e-4) << "s = " << s << " " << policy[0];
    }
  }
}

// Expected region means for the slab camera: f(cos theta) per pixel centre, averaged per region.
std::vector<Rgb> slabExpectation(const Scene& scene, int blocks, const std::function<Rgb(float)>& radiance) {
  const Camera& cam = scene.camera();
  std::vector<Rgb> out;
  for (int by = 0; by < blocks; ++by)
    for (int bx = 0; bx < blocks; ++bx) {
      Rgb sum(0.0f);
      int n = 0;
      for (int y = by * cam.height() / blocks; y < (by + 1) * cam.height() / blocks; ++y)
        for (int x = bx * cam.width() / blocks; x < (bx + 1) * cam.width() / blocks; ++x) {
          const Ray r = cam.generate(x + 0.5f, y + 0.5f);
          sum += radiance(-r.direction.z);
          ++n;
        }
      out.push_back(sum / static_cast<float>(n));
    }
  return out;
}

TEST(ClosedForm, AbsorbingSlabImage) {
  const SceneDesc desc = test::loadScene("assets/scenes/test/slab.json");
  auto scene = Scene::build(desc);
  const Film film = test::render(desc, 256);
  const auto expected = slabExpectation(*scene, 4, [](float cosTheta) { return Rgb(std::exp(-1.0f / cosTheta)); });
  const Agreement a = compareToExpected(film, 4, 4, expected);
  EXPECT_TRUE(a.agree) << a.worst;
  EXPECT_LT(a.maxRelativeDifference, 0.06);
}

TEST(ClosedForm, EmissionOnlySlab) {
  const SceneDesc desc = test::loadScene("assets/scenes/test/emission-slab.json");
  auto scene = Scene::build(desc);
  const Film film = test::render(desc, 256);
  const Rgb le = blackbody()(1500.0f);
  EXPECT_NEAR(luminance(le), 1.0f, 0.01f);
  const auto expected = slabExpectation(*scene, 4, [&](float cosTheta) { return le * (1.0f - std::exp(-1.0f / cosTheta)); });
  const Agreement a = compareToExpected(film, 4, 4, expected);
  EXPECT_TRUE(a.agree) << a.worst;
  EXPECT_LT(a.maxRelativeDifference, 0.03);
  EXPECT_EQ(film.rejectedSamples(), 0u);
}

// The emission integral of a light sample (tracking.h, emissionAlongRay: stratified points in
// proportion to the emission majorant, transmittance by ratio tracking) against the slab's closed
// form Le (1 - exp(-tau)), for rays through, into, out of and across the slab, with the majorant
// policies that give it emission maxima (and without: the collision estimator it falls back to).
TEST(ClosedForm, EmissionIntegralOfALightRay) {
  const std::vector<std::string> policies[] = {
      {"strategy.majorant.emission_term=true", "strategy.majorant.emission_weight=10"},
      {"strategy.majorant.emission_term=true", "strategy.majorant.structure=\"grid\"", "strategy.majorant.cell_size=1"},
      {"strategy.majorant.emission_term=true", "strategy.majorant.structure=\"global\""},
      {},  // no emission term: no maxima, the collision estimator
  };
  const Rgb le = blackbody()(1500.0f);
  struct Case {
    Ray ray;
    float tMax, tau;
  };
  const Vec3 oblique = glm::normalize(Vec3(0.6f, 0.0f, -0.8f));
  const Case cases[] = {
      {{Vec3(0.1f, -0.2f, 3.0f), Vec3(0.0f, 0.0f, -1.0f)}, 10.0f, 1.0f},       // straight through: tau = 2 x 0.5
      {{Vec3(0.1f, -0.2f, 3.0f), Vec3(0.0f, 0.0f, -1.0f)}, 2.875f, 0.25f},    // stopped a quarter of the way in
      {{Vec3(0.0f, 0.0f, 0.0f), Vec3(0.0f, 0.0f, -1.0f)}, 10.0f, 0.5f},       // from the middle out
      {{Vec3(-1.0f, 0.3f, 2.0f), oblique}, 10.0f, 1.0f / 0.8f},                // across, 1 / cos longer
  };
  for (const auto& policy : policies) {
    auto scene = Scene::build(test::loadScene("assets/scenes/test/emission-slab.json", policy));
    EXPECT_EQ(scene->media().media[0]->emissionMaxima().empty(), policy.empty());
    for (const Case& c : cases) {
      constexpr int kRuns = 20000;
      Rng rng(7, 3);
      double s = 0.0, s2 = 0.0;
      for (int i = 0; i < kRuns; ++i) {
        const double v = luminance(emissionAlongRay(scene->media(), c.ray, c.tMax, rng));
        s += v;
        s2 += v * v;
      }
      const double mean = s / kRuns, error = std::sqrt(std::max(0.0, s2 / kRuns - mean * mean) / kRuns);
      const double expected = luminance(le) * (1.0 - std::exp(-c.tau));
      EXPECT_NEAR(mean, expected, 5.0 * error + 1e-4) << (policy.empty() ? "no emission term" : policy.back()) << ", tau " << c.tau;
    }
  }
}

TEST(ClosedForm, DiffusePlaneUnderASphereLightWithMis) {
  const SceneDesc desc = test::loadScene("assets/scenes/test/sphere-light.json");
  auto scene = Scene::build(desc);
  const Film film = test::render(desc, 512);
  const Camera& cam = scene->camera();
  std::vector<Rgb> expected;
  constexpr int kBlocks = 4;
  for (int by = 0; by < kBlocks; ++by)
    for (int bx = 0; bx < kBlocks; ++bx) {
      double sum = 0.0;
      int n = 0;
      for (int y = by * cam.height() / kBlocks; y < (by + 1) * cam.height() / kBlocks; ++y)
        for (int x = bx * cam.width() / kBlocks; x < (bx + 1) * cam.width() / kBlocks; ++x)
          for (int sy = 0; sy < 4; ++sy)
            for (int sx = 0; sx < 4; ++sx) {
              const Ray r = cam.generate(x + (sx + 0.5f) / 4.0f, y + (sy + 0.5f) / 4.0f);
              const Vec3 p = r.at(-r.origin.y / r.direction.y);
              const Vec3 toLight = Vec3(0.0f, 2.0f, 0.0f) - p;
              const double d2 = glm::dot(toLight, toLight);
              sum += 0.5 * (0.25 / d2) * (toLight.y / std::sqrt(d2));
              ++n;
            }
      expected.push_back(Rgb(static_cast<float>(sum / n)));
    }
  const Agreement a = compareToExpected(film, kBlocks, kBlocks, expected);
  EXPECT_TRUE(a.agree) << a.worst;
  EXPECT_LT(a.maxRelativeDifference, 0.03);
}

TEST(ClosedForm, WhiteFurnaceReturnsTheEnvironment) {
  for (const char* g : {"0.6", "-0.7", "0.0"}) {
    const SceneDesc desc = test::loadScene("assets/scenes/test/furnace.json", {std::string("volumes.0.g=") + g});
    const Film film = test::render(desc, 128);
    const std::vector<Rgb> ones(16, Rgb(1.0f));
    const Agreement a = compareToExpected(film, 4, 4, ones);
    EXPECT_TRUE(a.agree) << "g = " << g << ": " << a.worst;
    EXPECT_LT(a.maxRelativeDifference, 0.03) << "g = " << g;
    EXPECT_EQ(film.rejectedSamples(), 0u);
  }
}

}  // namespace
}  // namespace candela
