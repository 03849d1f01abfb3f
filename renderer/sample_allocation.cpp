#include "sample_allocation.h"

#include "convergence.h"
#include "film.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

namespace candela {

std::string SplitMap::summary() const {
  if (split.empty()) return "adaptive split: none (no block's noise per unit of work calls for more samples, at " + std::to_string(decidedAt) + " camera samples per pixel)";
  char buf[320];
  std::snprintf(buf, sizeof buf, "adaptive split: %.0f%% of pixels take more than one camera sample per film sample (mean %.2f); the first samples "
                "predict x%.2f by MSE and x%.2f by relMSE per unit of work, cross-validated (decided at %d camera samples per pixel)", 100.0 * splitShare, meanSplit,
                predictedMse, predictedRelMse, decidedAt);
  if (!oneSided) return buf;
  return buf + std::string("; a split for ") + (predictedMse > predictedRelMse ? "MSE" : "relMSE") + " alone, at most " +
         std::to_string(std::lround(100.0 * (AdaptiveSplit::kOneSidedWork - 1.0))) + "% more work";
}

SplitMap AdaptiveSplit::decide(const Film& film, const Halves& sumSquares, const Halves& count, const std::vector<float>& pixelCost,
                               int maxSplit) {
  const int w = film.width(), h = film.height(), n = film.spp();
  const size_t pixels = static_cast<size_t>(w) * h;
  maxSplit = std::clamp(maxSplit, 1, kMaxSplit);
  if (n < 2 || maxSplit == 1 || pixelCost.size() != pixels) return {};
  for (int half = 0; half < 2; ++half)
    if (count[half].size() != pixels || sumSquares[half].size() != 3 * pixels) return {};
  const auto& sum = film.sum();
  double imageMean = 0.0;
  for (float s : sum) imageMean += s;
  imageMean /= static_cast<double>(sum.size()) * n;
  const double eps = relativeEpsilon(imageMean);  // the relMSE's

  // Per block and per half of the samples (even and odd film samples): the pixels' variance per
  // camera sample, absolute and relative, about the film's mean (the pixel's value, whatever k its
  // samples had; n / (n - 1) undoes the mean's own share), and the work per camera sample.
  const int bw = (w + kBlock - 1) / kBlock, bh = (h + kBlock - 1) / kBlock;
  const size_t blocks = static_cast<size_t>(bw) * bh;
  struct Figures {
    std::vector<double> absVar, relVar;
    double absTotal = 0.0, relTotal = 0.0;
  };
  std::array<Figures, 2> halves;
  for (Figures& f : halves) f.absVar.assign(blocks, 0.0), f.relVar.assign(blocks, 0.0);
  std::vector<double> cost(blocks, 0.0);
  const double unbias = static_cast<double>(n) / (n - 1.0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t p = static_cast<size_t>(y) * w + x, b = static_cast<size_t>(y / kBlock) * bw + x / kBlock;
      const double c = count[0][p] + count[1][p];
      if (!(c > 0.0)) continue;
      cost[b] += pixelCost[p] / c;
      for (int half = 0; half < 2; ++half) {
        const double ch = count[half][p];
        if (!(ch > 0.0)) continue;
        for (int k = 0; k < 3; ++k) {
          const double m = sum[3 * p + k] / n;
          const double var = std::max(0.0, (sumSquares[half][3 * p + k] / ch - m * m) * unbias);
          halves[half].absVar[b] += var;
          halves[half].relVar[b] += var / (m * m + eps);
        }
      }
    }
  // Half of each block's figures is its 3 x 3 neighbourhood's mean: at a few samples per pixel a
  // block that drew a rare bright sample and its neighbour that did not are alike more often than
  // their figures say.
  auto smoothed = [&](const std::vector<double>& v) {
    std::vector<double> out(blocks);
    for (int by = 0; by < bh; ++by)
      for (int bx = 0; bx < bw; ++bx) {
        double around = 0.0;
        int neighbours = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = bx + dx, ny = by + dy;
            if (nx < 0 || ny < 0 || nx >= bw || ny >= bh) continue;
            around += v[static_cast<size_t>(ny) * bw + nx], ++neighbours;
          }
        const size_t b = static_cast<size_t>(by) * bw + bx;
        out[b] = 0.5 * v[b] + 0.5 * around / neighbours;
      }
    return out;
  };
  // The splits are drawn from smoothed figures and scored by raw ones: smoothing lends a calm block
  // beside a noisy one some of its variance, and a block that is nearly free (the background a
  // camera ray meets nothing in) would then look worth splitting. Scored by its own figures it is
  // not (huge-sparse's sky: 45% of the pixels split, for no less variance and 6% more work).
  std::array<Figures, 2> raw = halves;
  Figures both;
  both.absVar.assign(blocks, 0.0), both.relVar.assign(blocks, 0.0);
  for (int half = 0; half < 2; ++half) {
    Figures& f = halves[half];
    f.absVar = smoothed(f.absVar), f.relVar = smoothed(f.relVar);
    for (size_t b = 0; b < blocks; ++b) {
      f.absTotal += f.absVar[b], f.relTotal += f.relVar[b];
      raw[half].absTotal += raw[half].absVar[b], raw[half].relTotal += raw[half].relVar[b];
    }
    // Samples so bright that their squares overflow float leave nothing to split by.
    if (!(f.absTotal > 0.0) || !(f.relTotal > 0.0) || !std::isfinite(f.absTotal) || !std::isfinite(f.relTotal)) return {};
    for (size_t b = 0; b < blocks; ++b) both.absVar[b] += 0.5 * f.absVar[b], both.relVar[b] += 0.5 * f.relVar[b];
  }
  both.absTotal = 0.5 * (halves[0].absTotal + halves[1].absTotal), both.relTotal = 0.5 * (halves[0].relTotal + halves[1].relTotal);
  // A block's camera samples cost at least 1% of the mean (a sample that meets no medium still
  // costs its camera ray, which the counted work leaves out).
  double costTotal = 0.0;
  for (double c : cost) costTotal += c;
  if (!(costTotal > 0.0)) return {};
  const double costFloor = 0.01 * costTotal / static_cast<double>(blocks);
  costTotal = 0.0;
  for (double& c : cost) c = std::max(c, costFloor), costTotal += c;

