// The one null-collision tracking loop (docs/method.md s.2). It merges the majorant DDAs of every
// medium the ray crosses into one piecewise-constant combined majorant mu_bar, draws tentative
// collisions with rate mu_bar (dt = -ln(1 - xi) / mu_bar), and hands each to a callback that
// decides what the collision is: delta tracking, ratio tracking and (later) emission gathering all
// differ only in that callback, never in copies of this loop. Segments with mu_bar = 0 cost nothing.
#pragma once

#include "work.h"

#include "medium.h"
#include "rng.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

namespace candela {

constexpr int kMaxMedia = 8;

// The media of a scene as the hot loop sees them.
struct MediaView {
  std::vector<const Medium*> media;
};

// State of one medium along the current ray.
struct MediumTrack {
  const Medium* medium = nullptr;
  Medium::Sampler sampler;
  Vec3 o, d;  // ray in the medium's index space
  MajorantDda dda;
  float t0 = 0.0f, t1 = 0.0f;  // current DDA segment
  float muBar = 0.0f;          // its majorant
  bool done = false;           // left its domain
  bool transmittanceOnly = false;  // walks the majorant of mu_t alone (trackCollisions)
  MediumTrack(const Medium& m, bool transmittance) : medium(&m), sampler(m), transmittanceOnly(transmittance) {}
  float cellMajorant(int cell) const { return transmittanceOnly ? medium->transmittanceCellMajorant(cell) : medium->cellMajorant(cell); }
};

// A tentative collision. Coefficients are evaluated for the media overlapping the point.
struct Collision {
  float t = 0.0f;
  Vec3 p{0.0f};       // world position
  float muBar = 0.0f; // combined majorant here
  int count = 0;      // overlapping media
  MediumTrack* track[kMaxMedia] = {};
  float sigmaT[kMaxMedia] = {};
  float sigmaTTotal = 0.0f;

