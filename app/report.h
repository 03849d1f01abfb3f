// candela-cli report: the speed-versus-accuracy report (one self-contained HTML page).
#pragma once

#include <string>

namespace candela {

// Renders every built-in scene with every strategy preset at a ladder of equal time budgets against
// cached references, runs the stability suite, and writes DIR/index.html plus DIR/headline.svg and
// DIR/headline.md (the torch-in-mist chart and efficiency table the README shows). `quick`: lower
// resolution, shorter budgets and fewer samples, for CI (under 5 minutes on 2 cores). `seedCount`:
// how many seeds (17, 18, ...) every strategy renders at the largest budget for auto's ratios; 0 for
// the default, kReportSeeds (kQuickReportSeeds with `quick`).
inline constexpr int kReportSeeds = 7;
inline constexpr int kQuickReportSeeds = 3;
int runReport(bool quick, const std::string& dir, int threads, int seedCount = 0);

}  // namespace candela
