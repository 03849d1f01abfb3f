#include "procedural.h"

#include "input_limits.h"

#include "rng.h"

#include <openvdb/openvdb.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <thread>

#include <unistd.h>

namespace candela {

namespace {

// Gradient noise (Perlin 2002 quintic fade) with seeded hashed gradients; range about [-1, 1].
class Noise {
 public:
  explicit Noise(uint32_t seed) : seed_(mixBits(seed + 0x51ed27ULL)) {}

  float operator()(const Vec3& p) const {
    const Vec3 fl = glm::floor(p);
    const glm::ivec3 i(fl);
    const Vec3 f = p - fl;
    const Vec3 u = f * f * f * (f * (f * 6.0f - 15.0f) + 10.0f);
    float c[2][2][2];
    for (int dz = 0; dz < 2; ++dz)
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx)
          c[dz][dy][dx] = glm::dot(gradient(i.x + dx, i.y + dy, i.z + dz), f - Vec3(dx, dy, dz));
    auto lerp = [](float a, float b, float t) { return a + t * (b - a); };
    const float y0 = lerp(lerp(c[0][0][0], c[0][0][1], u.x), lerp(c[0][1][0], c[0][1][1], u.x), u.y);
    const float y1 = lerp(lerp(c[1][0][0], c[1][0][1], u.x), lerp(c[1][1][0], c[1][1][1], u.x), u.y);
    return lerp(y0, y1, u.z);
  }

  float fbm(Vec3 p, int octaves) const {
    float sum = 0.0f, amplitude = 0.5f, norm = 0.0f;
    for (int o = 0; o < octaves; ++o) {
      sum += amplitude * (*this)(p + Vec3(17.3f * o));
      norm += amplitude;
      amplitude *= 0.5f;
      p *= 2.03f;
    }
    return sum / norm * 1.6f;
  }

 private:
  Vec3 gradient(int x, int y, int z) const {
    static const Vec3 kDirs[12] = {{1, 1, 0}, {-1, 1, 0}, {1, -1, 0}, {-1, -1, 0}, {1, 0, 1}, {-1, 0, 1},
                                   {1, 0, -1}, {-1, 0, -1}, {0, 1, 1}, {0, -1, 1}, {0, 1, -1}, {0, -1, -1}};
    const uint64_t h = hashCombine(hashCombine(hashCombine(seed_, static_cast<uint64_t>(x)), static_cast<uint64_t>(y)),
                                   static_cast<uint64_t>(z));
    return kDirs[h % 12];
  }
  uint64_t seed_;
};

float smoothstep(float a, float b, float x) {
  const float t = std::clamp((x - a) / (b - a), 0.0f, 1.0f);
  return t * t * (3.0f - 2.0f * t);
}

struct Sample {
  float density = 0.0f;
  float temperature = 0.0f;
};

// Shapes live in q in [-1, 1]^3 (the grid's extent, stretched by `size`); h = height in [0, 1].
Sample torchFlame(const Vec3& q, const Noise& noise) {
  const float h = 0.5f * (q.y + 1.0f);
  const float sway = 0.18f * h * h;
  const Vec2 xz(q.x - sway * noise(Vec3(0.0f, h * 1.3f, 0.0f)), q.z - sway * noise(Vec3(5.0f, h * 1.3f, 0.0f)));
  // Teardrop profile: widest a quarter of the way up, a tongue to the top.
  const float radius = h < 0.22f ? 0.62f * std::sqrt(h / 0.22f) : 0.62f * std::pow((1.0f - h) / 0.78f, 1.1f);
  const float r = glm::length(xz) / std::max(radius, 1e-3f);
  const float n = noise.fbm(Vec3(q.x * 2.5f, q.y * 2.0f - 1.7f, q.z * 2.5f), 4);
  const float shape = 1.0f - r + 0.5f * n * (0.25f + h);
  Sample s;
  s.density = smoothstep(0.0f, 0.45f, shape);
  s.temperature = smoothstep(0.0f, 0.9f, shape) * (1.0f - 0.45f * h);
  return s;
}

Sample mist(const Vec3& q, const Noise& noise) {
  Sample s;
  s.density = std::clamp(0.55f + 0.6f * noise.fbm(q * 1.6f, 3), 0.0f, 1.0f);
  return s;
}

Sample cloud(const Vec3& q, const Noise& noise, uint32_t seed) {
  // A cumulus: a union of seeded blobs with a flattened base, eroded by fBm at its edge.
  Rng rng(seed, 7);
  float sdf = 1e9f;
  for (int b = 0; b < 9; ++b) {
    const Vec3 c((rng.uniform() - 0.5f) * 1.0f, (rng.uniform() - 0.5f) * 0.5f - 0.05f, (rng.uniform() - 0.5f) * 0.7f);
    const float radius = 0.3f + 0.22f * rng.uniform();
    sdf = std::min(sdf, glm::length((q - c) * Vec3(1.0f, 1.15f, 1.0f)) - radius);
  }
  sdf = std::max(sdf, -(q.y + 0.45f));  // flat base
  const float n = noise.fbm(q * 3.5f, 5);
  Sample s;
  s.density = std::clamp((-sdf + 0.12f * n) * 9.0f, 0.0f, 1.0f);
  return s;
}

Sample plume(const Vec3& q, const Noise& noise) {
  // A rising, widening column that sways with height; hot at the base, breaking into tongues above.
  // It lives inside its box: a rounded source at the bottom, smoke that thins out before the top and
  // the sides, so no face of the box shows as a flat cut.
  const float h = 0.5f * (q.y + 1.0f);
  const Vec2 centre(0.35f * h * noise(Vec3(0.0f, h * 1.6f, 3.0f)), 0.35f * h * noise(Vec3(9.0f, h * 1.6f, 1.0f)));
  // Narrow at the source, opening out as it rises.
  const float radius = 0.2f + 0.6f * std::sqrt(h);
  const float r = glm::length(Vec2(q.x, q.z) - centre) / radius;
  const float n = noise.fbm(Vec3(q.x * 2.6f, q.y * 1.8f - 1.2f * h, q.z * 2.6f), 5);
  const float shape = 1.0f - r + 0.7f * n;
  const float inside = smoothstep(0.0f, 0.12f, h) * (1.0f - smoothstep(0.55f, 0.97f, h)) *
                       (1.0f - smoothstep(0.7f, 0.97f, std::max(std::abs(q.x), std::abs(q.z))));
  Sample s;
  s.density = smoothstep(0.0f, 0.5f, shape) * (1.0f - 0.45f * h) * inside;
  const float flicker = noise.fbm(Vec3(q.x * 4.0f + 3.0f, q.y * 3.0f, q.z * 4.0f), 3);
  // The flame: a rounded base that tapers into tongues, hottest low on the axis.
  const float core = 1.0f - glm::length(Vec2(q.x, q.z) - centre) / (0.2f + 0.45f * std::sqrt(h)) - 1.0f * h;
  s.temperature = smoothstep(0.05f, 0.9f, std::min(shape, core + 0.5f * n + 0.2f) + 0.35f * flicker) *
                  std::pow(std::max(0.0f, 1.0f - h), 1.3f) * smoothstep(0.0f, 0.08f, h);
  return s;
}

void initOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

}  // namespace

