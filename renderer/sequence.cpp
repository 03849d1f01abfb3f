#include "sequence.h"

#include "scene.h"

#include <algorithm>
#include <cctype>
#include <climits>
#include <cstdio>
#include <filesystem>
#include <regex>

namespace candela {

namespace fs = std::filesystem;

namespace {

// Where the pattern sits in a file name, and its width.
struct Pattern {
  size_t pos = std::string::npos, length = 0;
  int width = 0;
};

Pattern findPattern(const std::string& name) {
  Pattern p;
  // fire.####.vdb: a run of '#', one per digit.
  if (const size_t h = name.find('#'); h != std::string::npos) {
    size_t e = h;
    while (e < name.size() && name[e] == '#') ++e;
    return {h, e - h, static_cast<int>(e - h)};
  }
  // fire_$F4.vdb / fire_$F.vdb (Houdini): $F then an optional width digit.
  if (const size_t f = name.find("$F"); f != std::string::npos) {
    size_t e = f + 2;
    int width = 1;
    if (e < name.size() && std::isdigit(static_cast<unsigned char>(name[e]))) width = name[e++] - '0';
    return {f, e - f, std::max(1, width)};
  }
  // fire.%04d.vdb (printf).
  static const std::regex printf(R"(%0?(\d*)d)");
  std::smatch m;
  if (std::regex_search(name, m, printf)) {
    const int width = m[1].length() ? std::stoi(m[1].str()) : 1;
    return {static_cast<size_t>(m.position(0)), static_cast<size_t>(m.length(0)), std::clamp(width, 1, 9)};
  }
  return p;
}

std::string padded(int frame, int width) {
  char buf[32];
  if (frame < 0)
    std::snprintf(buf, sizeof(buf), "-%0*d", width, -frame);
  else
    std::snprintf(buf, sizeof(buf), "%0*d", width, frame);
  return buf;
}

}  // namespace

std::string volumeFilePath(const SceneDesc& scene, const VolumeDesc& volume) {
  if (fs::path(volume.file).is_absolute()) return volume.file;
  const fs::path base = scene.path.empty() ? fs::path(".") : fs::path(scene.path).parent_path();
  return (base / volume.file).lexically_normal().string();
}

std::string volumeFilePath(const SceneDesc& scene, const VolumeDesc& volume, int frame) {
  return substituteFrame(volumeFilePath(scene, volume), frame);
}

bool hasFramePattern(const std::string& file) { return findPattern(fs::path(file).filename().string()).pos != std::string::npos; }

std::string substituteFrame(const std::string& file, int frame) {
  const fs::path path(file);
  std::string name = path.filename().string();
  const Pattern p = findPattern(name);
  if (p.pos == std::string::npos) return file;
  name.replace(p.pos, p.length, padded(frame, p.width));
  return (path.parent_path() / name).string();
}

FrameRange parseFrameRange(const std::string& text, const std::string& origin) {
  const std::string expected = origin + ": expected a frame A or a range A-B with A <= B (e.g. 1-48), got \"" + text.substr(0, 80) + "\"";
  // One signed integer at `at`, in 64 bits; its end in `at`.
  auto number = [&](size_t& at, long long& value) {
    const size_t start = at;
    if (at < text.size() && (text[at] == '-' || text[at] == '+')) ++at;
    const size_t digits = at;
    while (at < text.size() && text[at] >= '0' && text[at] <= '9') ++at;
    if (at == digits || at - digits > 18) throw InputError(at - digits > 18 ? origin + ": frame numbers are at most " +
                                                                                  std::to_string(kMaxFrameNumber) + " (got \"" + text.substr(0, 80) + "\")"
                                                                            : expected);
    value = std::stoll(text.substr(start, at - start));
  };
  size_t at = 0;
  long long a = 0, b = 0;
  number(at, a);
  b = a;
  if (at < text.size()) {
    if (text[at] != '-') throw InputError(expected);
    ++at;
    number(at, b);
  }
  if (at != text.size()) throw InputError(expected);
  for (long long f : {a, b})
    if (f < -kMaxFrameNumber || f > kMaxFrameNumber)
      throw InputError(origin + ": frame " + std::to_string(f) + " is out of range; expected frames from " + std::to_string(-kMaxFrameNumber) +
                       " to " + std::to_string(kMaxFrameNumber));
  if (b < a) throw InputError(origin + ": the range " + text + " runs backwards; expected A-B with A <= B");
  if (b - a + 1 > kMaxFramesInRange)
    throw InputError(origin + ": " + std::to_string(b - a + 1) + " frames; expected at most " + std::to_string(kMaxFramesInRange) + " in one range");
  FrameRange r;
  r.first = static_cast<int>(a), r.last = static_cast<int>(b), r.count = static_cast<int>(b - a + 1);
  return r;
}

FrameRange findFrames(const std::string& patternPath) {
  FrameRange range;
  const fs::path path(patternPath);
  const std::string name = path.filename().string();
  const Pattern p = findPattern(name);
  if (p.pos == std::string::npos) return range;
  const std::string prefix = name.substr(0, p.pos), suffix = name.substr(p.pos + p.length);
  const fs::path dir = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  std::error_code ec;
  range.first = INT_MAX;
  range.last = INT_MIN;
  for (auto it = fs::directory_iterator(dir, ec); !ec && it != fs::directory_iterator(); it.increment(ec)) {
    const std::string f = it->path().filename().string();
    if (f.size() <= prefix.size() + suffix.size() || f.compare(0, prefix.size(), prefix) != 0 ||
        f.compare(f.size() - suffix.size(), suffix.size(), suffix) != 0)
      continue;
    const std::string digits = f.substr(prefix.size(), f.size() - prefix.size() - suffix.size());
    const bool negative = !digits.empty() && digits[0] == '-';
    const std::string body = negative ? digits.substr(1) : digits;
    if (body.empty() || body.size() > 9 || static_cast<int>(body.size()) < p.width ||
        !std::all_of(body.begin(), body.end(), [](unsigned char c) { return std::isdigit(c); }))
      continue;
    // Wider than the padding only without leading zeros (frame 12345 of ####).
    if (static_cast<int>(body.size()) > p.width && body[0] == '0') continue;
    const int frame = (negative ? -1 : 1) * std::stoi(body);
    range.first = std::min(range.first, frame);
    range.last = std::max(range.last, frame);
    ++range.count;
  }
  if (range.count == 0) return FrameRange{};
  return range;
}

FrameRange sceneFrames(const SceneDesc& scene) {
  FrameRange all;
  bool any = false;
  for (const auto& v : scene.volumes) {
    if (v.has_generator || !hasFramePattern(v.file)) continue;
    const FrameRange r = findFrames(volumeFilePath(scene, v));
    if (!any) {
      all = r;
      any = true;
    } else {
      all.first = std::max(all.first, r.first);
      all.last = std::min(all.last, r.last);
      all.count = std::min(all.count, r.count);
    }
  }
  return all;
}

bool detectSequence(const std::string& file, std::string& pattern, int& frame) {
  const fs::path path(file);
  const std::string stem = path.stem().string(), ext = path.extension().string();
  // The trailing digits of the stem, after '.', '_' or '-'.
  size_t d = stem.size();
  while (d > 0 && std::isdigit(static_cast<unsigned char>(stem[d - 1]))) --d;
  const size_t digits = stem.size() - d;
  if (digits == 0 || digits > 9 || d == 0 || (stem[d - 1] != '.' && stem[d - 1] != '_' && stem[d - 1] != '-')) return false;
  const std::string candidate = (path.parent_path() / (stem.substr(0, d) + std::string(digits, '#') + ext)).string();
  const FrameRange r = findFrames(candidate);
  if (r.count < 2) return false;
  pattern = candidate;
  frame = std::stoi(stem.substr(d));
  return true;
}

FramePrefetcher::~FramePrefetcher() {
  if (thread_.joinable()) thread_.join();
}

void FramePrefetcher::prefetch(const SceneDesc& scene) {
  if (busy_.load()) return;
  if (thread_.joinable()) thread_.join();
  busy_ = true;
  thread_ = std::thread([this, scene] {
    try {
      prefetchSceneGrids(scene);
    } catch (const std::exception&) {
      // The real load reports it.
    }
    busy_ = false;
  });
}

}  // namespace candela
