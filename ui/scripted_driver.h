// Scripted runs of the viewer, for tests and batch use: --screenshot/--after-spp, --figure,
// --measure-latency, --inspect, --edit, --undo/--redo, --save-as, --snapshot-compare,
// --frame-steps, --play, --drop/--edit-while-loading and --quit. Each step waits for the image it needs, so a
// run does the same thing on an idle or a busy machine. It drives the Viewer through the same calls
// the keys and menus make.
#pragma once

#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace candela {

class Viewer;

class ScriptedDriver {
 public:
  // Called once a frame after drawing. Sets the viewer's quit flag when the script is done.
  void step(Viewer& v);
  // The latency of an edit just measured (the viewer times edit-to-first-image).
  void editMeasured(double ms);
  bool measuring(const Viewer& v) const;
  bool active(const Viewer& v) const;

 private:
  bool waitingForFullFrame(Viewer& v);
  void applyEdits(Viewer& v);  // the --edit edits, once
  void measureLatency(Viewer& v);
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  bool dropped_ = false;
  bool imageOpened_ = false, sequenceStarted_ = false, regionSet_ = false;
  bool snapshotDone_ = false, editsDone_ = false, historyDone_ = false, saveDone_ = false, screenshotDone_ = false;
  int framesStepped_ = 0;
  bool frameRequested_ = false;
  std::vector<double> frameStepMs_;
  bool inspectDone_ = false, inspectReported_ = false, playPressed_ = false;
  int playFrom_ = 0;  // the frame --play started on
  int measureIndex_ = 0;
  std::chrono::steady_clock::time_point measureNext_, measureStart_;
  int measureFrames_ = 0;
  std::vector<std::pair<std::string, double>> measured_;
};

}  // namespace candela
