// Tests of the deterministic generators (core/random.hpp).
#include "vkloc/core/random.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace vkloc {
namespace {

TEST(Random, SplitMix64MatchesTheReferenceSequence) {
  // Reference values of SplitMix64 from state 0 (Steele, Lea, Flood; Vigna's splitmix64.c).
  uint64_t state = 0;
  EXPECT_EQ(splitMix64(state), 0xe220a8397b1dcdafull);
  EXPECT_EQ(splitMix64(state), 0x6e789e6aa1b965f4ull);
  EXPECT_EQ(splitMix64(state), 0x06c45d188009454full);
}

TEST(Random, SameSeedSameNumbersOtherSeedOthers) {
  Xoshiro256 a(42), b(42), c(43);
  for (int i = 0; i < 100; ++i) {
    const uint64_t x = a.next();
    EXPECT_EQ(x, b.next());
    EXPECT_NE(x, c.next());
  }
  EXPECT_NE(subSeed(1, 2), subSeed(1, 3));
  EXPECT_NE(subSeed(1, 2), subSeed(2, 2));
  EXPECT_EQ(subSeed(5, 9), subSeed(5, 9));
}

TEST(Random, DrawsHaveTheirDistributions) {
  Xoshiro256 rng(7);
  double sum = 0, sum2 = 0, usum = 0;
  int heads = 0;
  constexpr int kN = 200000;
  for (int i = 0; i < kN; ++i) {
    const double g = rng.gaussian();
    sum += g;
    sum2 += g * g;
    const double u = rng.uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    usum += u;
    const int r = rng.range(-2, 2);
    ASSERT_GE(r, -2);
    ASSERT_LE(r, 2);
    heads += rng.chance(0.25);
  }
  EXPECT_NEAR(sum / kN, 0.0, 0.01);
  EXPECT_NEAR(sum2 / kN, 1.0, 0.01);
  EXPECT_NEAR(usum / kN, 0.5, 0.005);
  EXPECT_NEAR(static_cast<double>(heads) / kN, 0.25, 0.005);
}

TEST(Random, Mt19937FollowsTheStandardEngine) {
  Mt19937 ours(123);
  std::mt19937_64 standard(123);
  for (int i = 0; i < 10; ++i) EXPECT_EQ(ours.next(), standard());
}

}  // namespace
}  // namespace vkloc