std::string cacheDirectory() {
  namespace fs = std::filesystem;
  if (const char* dir = std::getenv("CANDELA_CACHE_DIR"); dir && *dir) return dir;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return (fs::path(xdg) / "candela").string();
  if (const char* home = std::getenv("HOME"); home && *home) return (fs::path(home) / ".cache" / "candela").string();
  return "/tmp/candela-cache";
}

float standaloneDensity(const std::string& type) {
  // The sigma_t_scale the shipped scenes give each shape (cloud.json, fire.json, torch-in-mist.json).
  if (type == "cloud") return 12.0f;
  if (type == "torch") return 6.0f;
  if (type == "plume") return 1.5f;
  if (type == "mist") return 0.1f;
  return 1.0f;
}

void writeGeneratedVolume(const GeneratorDesc& gen, const std::string& path) {
  initOpenVdb();
  const float longest = std::max(gen.size.x, std::max(gen.size.y, gen.size.z));
  const float voxel = longest / static_cast<float>(gen.resolution);
  const glm::ivec3 dims = glm::max(glm::ivec3(glm::round(gen.size / voxel)), glm::ivec3(2));
  const size_t count = static_cast<size_t>(dims.x) * dims.y * dims.z;
  // Dense density and temperature arrays, then about as much again for the VDB trees.
  checkMemoryBudget(static_cast<double>(count) * 16.0, path, "generating a " + std::to_string(dims.x) + " x " + std::to_string(dims.y) + " x " +
                                                             std::to_string(dims.z) + " \"" + gen.type + "\" volume (generator.resolution)");
  std::vector<float> density(count, 0.0f), temperature(count, 0.0f);
  const Noise noise(gen.seed);
  const bool hasTemperature = gen.type == "torch" || gen.type == "plume" || gen.temperature > 0.0f;

  tbb::parallel_for(0, dims.z, [&](int k) {
    for (int j = 0; j < dims.y; ++j)
      for (int i = 0; i < dims.x; ++i) {
        // Voxel centres span the grid; q is the centre in [-1, 1]^3.
        const Vec3 q = (Vec3(i, j, k) + 0.5f) / Vec3(dims) * 2.0f - 1.0f;
        Sample s;
        if (gen.type == "constant") {
          s.density = gen.value;
          s.temperature = gen.temperature;
        } else if (gen.type == "ramp") {
          s.density = gen.value * static_cast<float>(i) / static_cast<float>(dims.x - 1);
          s.temperature = gen.temperature;
        } else if (gen.type == "torch") {
          s = torchFlame(q, noise);
        } else if (gen.type == "mist") {
          s = mist(q, noise);
        } else if (gen.type == "cloud") {
          s = cloud(q, noise, gen.seed);
        } else if (gen.type == "plume") {
          s = plume(q, noise);
        } else if (gen.type == "invalid") {
          // A deliberately broken grid for the stability suite: a constant box in which every 7th
          // voxel is NaN and every 11th negative. Loading must sanitise these, with a warning.
          const size_t n = (static_cast<size_t>(k) * dims.y + j) * dims.x + i;
          s.density = n % 7 == 0 ? std::numeric_limits<float>::quiet_NaN() : (n % 11 == 0 ? -gen.value : gen.value);
        } else {
          throw InputError("generator.type: unknown generator \"" + gen.type + "\"");
        }
        // A shape's density peaks at 1; `value` scales it (standaloneDensity).
        if (gen.type == "torch" || gen.type == "mist" || gen.type == "cloud" || gen.type == "plume") s.density *= gen.value;
        const size_t idx = (static_cast<size_t>(k) * dims.y + j) * dims.x + i;
        density[idx] = s.density;
        temperature[idx] = s.density > 0.0f ? s.temperature : 0.0f;
      }
  });

  auto densityGrid = openvdb::FloatGrid::create(0.0f);
  auto temperatureGrid = openvdb::FloatGrid::create(0.0f);
  auto transform = openvdb::math::Transform::createLinearTransform(voxel);
  // Voxel (0,0,0)'s centre sits half a voxel inside the grid's lower corner at -size/2.
  transform->postTranslate(openvdb::Vec3d(-0.5 * dims.x * voxel + 0.5 * voxel, -0.5 * dims.y * voxel + 0.5 * voxel,
                                          -0.5 * dims.z * voxel + 0.5 * voxel));
  densityGrid->setTransform(transform);
  temperatureGrid->setTransform(transform->copy());
  densityGrid->setName("density");
  temperatureGrid->setName("temperature");
  densityGrid->setGridClass(openvdb::GRID_FOG_VOLUME);
  {
    auto dAcc = densityGrid->getAccessor();
    auto tAcc = temperatureGrid->getAccessor();
    for (int k = 0; k < dims.z; ++k)
      for (int j = 0; j < dims.y; ++j)
        for (int i = 0; i < dims.x; ++i) {
          const size_t idx = (static_cast<size_t>(k) * dims.y + j) * dims.x + i;
          const bool invalidOnPurpose = gen.type == "invalid" && (std::isnan(density[idx]) || density[idx] < 0.0f);
          if (density[idx] > 1e-6f || invalidOnPurpose) dAcc.setValue(openvdb::Coord(i, j, k), density[idx]);
          if (temperature[idx] > 1e-6f) tAcc.setValue(openvdb::Coord(i, j, k), temperature[idx]);
        }
  }
  densityGrid->pruneGrid();
  temperatureGrid->pruneGrid();
  openvdb::GridPtrVec grids{densityGrid};
  if (hasTemperature) grids.push_back(temperatureGrid);
  openvdb::io::File file(path);
  file.write(grids);
  file.close();
}

std::string cachedGeneratedVolume(const GeneratorDesc& gen) {
  namespace fs = std::filesystem;
  // Bump the version when a generator changes so stale cache entries are not reused.
  const std::string key = "generator-v3 " + toJson(gen).dump();
  uint64_t h = 0x1234567ULL;
  for (char c : key) h = hashCombine(h, static_cast<uint64_t>(static_cast<unsigned char>(c)));
  char name[64];
  std::snprintf(name, sizeof name, "%016llx.vdb", static_cast<unsigned long long>(h));
  const fs::path dir = fs::path(cacheDirectory()) / "volumes";
  const fs::path target = dir / (gen.type + "-" + name);
  if (fs::exists(target)) return target.string();
  fs::create_directories(dir);
  // Write under a unique name, then rename: concurrent processes never read a partial file.
  const fs::path tmp = dir / (target.filename().string() + ".tmp" +
                              std::to_string(std::hash<std::thread::id>{}(std::this_thread::get_id()) ^ static_cast<size_t>(::getpid())));
  writeGeneratedVolume(gen, tmp.string());
  fs::rename(tmp, target);
  return target.string();
}

}  // namespace candela
