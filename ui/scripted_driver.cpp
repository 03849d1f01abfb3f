#include "scripted_driver.h"

#include "viewer_impl.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <thread>

namespace candela {

using Clock = std::chrono::steady_clock;

bool ScriptedDriver::measuring(const Viewer& v) const {
  return v.options_.measureEdits > 0 && measureIndex_ <= v.options_.measureEdits;
}

bool ScriptedDriver::active(const Viewer& v) const {
  const ViewerOptions& o = v.options_;
  return measuring(v) || !o.screenshotPath.empty() || !o.figurePath.empty() || o.frameSteps > 0 || !o.saveAsPath.empty() ||
         !o.renderSequencePattern.empty();
}

void ScriptedDriver::editMeasured(double ms) {
  for (auto it = measured_.rbegin(); it != measured_.rend(); ++it)
    if (it->second < 0.0) {
      it->second = ms;
      break;
    }
}

bool ScriptedDriver::waitingForFullFrame(Viewer& v) {
  // A frame of the scene opened last: the session publishes an open's scene before its first image.
  const bool fullFrame = v.frame_ && !v.frame_->preview && v.frame_->film.spp() > 0 && !v.session_.loading() && !v.pendingOpen_ &&
                         v.frame_->request >= v.openedRequest_;
  if (fullFrame) return false;
  // A scripted run whose scene never loads must not wait forever.
  // (A build that finished since the UI last polled the session is a loaded scene, not a failure.)
  if (v.options_.quit && !v.haveScene_ && !v.session_.loading() && !v.session_.openPending() &&
      std::chrono::duration<double>(Clock::now() - start_).count() > 2.0) {
    v.report("no scene could be loaded; quitting");
    v.exitCode_ = 1;
    v.quitNow_ = true;
  }
  return true;
}

void ScriptedDriver::measureLatency(Viewer& v) {
  // Alternate edits of three kinds an artist makes: a strategy value, the camera, a volume value.
  if (measureIndex_ == 0) {
    measureStart_ = Clock::now();
    measureNext_ = Clock::now();
    measureFrames_ = 0;
  }
  if (Clock::now() < measureNext_ || v.latencyRequest_ != 0) return;
  if (measureIndex_ == v.options_.measureEdits) {
    ++measureIndex_;
    const double wall = std::chrono::duration<double>(Clock::now() - measureStart_).count();
    std::map<std::string, std::vector<double>> byKind;
    for (const auto& [label, ms] : measured_)
      if (ms >= 0.0) byKind[label].push_back(ms);
    std::printf("edit-to-first-image latency (%dx%d, %u hardware threads):\n", v.frame_->width, v.frame_->height,
                std::thread::hardware_concurrency());
    for (auto& [label, times] : byKind) {
      std::sort(times.begin(), times.end());
      std::printf("  %-40s median %6.1f ms  max %6.1f ms  (%zu edits)\n", label.c_str(), times[times.size() / 2], times.back(), times.size());
    }
    std::printf("UI frame rate while rendering: %.1f fps over %.1f s\n", measureFrames_ / wall, wall);
    std::fflush(stdout);
    return;
  }
  const int kind = measureIndex_ % 3;
  std::string label;
  const bool up = (measureIndex_ / 3) % 2 == 0;  // every edit changes something
  SceneDesc& e = v.edited_;
  if (kind == 0) {
    e.strategy.majorant.emission_weight = e.strategy.majorant.emission_weight == 10.0f ? 5.0f : 10.0f;
    label = "strategy (emission weight)";
  } else if (kind == 1) {
    const float angle = 0.05f * (up ? 1.0f : -1.0f);
    Vec3 offset = e.camera.position - e.camera.look_at;
    offset = Vec3(glm::rotate(Mat4(1.0f), angle, Vec3(0, 1, 0)) * glm::vec4(offset, 0.0f));
    e.camera.position = e.camera.look_at + offset;
    label = "camera (tumble)";
  } else {
    if (!e.volumes.empty()) e.volumes[0].emission.intensity *= up ? 1.25f : 0.8f;
    label = "volume (emission intensity, rebuild)";
  }
  measured_.push_back({label, -1.0});
  v.submitEdit();
  ++measureIndex_;
  measureNext_ = Clock::now() + std::chrono::milliseconds(400);
}

void ScriptedDriver::applyEdits(Viewer& v) {
  // Each edit a separate undo step, as separate typed values would be.
  for (const auto& e : v.options_.editsAfterStart) {
    v.applySettingEdit(e);
    v.history_.endGroup();
  }
  if (v.options_.resetCamera) {
    v.resetCamera();
    v.history_.endGroup();
  }
  editsDone_ = true;
}

void ScriptedDriver::step(Viewer& v) {
  const ViewerOptions& o = v.options_;
  // The UI frame rate counts every frame drawn while the edits are measured, previews included.
  if (measureIndex_ > 0 && measuring(v)) ++measureFrames_;
  if (v.compare_) {
    // Scripted comparison: the figure once every pane has had --equal-time seconds.
    const auto& frame = v.compFrame_;
    if (!o.figurePath.empty() && !v.figureDone_ && !v.figureRequest_ && frame && frame->status.empty() && !frame->panes.empty()) {
      bool done = o.equalTime > 0.0;
      for (const auto& p : frame->panes) done = done && p.film && p.seconds >= o.equalTime;
      if (done) v.writeFigure(o.figurePath);
    }
    if (!o.openImagePath.empty() && !imageOpened_ && frame && frame->status.empty()) {
      imageOpened_ = true;
      if (!v.openImage(o.openImagePath, true)) v.exitCode_ = 1;
      return;
    }
    // --screenshot: the figure and every pane, once every pane has the spp or seconds asked for.
    if (!o.screenshotPath.empty() && !screenshotDone_ && frame && frame->status.empty() && !frame->panes.empty()) {
      bool ready = true;
      for (const auto& p : frame->panes)
        ready = ready && p.film && !p.preparing && (o.afterSpp > 0 ? p.film->spp() >= o.afterSpp : p.seconds >= o.afterSeconds);
      if (ready) {
        screenshotDone_ = true;
        if (!v.screenshot(o.screenshotPath)) v.exitCode_ = 1;
      }
    }
    const bool figureWritten = v.figureDone_ && !v.figureRequest_;
    if (o.quit && (o.figurePath.empty() || figureWritten) && (o.screenshotPath.empty() || (screenshotDone_ && figureWritten)))
      v.quitNow_ = true;
    if (o.quit && !frame && std::chrono::duration<double>(Clock::now() - start_).count() > 5.0) {
      v.report("the comparison could not start; quitting");
      v.exitCode_ = 1;
      v.quitNow_ = true;
    }
    return;
  }
  if (!o.dropPath.empty() && !dropped_) {
    if (waitingForFullFrame(v)) return;  // once the first scene shows
    // As if the file were dropped on the window: the same path as a real drop.
    dropped_ = true;
    if (o.editWhileLoading && o.holdBuildsMs > 0) v.holdBuildForScriptedEdits_ = true;  // until applyEdits below
    v.droppedPaths_.push_back(o.dropPath);
    return;
  }
  if (o.editWhileLoading && dropped_ && !editsDone_ && v.droppedPaths_.empty()) {
    // The dropped file has started to open (pollDrops ran): edit it while it loads.
    const bool loading = v.pendingOpen_ != 0;
    applyEdits(v);
    v.holdBuildForScriptedEdits_ = false;
    std::printf("scripted: %zu edits%s made %s %s\n", o.editsAfterStart.size(), o.resetCamera ? " and a camera reset" : "",
                loading ? "while loading" : "after loading", o.dropPath.c_str());
    std::fflush(stdout);
    return;
  }
  if (waitingForFullFrame(v)) return;
  if (o.play) {
    if (!playPressed_) {
      v.playing_ = true;
      playPressed_ = true;
      playFrom_ = v.edited_.render.frame;
      return;
    }
    // What follows (a screenshot) waits for the first step to another frame to show, or for playback to pause
    // by itself: the step comes at the timeline's spp, whatever the machine's speed. Then Play is
    // pressed again, so the screenshot shows the frame stepped to rather than race the next step.
    if (v.playing_ && (v.edited_.render.frame == playFrom_ || v.frameLatencyPending_)) return;
    if (v.playing_) {
      v.playing_ = false;
      std::printf("scripted: paused on frame %d\n", v.edited_.render.frame);
      std::fflush(stdout);
    }
  }
  if (o.region.size() == 4 && !regionSet_) {
    regionSet_ = true;
    v.setRegion(RegionRect{o.region[0], o.region[1], o.region[2], o.region[3]});
    return;
  }
  if (!o.openImagePath.empty() && !imageOpened_) {
    imageOpened_ = true;
    if (!v.openImage(o.openImagePath, false)) v.exitCode_ = 1;
    return;
  }
  // A snapshot of the first image, compared with the live render once the edits below land.
  if (o.snapshotCompare && !snapshotDone_) {
    if (o.afterSpp > 0 && v.frame_->film.spp() < o.afterSpp) return;
    v.takeSnapshot();
    if (!v.snapshots_.snapshots().empty()) v.compareSnapshot(v.snapshots_.snapshots().back().id);
    v.canvas_.setWipe(true);
    snapshotDone_ = true;
    return;
  }
  if (!editsDone_) {
    applyEdits(v);
    if (!o.editsAfterStart.empty()) return;  // let the edits reach the renderer first
  }
  if (!historyDone_) {
    for (int i = 0; i < o.undoSteps; ++i) v.undo();
    for (int i = 0; i < o.redoSteps; ++i) v.redo();
    historyDone_ = true;
    if (o.undoSteps + o.redoSteps > 0) return;
  }
  if (!o.saveAsPath.empty() && !saveDone_) {
    saveDone_ = true;
    if (!v.save(o.saveAsPath)) v.exitCode_ = 1;
    return;
  }
  if (framesStepped_ < o.frameSteps) {
    // Step the timeline and wait for each frame's first full image (the viewer times it).
    if (!frameRequested_) {
      v.setFrame(v.edited_.render.frame + 1);
      frameRequested_ = true;
      return;
    }
    if (v.frameLatencyPending_) return;
    frameStepMs_.push_back(v.lastFrameStepMs_);
    frameRequested_ = false;
    if (++framesStepped_ == o.frameSteps) {
      std::vector<double> sorted = frameStepMs_;
      std::sort(sorted.begin(), sorted.end());
      std::printf("timeline: %d steps, first image of the next frame: median %.0f ms, max %.0f ms\n", o.frameSteps,
                  sorted[sorted.size() / 2], sorted.back());
      std::fflush(stdout);
    }
    return;
  }
  if (measuring(v)) return measureLatency(v);
  if (o.inspectPixel.size() == 2 && !inspectDone_) {
    v.inspector_.request(v.edited_, o.inspectPixel[0], o.inspectPixel[1]);
    inspectDone_ = true;
  }
  if (inspectDone_ && !v.inspector_.finished()) return;  // a scripted screenshot shows the chart
  if (inspectDone_ && !inspectReported_) {
    std::printf("inspector: %s\n", v.inspector_.summary().c_str());
    std::fflush(stdout);
    inspectReported_ = true;
  }
  if (!o.screenshotPath.empty() && !screenshotDone_) {
    // The image of the newest edit (not the last one before it) at the budget asked for.
    // With a render region, its samples are the ones that count.
    const int spp = v.frame_->region ? v.frame_->regionFilm.spp() : v.frame_->film.spp();
    const bool ready = v.latencyRequest_ == 0 && ((o.afterSpp > 0 && spp >= o.afterSpp) || (o.afterSeconds > 0.0 && v.frame_->seconds >= o.afterSeconds) ||
                       (o.afterSpp <= 0 && o.afterSeconds <= 0.0));
    if (!ready) return;
    screenshotDone_ = true;
    if (!v.screenshot(o.screenshotPath)) v.exitCode_ = 1;
    return;  // the canvas capture (if any) happens in the next frame's draw
  }
  if (!o.renderSequencePattern.empty()) {
    if (!sequenceStarted_) {
      sequenceStarted_ = true;
      const int first = v.frames_.empty() ? v.edited_.render.frame : v.frames_.first;
      const int last = v.frames_.empty() ? v.edited_.render.frame : v.frames_.last;
      if (!v.startSequenceRender(v.sequenceRequest(first, last, o.afterSpp > 0 ? o.afterSpp : v.edited_.render.spp, 0.0, o.renderSequencePattern)))
        v.exitCode_ = 1;
      return;
    }
    if (v.sequenceRunning_) return;
  }
  if (o.quit && (o.screenshotPath.empty() || screenshotDone_) && !v.canvasCaptureRequest_) v.quitNow_ = true;
}

}  // namespace candela
