// The viewer's document machinery, headless: undo/redo grouping, snapshots on disk, frame patterns.
#include "edit_history.h"
#include "field_labels.h"
#include "histogram.h"
#include "message_severity.h"
#include "procedural.h"
#include "sequence.h"
#include "sequence_render.h"
#include "snapshot_store.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace candela {
namespace {

namespace fs = std::filesystem;

TEST(EditHistory, UndoRedoAndDropsRedoOnANewEdit) {
  EditHistory h;
  h.reset({{"g", 0}});
  h.record({{"g", 1}});
  h.record({{"g", 2}});
  EXPECT_EQ(*h.undo(), Json({{"g", 1}}));
  EXPECT_EQ(*h.undo(), Json({{"g", 0}}));
  EXPECT_FALSE(h.undo());
  EXPECT_EQ(*h.redo(), Json({{"g", 1}}));
  h.record({{"g", 5}});  // a new edit after undo: the old future is gone
  EXPECT_FALSE(h.canRedo());
  EXPECT_EQ(*h.undo(), Json({{"g", 1}}));
}

TEST(EditHistory, AGestureIsOneStepAndAnUnchangedStateRecordsNothing) {
  EditHistory h;
  h.reset({{"x", 0}});
  for (int i = 1; i <= 30; ++i) h.record({{"x", i}}, "camera");  // one tumble: 30 moves
  h.endGroup();
  h.record({{"x", 30}}, "camera");  // the same state: nothing
  EXPECT_EQ(h.undoSteps(), 1u);
  for (int i = 31; i <= 40; ++i) h.record({{"x", i}}, "camera");  // a second tumble
  EXPECT_EQ(h.undoSteps(), 2u);
  EXPECT_EQ(*h.undo(), Json({{"x", 30}}));
  EXPECT_EQ(*h.undo(), Json({{"x", 0}}));
  // A different group while one is open is a new step.
  EditHistory k;
  k.reset({{"a", 0}});
  k.record({{"a", 1}}, "panel");
  k.record({{"a", 2}}, "camera");
  EXPECT_EQ(k.undoSteps(), 2u);
  // amend changes the current state without a step (auto exposure on open).
  k.amend({{"a", 3}});
  EXPECT_EQ(*k.undo(), Json({{"a", 1}}));
  EXPECT_EQ(*k.redo(), Json({{"a", 3}}));
}

// Auto exposure on open comes with the first image; an edit made before it is its own undo step.
// Undoing that edit keeps the auto exposure: the choice fills every state that had no exposure of
// its own (the file gave none), and leaves one the artist set alone.
TEST(EditHistory, AutoExposureHoldsUnderEarlierEdits) {
  EditHistory h;
  h.reset({{"display", Json::object()}, {"seed", 1}});
  h.record({{"display", Json::object()}, {"seed", 7}});
  h.record({{"display", {{"exposure", 2.0}}}, {"seed", 7}});  // set by the artist
  h.undo();
  h.fillEverywhere(Json::json_pointer("/display/exposure"), -3.5);
  EXPECT_EQ(*h.undo(), Json({{"display", {{"exposure", -3.5}}}, {"seed", 1}}));
  EXPECT_EQ(*h.redo(), Json({{"display", {{"exposure", -3.5}}}, {"seed", 7}}));
  EXPECT_EQ(*h.redo(), Json({{"display", {{"exposure", 2.0}}}, {"seed", 7}}));
}

// The panels name fields in words; the key stays for the tooltip, scene files and --set.
TEST(Panels, FieldsAreLabelledInWords) {
  EXPECT_EQ(fieldLabel("sigma_t_scale"), "Density");
  EXPECT_EQ(fieldLabel("g"), "Anisotropy (forward > 0)");
  EXPECT_EQ(fieldLabel("guided_probability"), "Guided probability");
  EXPECT_EQ(fieldLabel("probe_time_cap_s"), "Probe time cap (seconds)");
  EXPECT_EQ(fieldLabel("cone_angle_deg"), "Cone angle (degrees)");
}

// Messages are coloured by what they are: information is not shown as an error.
TEST(Panels, MessagesHaveASeverity) {
  EXPECT_EQ(messageSeverity("auto exposure: +5.40 stops (E / Shift+E to change)"), Severity::Info);
  EXPECT_EQ(messageSeverity("saved out.json"), Severity::Info);
  EXPECT_EQ(messageSeverity("screenshot: wrote a.png and a.exr"), Severity::Info);
  EXPECT_EQ(messageSeverity("warning: volumes.0: emission.intensity is 0: the volume emits nothing"), Severity::Warning);
  EXPECT_EQ(messageSeverity("edit rejected: a.json: volumes.0.g: expected a value from -0.999 to 0.999"), Severity::Error);
  EXPECT_EQ(messageSeverity("could not open x.vdb: no such file (still showing the last good scene)"), Severity::Error);
  EXPECT_EQ(messageSeverity("save failed: cannot write"), Severity::Error);
}

// The histogram counts display values by luminance and what the screen clips.
TEST(Panels, HistogramCountsClipping) {
  const std::vector<float> rgb{0.0f, 0.0f, 0.0f,  1.0f, 0.2f, 0.2f,  0.5f, 0.5f, 0.5f,  0.99f, 0.99f, 0.99f};
  const DisplayHistogram h = displayHistogram(rgb, 4);
  EXPECT_EQ(h.total, 4u);
  EXPECT_EQ(h.over, 1u);
  EXPECT_EQ(h.under, 1u);
  EXPECT_FLOAT_EQ(h.counts[0], 1.0f);  // black
  EXPECT_FLOAT_EQ(h.counts[2], 1.0f);  // mid grey
  EXPECT_FLOAT_EQ(h.counts[3], 1.0f);  // near white
  EXPECT_FLOAT_EQ(h.counts[1], 1.0f);  // the clipped red's luminance, 0.37
  EXPECT_DOUBLE_EQ(h.overShare(), 0.25);
}

// A scene file without display.exposure asks for auto exposure; one with it keeps it, and the
// choice survives a save and reopen (the exposure is written once chosen, left out while it is not).
TEST(SceneFile, ExposureLeftOutMeansAuto) {
  const Json camera{{"position", {0, 0, 5}}, {"look_at", {0, 0, 0}}};
  SceneDesc open = parseSceneDesc(Json{{"camera", camera}}, "a.json");
  EXPECT_TRUE(open.display.autoExposure);
  EXPECT_FALSE(sceneToJson(open)["display"].contains("exposure"));
  EXPECT_TRUE(parseSceneDesc(sceneToJson(open), "a.json").display.autoExposure);
  SceneDesc given = parseSceneDesc(Json{{"camera", camera}, {"display", {{"exposure", 0.0}}}}, "b.json");
  EXPECT_FALSE(given.display.autoExposure);
  EXPECT_EQ(sceneToJson(given)["display"]["exposure"], 0.0);
  open.display.exposure = 3.25f, open.display.autoExposure = false;
  EXPECT_FLOAT_EQ(parseSceneDesc(sceneToJson(open), "a.json").display.exposure, 3.25f);
}

// An edit whose scene cannot build (a truncated VDB typed into the file field) leaves the history
// with the scene going back: undo after a later edit goes to the state before the failure, never
// to the failed state, which would fail again.
TEST(EditHistory, AFailedEditLeavesTheHistory) {
  EditHistory h;
  h.reset({{"file", "good.vdb"}});
  h.record({{"file", "truncated.vdb"}});
  h.revertCurrent({{"file", "good.vdb"}});  // the build failed: back to the good file
  EXPECT_FALSE(h.canUndo());
  EXPECT_FALSE(h.canRedo());
  h.record({{"file", "good.vdb"}, {"g", 0.5}});
  EXPECT_EQ(*h.undo(), Json({{"file", "good.vdb"}}));
  EXPECT_FALSE(h.canUndo());
  // An undo that lands on a state that fails (its file broke since): that state becomes the one
  // that renders, and the steps around it stay.
  EditHistory k;
  k.reset({{"v", 0}});
  k.record({{"v", 1}});
  k.record({{"v", 2}});
  ASSERT_TRUE(k.undo());
  k.revertCurrent({{"v", 2}});
  EXPECT_EQ(k.undoSteps(), 1u);
  EXPECT_EQ(*k.redo(), Json({{"v", 2}}));
  EXPECT_EQ(*k.undo(), Json({{"v", 2}}));
  EXPECT_EQ(*k.undo(), Json({{"v", 0}}));
}

TEST(EditHistory, KeepsAtMostItsLimit) {
  EditHistory h(5);
  h.reset({{"v", 0}});
  for (int i = 1; i <= 20; ++i) h.record({{"v", i}});
  EXPECT_EQ(h.undoSteps(), 4u);
  while (h.canUndo()) h.undo();
  EXPECT_EQ(*h.redo(), Json({{"v", 17}}));
}

TEST(Snapshots, KeptOnDiskWithTheirLookAndReadBack) {
  const fs::path dir = test::scratchDirectory("snapshots");
  Image image;
  image.width = 4, image.height = 2;
  image.rgb.assign(24, 0.25f);
  image.channels["spp"].assign(8, 16.0f);
  Json look = {{"display", {{"exposure", 1.0}}}, {"camera", {{"fov_y", 30}}}};
  SnapshotStore store(dir.string());
  const Snapshot& a = store.add(image, look, 16, "emission");
  EXPECT_EQ(a.label, "#1 emission 16 spp");
  EXPECT_TRUE(fs::exists(a.path));
  EXPECT_EQ(a.thumbWidth, 4);
  // 0.25 x 2^1 through sRGB: 0.5 -> 188.
  EXPECT_EQ(a.thumbnail[0], 188);
  image.rgb.assign(24, 1.0f);
  store.add(image, look, 32, "full");
  SnapshotStore reopened(dir.string());
  reopened.loadDirectory();
  ASSERT_EQ(reopened.snapshots().size(), 2u);
  EXPECT_EQ(reopened.snapshots()[1].label, "#2 full 32 spp");
  EXPECT_EQ(reopened.snapshots()[0].look, look);
  EXPECT_EQ(reopened.snapshots()[1].image.rgb, image.rgb);
  reopened.remove(1);
  EXPECT_EQ(reopened.snapshots().size(), 1u);
  EXPECT_FALSE(fs::exists(dir / "snapshot-001.exr"));
  // The next snapshot after reading the directory does not reuse a number.
  EXPECT_EQ(reopened.add(image, look, 1, "x").id, 3);
}

TEST(Sequences, PatternsSubstituteAndFindFramesOnDisk) {
  EXPECT_TRUE(hasFramePattern("/a/fire.####.vdb"));
  EXPECT_TRUE(hasFramePattern("fire_$F4.vdb"));
  EXPECT_TRUE(hasFramePattern("fire.%04d.vdb"));
  EXPECT_FALSE(hasFramePattern("/a#b/fire.vdb"));  // only the file name holds a pattern
  EXPECT_EQ(substituteFrame("/a/fire.####.vdb", 7), "/a/fire.0007.vdb");
  EXPECT_EQ(substituteFrame("fire_$F4.vdb", 12), "fire_0012.vdb");
  EXPECT_EQ(substituteFrame("fire_$F.vdb", 12), "fire_12.vdb");
  EXPECT_EQ(substituteFrame("fire.%04d.vdb", 3), "fire.0003.vdb");
  EXPECT_EQ(substituteFrame("fire.####.vdb", -3), "fire.-0003.vdb");
  EXPECT_EQ(substituteFrame("fire.####.vdb", 12345), "fire.12345.vdb");
  EXPECT_EQ(substituteFrame("fire.vdb", 3), "fire.vdb");

  const fs::path dir = test::scratchDirectory("sequence");
  for (const char* f : {"smoke.0003.vdb", "smoke.0004.vdb", "smoke.0006.vdb", "smoke.0004.vdb.bak", "smoke.00x5.vdb", "smoke.vdb"})
    std::ofstream(dir / f) << "x";
  const FrameRange r = findFrames((dir / "smoke.####.vdb").string());
  EXPECT_EQ(r.first, 3);
  EXPECT_EQ(r.last, 6);
  EXPECT_EQ(r.count, 3);
  std::string pattern;
  int frame = 0;
  ASSERT_TRUE(detectSequence((dir / "smoke.0004.vdb").string(), pattern, frame));
  EXPECT_EQ(pattern, (dir / "smoke.####.vdb").string());
  EXPECT_EQ(frame, 4);
  EXPECT_FALSE(detectSequence((dir / "smoke.vdb").string(), pattern, frame));
}

// File > Render sequence: every frame rendered as a batch render of it renders (the same samples),
// written under its numbered name with no temporary file left; a missing frame is reported and
// passed; a cancelled job writes nothing more, and never a partial file.
TEST(Sequences, TheViewerRendersASequenceToDisk) {
  const fs::path dir = test::scratchDirectory("render-sequence");
  for (int f = 1; f <= 3; ++f) {
    if (f == 2) continue;  // a hole in the sequence
    GeneratorDesc gen;
    gen.type = "constant";
    gen.resolution = 8;
    gen.value = static_cast<float>(f);
    writeGeneratedVolume(gen, (dir / ("box." + std::to_string(f) + ".vdb")).string());
  }
  SceneDesc scene = test::loadScene("assets/scenes/test/furnace.json");
  scene.path = (dir / "scene.json").string();
  scene.volumes[0].has_generator = false;
  scene.volumes[0].file = "box.$F.vdb";
  scene.camera.resolution = {8, 6};
  SequenceRenderRequest request;
  request.scene = scene;
  request.first = 1, request.last = 3, request.spp = 8;
  request.pattern = (dir / "out" / "box.####.exr").string();
  SequenceRenderJob job;
  job.start(request);
  job.wait();
  const SequenceProgress p = job.progress();
  EXPECT_FALSE(p.running);
  EXPECT_EQ(p.done, 3);
  ASSERT_EQ(p.written.size(), 2u);
  ASSERT_EQ(p.failed.size(), 1u);
  EXPECT_NE(p.failed[0].find("frame 2"), std::string::npos) << p.failed[0];
  EXPECT_FALSE(fs::exists(dir / "out" / "box.0002.exr"));
  scene.render.frame = 3;
  const Image written = readExr((dir / "out" / "box.0003.exr").string());
  // The same samples (passes of another size sum them in another order: float rounding apart).
  const std::vector<float> batch = test::render(scene, 8).meanImage();
  ASSERT_EQ(written.rgb.size(), batch.size());
  for (size_t i = 0; i < batch.size(); ++i) EXPECT_NEAR(written.rgb[i], batch[i], 1e-4f * std::max(1.0f, batch[i])) << i;
  for (const auto& entry : fs::directory_iterator(dir / "out")) EXPECT_EQ(entry.path().filename().string().find(".partial"), std::string::npos);

  // Cancelled at once: nothing past what was written, no partial file.
  request.pattern = (dir / "cancelled" / "box.####.exr").string();
  request.spp = 1 << 20;
  job.start(request);
  job.cancel();
  job.wait();
  EXPECT_TRUE(job.progress().cancelled);
  EXPECT_TRUE(!fs::exists(dir / "cancelled") || fs::is_empty(dir / "cancelled"));

  // A bad request is an error before anything renders.
  request.pattern = (dir / "no-pattern.exr").string();
  EXPECT_THROW(job.start(request), InputError);
  request.pattern = (dir / "x.####.tif").string();
  EXPECT_THROW(job.start(request), InputError);
  request.pattern = (dir / "x.####.exr").string();
  request.first = 5, request.last = 4;
  EXPECT_THROW(job.start(request), InputError);
}

// Frame ranges are parsed in 64 bits and bounded: overflowing, reversed, absurd or malformed ranges
// are refused with a message, never wrapped round to something else.
TEST(Sequences, FrameRangesAreBounded) {
  EXPECT_EQ(parseFrameRange("7", "--frames").first, 7);
  const FrameRange r = parseFrameRange("-10--1", "--frames");
  EXPECT_EQ(r.first, -10);
  EXPECT_EQ(r.last, -1);
  EXPECT_EQ(r.count, 10);
  EXPECT_EQ(parseFrameRange("1-100000", "--frames").count, 100000);
  for (const char* bad : {"-2147483648-2147483647", "-2000000000-2000000000", "2147483647", "1-100001", "5-4", "1-", "-", "a", " 1", "1-2x",
                          "99999999999999999999999", "1--", "1-+"}) {
    try {
      parseFrameRange(bad, "--frames");
      ADD_FAILURE() << bad << " was accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("--frames: ", 0), 0u) << e.what();
    }
  }
}

TEST(Sequences, ASceneRendersTheFrameItNames) {
  // Two frames that differ (constant densities 1 and 4): render.frame picks the file.
  const fs::path dir = test::scratchDirectory("frames");
  for (int f = 1; f <= 2; ++f) {
    GeneratorDesc gen;
    gen.type = "constant";
    gen.resolution = 8;
    gen.value = f == 1 ? 1.0f : 4.0f;
    writeGeneratedVolume(gen, (dir / ("box." + std::to_string(f) + ".vdb")).string());
  }
  SceneDesc scene = test::loadScene("assets/scenes/test/furnace.json");
  ASSERT_FALSE(scene.volumes.empty());
  scene.path = (dir / "scene.json").string();
  scene.volumes[0].has_generator = false;
  scene.volumes[0].file = "box.$F.vdb";
  scene.camera.resolution = {8, 8};
  EXPECT_EQ(sceneFrames(scene).first, 1);
  EXPECT_EQ(sceneFrames(scene).last, 2);
  scene.render.frame = 1;
  const auto one = Scene::build(scene);
  scene.render.frame = 2;
  const auto two = Scene::build(scene);
  EXPECT_EQ(one->media().media[0]->majorantGrid().maxDensities()[0] * 4.0f, two->media().media[0]->majorantGrid().maxDensities()[0]);
  scene.render.frame = 9;
  try {
    Scene::build(scene);
    FAIL() << "a missing frame must be an error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("box.9.vdb"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace candela
