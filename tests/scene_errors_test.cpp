// Bad input gets a clear error naming the file, the field and what was expected: a corpus of broken
// scene files (tests/bad_scenes), bad --set edits, and broken VDBs (missing, truncated, wrong grid
// type, missing grid). NaN and negative voxels are sanitised on load with a warning.
#include "procedural.h"
#include "test_support.h"

#include <openvdb/openvdb.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace candela {
namespace {

namespace fs = std::filesystem;

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("NOT AN InputError: ") + e.what();
  }
  return "no error";
}

struct BadScene {
  const char* file;
  std::vector<const char*> mustMention;  // the field and what was expected
};

void PrintTo(const BadScene& b, std::ostream* os) { *os << b.file; }

class BadSceneCorpus : public ::testing::TestWithParam<BadScene> {};

TEST_P(BadSceneCorpus, ErrorNamesFileFieldAndExpectation) {
  const BadScene& c = GetParam();
  const std::string path = test::assetPath(std::string("tests/bad_scenes/") + c.file);
  const std::string message = errorOf([&] { Scene::build(loadSceneDesc(path)); });
  EXPECT_NE(message.find(path), std::string::npos) << "does not name the file: " << message;
  for (const char* needle : c.mustMention) EXPECT_NE(message.find(needle), std::string::npos) << "'" << needle << "' missing from: " << message;
}

INSTANTIATE_TEST_SUITE_P(
    Corpus, BadSceneCorpus,
    ::testing::Values(BadScene{"not-json.json", {"not valid JSON"}}, BadScene{"missing-camera.json", {"camera", "required"}},
                      BadScene{"unknown-top-field.json", {"lightz", "unknown field", "lights"}},
                      BadScene{"unknown-volume-field.json", {"volumes.0.sigma_t_scal", "unknown field", "sigma_t_scale"}},
                      BadScene{"wrong-type.json", {"volumes.0.sigma_t_scale", "expected a number", "\"thick\""}},
                      BadScene{"negative-sigma.json", {"volumes.0.sigma_t_scale", "in [0", "-1"}},
                      BadScene{"albedo-out-of-range.json", {"volumes.0.albedo", "in [0, 1]"}},
                      BadScene{"g-equal-one.json", {"volumes.0.g", "in [-0.999, 0.999]"}},
                      BadScene{"resolution-arity.json", {"camera.resolution", "2 integers"}},
                      BadScene{"camera-degenerate.json", {"camera.look_at"}},
                      BadScene{"file-and-generator.json", {"volumes.0", "exactly one of"}},
                      BadScene{"no-source.json", {"volumes.0", "exactly one of"}},
                      BadScene{"missing-vdb.json", {"does-not-exist.vdb", "volumes.0", "does not exist"}},
                      BadScene{"unknown-generator.json", {"volumes.0.generator.type", "teapot"}},
                      BadScene{"blackbody-without-temperature.json", {"volumes.0.emission.mode", "temperature grid"}},
                      BadScene{"unknown-light-type.json", {"lights.0.type", "\"directional\"", "laser"}},
                      BadScene{"field-of-another-light-type.json", {"lights.0.cone_angle_deg", "unknown field"}},
                      BadScene{"inverted-box.json", {"surfaces.0.max"}},
                      BadScene{"unknown-preset.json", {"strategy.preset", "conventional", "magic"}},
                      BadScene{"zero-spp.json", {"render.spp", "integer"}},
                      BadScene{"fractional-depth.json", {"render.max_depth", "integer"}}),
    [](const auto& info) {
      std::string n = info.param.file;
      n = n.substr(0, n.find('.'));
      for (char& ch : n)
        if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
      return n;
    });

TEST(BadSettings, SetEditsAreValidatedLikeTheFile) {
  const std::string path = test::assetPath("assets/scenes/test/slab.json");
  EXPECT_NE(errorOf([&] { loadSceneDesc(path, {"volumes.3.g=0.5"}); }).find("volumes.3"), std::string::npos);
  EXPECT_NE(errorOf([&] { loadSceneDesc(path, {"volumes.0.g=7"}); }).find("volumes.0.g"), std::string::npos);
  EXPECT_NE(errorOf([&] { loadSceneDesc(path, {"strategy.majorant.cell_size=0"}); }).find("strategy.majorant.cell_size"), std::string::npos);
  EXPECT_NE(errorOf([&] { loadSceneDesc(path, {"no-equals-sign"}); }).find("key=value"), std::string::npos);
  EXPECT_NE(errorOf([&] { loadSceneDesc(path, {"strategy.majorant.structure=\"octree\""}); }).find("\"global\""), std::string::npos);
  // A valid edit lands in the struct.
  EXPECT_FLOAT_EQ(loadSceneDesc(path, {"volumes.0.g=0.25"}).volumes[0].g, 0.25f);
  EXPECT_EQ(loadSceneDesc(path, {"strategy.majorant.cell_size=16"}).strategy.majorant.cell_size, 16);
}

TEST(SettingsJson, RoundTripsEveryField) {
  const SceneDesc a = test::loadScene("assets/scenes/torch-in-mist.json", {"strategy.majorant.cell_size=4", "volumes.1.g=-0.3"});
  const Json doc = sceneToJson(a);
  const SceneDesc b = parseSceneDesc(doc, "roundtrip");
  EXPECT_EQ(sceneToJson(b), doc);
}

