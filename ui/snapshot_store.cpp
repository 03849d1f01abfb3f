#include "snapshot_store.h"

#include "procedural.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>

namespace candela {

namespace fs = std::filesystem;

std::string SnapshotStore::sessionDirectory() {
  const std::time_t now = std::time(nullptr);
  char stamp[32];
  std::strftime(stamp, sizeof(stamp), "%Y%m%d-%H%M%S", std::localtime(&now));
  return (fs::path(cacheDirectory()) / "snapshots" / (std::string(stamp) + "-" + std::to_string(::getpid()))).string();
}

void SnapshotStore::makeThumbnail(Snapshot& s) {
  const Image& im = s.image;
  if (im.width <= 0 || im.height <= 0) return;
  const int w = std::min(kThumbnailWidth, im.width);
  const int h = std::max(1, im.height * w / im.width);
  float exposure = 0.0f;
  if (s.look.contains("display") && s.look["display"].contains("exposure")) exposure = s.look["display"]["exposure"].get<float>();
  const float gain = std::exp2(exposure);
  s.thumbWidth = w, s.thumbHeight = h;
  s.thumbnail.assign(3 * static_cast<size_t>(w) * h, 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      // Box filter over the source pixels that map to this thumbnail pixel.
      const int x0 = x * im.width / w, x1 = std::max(x0 + 1, (x + 1) * im.width / w);
      const int y0 = y * im.height / h, y1 = std::max(y0 + 1, (y + 1) * im.height / h);
      for (int c = 0; c < 3; ++c) {
        double sum = 0.0;
        for (int sy = y0; sy < y1; ++sy)
          for (int sx = x0; sx < x1; ++sx) sum += im.rgb[3 * (static_cast<size_t>(sy) * im.width + sx) + c];
        const float mean = static_cast<float>(sum / ((x1 - x0) * (y1 - y0)));
        s.thumbnail[3 * (static_cast<size_t>(y) * w + x) + c] = static_cast<uint8_t>(std::lround(255.0f * srgbEncode(mean * gain)));
      }
    }
}

const Snapshot& SnapshotStore::add(const Image& image, const nlohmann::json& look, int spp, const std::string& strategy) {
  Snapshot s;
  s.id = nextId_++;
  s.label = "#" + std::to_string(s.id) + " " + strategy + " " + std::to_string(spp) + " spp";
  s.image = image;
  s.image.channels.clear();
  s.look = look;
  s.spp = spp;
  s.image.metadata["snapshot_label"] = s.label;
  s.image.metadata["look"] = look.dump();
  s.image.metadata["spp"] = std::to_string(spp);
  fs::create_directories(directory_);
  char name[32];
  std::snprintf(name, sizeof(name), "snapshot-%03d.exr", s.id);
  s.path = (fs::path(directory_) / name).string();
  writeExr(s.path, s.image);
  makeThumbnail(s);
  snapshots_.push_back(std::move(s));
  return snapshots_.back();
}

void SnapshotStore::remove(int id) {
  const auto it = std::find_if(snapshots_.begin(), snapshots_.end(), [&](const Snapshot& s) { return s.id == id; });
  if (it == snapshots_.end()) return;
  std::error_code ec;
  fs::remove(it->path, ec);
  snapshots_.erase(it);
}

const Snapshot* SnapshotStore::find(int id) const {
  for (const auto& s : snapshots_)
    if (s.id == id) return &s;
  return nullptr;
}

void SnapshotStore::loadDirectory() {
  std::error_code ec;
  std::vector<fs::path> files;
  for (auto it = fs::directory_iterator(directory_, ec); !ec && it != fs::directory_iterator(); it.increment(ec))
    if (it->path().extension() == ".exr" && it->path().filename().string().rfind("snapshot-", 0) == 0) files.push_back(it->path());
  std::sort(files.begin(), files.end());
  snapshots_.clear();
  for (const auto& f : files) {
    Snapshot s;
    s.path = f.string();
    s.image = readExr(s.path);
    s.image.channels.clear();
    s.id = std::atoi(f.stem().string().substr(9).c_str());
    s.label = s.image.metadata.count("snapshot_label") ? s.image.metadata["snapshot_label"] : f.filename().string();
    if (s.image.metadata.count("look")) s.look = nlohmann::json::parse(s.image.metadata["look"], nullptr, false);
    if (s.image.metadata.count("spp")) s.spp = std::atoi(s.image.metadata["spp"].c_str());
    makeThumbnail(s);
    nextId_ = std::max(nextId_, s.id + 1);
    snapshots_.push_back(std::move(s));
  }
}

}  // namespace candela
