// The artist's workflow, headless: opening a bare VDB (grid names, up axis, framing, light rig),
// saving a scene and reopening it to the same image, EXR layers and auto exposure.
#include "convergence.h"
#include "procedural.h"
#include "atomic_file.h"
#include "test_support.h"
#include "vdb_import.h"

#include <openvdb/openvdb.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

namespace candela {
namespace {

namespace fs = std::filesystem;

// A file shaped like a Blender Mantaflow bake: Z-up, a plume taller along Z than wide, grids
// density, flame, heat and a vec3 velocity, and Blender's metadata keys.
void writeBlenderLikeVdb(const std::string& path, bool blenderMetadata) {
  openvdb::initialize();
  auto density = openvdb::FloatGrid::create(0.0f), flame = openvdb::FloatGrid::create(0.0f), heat = openvdb::FloatGrid::create(0.0f);
  auto velocity = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
  density->setName("density"), flame->setName("flame"), heat->setName("heat"), velocity->setName("velocity");
  auto transform = openvdb::math::Transform::createLinearTransform(0.05);
  for (auto g : {openvdb::GridBase::Ptr(density), openvdb::GridBase::Ptr(flame), openvdb::GridBase::Ptr(heat), openvdb::GridBase::Ptr(velocity)})
    g->setTransform(transform);
  auto d = density->getAccessor(), f = flame->getAccessor(), h = heat->getAccessor();
  auto v = velocity->getAccessor();
  // 16 x 16 x 40 voxels: 0.8 x 0.8 x 2 world units, Z is the tall axis.
  for (int z = 0; z < 40; ++z)
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) {
        d.setValue(openvdb::Coord(x, y, z), 2.0f);
        if (z < 8) f.setValue(openvdb::Coord(x, y, z), 0.5f), h.setValue(openvdb::Coord(x, y, z), 1.0f);
        v.setValue(openvdb::Coord(x, y, z), openvdb::Vec3s(0.0f, 0.0f, 1.0f));
      }
  openvdb::GridPtrVec grids{density, flame, heat, velocity};
  openvdb::io::File file(path);
  openvdb::MetaMap meta;
  if (blenderMetadata) meta.insertMeta("blender/smoke/active_fields", openvdb::Int32Metadata(5));
  file.write(grids, meta);
  file.close();
}

TEST(OpenVdb, RecognisesBlenderGridsAndTurnsZUpToYUp) {
  const fs::path dir = test::scratchDirectory("zup");
  const std::string path = (dir / "fire_0001.vdb").string();
  writeBlenderLikeVdb(path, true);
  VdbImportReport report;
  const SceneDesc scene = sceneFromVdb(path, {}, &report);
  EXPECT_EQ(report.densityGrid, "density");
  EXPECT_EQ(report.emissionGrid, "flame");
  EXPECT_EQ(report.up, UpAxis::Z) << report.summary();
  ASSERT_EQ(scene.volumes.size(), 1u);
  const VolumeDesc& v = scene.volumes[0];
  EXPECT_EQ(v.file, "fire_0001.vdb");  // relative to the scene beside it
  EXPECT_EQ(scene.path, (dir / "fire_0001.json").string());
  EXPECT_EQ(v.emission.mode, EmissionMode::Grid);
  EXPECT_EQ(v.emission_grid, "flame");
  EXPECT_FLOAT_EQ(v.transform.rotate_deg.x, -90.0f);
  EXPECT_NE(report.summary().find("velocity (vec3s)"), std::string::npos) << report.summary();
  // A sun and a sky, and the camera looking at the volume's centre from outside it.
  ASSERT_EQ(scene.lights.size(), 2u);
  EXPECT_EQ(scene.lights[0].type, LightType::Directional);
  EXPECT_EQ(scene.lights[1].type, LightType::Environment);

  // After the turn the tall axis is world Y: the built scene's bounds (the majorant domain, padded
  // to whole majorant cells) say so.
  auto built = Scene::build(scene);
  Vec3 lo, hi;
  built->media().media[0]->worldBounds(lo, hi);
  EXPECT_GT(hi.y - lo.y, 1.8f);
  EXPECT_LT(hi.x - lo.x, 0.7f * (hi.y - lo.y));
  EXPECT_LT(hi.z - lo.z, 0.7f * (hi.y - lo.y));
  // The camera looks at the centre of the active voxels: index (7.5, 7.5, 19.5) x 0.05, turned.
  EXPECT_NEAR(scene.camera.look_at.x, 0.375f, 1e-4f);
  EXPECT_NEAR(scene.camera.look_at.y, 0.975f, 1e-4f);
  EXPECT_NEAR(scene.camera.look_at.z, -0.375f, 1e-4f);
  EXPECT_GT(glm::length(scene.camera.position - scene.camera.look_at), 1.0f);

  // The same file without Blender's metadata is taken as Y-up; --up z says otherwise.
  const std::string plain = (dir / "plain.vdb").string();
  writeBlenderLikeVdb(plain, false);
  VdbImportReport plainReport;
  EXPECT_FLOAT_EQ(sceneFromVdb(plain, {}, &plainReport).volumes[0].transform.rotate_deg.x, 0.0f);
  EXPECT_EQ(plainReport.up, UpAxis::Y);
  VdbImportOptions forced;
  forced.up = UpAxis::Z;
  EXPECT_FLOAT_EQ(sceneFromVdb(plain, forced).volumes[0].transform.rotate_deg.x, -90.0f);
  forced.light_rig = false;
  EXPECT_TRUE(sceneFromVdb(plain, forced).lights.empty());
}

TEST(OpenVdb, ACdGridColoursTheFlamePerVoxel) {
  // Density and flame over a slab; Cd red on the left half (x < 0), blue on the right.
  openvdb::initialize();
  auto density = openvdb::FloatGrid::create(0.0f), flame = openvdb::FloatGrid::create(0.0f);
  auto cd = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
  density->setName("density"), flame->setName("flame"), cd->setName("Cd");
  auto transform = openvdb::math::Transform::createLinearTransform(0.05);
  for (auto g : {openvdb::GridBase::Ptr(density), openvdb::GridBase::Ptr(flame), openvdb::GridBase::Ptr(cd)}) g->setTransform(transform);
  for (int z = -4; z < 4; ++z)
    for (int y = -10; y < 10; ++y)
      for (int x = -20; x < 20; ++x) {
        const openvdb::Coord c(x, y, z);
        density->tree().setValue(c, 0.5f);
        flame->tree().setValue(c, 1.0f);
        cd->tree().setValue(c, x < 0 ? openvdb::Vec3s(1.0f, 0.0f, 0.0f) : openvdb::Vec3s(0.0f, 0.0f, 1.0f));
      }
  const fs::path dir = test::scratchDirectory("cd");
  openvdb::io::File file((dir / "coloured.vdb").string());
  file.write({density, flame, cd});
  file.close();
  VdbImportReport report;
  SceneDesc scene = sceneFromVdb((dir / "coloured.vdb").string(), {}, &report);
  ASSERT_EQ(scene.volumes[0].color_grid, "Cd") << report.summary();
  EXPECT_NE(report.summary().find("coloured by \"Cd\""), std::string::npos) << report.summary();
  scene.lights.clear();  // emission only
  scene.camera.resolution = {32, 16};
  scene.camera.position = Vec3(0.0f, 0.0f, 3.0f);
  scene.camera.look_at = Vec3(0.0f);
  scene.camera.fov_y = 30.0f;
  const Film film = test::render(scene, 16, 2);
  Rgb left(0.0f), right(0.0f);
  for (int y = 4; y < 12; ++y)
    for (int x = 4; x < 28; ++x) (x < 16 ? left : right) += film.mean(x, y);
  EXPECT_GT(left.r, 10.0f * left.b) << "left " << left.r << " " << left.b;
  EXPECT_GT(right.b, 10.0f * right.r) << "right " << right.r << " " << right.b;
  // A colour grid that is not a vector grid is refused with the file, the field and the type.
  scene.volumes[0].color_grid = "flame";
  try {
    Scene::build(scene);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("color_grid"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("expected vec3s"), std::string::npos) << e.what();
  }
}

TEST(OpenVdb, EachGeneratorWrittenToVdbOpensAndRenders) {
  const fs::path dir = test::scratchDirectory("generators");
  for (const char* type : {"constant", "ramp", "torch", "mist", "cloud", "plume"}) {
    GeneratorDesc gen;
    gen.type = type;
    gen.resolution = 24;
    const std::string path = (dir / (std::string(type) + ".vdb")).string();
    writeGeneratedVolume(gen, path);
    VdbImportReport report;
    SceneDesc scene = sceneFromVdb(path, {}, &report);
    const bool hot = std::string(type) == "torch" || std::string(type) == "plume";
    EXPECT_EQ(scene.volumes[0].emission.mode, hot ? EmissionMode::Blackbody : EmissionMode::None) << type;
    scene.camera.resolution = {24, 16};
    const Film film = test::render(scene, 4, 1);
    double sum = 0.0;
    for (float x : film.meanImage()) sum += x;
    EXPECT_GT(sum, 0.0) << type;
    EXPECT_EQ(film.rejectedSamples(), 0u) << type;
  }
}

TEST(OpenVdb, AFileWithoutADensityGridNamesTheGridsItHolds) {
  const fs::path dir = test::scratchDirectory("nodensity");
  openvdb::initialize();
  auto a = openvdb::FloatGrid::create(0.0f), b = openvdb::FloatGrid::create(0.0f);
  a->setName("pressure"), b->setName("divergence");
  a->tree().setValue(openvdb::Coord(0), 1.0f);
  openvdb::io::File file((dir / "x.vdb").string());
  file.write({a, b});
  file.close();
  try {
    sceneFromVdb((dir / "x.vdb").string());
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("x.vdb"), std::string::npos) << m;
    EXPECT_NE(m.find("density_grid"), std::string::npos) << m;
    EXPECT_NE(m.find("pressure (float)"), std::string::npos) << m;
  }
}