class BrokenVdb : public ::testing::Test {
 protected:
  void SetUp() override {
    openvdb::initialize();
    dir_ = fs::temp_directory_path() / ("candela-bad-vdb-" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string sceneFor(const std::string& vdb, const std::string& extra = "") {
    const fs::path p = dir_ / "scene.json";
    std::ofstream(p) << R"({"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "resolution": [8, 8]},
                          "volumes": [{"file": ")" << vdb << "\"" << extra << "}]}";
    return p.string();
  }
  fs::path dir_;
};

TEST_F(BrokenVdb, TruncatedFile) {
  GeneratorDesc gen;
  gen.type = "cloud";
  gen.resolution = 24;
  const fs::path good = dir_ / "good.vdb";
  writeGeneratedVolume(gen, good.string());
  const auto size = fs::file_size(good);
  fs::copy_file(good, dir_ / "truncated.vdb");
  fs::resize_file(dir_ / "truncated.vdb", size / 2);
  const std::string scene = sceneFor("truncated.vdb");
  const std::string message = errorOf([&] { Scene::build(loadSceneDesc(scene)); });
  EXPECT_NE(message.find("truncated.vdb"), std::string::npos) << message;
  EXPECT_NE(message.find("volumes.0"), std::string::npos) << message;
  EXPECT_EQ(message.find("NOT AN InputError"), std::string::npos) << message;
  // Garbage that is not a VDB at all.
  std::ofstream(dir_ / "garbage.vdb") << "this is not a vdb file";
  const std::string garbage = errorOf([&] { Scene::build(loadSceneDesc(sceneFor("garbage.vdb"))); });
  EXPECT_NE(garbage.find("garbage.vdb"), std::string::npos) << garbage;
}

TEST_F(BrokenVdb, MissingGridListsThosepresent) {
  GeneratorDesc gen;
  gen.type = "constant";
  gen.resolution = 8;
  writeGeneratedVolume(gen, (dir_ / "c.vdb").string());
  const std::string message = errorOf([&] { Scene::build(loadSceneDesc(sceneFor("c.vdb", R"(, "density_grid": "smoke")"))); });
  EXPECT_NE(message.find("\"smoke\""), std::string::npos) << message;
  EXPECT_NE(message.find("density"), std::string::npos) << message;
}

TEST_F(BrokenVdb, NonFloatGrid) {
  auto grid = openvdb::Vec3SGrid::create();
  grid->setName("density");
  grid->tree().setValue(openvdb::Coord(0, 0, 0), openvdb::Vec3s(1, 2, 3));
  openvdb::io::File((dir_ / "vec.vdb").string()).write({grid});
  const std::string message = errorOf([&] { Scene::build(loadSceneDesc(sceneFor("vec.vdb"))); });
  EXPECT_NE(message.find("vec3s"), std::string::npos) << message;
  EXPECT_NE(message.find("expected float"), std::string::npos) << message;
}

TEST_F(BrokenVdb, NanAndNegativeVoxelsAreSanitisedWithAWarning) {
  auto grid = openvdb::FloatGrid::create(0.0f);
  grid->setName("density");
  auto acc = grid->getAccessor();
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j)
      for (int k = 0; k < 8; ++k) acc.setValue(openvdb::Coord(i, j, k), 1.0f);
  acc.setValue(openvdb::Coord(2, 2, 2), std::numeric_limits<float>::quiet_NaN());
  acc.setValue(openvdb::Coord(3, 3, 3), -5.0f);
  acc.setValue(openvdb::Coord(4, 4, 4), std::numeric_limits<float>::infinity());
  grid->setTransform(openvdb::math::Transform::createLinearTransform(0.1));
  openvdb::io::File((dir_ / "nan.vdb").string()).write({grid});
  std::vector<std::string> warnings;
  const SceneDesc desc = loadSceneDesc(sceneFor("nan.vdb"));
  auto scene = Scene::build(desc, &warnings);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("3 NaN, infinite or negative"), std::string::npos) << warnings[0];
  // And nothing non-finite reaches the film.
  ProgressiveRenderer renderer(scene, RenderOptions{1, 8});
  Film film;
  renderer.renderPass(film, 4);
  for (float v : film.sum()) ASSERT_TRUE(std::isfinite(v));
}

}  // namespace
}  // namespace candela

namespace candela {
namespace {

// A float field at its bound reads back in range: the viewer's sliders write the float nearest
// the bound (0.99f is 0.99000001 as a double), found by the GUI soak (scripts/soak.sh).
TEST(Fields, FloatAtItsBoundReadsBackInRange) {
  GuidingSettings g;
  g.guided_probability = 0.99f;
  GuidingSettings back;
  EXPECT_NO_THROW(fromJson(toJson(g), back, "session.json", "strategy.guiding"));
  EXPECT_EQ(back.guided_probability, 0.99f);
  VolumeDesc v;
  v.g = 0.999f;
  v.has_generator = true;
  VolumeDesc vBack;
  EXPECT_NO_THROW(fromJson(toJson(v), vBack, "session.json", "volumes.0"));
  // Beyond the bound in float is still an error.
  Json j = toJson(g);
  j["guided_probability"] = 0.995;
  EXPECT_THROW(fromJson(j, back, "session.json", "strategy.guiding"), InputError);
}

}  // namespace
}  // namespace candela
