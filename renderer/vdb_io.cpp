// OpenVDB -> NanoVDB loading. Heavy headers live here on purpose: OpenVDB headers cost tens of seconds per file to compile.
#include "vdb_io.h"

#include "fields.h"
#include "input_limits.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetUtil.h>
#include <nanovdb/util/OpenToNanoVDB.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <filesystem>
#include <mutex>

namespace candela {

namespace {

void initOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

Mat4 toGlm(const openvdb::math::Mat4d& m) {
  // OpenVDB multiplies row vectors (p' = p M, translation in row 3); glm uses column vectors with
  // translation in column 3, so element (i, j) maps to glm's m[i][j].
  Mat4 out;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) out[i][j] = static_cast<float>(m(i, j));
  return out;
}

// Reads the parts of a VDB file where OpenVDB trusts a length field (the header, the file's and
// each grid's metadata, the grid descriptors) and checks every length and offset against the file
// size before OpenVDB sees the file: a corrupt length would otherwise make OpenVDB build a
// multi-gigabyte string or seek past the end (found by tests/fuzz/fuzz_vdb.cpp). Returns an
// empty string when the structure is sound, else what is wrong.
// A file read through one 64 KB window. The structure check skips most of what it walks (the data
// chunks); a seek of the stream per skip was a system call each, 0.4-0.9 s on a 150 MB file of 65
// thousand leaves, where the window reads each byte of it once.
class WindowedFile {
 public:
  explicit WindowedFile(const std::string& path) : in_(path, std::ios::binary), window_(kWindow) {
    in_.seekg(0, std::ios::end);
    size_ = static_cast<uint64_t>(std::max<std::streamoff>(0, in_.tellg()));
    in_.seekg(0);
  }
  bool good() const { return static_cast<bool>(in_); }
  uint64_t size() const { return size_; }
  uint64_t tell() const { return pos_; }
  uint64_t remaining() const { return pos_ < size_ ? size_ - pos_ : 0; }
  void seek(uint64_t pos) { pos_ = pos; }
  bool skip(uint64_t n) {
    if (n > remaining()) return false;
    pos_ += n;
    return true;
  }
  bool read(char* out, uint64_t n) {
    if (n > remaining()) return false;
    while (n > 0) {
      if (pos_ < start_ || pos_ >= start_ + length_) {
        start_ = pos_;
        length_ = std::min<uint64_t>(kWindow, size_ - pos_);
        in_.clear();
        in_.seekg(static_cast<std::streamoff>(start_));
        in_.read(window_.data(), static_cast<std::streamsize>(length_));
        if (static_cast<uint64_t>(in_.gcount()) != length_) {
          length_ = 0;
          return false;
        }
      }
      const uint64_t take = std::min(n, start_ + length_ - pos_);
      std::memcpy(out, window_.data() + (pos_ - start_), take);
      out += take, n -= take, pos_ += take;
    }
    return true;
  }

 private:
  static constexpr uint64_t kWindow = 64 * 1024;
  std::ifstream in_;
  std::vector<char> window_;
  uint64_t size_ = 0, pos_ = 0, start_ = 0, length_ = 0;
};

class VdbStructureCheck {
 public:
  explicit VdbStructureCheck(const std::string& path) : in_(path), size_(in_.size()) {}

