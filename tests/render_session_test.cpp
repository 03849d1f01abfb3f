// The viewer's render session, headless: progressive frames, exact spp limits, live edits restarting
// with a preview, bad edits and bad scenes keeping the last good scene, and agreement with a batch
// render of the same seed.
#include "render_session.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

namespace candela {
namespace {

using Clock = std::chrono::steady_clock;

// Waits (up to `seconds`) for a frame satisfying `pred`.
template <class Pred>
std::shared_ptr<const Frame> waitFor(RenderSession& session, Pred pred, double seconds = 30.0) {
  const auto start = Clock::now();
  while (std::chrono::duration<double>(Clock::now() - start).count() < seconds) {
    auto f = session.latest();
    if (f && pred(*f)) return f;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return nullptr;
}

SceneDesc smallScene(const std::string& relative) {
  return test::loadScene(relative, {"camera.resolution=[48,32]"});
}

TEST(RenderSession, StopsExactlyAtTheSppLimitAndMatchesABatchRender) {
  const SceneDesc desc = smallScene("assets/scenes/test/slab.json");
  RenderSession session;
  session.setLimits(ProgressLimits{13, 0.0f});
  session.open(desc);
  auto frame = waitFor(session, [](const Frame& f) { return f.finished; });
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->film.spp(), 13);
  EXPECT_FALSE(frame->preview);
  // Same seed, same samples: the batch renderer gives the same image, whatever the pass sizes.
  const Film batch = test::render(desc, 13);
  double worst = 0.0;
  for (int y = 0; y < batch.height(); ++y)
    for (int x = 0; x < batch.width(); ++x) {
      const Rgb a = frame->film.mean(x, y), b = batch.mean(x, y);
      worst = std::max(worst, static_cast<double>(std::abs(a.r - b.r) / std::max(1e-3f, b.r)));
    }
  EXPECT_LT(worst, 1e-4);
}

// Paused: no sample is added (the frame shown keeps its spp however long it waits); resumed, the
// render goes on to its limit and matches the batch render of the same samples.
TEST(RenderSession, PauseHoldsTheSamplesAndResumeGoesOn) {
  const SceneDesc desc = smallScene("assets/scenes/test/slab.json");
  RenderSession session;
  session.setLimits(ProgressLimits{4096, 0.0f});
  session.open(desc);
  ASSERT_TRUE(waitFor(session, [](const Frame& f) { return !f.preview && f.film.spp() >= 8; }));
  session.setPaused(true);
  // The pass in flight may still land; after that nothing changes.
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const auto held = session.latest();
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  EXPECT_EQ(session.latest()->version, held->version);
  EXPECT_EQ(session.latest()->film.spp(), held->film.spp());
  session.setLimits(ProgressLimits{held->film.spp() + 16, 0.0f});
  session.setPaused(false);
  auto done = waitFor(session, [](const Frame& f) { return f.finished; });
  ASSERT_TRUE(done);
  EXPECT_EQ(done->film.spp(), held->film.spp() + 16);
  EXPECT_EQ(done->film.meanImage(), test::render(desc, done->film.spp()).meanImage());
}

// A render region: only its pixels refine, in a film of their own, while the rest of the image
// holds; its pixels see what the whole image's pixels at the same place see (the camera's window);
// cleared, the whole image refines again from where it was.
TEST(RenderSession, ARenderRegionRefinesOnlyItsPixels) {
  const SceneDesc desc = smallScene("assets/scenes/test/slab.json");
  const Camera whole(desc.camera);
  const Camera window = whole.window(10, 6, 20, 12);
  EXPECT_EQ(window.width(), 20);
  const Ray a = window.generate(3.25f, 4.5f), b = whole.generate(13.25f, 10.5f);
  EXPECT_EQ(a.direction, b.direction);
  EXPECT_EQ(a.origin, b.origin);

  RenderSession session;
  session.setLimits(ProgressLimits{2, 0.0f});
  session.open(desc);
  ASSERT_TRUE(waitFor(session, [](const Frame& f) { return f.finished && f.film.spp() == 2; }));
  session.setRegion(RegionRect{10, 6, 20, 12});
  session.setLimits(ProgressLimits{16, 0.0f});
  auto f = waitFor(session, [](const Frame& f) { return f.finished && f.region && f.regionFilm.spp() == 16; });
  ASSERT_TRUE(f);
  EXPECT_EQ(f->regionFilm.width(), 20);
  EXPECT_EQ(f->regionFilm.height(), 12);
  EXPECT_EQ(f->film.spp(), 2) << "the rest of the image holds";
  // Shown: the region's pixels inside it, the image's outside.
  const std::vector<float> shown = f->shownImage(), inside = f->regionFilm.meanImage(), outside = f->film.meanImage();
  const auto at = [&](const std::vector<float>& v, int x, int y, int w) { return v[3 * (static_cast<size_t>(y) * w + x)]; };
  EXPECT_EQ(at(shown, 12, 7, 48), at(inside, 2, 1, 20));
  EXPECT_EQ(at(shown, 2, 2, 48), at(outside, 2, 2, 48));
  // Cleared: the whole image goes on to the limit.
  session.setRegion(std::nullopt);
  auto all = waitFor(session, [](const Frame& f) { return f.finished && !f.region && f.film.spp() == 16; });
  ASSERT_TRUE(all);
}

TEST(RenderSession, EditRestartsWithAPreviewThenRefines) {
  // Every published frame, in order (the notification runs on the worker right after publishing).
  // Declared before the session: its worker may still notify until the session is destroyed.
  std::mutex mutex;
  std::vector<std::shared_ptr<const Frame>> frames;
  RenderSession session;
  session.setNotify([&] {
    std::lock_guard<std::mutex> lock(mutex);
    auto f = session.latest();
    if (f && (frames.empty() || frames.back() != f)) frames.push_back(f);
  });
  SceneDesc desc = smallScene("assets/scenes/test/slab.json");
  session.open(desc);
  ASSERT_TRUE(waitFor(session, [](const Frame& f) { return !f.preview && f.film.spp() >= 4; }));
  desc.strategy = strategyPreset("emission");
  desc.strategy.majorant.emission_weight = 3.0f;
  const uint64_t id = session.edit(desc);
  ASSERT_TRUE(waitFor(session, [&](const Frame& f) { return f.request >= id; }));
  std::shared_ptr<const Frame> first;
  {
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& f : frames)
      if (f->request >= id) {
        first = f;
        break;
      }
  }
  ASSERT_TRUE(first);
  EXPECT_TRUE(first->preview);
  EXPECT_LT(first->film.width(), desc.camera.resolution.first);
  EXPECT_EQ(first->scene->strategy.majorant.emission_weight, 3.0f);
  auto later = waitFor(session, [&](const Frame& f) { return f.request >= id && !f.preview && f.film.spp() >= 2; });
  ASSERT_TRUE(later);
  EXPECT_EQ(later->film.width(), desc.camera.resolution.first);
}

TEST(RenderSession, VolumeEditRebuildsAndAppliesTheNewValue) {
  RenderSession session;
  SceneDesc desc = smallScene("assets/scenes/test/slab.json");
  session.open(desc);
  auto before = waitFor(session, [](const Frame& f) { return !f.preview && f.film.spp() >= 8; });
  ASSERT_TRUE(before);
  desc.volumes[0].sigma_t_scale *= 4.0f;  // much thicker: the slab gets darker (it absorbs)
  const uint64_t id = session.edit(desc);
  auto after = waitFor(session, [&](const Frame& f) { return f.request >= id && !f.preview && f.film.spp() >= 8; });
  ASSERT_TRUE(after);
  EXPECT_FLOAT_EQ(after->scene->volumes[0].sigma_t_scale, desc.volumes[0].sigma_t_scale);
  auto average = [](const Film& film) {
    double s = 0.0;
    for (float v : film.meanImage()) s += v;
    return s;
  };
  EXPECT_NE(average(after->film), average(before->film));
}

TEST(RenderSession, BadEditKeepsTheLastGoodSceneAndRestoresItsFields) {
  RenderSession session;
  const SceneDesc good = smallScene("assets/scenes/test/slab.json");
  session.open(good);
  ASSERT_TRUE(waitFor(session, [](const Frame& f) { return !f.preview && f.film.spp() >= 2; }));
  (void)session.takeShownDesc();
  SceneDesc bad = good;
  bad.volumes[0].has_generator = false;
  bad.volumes[0].file = "does-not-exist.vdb";
  const uint64_t id = session.edit(bad);
  // The error arrives as a message naming the file and field; the fields go back.
  std::vector<std::string> messages;
  std::optional<RenderSession::ShownDesc> restored;
  for (int i = 0; i < 3000 && (messages.empty() || !restored); ++i) {
    for (auto& m : session.takeMessages()) messages.push_back(m);
    if (!restored) restored = session.takeShownDesc();
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ASSERT_FALSE(messages.empty());
  EXPECT_NE(messages.front().find("does-not-exist.vdb"), std::string::npos) << messages.front();
  EXPECT_NE(messages.front().find("volumes.0"), std::string::npos) << messages.front();
  ASSERT_TRUE(restored);
  EXPECT_FALSE(restored->opened);
  EXPECT_EQ(restored->request, id);
  EXPECT_TRUE(restored->desc.volumes[0].has_generator);
  // And the last good scene keeps refining.
  const int spp = session.latest()->film.spp();
  EXPECT_TRUE(waitFor(session, [&](const Frame& f) { return f.request >= id && f.film.spp() > spp + 2; }));
}

TEST(RenderSession, BrokenSceneOpenKeepsTheCurrentScene) {
  RenderSession session;
  session.open(smallScene("assets/scenes/test/slab.json"));
  ASSERT_TRUE(waitFor(session, [](const Frame& f) { return !f.preview && f.film.spp() >= 2; }));
  (void)session.takeShownDesc();
  SceneDesc broken = smallScene("assets/scenes/test/slab.json");
  broken.path = "/tmp/elsewhere/scene.json";
  broken.volumes[0].has_generator = false;
  broken.volumes[0].file = "missing.vdb";
  session.open(broken);
  std::vector<std::string> messages;
  for (int i = 0; i < 3000 && messages.empty(); ++i) {
    messages = session.takeMessages();
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ASSERT_FALSE(messages.empty());
  EXPECT_NE(messages.front().find("missing.vdb"), std::string::npos);
  EXPECT_NE(messages.front().find("last good scene"), std::string::npos);
  auto frame = session.latest();
  EXPECT_EQ(frame->scene->path, test::assetPath("assets/scenes/test/slab.json"));
  const int spp = frame->film.spp();
  EXPECT_TRUE(waitFor(session, [&](const Frame& f) { return f.film.spp() > spp; }));
}

// Holds the session's builds back until released: requests made meanwhile arrive while a build runs,
// as an artist's do during a long load.
class BuildGate {
 public:
  // The first `passing` builds go through at once; the gate holds the ones after them.
  explicit BuildGate(size_t passing = 0) { state_->passing = passing; }
  // The hook shares the gate's state, so a build that reaches it after the gate is gone is safe.
  // Declare the gate after the session: its destructor opens the gate before the session joins.
  void attach(RenderSession& session) {
    session.setBuildHook([state = state_](const SceneDesc& desc) {
      std::unique_lock<std::mutex> lock(state->mutex);
      state->building.push_back(desc.path);
      state->changed.notify_all();
      if (state->building.size() <= state->passing) return;
      state->changed.wait(lock, [&] { return state->open; });
    });
  }
  // Waits until `count` builds have reached the gate.
  bool waitForBuilds(size_t count) {
    std::unique_lock<std::mutex> lock(state_->mutex);
    return state_->changed.wait_for(lock, std::chrono::seconds(30), [&] { return state_->building.size() >= count; });
  }
  void release() {
    std::lock_guard<std::mutex> lock(state_->mutex);
    state_->open = true;
    state_->changed.notify_all();
  }
  ~BuildGate() { release(); }

 private:
  struct State {
    std::mutex mutex;
    std::condition_variable changed;
    std::vector<std::string> building;
    size_t passing = 0;
    bool open = false;
  };
  std::shared_ptr<State> state_ = std::make_shared<State>();
};

// Collects every shown-description update until `pred` holds for one (or the time runs out).
template <class Pred>
std::vector<RenderSession::ShownDesc> takeShownUntil(RenderSession& session, Pred pred) {
  std::vector<RenderSession::ShownDesc> shown;
  for (int i = 0; i < 15000; ++i) {
    if (auto s = session.takeShownDesc()) {
      shown.push_back(*s);
      if (pred(shown.back())) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return shown;
}

TEST(RenderSession, EditsMadeWhileASceneOpensApplyToTheOpenedScene) {
  RenderSession session;
  BuildGate gate;
  gate.attach(session);
  session.setLimits(ProgressLimits{6, 0.0f});
  const SceneDesc opened = smallScene("assets/scenes/test/slab.json");
  const uint64_t openId = session.open(opened);
  ASSERT_TRUE(gate.waitForBuilds(1));
  // While it loads, the artist changes a live setting (the worker applies it without a rebuild).
  SceneDesc edited = opened;
  edited.strategy.majorant.emission_weight = 7.0f;
  const uint64_t liveEdit = session.edit(edited);
  EXPECT_GT(liveEdit, openId);
  gate.release();
  // The open reports itself by its own id, so the UI knows the file it waits for has loaded...
  const auto shown = takeShownUntil(session, [](const RenderSession::ShownDesc& s) { return s.opened; });
  ASSERT_FALSE(shown.empty());
  EXPECT_TRUE(shown.back().opened);
  EXPECT_EQ(shown.back().request, openId);
  // ...and what renders is the opened scene with the edit, never the open's fields alone.
  auto frame = waitFor(session, [&](const Frame& f) { return f.finished; });
  ASSERT_TRUE(frame);
  EXPECT_GE(frame->request, liveEdit);
  EXPECT_EQ(frame->scene->strategy.majorant.emission_weight, 7.0f);
  EXPECT_EQ(frame->film.spp(), 6);
  EXPECT_FALSE(session.takeShownDesc()) << "nothing may send the fields back to the scene as opened";
}

TEST(RenderSession, AnEditBeforeTheOpensBuildStartsKeepsTheOpensId) {
  RenderSession session;
  BuildGate gate;
  gate.attach(session);
  session.open(smallScene("assets/scenes/test/slab.json"));
  ASSERT_TRUE(gate.waitForBuilds(1));  // the first scene builds; the next open waits in the queue
  const SceneDesc second = smallScene("assets/scenes/test/glow-box.json");
  const uint64_t openId = session.open(second);
  SceneDesc edited = second;
  edited.volumes[0].g = 0.2f;  // structural: the queued open builds it
  session.edit(edited);
  gate.release();
  const auto shown = takeShownUntil(session, [&](const RenderSession::ShownDesc& s) { return s.request == openId; });
  ASSERT_FALSE(shown.empty());
  EXPECT_EQ(shown.back().request, openId);
  EXPECT_TRUE(shown.back().opened);
  EXPECT_FLOAT_EQ(shown.back().desc.volumes[0].g, 0.2f);
}

TEST(RenderSession, AnOpenReplacedWhileItLoadsIsNeverShown) {
  // Every published frame (the notification runs right after publishing); declared before the
  // session, whose threads may notify until it is destroyed.
  std::mutex mutex;
  std::vector<std::string> framePaths;
  RenderSession session;
  BuildGate gate;
  session.setNotify([&] {
    auto f = session.latest();
    std::lock_guard<std::mutex> lock(mutex);
    if (f && f->scene) framePaths.push_back(f->scene->path);
  });
  gate.attach(session);
  session.setLimits(ProgressLimits{4, 0.0f});
  const SceneDesc first = smallScene("assets/scenes/test/slab.json");
  SceneDesc broken = first;
  broken.volumes[0].has_generator = false;
  broken.volumes[0].file = "missing-replaced.vdb";
  session.open(broken);
  ASSERT_TRUE(gate.waitForBuilds(1));
  // A second file dropped while the first loads: the first, here a broken one, is forgotten.
  const SceneDesc second = smallScene("assets/scenes/test/glow-box.json");
  const uint64_t secondId = session.open(second);
  gate.release();
  const auto shown = takeShownUntil(session, [&](const RenderSession::ShownDesc& s) { return s.request == secondId; });
  ASSERT_EQ(shown.size(), 1u);
  EXPECT_EQ(shown[0].request, secondId);
  EXPECT_TRUE(shown[0].opened);
  ASSERT_TRUE(waitFor(session, [](const Frame& f) { return f.finished; }));
  for (const auto& m : session.takeMessages()) EXPECT_EQ(m.find("missing-replaced.vdb"), std::string::npos) << m;
  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_FALSE(framePaths.empty());
  for (const auto& p : framePaths) EXPECT_EQ(p, second.path);
}

TEST(RenderSession, AFailedEditWhileASceneOpensReturnsTheFieldsToTheOpenedScene) {
  RenderSession session;
  BuildGate gate(1);  // the first scene loads; the second is held while the artist edits it
  gate.attach(session);
  const SceneDesc first = smallScene("assets/scenes/test/slab.json");
  session.open(first);
  ASSERT_TRUE(waitFor(session, [](const Frame& f) { return !f.preview && f.film.spp() >= 1; }));
  ASSERT_TRUE(session.takeShownDesc());
  const SceneDesc second = smallScene("assets/scenes/test/glow-box.json");
  const uint64_t openId = session.open(second);
  ASSERT_TRUE(gate.waitForBuilds(2));
  SceneDesc bad = second;
  bad.volumes[0].has_generator = false;
  bad.volumes[0].file = "missing-edit.vdb";
  const uint64_t editId = session.edit(bad);
  gate.release();
  // In order: the open, then the failed edit, whose fields are the opened scene's, not the first's
  // (also when the edit fails before the worker has taken the opened scene, an interleaving this
  // test cannot force).
  const auto shown = takeShownUntil(session, [](const RenderSession::ShownDesc& s) { return !s.opened; });
  ASSERT_EQ(shown.size(), 2u);
  EXPECT_TRUE(shown[0].opened);
  EXPECT_EQ(shown[0].request, openId);
  EXPECT_FALSE(shown[1].opened);
  EXPECT_EQ(shown[1].request, editId);
  EXPECT_EQ(shown[1].desc.path, second.path);
  EXPECT_TRUE(shown[1].desc.volumes[0].has_generator);
  EXPECT_TRUE(waitFor(session, [&](const Frame& f) { return !f.preview && f.scene->path == second.path && f.film.spp() >= 2; }));
}

TEST(RenderSession, SceneDiffSeparatesLiveEditsFromRebuilds) {
  const SceneDesc a = smallScene("assets/scenes/test/slab.json");
  SceneDesc b = a;
  EXPECT_FALSE(diffScenes(a, b).any());
  b.strategy.majorant.emission_weight = 7.0f;
  b.camera.fov_y = 30.0f;
  b.render.max_depth = 3;
  auto d = diffScenes(a, b);
  EXPECT_TRUE(d.strategy && d.camera && d.render);
  EXPECT_FALSE(d.structure);
  b.volumes[0].g = 0.3f;
  EXPECT_TRUE(diffScenes(a, b).structure);
}

}  // namespace
}  // namespace candela
