// Majorant grid and DDA (docs/method.md s.1): the DDA visits exactly the cells a brute-force slab test
// finds, in order; no trilinear lookup ever exceeds its cell's majorant (randomised).
#include "majorant.h"
#include "medium.h"
#include "procedural.h"
#include "scene.h"
#include "rng.h"
#include "test_support.h"
#include "vdb_io.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>

namespace candela {
namespace {

VoxelGrid generatedGrid(const std::string& type, int resolution, Vec3 size, uint32_t seed = 1) {
  GeneratorDesc gen;
  gen.type = type;
  gen.resolution = resolution;
  gen.size = size;
  gen.seed = seed;
  return loadVdbGrids(cachedGeneratedVolume(gen), {"density"}, "test")[0].grid;
}

struct CellVisit {
  int cell;
  float t0, t1;
};

// Every cell whose box the ray overlaps for longer than `minLength`, sorted by entry.
std::vector<CellVisit> bruteForceCells(const MajorantGrid& grid, const Vec3& o, const Vec3& d, float tMax, float minLength) {
  std::vector<CellVisit> out;
  const glm::ivec3 res = grid.resolution();
  for (int z = 0; z < res.z; ++z)
    for (int y = 0; y < res.y; ++y)
      for (int x = 0; x < res.x; ++x) {
        const Vec3 lo = grid.origin() + grid.cellExtent() * Vec3(x, y, z);
        const Vec3 hi = lo + grid.cellExtent();
        float t0 = 0.0f, t1 = tMax;
        bool miss = false;
        for (int a = 0; a < 3; ++a) {
          if (d[a] == 0.0f) {
            if (o[a] < lo[a] || o[a] > hi[a]) miss = true;
            continue;
          }
          float ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
          if (ta > tb) std::swap(ta, tb);
          t0 = std::max(t0, ta);
          t1 = std::min(t1, tb);
        }
        if (!miss && t1 - t0 > minLength) out.push_back({grid.cellIndex(x, y, z), t0, t1});
      }
  std::sort(out.begin(), out.end(), [](const CellVisit& a, const CellVisit& b) { return a.t0 < b.t0; });
  return out;
}

TEST(MajorantDda, VisitsExactlyTheCellsABruteForceWalkFinds) {
  const VoxelGrid grid = generatedGrid("constant", 40, Vec3(2.0f, 1.3f, 0.9f));
  for (int cellSize : {1, 3, 8}) {
    const MajorantGrid majorants(grid, MajorantStructure::Grid, cellSize);
    Rng rng(7, static_cast<uint64_t>(cellSize));
    const Vec3 lo = majorants.origin(), hi = majorants.domainMax();
    for (int trial = 0; trial < 300; ++trial) {
      // Rays from outside and from inside the domain, in random directions.
      const Vec3 o = lo + (hi - lo) * Vec3(rng.uniform() * 1.6f - 0.3f, rng.uniform() * 1.6f - 0.3f, rng.uniform() * 1.6f - 0.3f);
      Vec3 d(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f);
      if (trial % 10 == 0) d = Vec3(trial % 20 == 0 ? 1.0f : 0.0f, 0.0f, trial % 20 == 0 ? 0.0f : -1.0f);  // axis-aligned
      d = glm::normalize(d) * (0.5f + rng.uniform());
      const float tMax = 200.0f;
      const float minLength = 1e-3f;
      const auto expected = bruteForceCells(majorants, o, d, tMax, minLength);
      std::vector<CellVisit> visited;
      MajorantDda dda(majorants, o, d, 0.0f, tMax);
      float t0, t1, prevEnd = -1.0f;
      int cell;
      while (dda.next(t0, t1, cell)) {
        if (prevEnd >= 0.0f) {
          EXPECT_FLOAT_EQ(t0, prevEnd) << "segments must be contiguous";
        }
        prevEnd = t1;
        if (t1 - t0 > minLength) visited.push_back({cell, t0, t1});
      }
      ASSERT_EQ(visited.size(), expected.size()) << "cell size " << cellSize << ", trial " << trial;
      for (size_t i = 0; i < visited.size(); ++i) {
        EXPECT_EQ(visited[i].cell, expected[i].cell) << "trial " << trial << " step " << i;
        EXPECT_NEAR(visited[i].t0, expected[i].t0, 1e-3f);
        EXPECT_NEAR(visited[i].t1, expected[i].t1, 1e-3f);
      }
    }
  }
}

TEST(MajorantGrid, NeverBelowTheTrilinearDensityItBounds) {
  for (const char* type : {"torch", "cloud", "mist"}) {
    const VoxelGrid grid = generatedGrid(type, 40, Vec3(1.0f, 1.5f, 1.0f), 9);
    auto sampler = grid.sampler();
    for (auto [structure, cellSize] : {std::pair{MajorantStructure::Grid, 2}, std::pair{MajorantStructure::Grid, 8},
                                       std::pair{MajorantStructure::Global, 0}}) {
      const MajorantGrid majorants(grid, structure, cellSize);
      ASSERT_FALSE(majorants.empty());
      Rng rng(3, static_cast<uint64_t>(cellSize));
      const Vec3 lo = majorants.origin(), hi = majorants.domainMax();
      int tight = 0;
      for (int i = 0; i < 200000; ++i) {
        const Vec3 p = lo + (hi - lo) * Vec3(rng.uniform(), rng.uniform(), rng.uniform());
        const glm::ivec3 c = glm::clamp(glm::ivec3(glm::floor((p - lo) / majorants.cellExtent())), glm::ivec3(0),
                                        majorants.resolution() - 1);
        const float bound = majorants.maxDensity(majorants.cellIndex(c.x, c.y, c.z));
        const float value = sampler.trilinear(p);
        ASSERT_LE(value, bound) << type << " at " << p.x << "," << p.y << "," << p.z;
        tight += value > 0.5f * bound;
      }
      EXPECT_GT(tight, 0) << "majorant far looser than the density everywhere";
    }
  }
}

TEST(MajorantGrid, GlobalIsTheOneCellCaseAndBoundsTheGridMajorants) {
  const VoxelGrid grid = generatedGrid("cloud", 32, Vec3(1.0f));
  const MajorantGrid global(grid, MajorantStructure::Global, 8);
  const MajorantGrid cells(grid, MajorantStructure::Grid, 4);
  ASSERT_EQ(global.cellCount(), 1u);
  const float globalMax = global.maxDensity(0);
  float cellMax = 0.0f;
  for (float v : cells.maxDensities()) cellMax = std::max(cellMax, v);
  EXPECT_FLOAT_EQ(globalMax, cellMax);
  EXPECT_EQ(global.origin(), cells.origin());
}

// A coarsened grid keeps the domain (walks reach no further) and bounds every fine cell it covers;
// where the factor divides the resolution it is the grid built with larger cells.
TEST(MajorantGrid, CoarsenedKeepsTheDomainAndBoundsTheFineCells) {
  const VoxelGrid grid = generatedGrid("cloud", 40, Vec3(1.0f, 0.6f, 0.8f));
  const MajorantGrid fine(grid, MajorantStructure::Grid, 4);
  Rng rng(3, 1);
  for (int factor : {2, 3, 4, 16}) {
    const MajorantGrid coarse = fine.coarsened(factor);
    EXPECT_EQ(coarse.resolution(), (fine.resolution() + factor - 1) / factor);
    EXPECT_EQ(coarse.origin(), fine.origin());
    EXPECT_LT(glm::length(coarse.domainMax() - fine.domainMax()), 1e-4f) << factor;
    auto cellAt = [](const MajorantGrid& g, const Vec3& p) {
      const glm::ivec3 c = glm::clamp(glm::ivec3(glm::floor((p - g.origin()) / g.cellExtent())), glm::ivec3(0), g.resolution() - 1);
      return g.maxDensity(g.cellIndex(c.x, c.y, c.z));
    };
    for (int i = 0; i < 20000; ++i) {
      const Vec3 p = fine.origin() + (fine.domainMax() - fine.origin()) * Vec3(rng.uniform(), rng.uniform(), rng.uniform());
      ASSERT_GE(cellAt(coarse, p), cellAt(fine, p)) << "factor " << factor << " at " << p.x << "," << p.y << "," << p.z;
    }
    if (glm::all(glm::equal(fine.resolution() % factor, glm::ivec3(0)))) {
      const MajorantGrid built(grid, MajorantStructure::Grid, 4 * factor);
      EXPECT_EQ(coarse.maxDensities(), built.maxDensities()) << factor;
    }
  }
  const MajorantGrid global(grid, MajorantStructure::Global, 0);
  EXPECT_EQ(fine.coarsened(1000).maxDensities(), global.maxDensities());
}

// majorant.coarsen_thin: thin media that emit nothing walk fewer, larger cells; a dense cloud and an
// emitter keep the cells asked for.
TEST(MajorantGrid, OnlyThinMediaThatEmitNothingGetCoarserCells) {
  auto coarsening = [](const char* scene, const std::vector<std::string>& edits) {
    std::vector<std::string> all = {"camera.resolution=[8,8]", "strategy.preset=\"conventional\""};
    all.insert(all.end(), edits.begin(), edits.end());
    auto built = Scene::build(test::loadScene(std::string("assets/scenes/") + scene + ".json", all));
    std::map<std::string, int> out;
    for (const Medium* m : built->media().media) out[m->desc().name] = m->majorantCoarsening();
    return out;
  };
  const auto torch = coarsening("torch-in-mist", {"strategy.majorant.cell_size=8"});
  EXPECT_GT(torch.at("mist"), 1);   // optical depth about 0.6 across: a few large cells
  EXPECT_EQ(torch.at("flame"), 1);  // an emitter: its cells shape the emission-aware majorant
  EXPECT_EQ(coarsening("cloud", {}).at("cloud"), 1);
  EXPECT_EQ(coarsening("torch-in-mist", {"strategy.majorant.coarsen_thin=false"}).at("mist"), 1);
  // The walks' domain stays the asked-for grid's, and probes are placed by the asked-for cells.
  auto built = Scene::build(test::loadScene("assets/scenes/torch-in-mist.json", {"camera.resolution=[8,8]", "strategy.preset=\"conventional\""}));
  for (const Medium* m : built->media().media) {
    const MajorantGrid asked(m->densityGrid(), MajorantStructure::Grid, 8);
    EXPECT_LT(glm::length(m->majorantGrid().domainMax() - asked.domainMax()), 1e-4f) << m->desc().name;
    EXPECT_EQ(m->occupancyGrid().maxDensities(), asked.maxDensities()) << m->desc().name;
  }
}

}  // namespace
}  // namespace candela