TEST(SaveScene, SavedSceneReopensToTheSameImage) {
  // An opened VDB with edits, saved into another directory: the relative VDB path is rewritten and
  // the reopened scene renders the identical image (same seed, same spp).
  const fs::path dir = test::scratchDirectory("save");
  GeneratorDesc gen;
  gen.type = "plume";
  gen.resolution = 24;
  const std::string vdb = (dir / "plume.vdb").string();
  writeGeneratedVolume(gen, vdb);
  SceneDesc scene = sceneFromVdb(vdb);
  scene.camera.resolution = {32, 24};
  scene.volumes[0].g = 0.4f;
  scene.volumes[0].emission.intensity = 2.0f;
  scene.display.exposure = 1.5f;
  scene.display.autoExposure = false;  // the artist's exposure (an opened VDB starts with auto exposure)
  scene.description = "saved by the test";
  fs::create_directories(dir / "looks");
  const std::string savedPath = (dir / "looks" / "plume-look.json").string();
  const SceneDesc saved = saveSceneDesc(scene, savedPath);
  EXPECT_EQ(saved.volumes[0].file, "../plume.vdb");
  const SceneDesc reopened = loadSceneDesc(savedPath);
  EXPECT_EQ(toJson(reopened.volumes[0]), toJson(saved.volumes[0]));
  EXPECT_FLOAT_EQ(reopened.display.exposure, 1.5f);
  EXPECT_EQ(reopened.description, "saved by the test");
  const Film a = test::render(scene, 8, 2), b = test::render(reopened, 8, 1);
  EXPECT_EQ(a.meanImage(), b.meanImage());
  // Saving over an existing file replaces it whole (no temporary left behind).
  saveSceneDesc(reopened, savedPath);
  for (const auto& entry : fs::directory_iterator(fs::path(savedPath).parent_path()))
    EXPECT_EQ(entry.path().filename().string().find(".partial"), std::string::npos) << entry.path();
  EXPECT_EQ(sceneToJson(loadSceneDesc(savedPath)), sceneToJson(reopened));
}