  Vec3 indexPos(int i) const { return track[i]->o + t * track[i]->d; }
  const Medium& medium(int i) const { return *track[i]->medium; }
  // mu_s per channel summed over media.
  Rgb sigmaS() const {
    Rgb s(0.0f);
    for (int i = 0; i < count; ++i) s += track[i]->medium->albedo() * sigmaT[i];
    return s;
  }
  // Source term sum_i mu_a,i * Le,i (talk Eq. 1), per channel, with per_length media's E_i.
  // Non-emissive media cost nothing.
  Rgb emissionSource() const {
    Rgb s(0.0f);
    for (int i = 0; i < count; ++i)
      if (track[i]->medium->emissive()) s += track[i]->sampler.source(indexPos(i), sigmaT[i]);
    return s;
  }
  // The source of the media that emit per unit length (perLength) or in radiance units (not): an
  // analog walk gathers the first at every collision, the second at absorption only.
  Rgb emissionSourceOf(bool perLength) const {
    Rgb s(0.0f);
    for (int i = 0; i < count; ++i) {
      const Medium& m = *track[i]->medium;
      if (m.emissive() && m.emitsPerLength() == perLength) s += track[i]->sampler.source(indexPos(i), sigmaT[i]);
    }
    return s;
  }
};

// Walks tentative collisions along `ray` over (0, tMax). `onCollision(Collision&)` returns true to
// continue, false to stop. Returns true when the walk reached tMax (or left all media), false when
// the callback stopped it. `transmittanceOnly`: the walk serves a transmittance estimate alone and
// takes the majorant of mu_t (no emission term, so no collisions spent where nothing extinguishes).
template <class OnCollision>
bool trackCollisions(const MediaView& view, const Ray& ray, float tMax, Rng& rng, OnCollision&& onCollision, bool transmittanceOnly = false) {
  // Set up every medium whose majorant domain the ray crosses. Stack storage: no allocation.
  alignas(MediumTrack) unsigned char storage[kMaxMedia * sizeof(MediumTrack)];
  MediumTrack* tracks = reinterpret_cast<MediumTrack*>(storage);
  int n = 0;
  for (const Medium* m : view.media) {
    const Mat4& ifw = m->indexFromWorld();
    const Vec3 o = Vec3(ifw * glm::vec4(ray.origin, 1.0f));
    const Vec3 d = Vec3(ifw * glm::vec4(ray.direction, 0.0f));
    MajorantDda dda(m->majorantGrid(), o, d, 0.0f, tMax);
    float t0, t1;
    int cell;
    // A medium whose domain the ray misses (a light sample past the flame, a camera ray beside it)
    // costs its DDA's slab test only, not the setup of its grids' accessors.
    if (!dda.next(t0, t1, cell)) continue;
    MediumTrack* tr = new (&tracks[n++]) MediumTrack(*m, transmittanceOnly);
    tr->o = o, tr->d = d, tr->dda = dda, tr->t0 = t0, tr->t1 = t1;
    tr->muBar = tr->cellMajorant(cell);
  }
  struct Cleanup {
    MediumTrack* t;
    int& n;
    ~Cleanup() {
      for (int i = 0; i < n; ++i) t[i].~MediumTrack();
    }
  } cleanup{tracks, n};

  float t = 0.0f;
  Collision c;
  while (n > 0) {  // exits by break once every medium is done
    // The merged segment starts at t and ends at the nearest boundary of any medium's segment.
    float end = kInfinity, muBar = 0.0f;
    c.count = 0;
    for (int i = 0; i < n; ++i) {
      if (tracks[i].done) continue;
      if (tracks[i].t0 > t) {
        end = std::min(end, tracks[i].t0);
      } else {
        end = std::min(end, tracks[i].t1);
        if (tracks[i].muBar > 0.0f) {
          muBar += tracks[i].muBar;
          c.track[c.count++] = &tracks[i];
        }
      }
    }
    if (muBar > 0.0f) {
      float tc = t;
      for (;;) {
        // 1 - u is exact for our 24-bit uniforms, and logf is several times cheaper than log1pf.
        tc -= std::log(1.0f - rng.uniform()) / muBar;
        if (!(tc < end)) break;
        ++threadWork().collisions;
        c.t = tc;
        c.p = ray.at(tc);
        c.muBar = muBar;
        c.sigmaTTotal = 0.0f;
        for (int i = 0; i < c.count; ++i) {
          c.sigmaT[i] = c.track[i]->sampler.sigmaT(c.indexPos(i));
          c.sigmaTTotal += c.sigmaT[i];
        }
        if (!onCollision(c)) return false;
      }
    }
    t = end;
    ++threadWork().segments;
    // Advance the media whose segment ended; those that left their domain are marked done.
    int live = 0;
    for (int i = 0; i < n; ++i) {
      MediumTrack& tr = tracks[i];
      if (tr.done) continue;
      if (tr.t1 <= t) {
        int cell;
        if (tr.dda.next(tr.t0, tr.t1, cell)) {
          tr.muBar = tr.cellMajorant(cell);
        } else {
          tr.done = true;
          continue;
        }
      }
      ++live;
    }
    if (live == 0) break;
  }
  return true;
}

// Roulette once a ratio-tracking weight is small: survive with probability 10 w and carry 0.1, so the
// expectation stays w. False when the walk ends (w is then 0).
inline bool rouletteSmallWeight(float& weight, Rng& rng) {
  if (weight < 0.1f) {
    if (rng.uniform() >= weight * 10.0f) {
      weight = 0.0f;
      return false;
    }
    weight = 0.1f;
  }
  return weight > 0.0f;
}

// Ratio-tracking transmittance (Novak et al. 2014) with Russian roulette once it is small:
// T *= mu_n / mu_bar at every tentative collision. Unbiased; returns 0..1.
inline float ratioTrackingTransmittance(const MediaView& view, const Ray& ray, float tMax, Rng& rng) {
  float transmittance = 1.0f;
  trackCollisions(view, ray, tMax, rng, [&](const Collision& c) {
    transmittance *= std::max(0.0f, 1.0f - c.sigmaTTotal / c.muBar);
    return rouletteSmallWeight(transmittance, rng);
  }, true);
  return transmittance;
}

// Algorithm 1 of the talk: the emission integral along a ray by ratio tracking with the
// emission-aware majorant: L += w mu_a Le / mu_bar, w *= mu_n / mu_bar at every tentative collision.
// It includes the transmittance of every medium in between. Roulette keeps long walks cheap and the
// estimate unbiased. emissionAlongRay's fallback.
inline Rgb emissionByCollisions(const MediaView& view, const Ray& ray, float tMax, Rng& rng) {
  Rgb radiance(0.0f);
  float weight = 1.0f;
  trackCollisions(view, ray, tMax, rng, [&](const Collision& c) {
    radiance += c.emissionSource() * (weight / c.muBar);
    weight *= std::max(0.0f, 1.0f - c.sigmaTTotal / c.muBar);
    return rouletteSmallWeight(weight, rng);
  });
  return radiance;
}

// The emission integral along a light ray, int_0^tMax T(t) S(t) dt with S = sum_m mu_a,m Le,m
// (talk Eq. 1), where only the emission is needed (NEE toward emissive volumes, probe learning),
// at kEmissionPoints points instead of at every collision of the emission-aware majorant
// (docs/method.md s.3, "The emission integral of a light sample"):
// - the points are drawn in proportion to each emissive medium's per-cell emission maximum along the
//   ray (a piecewise-constant density over its majorant cells), stratified: one in each 1/N of that
//   density's CDF;
// - T(t_j) comes from one ratio-tracking walk with the majorant of mu_t alone, read at each point on
//   the way (its running product, roulette included, estimates T(t) without bias at every t).
// Unbiased: the density is positive wherever a medium may emit (every cell of an emissive medium with
// a positive majorant or maximum has at least Medium::emissionFloor).
// Without emission maxima (no emission term in the strategy's majorant) or past kMaxEmissionCells
// cells it falls back to emissionByCollisions.
inline constexpr int kEmissionPoints = 8;
inline constexpr int kMaxEmissionCells = 256;
inline Rgb emissionAlongRay(const MediaView& view, const Ray& ray, float tMax, Rng& rng) {
  struct Cell {
    float t0, t1;
    float density;  // the cell's emission maximum plus the floor: p(t) = density / total
    double mass;    // density x (t1 - t0)
    int medium;
  };
  Cell cells[kMaxEmissionCells];
  int count = 0;
  double total = 0.0;
  for (size_t m = 0; m < view.media.size(); ++m) {
    const Medium& medium = *view.media[m];
    if (!medium.emissive()) continue;
    const std::vector<float>& maxima = medium.emissionMaxima();
    if (maxima.empty() || medium.majorantGrid().empty()) return emissionByCollisions(view, ray, tMax, rng);
    const Mat4& ifw = medium.indexFromWorld();
    MajorantDda dda(medium.majorantGrid(), Vec3(ifw * glm::vec4(ray.origin, 1.0f)), Vec3(ifw * glm::vec4(ray.direction, 0.0f)), 0.0f, tMax);
    float t0 = 0.0f, t1 = 0.0f;
    int cell = 0;
    while (dda.next(t0, t1, cell)) {
      ++threadWork().segments;
      // Every cell where the medium may be (or emit) gets the floor: the density stays positive
      // wherever the source may be.
      const float maximum = maxima[static_cast<size_t>(cell)];
      if ((!(maximum > 0.0f) && !(medium.transmittanceCellMajorant(cell) > 0.0f)) || !(t1 > t0)) continue;
      if (count == kMaxEmissionCells) return emissionByCollisions(view, ray, tMax, rng);
      const float density = maximum + medium.emissionFloor();
      cells[count++] = {t0, t1, density, static_cast<double>(density) * (t1 - t0), static_cast<int>(m)};
      total += cells[count - 1].mass;
    }
  }
  if (!(total > 0.0)) return Rgb(0.0f);
  // Maxima too large for a finite CDF: the collision estimator needs none.
  if (!std::isfinite(total)) return emissionByCollisions(view, ray, tMax, rng);

  struct Point {
    float t, pdf;
    int medium;
  };
  Point points[kEmissionPoints];
  int c = 0;
  double before = 0.0;  // the CDF's mass before cell c
  for (int j = 0; j < kEmissionPoints; ++j) {
    const double target = (j + static_cast<double>(rng.uniform())) / kEmissionPoints * total;
    while (c + 1 < count && before + cells[c].mass <= target) before += cells[c++].mass;
    const Cell& in = cells[c];
    const double f = std::clamp((target - before) / in.mass, 0.0, 1.0);
    points[j] = {in.t0 + static_cast<float>(f) * (in.t1 - in.t0), static_cast<float>(in.density / total), in.medium};
  }
  std::sort(points, points + kEmissionPoints, [](const Point& a, const Point& b) { return a.t < b.t; });

  std::optional<Medium::Sampler> samplers[kMaxMedia];
  Rgb radiance(0.0f);
  float weight = 1.0f;
  int next = 0;
  auto gatherBefore = [&](float t) {
    for (; next < kEmissionPoints && points[next].t < t; ++next) {
      const Point& q = points[next];
      const Medium& medium = *view.media[static_cast<size_t>(q.medium)];
      std::optional<Medium::Sampler>& sampler = samplers[q.medium];
      if (!sampler) sampler.emplace(medium);
      ++threadWork().collisions;  // a density and an emission lookup, as a collision's
      const Vec3 index = Vec3(medium.indexFromWorld() * glm::vec4(ray.at(q.t), 1.0f));
      radiance += sampler->source(index, sampler->sigmaT(index)) * (weight / (kEmissionPoints * q.pdf));
    }
  };
  trackCollisions(view, ray, points[kEmissionPoints - 1].t, rng, [&](const Collision& col) {
    gatherBefore(col.t);
    weight *= std::max(0.0f, 1.0f - col.sigmaTTotal / col.muBar);
    return rouletteSmallWeight(weight, rng);
  }, true);
  if (weight > 0.0f) gatherBefore(kInfinity);
  return radiance;
}

// Visits the majorant cells each emissive medium's DDA crosses along a ray, in medium order:
// visit(t0, t1, the cell's emission maximum). False, and stops, at an emissive medium without
// maxima (nothing bounds its emission). No lookups: what it reports depends on the ray alone.
template <class Visit>
inline bool forEachEmissionCell(const MediaView& view, const Ray& ray, float tMax, Visit&& visit) {
  for (const Medium* medium : view.media) {
    if (!medium->emissive()) continue;
    const std::vector<float>& maxima = medium->emissionMaxima();
    if (maxima.empty() || medium->majorantGrid().empty()) return false;
    const Mat4& ifw = medium->indexFromWorld();
    MajorantDda dda(medium->majorantGrid(), Vec3(ifw * glm::vec4(ray.origin, 1.0f)), Vec3(ifw * glm::vec4(ray.direction, 0.0f)), 0.0f, tMax);
    float t0 = 0.0f, t1 = 0.0f;
    int cell = 0;
    while (dda.next(t0, t1, cell)) visit(t0, t1, maxima[static_cast<size_t>(cell)]);
  }
  return true;
}

// An upper bound of the emission along a ray, without its transmittance: int_0^tMax lum(S(t)) dt <=
// the sum over the majorant cells it crosses of each emissive medium's cell maximum of lum(S) times
// the length inside. Deterministic and cheap, for choices that must depend on the ray alone
// (camera_guides.h). Infinite for an emissive medium without maxima (nothing bounds it).
inline double emissionBoundAlongRay(const MediaView& view, const Ray& ray, float tMax) {
  double bound = 0.0;
  const bool bounded = forEachEmissionCell(view, ray, tMax, [&](float t0, float t1, float maximum) {
    bound += static_cast<double>(maximum) * std::max(0.0f, t1 - t0);
  });
  return bounded ? bound : std::numeric_limits<double>::infinity();
}

// The far end of the emission along a ray: the largest t <= tMax where some emissive medium may emit
// (the exit of the last majorant cell with a positive emission maximum), 0 when none can. tMax for
// an emissive medium without maxima (nothing bounds it). Counted as the DDA segments it walks.
inline float lastEmissionAlongRay(const MediaView& view, const Ray& ray, float tMax) {
  float last = 0.0f;
  const bool bounded = forEachEmissionCell(view, ray, tMax, [&](float, float t1, float maximum) {
    ++threadWork().segments;
    if (maximum > 0.0f) last = std::max(last, t1);
  });
  return bounded ? last : tMax;
}

}  // namespace candela
