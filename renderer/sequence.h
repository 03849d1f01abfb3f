// Volume sequences: a volume file may name a frame pattern, as simulation caches are written:
// fire.####.vdb (Houdini, one # per digit), fire_$F4.vdb (Houdini's $F with a width) or
// fire.%04d.vdb (printf). render.frame says which frame a scene shows. Headless: the CLI's
// --frames and the viewer's timeline both use it.
#pragma once

#include "scene_desc.h"

#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace candela {

// A volume file resolved against its scene's directory (absolute paths stay): with its frame
// pattern as written, or with `frame` substituted.
std::string volumeFilePath(const SceneDesc& scene, const VolumeDesc& volume);
std::string volumeFilePath(const SceneDesc& scene, const VolumeDesc& volume, int frame);

// True when `file` holds a frame pattern.
bool hasFramePattern(const std::string& file);
// The file of frame `frame`: the pattern replaced by the zero-padded number (negative frames keep
// their sign before the padding, as Houdini writes them). Files without a pattern come back as is.
std::string substituteFrame(const std::string& file, int frame);

struct FrameRange {
  int first = 0, last = -1;  // inclusive; empty when last < first
  int count = 0;             // frames found on disk (gaps are allowed)
  bool empty() const { return last < first; }
};
// The most frames one range may name, and the largest frame number (render.frame's range): a range
// past them is a typing error, refused before anything renders.
inline constexpr long long kMaxFramesInRange = 100000;
inline constexpr long long kMaxFrameNumber = 1000000;
// "A" or "A-B" (frames A to B inclusive; either may be negative: "-10--1"), parsed in 64 bits and
// checked: A <= B, both within +-kMaxFrameNumber, at most kMaxFramesInRange frames. Errors name
// `origin` (e.g. "--frames") and what was expected.
FrameRange parseFrameRange(const std::string& text, const std::string& origin);

// The frames on disk that match the pattern `path` (a path with a pattern in its file name).
FrameRange findFrames(const std::string& path);
// The frames of every patterned volume of `scene` (resolved against its path): their intersection,
// or empty when no volume has a pattern.
FrameRange sceneFrames(const SceneDesc& scene);

// For a file that looks like one frame of a sequence (fire.0012.vdb, fire_0012.vdb) with at least
// one other frame beside it: the pattern ("fire.####.vdb") and the frame number. Else false.
bool detectSequence(const std::string& path, std::string& pattern, int& frame);

// Loads the grids of `scene` (at its render.frame) into the loader's cache on a thread of its own,
// so stepping to that frame finds them ready. Errors are ignored here: the real load reports them.
class FramePrefetcher {
 public:
  ~FramePrefetcher();
  // Starts loading `scene`'s grids unless a load is running (then it is skipped: the next step asks
  // again).
  void prefetch(const SceneDesc& scene);
  bool busy() const { return busy_.load(); }

 private:
  std::thread thread_;
  std::atomic<bool> busy_{false};
};

}  // namespace candela