  std::string run() {
    if (!in_.good()) return "cannot read the file";
    int64_t magic = 0;
    uint32_t version = 0, libraryMajor = 0, libraryMinor = 0;
    if (!read(magic) || magic != 0x56444220) return "not a VDB file (no VDB magic number at the start)";
    if (!read(version)) return "truncated header";
    if (version < openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION)
      return "written by an OpenVDB older than 3.0 (file format " + std::to_string(version) + "); re-save it with a current OpenVDB";
    if (version > openvdb::OPENVDB_FILE_VERSION) return "file format " + std::to_string(version) + " is newer than this OpenVDB reads";
    char hasGridOffsets = 0;
    if (!read(libraryMajor) || !read(libraryMinor) || !read(hasGridOffsets)) return "truncated header";
    if (!uuid()) return "corrupt header (the file's UUID is not 36 hex digits and dashes)";
    if (const std::string e = metaMap("file metadata"); !e.empty()) return e;
    // Without offsets (a stream, not a file) OpenVDB reads whole grids before any can be checked.
    if (!hasGridOffsets) return "written as a stream without grid offsets; re-save it as a .vdb file";
    int32_t gridCount = 0;
    if (!read(gridCount) || gridCount < 0 || static_cast<uint64_t>(gridCount) > remaining() / 36)
      return "corrupt grid count (" + std::to_string(gridCount) + ")";
    for (int32_t g = 0; g < gridCount; ++g) {
      std::string name, type, parent;
      int64_t gridPos = 0, blockPos = 0, endPos = 0;
      if (!string(name) || !string(type) || !string(parent)) return "corrupt descriptor of grid " + std::to_string(g);
      if (!read(gridPos) || !read(blockPos) || !read(endPos)) return "truncated descriptor of grid " + std::to_string(g);
      const auto inFile = [this](int64_t p) { return p >= 0 && static_cast<uint64_t>(p) <= size_; };
      const int64_t here = static_cast<int64_t>(in_.tell());
      if (!inFile(gridPos) || !inFile(blockPos) || !inFile(endPos) || gridPos < here || blockPos < gridPos || endPos < blockPos)
        return "grid \"" + printable(name) + "\" has offsets outside the file (is it truncated?)";
      in_.seek(static_cast<uint64_t>(gridPos));
      uint32_t compression = 0;
      if (!read(compression)) return "truncated grid \"" + printable(name) + "\"";
      if (const std::string e = metaMap("metadata of grid \"" + printable(name) + "\""); !e.empty()) return e;
      const std::string baseType = type.substr(0, type.find("_HalfFloat"));
      types[name] = baseType;
      if (parent.empty()) {
        if (const std::string e = transformAndRoot(printable(name), baseType, type != baseType, compression, blockPos); !e.empty())
          return e;
      }
      in_.seek(static_cast<uint64_t>(endPos));
    }
    return {};
  }

  // Grid type of each grid, by unique name (the type OpenVDB would instantiate).
  std::map<std::string, std::string> types;

