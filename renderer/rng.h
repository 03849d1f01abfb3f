// Deterministic random numbers. Every camera sample gets its own stream keyed by (seed, pixel,
// sample index), so images do not depend on how tiles are scheduled across threads.
#pragma once

#include <cstdint>

namespace candela {

inline uint64_t mixBits(uint64_t v) {
  // SplitMix64 finaliser: a cheap, well-distributed 64-bit hash.
  v ^= v >> 30;
  v *= 0xbf58476d1ce4e5b9ULL;
  v ^= v >> 27;
  v *= 0x94d049bb133111ebULL;
  v ^= v >> 31;
  return v;
}

inline uint64_t hashCombine(uint64_t a, uint64_t b) { return mixBits(a ^ (mixBits(b) + 0x9e3779b97f4a7c15ULL)); }

// PCG32 (O'Neill 2014): small state, good statistics, fast.
class Rng {
 public:
  Rng() = default;
  explicit Rng(uint64_t seed, uint64_t stream = 0) { reset(seed, stream); }

  void reset(uint64_t seed, uint64_t stream) {
    state_ = 0;
    inc_ = (stream << 1u) | 1u;
    nextU32();
    state_ += seed;
    nextU32();
  }

  uint32_t nextU32() {
    const uint64_t old = state_;
    state_ = old * 6364136223846793005ULL + inc_;
    const uint32_t xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
    const uint32_t rot = static_cast<uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31u));
  }

  // Uniform in [0, 1): 24 random mantissa bits, never returns 1.
  float uniform() { return static_cast<float>(nextU32() >> 8) * (1.0f / 16777216.0f); }

 private:
  uint64_t state_ = 0x853c49e6748fea9bULL;
  uint64_t inc_ = 0xda3e39cb94b95bdbULL;
};

}  // namespace candela
