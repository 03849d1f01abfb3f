// Statistical agreement between renders (docs/method.md s.5): the image is split into regions; each
// region's mean (per channel) has a standard error from the per-pixel sums of squares; two renders
// agree when no region differs by more than a Bonferroni-corrected z threshold. Used by the tests
// to show strategies converge to the same image, and by the viewer's agreement indicator later.
#pragma once

#include "film.h"

#include <string>
#include <vector>

namespace candela {

struct RegionEstimate {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // pixel rectangle [x0, x1) x [y0, y1)
  Rgb mean{0.0f};
  Rgb standardError{0.0f};
};

// Splits the film into blocksX x blocksY regions and estimates each region's mean radiance.
std::vector<RegionEstimate> regionEstimates(const Film& film, int blocksX, int blocksY);

struct Agreement {
  bool agree = true;
  double maxAbsZ = 0.0;     // largest |z| over regions and channels
  double threshold = 0.0;   // Bonferroni-corrected two-sided threshold for the family-wise alpha
  int tests = 0;
  double maxRelativeDifference = 0.0;  // largest |a - b| / max(|a|, |b|) over tested regions
  std::string worst;        // description of the worst region
};

// Two independent renders of the same scene: do their region means agree? `alpha` is the family-wise
// false-alarm rate. Differences below 0.1% of the brightest region mean are not tested: a region
// that one estimator has never hit reads 0 +- 0 there, and no z-score is meaningful.
// Heavy-tailed estimators (conventional tracking of small bright emitters) need enough samples for
// their standard error to be trustworthy; callers choose spp accordingly.
Agreement compareRenders(const Film& a, const Film& b, int blocksX, int blocksY, double alpha = 1e-3);
// A render against region estimates made elsewhere (the sum of renders of parts of a scene, say),
// with their standard errors: regions as regionEstimates(film, blocksX, blocksY) splits them.
Agreement compareToEstimates(const Film& film, int blocksX, int blocksY, const std::vector<RegionEstimate>& expected,
                             double alpha = 1e-3);
// A render against a known value per region and channel (closed forms).
Agreement compareToExpected(const Film& film, int blocksX, int blocksY, const std::vector<Rgb>& expected, double alpha = 1e-3);

// The two-sided standard-normal threshold z with P(|Z| > z) = p.
double normalTwoSidedThreshold(double p);

}  // namespace candela