 private:
  template <class T>
  bool read(T& v) {
    return in_.read(reinterpret_cast<char*>(&v), sizeof(T));
  }
  bool skip(uint64_t n) {
    return in_.skip(n);
  }
  // OpenVDB reads the UUID with boost's formatted operator>>, which skips whitespace before and
  // inside it: a stray tab or newline there shifts every later field by a byte from where this
  // check reads them, and OpenVDB then sized a string by 3 GB of garbage (a fuzz finding). Files
  // OpenVDB writes hold the canonical 8-4-4-4-12 form, so nothing else is accepted.
  bool uuid() {
    char text[36];
    if (!in_.read(text, sizeof(text))) return false;
    for (int i = 0; i < 36; ++i) {
      const bool dash = i == 8 || i == 13 || i == 18 || i == 23;
      const char c = text[i];
      const bool hex = (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F');
      if (dash ? c != '-' : !hex) return false;
    }
    return true;
  }
  bool string(std::string& out) {
    uint32_t length = 0;
    if (!read(length) || length > remaining() || length > 4096) return false;
    out.resize(length);
    return in_.read(out.data(), length);
  }
  std::string metaMap(const std::string& what) {
    int32_t count = 0;
    if (!read(count) || count < 0 || static_cast<uint64_t>(count) > remaining() / 12) return "corrupt " + what + " (entry count)";
    for (int32_t i = 0; i < count; ++i) {
      std::string name, type;
      uint32_t valueSize = 0;
      if (!string(name) || !string(type) || !read(valueSize) || valueSize > remaining())
        return "corrupt " + what + " (entry " + std::to_string(i) + ")";
      // A registered fixed-size type is read at its own size whatever the entry says (TypedMetadata::
      // readValue): any other size puts OpenVDB out of step with the file (a fuzz finding: a vec4i
      // of 12 bytes, after which OpenVDB sized a name by 1.7 GB of garbage).
      static const std::map<std::string, uint32_t> fixedSizes = {
          {"bool", 1},   {"double", 8}, {"float", 4},  {"int32", 4},  {"int64", 8},  {"vec2i", 8},  {"vec2s", 8},  {"vec2d", 16},
          {"vec3i", 12}, {"vec3s", 12}, {"vec3d", 24}, {"vec4i", 16}, {"vec4s", 16}, {"vec4d", 32}, {"mat4s", 64}, {"mat4d", 128}};
      if (const auto fixed = fixedSizes.find(type); fixed != fixedSizes.end() && fixed->second != valueSize)
        return "corrupt " + what + " (entry " + std::to_string(i) + ": a " + type + " of " + std::to_string(valueSize) + " bytes)";
      if (type == "__delayedload" && valueSize > 0) {
        if (const std::string e = delayedLoad(valueSize); !e.empty()) return "corrupt " + what + " (delayed-load metadata: " + e + ")";
      } else if (!skip(valueSize)) {
        return "corrupt " + what + " (entry " + std::to_string(i) + ")";
      }
    }
    return {};
  }
  // io::DelayedLoadMetadata::readValue: a leaf count, then a mask per leaf (1 byte each) and
  // optionally a compressed size per leaf (8 bytes), each stored raw or as one blosc buffer. OpenVDB
  // sizes its arrays by the count and by the blosc header's uncompressed size, and reads what the
  // parts say whatever the entry's size; each is checked against the entry and the file.
  std::string delayedLoad(uint32_t valueSize) {
    const uint64_t end = in_.tell() + valueSize;
    uint32_t leaves = 0, bytes = 0;
    // Every leaf stores at least its 64-byte value mask in the file, which bounds the count.
    if (!read(leaves) || leaves > size_ / 64) return "leaf count " + std::to_string(leaves);
    for (const uint64_t element : {uint64_t{1}, uint64_t{8}}) {
      if (!read(bytes)) return "truncated";
      if (element == 8 && bytes == std::numeric_limits<uint32_t>::max()) break;  // no compressed sizes stored
      if (bytes == 0) {
        if (!skip(leaves * element)) return "truncated";
        continue;
      }
      // A blosc buffer: its 16-byte header's uncompressed and compressed sizes (bytes 4-7, 12-15)
      // must be what the count asks for (OpenVDB pads less than 128 bytes to 128 before it
      // compresses: compression::bloscCompress) and what the entry holds.
      std::array<uint32_t, 4> header{};
      const uint64_t expected = std::max<uint64_t>(leaves * element, 128);
      if (bytes < sizeof(header) || !read(header) || header[1] != expected || header[3] != bytes)
        return "a blosc buffer whose sizes disagree with its leaf count";
      if (!skip(bytes - sizeof(header))) return "truncated";
    }
    if (in_.tell() > end) return "longer than its entry";
    in_.seek(end);
    return {};
  }
  // The transform (its map's type name, then fixed-size data) and, for the grid types Candela reads
  // (float, double, vec3s), the root node's tile and child counts, which OpenVDB allocates by: the
  // topology lies between here and blockPos, and each tile takes 12 bytes and a value there, each
  // child at least 12 + 8192 (origin, masks). Then the whole tree (tree()).
  std::string transformAndRoot(const std::string& name, const std::string& gridType, bool savedAsHalf, uint32_t compression,
                               int64_t blockPos) {
    std::string map;
    if (!string(map)) return "corrupt transform of grid \"" + name + "\"";
    static const std::map<std::string, uint64_t> mapBytes = {
        {"AffineMap", 128},         {"UnitaryMap", 128},         {"ScaleMap", 120},
        {"UniformScaleMap", 120},   {"TranslationMap", 24},      {"ScaleTranslateMap", 144},
        {"UniformScaleTranslateMap", 144}};
    if (map == "NonlinearFrustumMap") return "grid \"" + name + "\" has a non-linear (frustum) transform, expected a linear one";
    const auto it = mapBytes.find(map);
    if (it == mapBytes.end()) return "grid \"" + name + "\" has an unknown transform type \"" + printable(map) + "\"";
    if (!skip(it->second)) return "truncated transform of grid \"" + name + "\"";
    // Bytes of a value stored whole (background, tiles, inactive values), and in a data chunk
    // saved as half (Compression.h's RealToHalf).
    static const std::map<std::string, std::pair<uint64_t, uint64_t>> valueBytes = {
        {"Tree_float_5_4_3", {4, 2}}, {"Tree_double_5_4_3", {8, 2}}, {"Tree_vec3s_5_4_3", {12, 6}}};
    const auto format = valueBytes.find(gridType);
    if (format == valueBytes.end()) return {};
    TreeFormat f;
    f.value = format->second.first;
    f.chunkValue = savedAsHalf ? format->second.second : f.value;
    f.half = savedAsHalf;
    f.compression = compression;
    int32_t bufferCount = 0;
    uint32_t tiles = 0, children = 0;
    if (!read(bufferCount) || !skip(f.value) || !read(tiles) || !read(children)) return "truncated topology of grid \"" + name + "\"";
    const int64_t here = static_cast<int64_t>(in_.tell());
    const double topology = static_cast<double>(blockPos - here);
    if ((13.0 + static_cast<double>(f.value)) * tiles + (12.0 + 8192.0) * children > topology)
      return "corrupt topology of grid \"" + name + "\" (" + std::to_string(tiles) + " tiles and " + std::to_string(children) +
             " children in " + std::to_string(blockPos - here) + " bytes)";
    // Each tile: its origin, its value and an active flag OpenVDB reads into a bool, so a byte other
    // than 0 or 1 is undefined behaviour wherever the flag is used (a fuzz finding).
    for (uint32_t t = 0; t < tiles; ++t) {
      uint8_t active = 0;
      if (!skip(12 + f.value) || !read(active)) return "truncated topology of grid \"" + name + "\"";
      if (active > 1) return "corrupt tree of grid \"" + name + "\" (root tile " + std::to_string(t) + ")";
    }
    return tree(name, f, children);
  }

  // How a grid's values are stored: the sizes above and the grid's compression flags.
  struct TreeFormat {
    uint64_t value = 4, chunkValue = 4;
    bool half = false;
    uint32_t compression = 0;
  };
  static constexpr uint32_t kZip = 0x1, kActiveMask = 0x2, kBlosc = 0x4;  // io::COMPRESS_*

  // The root's children (5-4-3 internal nodes and leaves) as OpenVDB 10 reads them: each node's
  // masks, its values (io::readCompressedValues), then the leaves' buffers in the root's order.
  // OpenVDB reads a chunk that claims to be stored uncompressed into a buffer sized by the node's
  // active values before it compares the two sizes (io::unzipFromStream, bloscFromStream): a corrupt
  // count wrote past the buffer (a fuzz finding). Every chunk is checked here instead.
  std::string tree(const std::string& name, const TreeFormat& f, uint32_t children) {
    const std::string corrupt = "corrupt tree of grid \"" + name + "\"";
    // Per root child, by its origin (the root's std::map order, in which buffers are read): the
    // active counts of its leaves, in the order their topology was read.
    std::map<std::array<int32_t, 3>, std::vector<uint16_t>> leavesByOrigin;
    std::vector<uint64_t> mask5(512), values5(512), mask4(64), values4(64), leaf(8);
    for (uint32_t c = 0; c < children; ++c) {
      std::array<int32_t, 3> origin{};
      if (!read(origin)) return corrupt + " (root child " + std::to_string(c) + ")";
      std::vector<uint16_t> leaves;
      if (!words(mask5) || !words(values5) || !valueChunk(f, 32768, popcount(values5)))
        return corrupt + " (internal node at root child " + std::to_string(c) + ")";
      for (uint64_t w = 0; w < mask5.size(); ++w)
        for (uint64_t bits = mask5[w]; bits; bits &= bits - 1) {
          if (!words(mask4) || !words(values4) || !valueChunk(f, 4096, popcount(values4)))
            return corrupt + " (internal node under root child " + std::to_string(c) + ")";
          for (uint64_t v = 0; v < mask4.size(); ++v)
            for (uint64_t leafBits = mask4[v]; leafBits; leafBits &= leafBits - 1) {
              if (!words(leaf)) return corrupt + " (leaf topology)";
              leaves.push_back(static_cast<uint16_t>(popcount(leaf)));
            }
        }
      // A repeated origin replaces the earlier child in OpenVDB's table (which it then leaks).
      if (!leavesByOrigin.emplace(origin, std::move(leaves)).second) return corrupt + " (two root children at one origin)";
    }
    for (const auto& [origin, leaves] : leavesByOrigin)
      for (const uint16_t active : leaves) {
        // The buffer repeats the leaf's value mask, which the file reader skips for the topology's.
        if (!words(leaf) || popcount(leaf) != active || !valueChunk(f, 512, active)) return corrupt + " (leaf buffer)";
      }
    return {};
  }
  bool words(std::vector<uint64_t>& out) {
    return in_.read(reinterpret_cast<char*>(out.data()), out.size() * 8);
  }
  static uint64_t popcount(const std::vector<uint64_t>& mask) {
    uint64_t n = 0;
    for (const uint64_t w : mask) n += static_cast<uint64_t>(__builtin_popcountll(w));
    return n;
  }
  // io::readCompressedValues for `count` values of which `active` are on.
  bool valueChunk(const TreeFormat& f, uint64_t count, uint64_t active) {
    int8_t metadata = 0;
    if (!read(metadata)) return false;
    enum : int8_t { kOneInactive = 2, kMaskNoInactive = 3, kMaskOneInactive = 4, kMaskTwoInactive = 5, kAllValues = 6 };
    if (metadata == kOneInactive || metadata == kMaskOneInactive || metadata == kMaskTwoInactive)
      if (!skip(f.value * (metadata == kMaskTwoInactive ? 2 : 1))) return false;
    if (metadata == kMaskNoInactive || metadata == kMaskOneInactive || metadata == kMaskTwoInactive)
      if (!skip(count / 8)) return false;  // the selection mask
    const uint64_t stored = (f.compression & kActiveMask) && metadata != kAllValues ? active : count;
    if (f.half && stored == 0) return true;  // HalfReader reads nothing at all then
    const uint64_t bytes = stored * f.chunkValue;
    if (!(f.compression & (kZip | kBlosc))) return skip(bytes);
    int64_t chunk = 0;
    if (!read(chunk)) return false;
    if (chunk <= 0) return chunk != std::numeric_limits<int64_t>::min() && static_cast<uint64_t>(-chunk) == bytes && skip(bytes);
    return skip(static_cast<uint64_t>(chunk));
  }
  uint64_t remaining() const { return in_.remaining(); }
  static std::string printable(const std::string& s) {
    std::string out;
    for (char c : s.substr(0, 60)) out += (c >= 32 && c < 127) ? c : '?';
    return out;
  }

  WindowedFile in_;
  uint64_t size_ = 0;
};

}  // namespace

namespace {

// The checks every float grid passes before it is used (what the renderer can represent:
// input_limits.h), a level set turned into its fog volume, NaN / Inf / negative values set to 0, and
// the NanoVDB conversion.
LoadedGrid convertFloatGrid(const openvdb::FloatGrid::Ptr& floatGrid, const std::string& path, const std::string& field,
                            const std::string& name) {
  if (!floatGrid->transform().isLinear())
    throw InputError(path + ": " + field + ": grid \"" + name + "\" has a non-linear (frustum) transform, expected a linear one");
  // What the renderer can represent (input_limits.h), checked before any dense or NanoVDB copy.
  const auto fail = [&](const std::string& what) { throw InputError(path + ": " + field + ": grid \"" + name + "\" " + what); };
  // OpenVDB builds the affine form of a scale map and throws when it is nearly singular (a fuzz
  // finding: a scale of 1e-30 in a ScaleMap).
  openvdb::math::Mat4d map;
  try {
    map = floatGrid->transform().baseMap()->getAffineMap()->getMat4();
  } catch (const openvdb::Exception& e) {
    fail(std::string("has a degenerate (flat) index-to-world transform (") + e.what() + ")");
  }
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      if (!std::isfinite(map(i, j)) || std::abs(map(i, j)) > 1e12) fail("has a non-finite or absurd index-to-world transform");
  const double det = std::abs(map.getMat3().det());
  if (!(det > 0.0)) fail("has a degenerate (flat) index-to-world transform");
  const double voxelSize = std::cbrt(det);
  if (voxelSize < limits::kMinVoxelSize || voxelSize > limits::kMaxVoxelSize)
    fail("has voxels " + std::to_string(voxelSize) + " world units wide; expected between 1e-6 and 1e6");
  // A level set (a signed distance field: a collision object, a mesh converted to VDB) holds no
  // density; read as one it would render as a thin shell. It is rendered as the fog volume it
  // bounds, as Houdini's Convert VDB makes one: 1 inside, falling to 0 across the band's inner half.
  const bool levelSet = floatGrid->getGridClass() == openvdb::GRID_LEVEL_SET;
  if (levelSet && !(std::isfinite(floatGrid->background()) && floatGrid->background() > 0.0f))
    fail("is a level set with background value " + std::to_string(floatGrid->background()) +
         "; expected a positive narrow-band half width (the distance outside the active voxels)");
  if (!levelSet && floatGrid->background() != 0.0f)
    fail("has background value " + std::to_string(floatGrid->background()) + "; expected 0 (the value outside the active voxels)" +
         (floatGrid->background() > 0.0f ? "; a positive background is what a signed distance field has: if the grid is one, convert "
                                            "it to a fog volume (Houdini: Convert VDB) or set its class to level set, which Candela "
                                            "renders as the fog volume it bounds"
                                          : ""));
  const openvdb::CoordBBox box = floatGrid->evalActiveVoxelBoundingBox();
  if (!box.empty()) {
    for (int a = 0; a < 3; ++a)
      if (std::abs(box.min()[a]) > limits::kMaxIndexCoordinate || std::abs(box.max()[a]) > limits::kMaxIndexCoordinate)
        fail("has active voxels at index " + std::to_string(std::max(std::abs(box.min()[a]), std::abs(box.max()[a]))) +
             "; expected indices within 2^28");
    const openvdb::Coord dim = box.dim();
    const double boxVoxels = static_cast<double>(dim.x()) * dim.y() * dim.z();
    if (boxVoxels > limits::kMaxBoxVoxels)
      fail("has active voxels spanning " + std::to_string(dim.x()) + " x " + std::to_string(dim.y()) + " x " + std::to_string(dim.z()) +
           " voxels; expected a bounding box of at most 4e9 voxels (are there stray voxels far from the rest?)");
  }
  checkMemoryBudget(2.0 * static_cast<double>(floatGrid->memUsage()), path + ": " + field, "grid \"" + name + "\"");
  LoadedGrid loaded;
  if (levelSet) {
    // Interior tiles become active at 1, so the grid may grow by its interior's leaf-free tiles only.
    openvdb::tools::sdfToFogVolume(*floatGrid);
    loaded.fromLevelSet = true;
  }
  // NaN, Inf and negative values would poison majorants and the film: replace them with 0.
  openvdb::CoordBBox positive;
  for (auto it = floatGrid->tree().beginValueAll(); it; ++it) {
    const float v = *it;
    if (!std::isfinite(v) || v < 0.0f) {
      it.setValue(0.0f);
      ++loaded.sanitizedVoxels;
    } else if (v > 0.0f && it.isValueOn()) {
      positive.expand(it.getBoundingBox());
    }
  }
  if (!positive.empty())
    loaded.positiveBox = IndexBox{glm::ivec3(positive.min().x(), positive.min().y(), positive.min().z()),
                                  glm::ivec3(positive.max().x(), positive.max().y(), positive.max().z())};
  const Mat4 worldFromIndex = toGlm(floatGrid->transform().baseMap()->getAffineMap()->getMat4());
  auto handle = nanovdb::openToNanoVDB(*floatGrid);
  loaded.grid = VoxelGrid(std::move(handle), worldFromIndex, name);
  return loaded;
}

}  // namespace

std::vector<LoadedGrid> loadVdbGrids(const std::string& path, const std::vector<std::string>& gridNames,
                                     const std::string& field) {
  initOpenVdb();
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec || !fs::exists(status))
    throw InputError(path + ": " + field + ": the VDB file does not exist" + (ec && fs::exists(status) ? " (" + ec.message() + ")" : ""));
  if (!fs::is_regular_file(status))
    throw InputError(path + ": " + field + ": expected a VDB file, got " + (fs::is_directory(status) ? "a directory" : "a device, pipe or socket"));
  VdbStructureCheck structure(path);
  if (const std::string problem = structure.run(); !problem.empty())
    throw InputError(path + ": " + field + ": cannot read the VDB file: " + problem + "; is it truncated or not a VDB?");
  openvdb::io::File file(path);
  try {
    file.open(false);
  } catch (const std::exception& e) {
    throw InputError(path + ": " + field + ": cannot read the VDB file (" + e.what() + "); is it truncated or not a VDB?");
  }
  std::vector<LoadedGrid> out;
  for (const std::string& name : gridNames) {
    if (!file.hasGrid(name)) {
      std::string present;
      for (auto it = file.beginName(); it != file.endName(); ++it) present += (present.empty() ? "" : ", ") + *it;
      file.close();
      throw InputError(path + ": " + field + ": expected a grid named \"" + name + "\", the file holds: " +
                       (present.empty() ? "no grids" : present));
    }
    // Only float grids, and double ones (Houdini's 64-bit precision) read as float, are read at all
    // (a wrong type is refused before OpenVDB allocates it).
    if (const auto t = structure.types.find(name);
        t != structure.types.end() && t->second != "Tree_float_5_4_3" && t->second != "Tree_double_5_4_3") {
      file.close();
      throw InputError(path + ": " + field + ": grid \"" + name + "\" is of type " + t->second +
                       ", expected float or double (Tree_float_5_4_3, Tree_double_5_4_3)");
    }
    openvdb::GridBase::Ptr base;
    try {
      base = file.readGrid(name);
    } catch (const std::exception& e) {
      file.close();
      throw InputError(path + ": " + field + ": cannot read grid \"" + name + "\" (" + e.what() + "); is the file truncated?");
    }
    auto floatGrid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
    if (auto doubleGrid = openvdb::gridPtrCast<openvdb::DoubleGrid>(base)) {
      try {
        checkMemoryBudget(1.5 * static_cast<double>(doubleGrid->memUsage()), path + ": " + field, "grid \"" + name + "\"");
      } catch (const InputError&) {
        file.close();
        throw;
      }
      // The same tree with each value cast to float (a value beyond float's range becomes infinite
      // and is then set to 0 and counted, as any other).
      floatGrid = openvdb::FloatGrid::create(openvdb::FloatTree::Ptr(new openvdb::FloatTree(doubleGrid->tree())));
      floatGrid->setTransform(doubleGrid->transform().copy());
      floatGrid->setName(doubleGrid->getName());
      floatGrid->setGridClass(doubleGrid->getGridClass());
    }
    if (!floatGrid) {
      file.close();
      throw InputError(path + ": " + field + ": grid \"" + name + "\" is of type " + base->valueType() + ", expected float");
    }
    try {
      out.push_back(convertFloatGrid(floatGrid, path, field, name));
    } catch (const InputError&) {
      file.close();
      throw;
    } catch (const openvdb::Exception& e) {
      // Whatever else OpenVDB refuses in a grid it has read is the file's fault, and names it.
      file.close();
      throw InputError(path + ": " + field + ": grid \"" + name + "\": " + e.what());
    }
  }
  file.close();
  return out;
}


