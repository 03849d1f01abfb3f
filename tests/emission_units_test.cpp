// Emission per unit length (EmissionUnits::PerLength, docs/conventions.md "Emission"): the source is
// E whatever the density and albedo. Closed forms for a slab and for glowing gas with no extinction at
// all, each strategy; and agreement between strategies where the emitter scatters every photon.
#include "blackbody.h"
#include "stats.h"
#include "test_support.h"

#include <openvdb/openvdb.h>

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>

namespace candela {
namespace {

namespace fs = std::filesystem;

// Emission reaching the camera through a non-scattering medium, by quadrature along each pixel's
// central ray of the model's own fields (trilinear sigma_t and source): integral of S(t) T(t) dt.
// Averaged over 4 x 4 pixel blocks. Independent of every sampling decision the renderer makes.
std::vector<Rgb> quadratureExpectation(const Scene& scene, float t0, float t1) {
  const Camera& cam = scene.camera();
  const Medium& m = *scene.media().media[0];
  Medium::Sampler sampler(m);
  std::vector<Rgb> out;
  constexpr int kSteps = 4000;
  const float dt = (t1 - t0) / kSteps;
  for (int by = 0; by < 4; ++by)
    for (int bx = 0; bx < 4; ++bx) {
      Rgb sum(0.0f);
      int n = 0;
      for (int y = by * cam.height() / 4; y < (by + 1) * cam.height() / 4; ++y)
        for (int x = bx * cam.width() / 4; x < (bx + 1) * cam.width() / 4; ++x, ++n) {
          const Ray r = cam.generate(x + 0.5f, y + 0.5f);
          double tau = 0.0;
          Rgb L(0.0f);
          for (int i = 0; i < kSteps; ++i) {
            const Vec3 p = Vec3(m.indexFromWorld() * glm::vec4(r.at(t0 + (i + 0.5f) * dt), 1.0f));
            const float sigmaT = sampler.sigmaT(p);
            const float transmittance = static_cast<float>(std::exp(-(tau + 0.5 * sigmaT * dt)));
            L += sampler.source(p, sigmaT) * (transmittance * dt);
            tau += sigmaT * dt;
          }
          sum += L;
        }
      out.push_back(sum / static_cast<float>(n));
    }
  return out;
}

TEST(EmissionPerLength, SlabMatchesQuadratureWhateverTheStrategy) {
  // emission-slab (mu_t = 2, albedo 0, E constant wherever the temperature grid is non-zero): per
  // unit length it emits E wherever that is, also where the density ramps to 0 at the faces.
  uint32_t seed = 1;
  for (const char* preset : {"conventional", "emission", "full"}) {
    const SceneDesc desc = test::loadScene("assets/scenes/test/emission-slab.json",
                                           {"volumes.0.emission.units=\"per_length\"", std::string("strategy.preset=\"") + preset + "\"",
                                            "render.seed=" + std::to_string(seed++)});
    auto scene = Scene::build(desc);
    const Film film = test::render(desc, 256);
    const auto expected = quadratureExpectation(*scene, 2.0f, 4.0f);
    const Agreement a = compareToExpected(film, 4, 4, expected);
    EXPECT_TRUE(a.agree) << preset << ": " << a.worst;
    EXPECT_LT(a.maxRelativeDifference, 0.03) << preset;
    EXPECT_EQ(film.rejectedSamples(), 0u);
  }
}

// A slab of glowing gas with no extinction at all (density 0 everywhere, emission grid 1): each ray
// gathers E x path length. In radiance units the same volume is black, and says why.
TEST(EmissionPerLength, GlowWithoutDensityEmitsAlongThePath) {
  openvdb::initialize();
  const fs::path dir = fs::temp_directory_path() / ("candela-units-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  auto density = openvdb::FloatGrid::create(0.0f), glow = openvdb::FloatGrid::create(0.0f);
  density->setName("density"), glow->setName("glow");
  auto transform = openvdb::math::Transform::createLinearTransform(0.125);
  density->setTransform(transform), glow->setTransform(transform);
  // 4 x 4 x 0.5 world units: x, y in [-16, 15], z in [-2, 1] voxels (cells reach +-0.5 voxel).
  for (int z = -2; z <= 1; ++z)
    for (int y = -16; y <= 15; ++y)
      for (int x = -16; x <= 15; ++x) {
        density->tree().setValueOn(openvdb::Coord(x, y, z), 0.0f);
        glow->tree().setValueOn(openvdb::Coord(x, y, z), 1.0f);
      }
  const std::string path = (dir / "glow.vdb").string();
  openvdb::io::File file(path);
  file.write({density, glow});
  file.close();
  Json doc = {{"camera", {{"position", {0.0, 0.0, 3.0}}, {"look_at", {0.0, 0.0, 0.0}}, {"fov_y", 10}, {"resolution", {24, 24}}}},
              {"render", {{"max_depth", 4}}},
              {"volumes",
               {{{"file", path},
                 {"emission_grid", "glow"},
                 {"albedo", {1.0, 1.0, 1.0}},
                 {"emission", {{"mode", "grid"}, {"units", "per_length"}, {"intensity", 2.0}}}}}}};
  uint32_t seed = 1;
  for (const char* preset : {"conventional", "emission"}) {
    doc["strategy"] = {{"preset", preset}};
    doc["render"]["seed"] = seed++;
    const SceneDesc desc = parseSceneDesc(doc, (dir / "glow.json").string());
    auto scene = Scene::build(desc);
    const Film film = test::render(desc, 256);
    // Voxel centres z in [-2, 1] at 1, ramping to 0 one voxel beyond: 4 voxels = 0.5 world units of
    // E = 2 along the axis, 1 / cos theta longer off it (the quadrature says the same).
    const auto expected = quadratureExpectation(*scene, 2.0f, 4.0f);
    EXPECT_NEAR(luminance(expected[5]), 2.0f * 0.5f, 0.01f);
    const Agreement a = compareToExpected(film, 4, 4, expected);
    EXPECT_TRUE(a.agree) << preset << ": " << a.worst;
    EXPECT_LT(a.maxRelativeDifference, 0.03) << preset;
  }
  // In radiance units: nothing absorbs, so nothing emits; the warning says so.
  doc["volumes"][0]["emission"]["units"] = "radiance";
  const SceneDesc dark = parseSceneDesc(doc, (dir / "glow.json").string());
  std::vector<std::string> warnings;
  Scene::build(dark, &warnings);
  bool said = false;
  for (const auto& w : warnings) said |= w.find("albedo 1") != std::string::npos && w.find("per_length") != std::string::npos;
  EXPECT_TRUE(said);
  const Film black = test::render(dark, 4);
  for (float v : black.meanImage()) ASSERT_EQ(v, 0.0f);
}

TEST(EmissionPerLength, WarningsNameWhatMakesAnEmitterDark) {
  VolumeDesc v;
  v.emission.mode = EmissionMode::Blackbody;
  EXPECT_TRUE(emissionWarnings(v).empty());
  v.albedo = Vec3(1.0f);
  ASSERT_EQ(emissionWarnings(v).size(), 1u);
  v.emission.units = EmissionUnits::PerLength;
  EXPECT_TRUE(emissionWarnings(v).empty());
  v.emission.intensity = 0.0f;
  EXPECT_EQ(emissionWarnings(v).size(), 1u);
  v.emission.mode = EmissionMode::None;
  EXPECT_TRUE(emissionWarnings(v).empty());
}

}  // namespace
}  // namespace candela
