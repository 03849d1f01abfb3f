// candela-cli report: the speed-versus-accuracy report (one self-contained HTML page).
#pragma once

#include <string>
#include <vector>

namespace candela {

// Renders every built-in scene with every strategy preset at a ladder of equal time budgets against
// cached references, runs the stability suite, and writes DIR/index.html plus DIR/headline.svg and
// DIR/headline.md (the torch-in-mist chart and efficiency table the README shows). `quick`: lower
// resolution, shorter budgets and fewer samples, for CI (under 5 minutes on 2 cores). `seedCount`:
// how many seeds (17, 18, ...) every strategy renders at the largest budget for auto's ratios, on
// every scene; 0 for the defaults: kReportSeeds, kWideSpreadReportSeeds on the scenes whose seeds
// disagree most, kQuickReportSeeds on all with `quick`. `scenes`: the report scenes to render
// (empty: all of them; reportSceneList() names them; an unknown name throws InputError), and
// `stability` whether the stability suite runs: a rendering engineer measuring one scene with more
// seeds runs that scene alone.
inline constexpr int kReportSeeds = 7;
inline constexpr int kWideSpreadReportSeeds = 15;  // on the scenes whose seeds disagree most (report.cpp, kReportScenes)
inline constexpr int kQuickReportSeeds = 3;
std::string reportSceneList();  // the report scenes' names, comma-separated
int runReport(bool quick, const std::string& dir, int threads, int seedCount = 0, const std::vector<std::string>& scenes = {},
              bool stability = true);

}  // namespace candela
