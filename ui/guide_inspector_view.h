// The viewer's guide inspector (Ctrl+click on a pixel): renderer/guide_inspector.h's densities
// along that pixel's camera ray (or a secondary ray), charted with ImGui's draw lists, with each
// technique's variance factor. The inspection runs on its own thread over its own copy of the
// scene, so a slow one never blocks the UI or the render.
#pragma once

#include "guide_inspector.h"
#include "scene_desc.h"

#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace candela {

class GuideInspectorView {
 public:
  ~GuideInspectorView();
  // Inspects pixel (x, y) of `desc` (the scene as edited now). While one runs, the newest request
  // waits and starts when it finishes: the UI thread never waits for an inspection.
  void request(const SceneDesc& desc, int x, int y);
  // Draws the window while it is open.
  void draw();
  bool busy() const { return running_.load(); }
  // An inspection has finished (with a chart or an error).
  bool finished() const;
  // The finished inspection in one line (inspectionSummary), or its error.
  std::string summary() const;

 private:
  void join();
  void start();
  bool pending_ = false;
  std::thread worker_;
  std::atomic<bool> running_{false};
  mutable std::mutex mutex_;
  std::shared_ptr<const GuideInspection> result_;
  std::string title_, error_;
  SceneDesc desc_;
  int x_ = 0, y_ = 0;
  int secondarySeed_ = -1;  // -1: the camera ray
  bool open_ = false;
};

}  // namespace candela
