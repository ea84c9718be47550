// Tests of the count of cores a parallel stage may use.
#include "vkloc/core/threads.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <thread>

#ifdef __linux__
#include <sched.h>
#endif

namespace vkloc {
namespace {

TEST(Threads, AvailableCoresFollowTheAffinityMask) {
  const int cores = availableCores();
  EXPECT_GE(cores, 1);
  EXPECT_LE(cores, 64);
  const unsigned hardware = std::thread::hardware_concurrency();
  if (hardware > 0) {
    EXPECT_LE(cores, static_cast<int>(hardware));
  }
#ifdef __linux__
  cpu_set_t set;
  CPU_ZERO(&set);
  ASSERT_EQ(sched_getaffinity(0, sizeof(set), &set), 0);
  EXPECT_EQ(cores, std::min(CPU_COUNT(&set), 64));
#endif
}

}  // namespace
}  // namespace vkloc
