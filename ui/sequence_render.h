// File > Render sequence: the frames of the look being edited rendered to disk on a thread of their
// own, while the viewer stays live. Each frame renders as `candela-cli render --frames` renders it
// (the same description, frame number, spp and seed: the same image) and is written to a temporary
// file beside its final name, then renamed: a cancelled or failed frame never leaves a partial file
// under the final name, and a frame written earlier stays as it was. No GL: tests drive it headless.
#pragma once

#include "scene_desc.h"

#include <atomic>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace candela {

struct SequenceRenderRequest {
  SceneDesc scene;           // the look, as edited
  int first = 1, last = 1;   // frames, inclusive
  int spp = 16;              // samples per pixel of every frame (used when seconds is 0)
  double seconds = 0.0;      // else: this many seconds of rendering per frame
  std::string pattern;       // output: OUT.####.exr (or %04d, $F4); .exr or .png
  float exposure = 0.0f;     // a PNG's exposure in stops: the viewer's, one for every frame
  bool autoExposure = false; // none chosen yet: auto exposure from the first frame, kept for the rest
  int threads = 0;
};

struct SequenceProgress {
  bool running = false, cancelled = false;
  int total = 0, done = 0;        // frames asked for, frames finished (written or failed)
  int frame = 0;                  // the frame rendering now
  double frameFraction = 0.0;     // of it, 0 to 1
  std::vector<std::string> written;
  std::vector<std::string> failed;  // "frame N: why"
  double fraction() const { return total ? (done + frameFraction) / total : 0.0; }
};

class SequenceRenderJob {
 public:
  explicit SequenceRenderJob(bool yieldToUi = false) : yieldToUi_(yieldToUi) {}
  ~SequenceRenderJob();
  SequenceRenderJob(const SequenceRenderJob&) = delete;
  SequenceRenderJob& operator=(const SequenceRenderJob&) = delete;

  // Checks the request (InputError naming what is wrong: no frame pattern, an extension that is not
  // .exr or .png, a reversed range, no spp or seconds) and starts; a job still running is cancelled
  // first.
  void start(const SequenceRenderRequest& request);
  void cancel();  // the frame in flight stops and is not written
  void wait();    // until the job ends
  SequenceProgress progress() const;

 private:
  void run(SequenceRenderRequest request);
  bool yieldToUi_;
  std::atomic<bool> cancel_{false};
  mutable std::mutex mutex_;
  SequenceProgress progress_;
  std::thread worker_;
};

}  // namespace candela
