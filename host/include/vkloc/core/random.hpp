// vkloc: deterministic random numbers. The same seed gives the same numbers on every platform
// and standard library (no std::*_distribution, whose algorithms differ between libraries):
// simulated sequences, demo models and seeded tests are reproducible bit for bit.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

namespace vkloc {

/// One SplitMix64 step (Steele, Lea, Flood 2014): advances `state` and returns a well-mixed
/// 64-bit value.
inline uint64_t splitMix64(uint64_t& state) {
  uint64_t z = (state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

/// SplitMix64 finaliser of x: a 64-bit hash, used to derive independent seeds.
inline uint64_t mixSeed(uint64_t x) { return splitMix64(x); }

/// Seed of a named sub-stream (`tag`) of `seed`: streams for different tags are independent.
inline uint64_t subSeed(uint64_t seed, uint64_t tag) {
  return mixSeed(mixSeed(seed) ^ mixSeed(tag * 0x2545f4914f6cdd1dull));
}

/// Draws shared by the generators below; `Engine::next()` gives 64 uniform bits.
template <typename Engine>
class RandomDraws {
 public:
  /// Uniform in [0, 1), 53 bits.
  double uniform() { return static_cast<double>(self().next() >> 11) * 0x1.0p-53; }
  /// Uniform in [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Integer in [lo, hi] (modulo draw; the bias is below 2^-32 for ranges under 2^32).
  int range(int lo, int hi) { return lo + static_cast<int>(self().next() % static_cast<uint64_t>(hi - lo + 1)); }
  /// True with probability p.
  bool chance(double p) { return uniform() < p; }
  /// +1 or -1 from the top bit.
  double sign() { return (self().next() >> 63) != 0 ? 1.0 : -1.0; }
  /// Standard normal (Box-Muller; both values of a pair are used).
  double gaussian() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double u1 = 1.0 - uniform();  // (0, 1]
    const double u2 = uniform();
    const double r = std::sqrt(-2.0 * std::log(u1));
    const double a = 6.283185307179586 * u2;
    spare_ = r * std::sin(a);
    has_spare_ = true;
    return r * std::cos(a);
  }

 private:
  Engine& self() { return static_cast<Engine&>(*this); }
  double spare_ = 0.0;
  bool has_spare_ = false;
};

/// xoshiro256** (Blackman, Vigna 2018), seeded through SplitMix64: the general-purpose generator.
class Xoshiro256 : public RandomDraws<Xoshiro256> {
 public:
  explicit Xoshiro256(uint64_t seed) {
    uint64_t x = seed;
    for (uint64_t& v : s_) {
      x = mixSeed(x);
      v = x;
    }
  }
  uint64_t next() {
    const uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }

 private:
  static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  uint64_t s_[4] = {};
};

/// SplitMix64 as a stream generator from a raw 64-bit state (small and fast; the demo models'
/// procedural textures use it).
class SplitMix64 : public RandomDraws<SplitMix64> {
 public:
  explicit SplitMix64(uint64_t state) : state_(state) {}
  uint64_t next() { return splitMix64(state_); }

 private:
  uint64_t state_;
};

/// The standard's 64-bit Mersenne twister, whose output sequence the standard fixes (unlike its
/// distributions), with the draws above. Trajectory generation uses it.
class Mt19937 : public RandomDraws<Mt19937> {
 public:
  explicit Mt19937(uint64_t seed) : engine_(seed) {}
  uint64_t next() { return engine_(); }
  // UniformRandomBitGenerator, for code that still feeds standard distributions (the simulated
  // IMU's noise: kept so that existing seeds give the same sequences on this standard library).
  using result_type = uint64_t;
  static constexpr uint64_t min() { return std::mt19937_64::min(); }
  static constexpr uint64_t max() { return std::mt19937_64::max(); }
  uint64_t operator()() { return engine_(); }

 private:
  std::mt19937_64 engine_;
};

}  // namespace vkloc