// `candela plume.vdb` then Save As `out.json`, both bare names in the working folder: the paths
// have no parent folder, and saving must still resolve them against the working folder.
TEST(SaveScene, BareFileNamesInTheWorkingFolder) {
  const fs::path dir = test::scratchDirectory("save-bare");
  const fs::path before = fs::current_path();
  fs::current_path(dir);
  GeneratorDesc gen;
  gen.type = "plume";
  gen.resolution = 16;
  writeGeneratedVolume(gen, "plume.vdb");
  const SceneDesc scene = sceneFromVdb("plume.vdb");
  EXPECT_EQ(scene.path, "plume.json");
  SceneDesc saved;
  EXPECT_NO_THROW(saved = saveSceneDesc(scene, "out.json"));
  EXPECT_EQ(saved.volumes[0].file, "plume.vdb");
  EXPECT_NO_THROW(saveSceneDesc(loadSceneDesc("out.json"), "again.json"));
  fs::current_path(before);
  EXPECT_TRUE(fs::exists(dir / "out.json"));
  EXPECT_EQ(toJson(loadSceneDesc((dir / "again.json").string()).volumes[0]), toJson(saved.volumes[0]));
}

TEST(SaveScene, ASceneFileRoundTripsEveryField) {
  for (const char* name : {"torch-in-mist", "god-rays", "fire", "cloud"}) {
    const SceneDesc scene = test::loadScene(std::string("assets/scenes/") + name + ".json");
    const fs::path dir = test::scratchDirectory("roundtrip");
    const SceneDesc saved = saveSceneDesc(scene, (dir / (std::string(name) + ".json")).string());
    EXPECT_EQ(sceneToJson(loadSceneDesc(saved.path)), sceneToJson(saved)) << name;
  }
}

