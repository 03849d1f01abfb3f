// Work counted instead of time: what a sample cost, in operations whose count does not depend on
// the machine or its load. The auto strategy's pilot (auto_strategy.h) compares strategies by
// variance x work, so its decision is the same on an idle or a busy machine. Counters are per
// thread (no sharing in the hot loop); ProgressiveRenderer sums them over a pass.
#pragma once

#include <cstdint>

namespace candela {

// Nanoseconds per operation on one core of the calibration machine (candela-cli calibrate: a
// least-squares fit of pass time against these counts over the report scenes and presets). Refitted
// 2026-12-02 (medians of four fits on the 2-core development machine, whose constants agreed to
// 10-15%): the fit of 2026-12-01, before coarser cells for thin media and the cheaper light sample,
// put guided depth 8 at 3.6x full's cost on god-rays-dark where it measures 2.7x; over the rows of
// two calibrate runs its rms relative error was 14-17%, these constants' 7-12% (calibrate prints
// both). The fit leaves a camera sample and a guide's preparation no cost of their own (their work
// is in the rays and segments they start). Only ratios matter.
struct WorkCost {
  static constexpr double kSample = 0.0, kCollision = 72.0, kSegment = 52.0, kRay = 135.0, kKnot = 131.0, kGuided = 162.0,
                          kGuide = 0.0;
};

struct WorkCounters {
  uint64_t samples = 0;     // camera samples
  uint64_t collisions = 0;  // tentative collisions (a density lookup each, per medium)
  uint64_t segments = 0;    // majorant DDA segments walked
  uint64_t rays = 0;        // surface rays traced (Embree intersect or occlusion)
  uint64_t knots = 0;       // probe knots gathered into guided distance densities
  uint64_t guided = 0;      // guided distance samples drawn (a table lookup and a vertex each)
  uint64_t guides = 0;      // ray segments that prepared a guided density (interval, thickness walk)

  WorkCounters& operator+=(const WorkCounters& o) {
    samples += o.samples, collisions += o.collisions, segments += o.segments, rays += o.rays, knots += o.knots, guided += o.guided, guides += o.guides;
    return *this;
  }
  // The work done between two readings of the same counters.
  WorkCounters operator-(const WorkCounters& o) const {
    WorkCounters d = *this;
    d.samples -= o.samples, d.collisions -= o.collisions, d.segments -= o.segments, d.rays -= o.rays, d.knots -= o.knots,
        d.guided -= o.guided, d.guides -= o.guides;
    return d;
  }
  // The cost in nanoseconds of one core of the calibration machine: constants fitted once by least
  // squares against render time (candela-cli calibrate, docs/performance.md, "The auto strategy"); never the clock.
  // Inline: measured q reads it twice per guided vertex of a measured pixel and once per pass
  // (camera_guides.h); out of line it was 0.5% of a `full` render of fire.
  double cost() const {
    using C = WorkCost;
    return C::kSample * static_cast<double>(samples) + C::kCollision * static_cast<double>(collisions) +
           C::kSegment * static_cast<double>(segments) + C::kRay * static_cast<double>(rays) + C::kKnot * static_cast<double>(knots) +
           C::kGuided * static_cast<double>(guided) + C::kGuide * static_cast<double>(guides);
  }
};

// This thread's counters (the hot loop adds to them; renderPass collects them).
inline WorkCounters& threadWork() {
  thread_local WorkCounters counters;
  return counters;
}

}  // namespace candela