  // The candidates: k proportional to sqrt(variance / cost), the split that minimises variance x
  // cost for a variance that weighs the two metrics by alpha and 1 - alpha (each over its image
  // total), at a scale from "the noisiest block gets 1" up. Each is judged by cross-validation:
  // the split that one half of the samples calls for, scored by the other half's figures (the
  // efficiency gain (sum v)(sum c) / ((sum v / k)(sum c k)) per metric, the two ways round
  // averaged), so that a split fitted to its own samples' noise scores no gain. The score is the
  // worse of the two metrics, so that neither is given away for the other.
  auto splitOf = [&](const Figures& f, double alpha, int step, std::vector<uint8_t>& out) {
    std::vector<double> ratio(blocks);
    double largest = 0.0;
    for (size_t b = 0; b < blocks; ++b) {
      ratio[b] = std::sqrt((alpha * f.absVar[b] / f.absTotal + (1.0 - alpha) * f.relVar[b] / f.relTotal) / cost[b]);
      largest = std::max(largest, ratio[b]);
    }
    if (!(largest > 0.0)) return false;
    const double scale = (1.0 / largest) * std::pow(4.0 * maxSplit, step / 32.0);
    out.resize(blocks);
    for (size_t b = 0; b < blocks; ++b) out[b] = static_cast<uint8_t>(std::clamp(static_cast<int>(std::lround(scale * ratio[b])), 1, maxSplit));
    return true;
  };
  auto gains = [&](const Figures& f, const std::vector<uint8_t>& k, double& absGain, double& relGain, double& work) {
    double absError = 0.0, relError = 0.0;
    work = 0.0;
    for (size_t b = 0; b < blocks; ++b) absError += f.absVar[b] / k[b], relError += f.relVar[b] / k[b], work += cost[b] * k[b];
    absGain = f.absTotal / absError * costTotal / work, relGain = f.relTotal / relError * costTotal / work;
  };
  struct Candidate {
    double alpha;
    int step;
    double gain, absGain, relGain, work;
  };
  std::vector<Candidate> candidates;
  std::vector<uint8_t> fromA, fromB, fromBoth;
  for (int a = 0; a <= 10; ++a)
    for (int step = 0; step <= 32; ++step) {
      const double alpha = a / 10.0;
      if (!splitOf(halves[0], alpha, step, fromA) || !splitOf(halves[1], alpha, step, fromB) || !splitOf(both, alpha, step, fromBoth)) continue;
      double absAB, relAB, absBA, relBA, work, unused;
      gains(raw[1], fromA, absAB, relAB, unused);
      gains(raw[0], fromB, absBA, relBA, unused);
      gains(both, fromBoth, unused, unused, work);
      const double absGain = 0.5 * (absAB + absBA), relGain = 0.5 * (relAB + relBA);
      candidates.push_back({alpha, step, std::min(absGain, relGain), absGain, relGain, work});
    }
  // Kept: the least work per film sample among the candidates within 10% of the best cross-validated
  // gain, and only if that gain is 10% or more. Four samples per pixel see few of the rare bright
  // paths that carry a dim region's relMSE, so even cross-validated the gain of splitting the
  // bright blocks is overstated; the least of the near-best splits bets less on it. On fire (bench,
  // 8 s, medians by time) the least work within 2% split 26% of the pixels (mean k 1.86) and
  // measured x1.10 / x1.52 of the best preset by relMSE / MSE over five seeds; within 10%, 14%
  // (mean k 1.21) and x1.37 / x1.32 over ten (docs/performance.md, "Adaptive sampling by splitting").
  double bestGain = 0.0;
  for (const Candidate& c : candidates) bestGain = std::max(bestGain, c.gain);
  const Candidate* kept = nullptr;
  const bool oneSided = !(bestGain >= kMinimumGain);
  if (!oneSided) {
    for (const Candidate& c : candidates)
      if (c.gain >= kNearBest * bestGain && (!kept || c.work < kept->work)) kept = &c;
  } else {
    // No split gains both metrics: a small one for one metric (the header says when). With up to
    // 5% more work the flame core's blocks on torch-in-mist and torch-in-fog predicted x2.2-2.6 by
    // MSE and x0.97-0.98 by relMSE and measured about x2.1 and x0.94-0.96 (six to nine seeds); with
    // the 2% kept, x1.4-1.5 and x0.98. Broader splits predicted as much and measured x0.70-1.19 by
    // relMSE on shed-fire.
    auto oneMetric = [](const Candidate& c) { return std::max(c.absGain, c.relGain); };
    for (const Candidate& c : candidates)
      if (c.gain >= kOneSidedFloor && oneMetric(c) >= kOneSidedGain && c.work <= kOneSidedWork * costTotal && (!kept || oneMetric(c) > oneMetric(*kept)))
        kept = &c;
  }
  if (!kept) return {};
  splitOf(both, kept->alpha, kept->step, fromBoth);
  SplitMap map;
  map.split.assign(pixels, 1);
  double total = 0.0, split = 0.0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const uint8_t k = fromBoth[static_cast<size_t>(y / kBlock) * bw + x / kBlock];
      map.split[static_cast<size_t>(y) * w + x] = k;
      total += k, split += k > 1;
    }
  map.predictedMse = kept->absGain, map.predictedRelMse = kept->relGain;
  map.oneSided = oneSided;
  map.meanSplit = total / static_cast<double>(pixels), map.splitShare = split / static_cast<double>(pixels);
  return map;
}

