// Snapshots of the live render, as in RenderView and `it`: the image (scene-linear) and the look
// that made it (scene + display JSON), kept on disk for the session so a crash loses none. The
// viewer lists them with thumbnails, compares any with the live render (wipe or side by side) and
// restores a snapshot's settings. Headless: tests use it without a window.
#pragma once

#include "image_io.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace candela {

struct Snapshot {
  int id = 0;
  std::string label;      // "#3 emission 64 spp"
  std::string path;       // its EXR (settings in the metadata)
  Image image;            // scene-linear mean
  nlohmann::json look;    // {"scene": ..., "display": ...}
  int spp = 0;
  // 8-bit sRGB thumbnail at most kThumbnailWidth wide (exposure of the look applied).
  int thumbWidth = 0, thumbHeight = 0;
  std::vector<uint8_t> thumbnail;
};

class SnapshotStore {
 public:
  static constexpr int kThumbnailWidth = 160;
  // Snapshots live in `directory` (created on the first snapshot).
  explicit SnapshotStore(std::string directory) : directory_(std::move(directory)) {}
  // A directory for this viewer session under the cache: snapshots/YYYYMMDD-HHMMSS-PID.
  static std::string sessionDirectory();

  // Keeps `image` with the look that produced it; writes it to disk. Throws on I/O errors.
  const Snapshot& add(const Image& image, const nlohmann::json& look, int spp, const std::string& strategy);
  void remove(int id);
  const std::vector<Snapshot>& snapshots() const { return snapshots_; }
  const Snapshot* find(int id) const;
  const std::string& directory() const { return directory_; }
  // Reads back every snapshot in the directory (a session reopened after a crash).
  void loadDirectory();

 private:
  static void makeThumbnail(Snapshot& s);
  std::string directory_;
  std::vector<Snapshot> snapshots_;
  int nextId_ = 1;
};

}  // namespace candela