namespace {

// Opens a VDB file after the same existence and structure checks as loadVdbGrids.
void openChecked(openvdb::io::File& file, const std::string& path, const std::string& field, VdbStructureCheck& structure) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec || !fs::exists(status)) throw InputError(path + ": " + field + ": the VDB file does not exist");
  if (!fs::is_regular_file(status))
    throw InputError(path + ": " + field + ": expected a VDB file, got " + (fs::is_directory(status) ? "a directory" : "a device, pipe or socket"));
  if (const std::string problem = structure.run(); !problem.empty())
    throw InputError(path + ": " + field + ": cannot read the VDB file: " + problem + "; is it truncated or not a VDB?");
  try {
    file.open(false);
  } catch (const std::exception& e) {
    throw InputError(path + ": " + field + ": cannot read the VDB file (" + e.what() + "); is it truncated or not a VDB?");
  }
}

void collectMetadata(const openvdb::MetaMap& meta, std::vector<std::string>& out) {
  for (auto it = meta.beginMeta(); it != meta.endMeta(); ++it) {
    out.push_back(it->first);
    if (it->second && it->second->typeName() == "string") out.push_back(it->first + "=" + it->second->str());
  }
}

}  // namespace

std::vector<LoadedGrid> loadVdbVectorGrid(const std::string& path, const std::string& name, const std::string& field) {
  initOpenVdb();
  VdbStructureCheck structure(path);
  openvdb::io::File file(path);
  openChecked(file, path, field, structure);
  try {
    if (!file.hasGrid(name)) throw InputError(path + ": " + field + ": expected a vector grid named \"" + name + "\"");
    if (const auto t = structure.types.find(name); t != structure.types.end() && t->second != "Tree_vec3s_5_4_3")
      throw InputError(path + ": " + field + ": grid \"" + name + "\" is of type " + t->second + ", expected vec3s (Tree_vec3s_5_4_3)");
    auto vec = openvdb::gridPtrCast<openvdb::Vec3SGrid>(file.readGrid(name));
    if (!vec) throw InputError(path + ": " + field + ": grid \"" + name + "\" is not a vec3s grid");
    checkMemoryBudget(4.0 * static_cast<double>(vec->memUsage()), path + ": " + field, "grid \"" + name + "\"");
    // One float grid per component, with the vector grid's transform and active voxels.
    std::vector<LoadedGrid> out;
    for (int c = 0; c < 3; ++c) {
      auto component = openvdb::FloatGrid::create(0.0f);
      component->setTransform(vec->transform().copy());
      auto acc = component->getAccessor();
      for (auto it = vec->cbeginValueOn(); it; ++it) acc.setValue(it.getCoord(), (*it)[c]);
      out.push_back(convertFloatGrid(component, path, field, name + ".xyz"[0] + std::string(1, "xyz"[c])));
    }
    file.close();
    return out;
  } catch (const InputError&) {
    file.close();
    throw;
  } catch (const std::exception& e) {
    file.close();
    throw InputError(path + ": " + field + ": cannot read grid \"" + name + "\" (" + e.what() + "); is the file truncated?");
  }
}