// Outputs are written under a temporary name and renamed: a writer that fails halfway leaves the
// previous file as it was and no temporary file behind.
TEST(Outputs, AFailedWriteLeavesThePreviousFile) {
  const fs::path dir = test::scratchDirectory("atomic");
  const std::string path = (dir / "result.csv").string();
  writeTextAtomically(path, "the good result\n");
  EXPECT_THROW(writeAtomically(path, [](const std::string& temporary) {
                 std::ofstream(temporary) << "half of";
                 throw std::runtime_error("killed");
               }),
               std::runtime_error);
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "the good result");
  // A writer that writes nothing leaves no 0-byte file.
  const std::string empty = (dir / "empty.csv").string();
  EXPECT_THROW(writeAtomically(empty, [](const std::string& temporary) { std::ofstream{temporary}; }), std::runtime_error);
  EXPECT_FALSE(fs::exists(empty));
  for (const auto& entry : fs::directory_iterator(dir)) EXPECT_EQ(entry.path().filename().string().find(".partial"), std::string::npos);
}

// A full disk (a 64 KB tmpfs; skipped where the test cannot mount one): the EXR that does not fit
// is an error naming the file; the good EXR already there stays whole, and no partial file is left.
TEST(Outputs, AFullDiskKeepsTheGoodFile) {
  const fs::path dir = test::scratchDirectory("full-disk") / "mnt";
  fs::create_directories(dir);
  if (std::system(("mount -t tmpfs -o size=64k tmpfs " + dir.string() + " 2>/dev/null").c_str()) != 0)
    GTEST_SKIP() << "cannot mount a tmpfs here (needs root): the full-disk case is not tested";
  struct Unmount {
    fs::path dir;
    ~Unmount() { std::system(("umount " + dir.string() + " 2>/dev/null").c_str()); }
  } unmount{dir};
  Image small;
  small.width = small.height = 8;
  small.rgb.assign(3 * 64, 0.5f);
  const std::string path = (dir / "frame.exr").string();
  writeExr(path, small);
  const auto goodSize = fs::file_size(path);
  Image large;
  large.width = large.height = 256;
  large.rgb.resize(3 * 256 * 256);
  for (size_t i = 0; i < large.rgb.size(); ++i) large.rgb[i] = static_cast<float>((i * 2654435761u) % 1000003) / 1000003.0f;  // incompressible
  try {
    writeExr(path, large);
    ADD_FAILURE() << "a 768 KB EXR fitted a 64 KB disk";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  EXPECT_EQ(fs::file_size(path), goodSize);
  EXPECT_EQ(readExr(path).rgb, small.rgb);
  // Nothing there before: nothing there after (no 0-byte file).
  Image noise;
  noise.width = noise.height = 512;
  std::mt19937 random(7);
  for (int i = 0; i < 3 * 512 * 512; ++i) noise.rgb.push_back(std::uniform_real_distribution<float>(0.0f, 1.0f)(random));
  EXPECT_THROW(writePng((dir / "new.png").string(), noise, 0.0f), std::exception);
  EXPECT_FALSE(fs::exists(dir / "new.png"));
  for (const auto& entry : fs::directory_iterator(dir)) EXPECT_EQ(entry.path().filename().string().find(".partial"), std::string::npos);
}

TEST(ExrLayers, VarianceAndSppTravelWithTheImage) {
  SceneDesc scene = test::loadScene("assets/scenes/test/furnace.json");
  scene.camera.resolution = {8, 6};
  const Film film = test::render(scene, 16, 1);
  const Image image = film.image();
  const fs::path path = test::scratchDirectory("exr") / "layers.exr";
  writeExr(path.string(), image);
  const Image back = readExr(path.string());
  ASSERT_EQ(back.channels.count("variance.R"), 1u);
  ASSERT_EQ(back.channels.count("spp"), 1u);
  EXPECT_EQ(back.channels.at("spp")[0], 16.0f);
  const Rgb se = film.standardError(3, 2);
  EXPECT_FLOAT_EQ(back.channels.at("variance.G")[2 * 8 + 3], se.g * se.g);
  EXPECT_EQ(back.rgb, image.rgb);
}

TEST(AutoExposure, BringsTheLogAverageToMiddleGrey) {
  std::vector<float> rgb(300, 0.0f);
  for (size_t i = 0; i < 150; ++i) rgb[i] = 0.045f;  // 50 grey pixels at 0.045, the rest black
  EXPECT_NEAR(autoExposureStops(rgb), 2.0f, 1e-3f);
  EXPECT_EQ(autoExposureStops(std::vector<float>(30, 0.0f)), 0.0f);
  EXPECT_EQ(autoExposureStops(std::vector<float>(30, 1e-30f)), 16.0f);
}

// The cached references of bench and report are keyed on what the volume files hold, not on their
// names in the scene: `bench` on shot-a/fire.vdb and then on shot-b/fire.vdb (two scenes that read
// alike) used to judge the second against the first one's reference, and so did a file written again.
TEST(ReferenceCache, KeyedOnTheVolumeFilesNotTheirNames) {
  const fs::path dir = test::scratchDirectory("reference-cache");
  fs::create_directories(dir / "shot-a"), fs::create_directories(dir / "shot-b");
  std::ofstream(dir / "shot-a" / "fire.vdb") << "the first simulation";
  std::ofstream(dir / "shot-b" / "fire.vdb") << "another simulation";
  SceneDesc a = test::loadScene("assets/scenes/cloud.json");
  a.volumes.resize(1);
  a.volumes[0].has_generator = false;
  a.volumes[0].file = "fire.vdb";
  a.path = (dir / "shot-a" / "fire.json").string();
  SceneDesc b = a;
  b.path = (dir / "shot-b" / "fire.json").string();
  const std::string keyA = sceneContentHash(a, "");
  EXPECT_NE(keyA, sceneContentHash(b, ""));
  // The same file by another name (absolute, or from another directory) is the same key.
  SceneDesc absolute = a;
  absolute.volumes[0].file = (dir / "shot-a" / "fire.vdb").string();
  absolute.path = (dir / "shot-b" / "fire.json").string();
  EXPECT_EQ(keyA, sceneContentHash(absolute, ""));
  // Written again (a simulation rerun): another key.
  std::ofstream(dir / "shot-a" / "fire.vdb") << "the simulation run again, longer";
  EXPECT_NE(keyA, sceneContentHash(a, ""));
}

}  // namespace
}  // namespace candela
