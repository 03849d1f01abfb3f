// Shared helpers for the tests: asset paths, loading scenes with --set style edits, rendering films.
#pragma once

#include "renderer.h"
#include "scene.h"
#include "stats.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>

#include <unistd.h>

#include <string>
#include <vector>

namespace candela::test {

inline std::string assetPath(const std::string& relative) { return std::string(CANDELA_SOURCE_DIR) + "/" + relative; }

// An empty scratch directory for this test process: TMP/candela-test-PID/NAME. The process removes
// TMP/candela-test-PID when it exits, unless CANDELA_KEEP_TEST_FILES is set (to look at what a
// failing test wrote).
inline std::filesystem::path scratchDirectory(const std::string& name) {
  struct RemovedAtExit {
    std::filesystem::path root;
    ~RemovedAtExit() {
      std::error_code ec;
      if (!std::getenv("CANDELA_KEEP_TEST_FILES")) std::filesystem::remove_all(root, ec);
    }
  };
  static const RemovedAtExit process{std::filesystem::temp_directory_path() / ("candela-test-" + std::to_string(::getpid()))};
  const std::filesystem::path dir = process.root / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline SceneDesc loadScene(const std::string& relative, const std::vector<std::string>& settings = {}) {
  return loadSceneDesc(assetPath(relative), settings);
}

// Upper critical value of chi-square with `dof` degrees of freedom at tail probability p
// (Wilson-Hilferty approximation).
inline double chiSquareCritical(int dof, double p) {
  const double z = normalTwoSidedThreshold(2.0 * p);
  const double k = dof;
  const double t = 1.0 - 2.0 / (9.0 * k) + z * std::sqrt(2.0 / (9.0 * k));
  return k * t * t * t;
}

inline Film render(const SceneDesc& desc, int spp, int threads = 0) {
  auto scene = Scene::build(desc);
  ProgressiveRenderer renderer(scene, RenderOptions{threads, 16});
  Film film = continueFromPilot(*scene, spp);  // auto's pilot samples start the image, as in the CLI
  renderer.renderBudget(film, spp, 0.0, std::min(spp, 16));
  return film;
}

}  // namespace candela::test