VdbFileInfo describeVdbFile(const std::string& path, const std::vector<std::string>& measure) {
  initOpenVdb();
  VdbStructureCheck structure(path);
  openvdb::io::File file(path);
  openChecked(file, path, "file", structure);
  VdbFileInfo info;
  try {
    if (auto meta = file.getMetadata()) collectMetadata(*meta, info.metadata);
    openvdb::GridPtrVecPtr grids = file.readAllGridMetadata();
    for (const auto& g : *grids) {
      VdbGridInfo gi;
      gi.name = g->getName();
      gi.type = g->valueType();
      gi.isFloat = gi.type == "float" || gi.type == "double";  // double is read as float
      gi.levelSet = g->getGridClass() == openvdb::GRID_LEVEL_SET;
      collectMetadata(*g, info.metadata);
      // The active box OpenVDB stores with each grid; without it, the grid is read below if wanted.
      openvdb::CoordBBox box;
      if (auto lo = g->getMetadata<openvdb::Vec3IMetadata>(openvdb::GridBase::META_FILE_BBOX_MIN),
          hi = g->getMetadata<openvdb::Vec3IMetadata>(openvdb::GridBase::META_FILE_BBOX_MAX);
          lo && hi)
        box = openvdb::CoordBBox(openvdb::Coord(lo->value()), openvdb::Coord(hi->value()));
      const bool wanted = gi.isFloat && std::find(measure.begin(), measure.end(), gi.name) != measure.end();
      if (wanted) {
        auto loaded = loadVdbGrids(path, {gi.name}, "file");
        const VoxelGrid& v = loaded[0].grid;
        gi.maxValue = v.maxValue();
        gi.read = true;
        const IndexBox ib = v.activeBox();
        if (!ib.empty()) box = openvdb::CoordBBox(openvdb::Coord(ib.min.x, ib.min.y, ib.min.z), openvdb::Coord(ib.max.x, ib.max.y, ib.max.z));
      }
      if (!box.empty()) {
        // World bounds of the voxel cells (centres at integer indices, +-0.5).
        Vec3 lo(kInfinity), hi(-kInfinity);
        const openvdb::Vec3d a = box.min().asVec3d() - openvdb::Vec3d(0.5), b = box.max().asVec3d() + openvdb::Vec3d(0.5);
        for (int c = 0; c < 8; ++c) {
          const openvdb::Vec3d p((c & 1) ? b.x() : a.x(), (c & 2) ? b.y() : a.y(), (c & 4) ? b.z() : a.z());
          const openvdb::Vec3d w = g->transform().indexToWorld(p);
          const Vec3 wf(static_cast<float>(w.x()), static_cast<float>(w.y()), static_cast<float>(w.z()));
          lo = glm::min(lo, wf);
          hi = glm::max(hi, wf);
        }
        if (std::isfinite(lo.x + lo.y + lo.z + hi.x + hi.y + hi.z)) gi.worldMin = lo, gi.worldMax = hi;
      }
      info.grids.push_back(gi);
    }
  } catch (const InputError&) {
    file.close();
    throw;
  } catch (const std::exception& e) {
    file.close();
    throw InputError(path + ": file: cannot read the grid list (" + e.what() + "); is it truncated?");
  }
  file.close();
  return info;
}

}  // namespace candela