void AdaptiveSplit::reset(int width, int height) {
  width_ = width;
  const size_t pixels = static_cast<size_t>(width) * height;
  for (int half = 0; half < 2; ++half) sumSquares_[half].assign(3 * pixels, 0.0f), count_[half].assign(pixels, 0.0f);
  cost_.assign(pixels, 0.0f);
  positions_.clear();
  map_ = {};
  decided_ = false;
  cameraSamples_ = 0.0;
}

bool AdaptiveSplit::passFinished(const Film& film, int maxSplit, uint64_t nextSampleIndex) {
  if (decided_ || count_[0].empty()) return false;
  double total = 0.0;
  for (int half = 0; half < 2; ++half)
    for (float c : count_[half]) total += c;
  cameraSamples_ = total / static_cast<double>(count_[0].size());
  if (cameraSamples_ < kFirstDecision) return false;
  map_ = decide(film, sumSquares_, count_, cost_, maxSplit);
  map_.decidedAt = static_cast<int>(std::lround(cameraSamples_));
  decided_ = true;
  // From the first split on, every pixel's positions continue from where the film's samples are.
  if (!map_.split.empty() && positions_.empty()) positions_.assign(count_[0].size(), nextSampleIndex);
  // The figures are read once: their memory goes back (two thirds of the split's 44 bytes a pixel).
  for (int half = 0; half < 2; ++half) std::vector<float>().swap(sumSquares_[half]), std::vector<float>().swap(count_[half]);
  std::vector<float>().swap(cost_);
  return true;
}

}  // namespace candela
