// Throughput benchmarks (Google Benchmark; never timed tests): trilinear lookups, majorant DDA
// segments, camera paths on torch-in-mist at 1 and 2 threads, and the camera-ray guide tables'
// rebuild after a camera move.
//   ./build/bench/renderer_bench
#include "camera_guides.h"
#include "integrator.h"
#include "majorant.h"
#include "procedural.h"
#include "renderer.h"
#include "scene.h"
#include "vdb_io.h"

#include <benchmark/benchmark.h>

using namespace candela;

namespace {

std::string scenePath(const char* name) { return std::string(CANDELA_SOURCE_DIR) + "/assets/scenes/" + name; }

const Scene& torchScene() {
  static std::shared_ptr<Scene> scene = Scene::build(loadSceneDesc(scenePath("torch-in-mist.json"), {"camera.resolution=[160,90]"}));
  return *scene;
}

void BM_TrilinearLookup(benchmark::State& state) {
  const Medium& mist = *torchScene().mediaOwned()[1];
  auto sampler = mist.densityGrid().sampler();
  const MajorantGrid& m = mist.majorantGrid();
  Rng rng(1, 2);
  std::vector<Vec3> points(4096);
  for (auto& p : points) p = m.origin() + (m.domainMax() - m.origin()) * Vec3(rng.uniform(), rng.uniform(), rng.uniform());
  size_t i = 0;
  float sum = 0.0f;
  for (auto _ : state) {
    sum += sampler.trilinear(points[i++ & 4095]);
  }
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_TrilinearLookup);

void BM_TrilinearLookupCoherent(benchmark::State& state) {
  // Steps along a ray, as tracking does: the accessor cache hits.
  const Medium& mist = *torchScene().mediaOwned()[1];
  auto sampler = mist.densityGrid().sampler();
  const MajorantGrid& m = mist.majorantGrid();
  const Vec3 a = m.origin(), b = m.domainMax();
  float t = 0.0f, sum = 0.0f;
  for (auto _ : state) {
    t += 0.37f;
    if (t > 1000.0f) t = 0.0f;
    sum += sampler.trilinear(a + (b - a) * Vec3(t / 1000.0f, 0.43f + 0.1f * t / 1000.0f, 0.5f + 0.3f * t / 1000.0f));
  }
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_TrilinearLookupCoherent);

void BM_DdaSegments(benchmark::State& state) {
  const Medium& mist = *torchScene().mediaOwned()[1];
  const MajorantGrid& m = mist.majorantGrid();
  Rng rng(3, 4);
  int64_t segments = 0;
  for (auto _ : state) {
    const Vec3 o = m.origin() + (m.domainMax() - m.origin()) * Vec3(rng.uniform(), rng.uniform(), rng.uniform());
    const Vec3 d = glm::normalize(Vec3(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f));
    MajorantDda dda(m, o, d, 0.0f, 1e6f);
    float t0, t1;
    int cell;
    while (dda.next(t0, t1, cell)) ++segments;
  }
  state.SetItemsProcessed(segments);
  state.counters["segments/ray"] = static_cast<double>(segments) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_DdaSegments);

void BM_CameraPaths(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  static std::shared_ptr<Scene> scene = Scene::build(loadSceneDesc(scenePath("torch-in-mist.json"), {"camera.resolution=[160,90]"}));
  ProgressiveRenderer renderer(scene, RenderOptions{threads, 16});
  Film film;
  for (auto _ : state) renderer.renderPass(film, 1);
  state.SetItemsProcessed(state.iterations() * 160 * 90);
  state.SetLabel("torch-in-mist conventional, paths/s");
}
BENCHMARK(BM_CameraPaths)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// Live-edit cost of the majorant policy on torch-in-mist (both media): what a slider change costs.
//   k or cap or safety factor: per-cell mu_bar only; cell size: majorant grid + emission maxima;
//   emission grid cell size: the emission-energy grid.
void BM_PolicyRebuild(benchmark::State& state) {
  auto scene = Scene::build(loadSceneDesc(scenePath("torch-in-mist.json"), {"strategy.preset=\"emission\""}));
  StrategySettings a = scene->strategy(), b = a;
  switch (state.range(0)) {
    case 0: b.majorant.emission_weight = a.majorant.emission_weight * 2.0f; state.SetLabel("emission weight k"); break;
    case 1: b.majorant.cell_size = 16; state.SetLabel("majorant cell size 8 <-> 16"); break;
    case 2: b.emission.grid_cell_size = 8; state.SetLabel("emission grid cell 4 <-> 8"); break;
    default: b.majorant.structure = MajorantStructure::Global; state.SetLabel("grid <-> global"); break;
  }
  bool flip = false;
  for (auto _ : state) {
    scene->setStrategy(flip ? a : b);
    flip = !flip;
  }
}
BENCHMARK(BM_PolicyRebuild)->DenseRange(0, 3)->Unit(benchmark::kMillisecond);

// A volume with no emission must cost nothing extra under the emission preset: camera paths/s on
// the cloud scene, conventional (0) versus emission (1), 2 threads.
void BM_NonEmissiveCost(benchmark::State& state) {
  const char* preset = state.range(0) == 0 ? "conventional" : "emission";
  auto scene = Scene::build(loadSceneDesc(scenePath("cloud.json"), {"camera.resolution=[160,90]", std::string("strategy.preset=\"") + preset + "\""}));
  ProgressiveRenderer renderer(scene, RenderOptions{2, 16});
  Film film;
  for (auto _ : state) renderer.renderPass(film, 1);
  state.SetItemsProcessed(state.iterations() * 160 * 90);
  state.SetLabel(std::string("cloud, ") + preset);
}
BENCHMARK(BM_NonEmissiveCost)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

// What a camera move costs `full` before its first pass: every pixel's camera-ray guide table
// (probe knots along the centre ray, the thickness test, a piecewise-linear table) rebuilt, on
// torch-in-mist at the viewer's 640x360, all threads. Two cameras alternate so that each iteration
// rebuilds.
void BM_CameraGuideRebuild(benchmark::State& state) {
  static std::shared_ptr<Scene> scene = Scene::build(loadSceneDesc(scenePath("torch-in-mist.json"), {"strategy.preset=\"full\""}));
  const PathTracer tracer(*scene);
  CameraDesc a = scene->desc().camera, b = a;
  b.position.x += 0.01f;
  CameraGuides guides;
  int i = 0;
  for (auto _ : state) {
    scene->setCamera(i++ & 1 ? b : a);  // the tables' key holds the camera: each prepare rebuilds
    guides.prepare(*scene, tracer, scene->camera());
  }
  if (guides.builds() != static_cast<int>(state.iterations())) state.SkipWithError("a prepare did not rebuild");
  state.SetItemsProcessed(state.iterations() * a.resolution.first * a.resolution.second);
  state.SetLabel("torch-in-mist full, 640x360 tables");
}
BENCHMARK(BM_CameraGuideRebuild)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
