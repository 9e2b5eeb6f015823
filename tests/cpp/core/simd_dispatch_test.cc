#include "indoorloc/core/simd_dispatch.h"

#include <cstdlib>
#include <cstring>

#include <gtest/gtest.h>

namespace indoorloc {
namespace {

// The choice follows the CPU unless INDOORLOC_DISABLE_AVX2 asks for the portable loops (the
// Python test test_filter_gives_the_same_numbers_with_and_without_avx2 runs both ways and checks
// identical results); it is made once.
TEST(SimdDispatch, FollowsTheCpuAndTheEnvironmentAndIsStable) {
  const char* off = std::getenv("INDOORLOC_DISABLE_AVX2");
  const bool disabled = off != nullptr && std::strcmp(off, "") != 0 && std::strcmp(off, "0") != 0;
#if defined(__x86_64__) || defined(__i386__)
  const bool cpu = __builtin_cpu_supports("avx2") != 0;
#else
  const bool cpu = false;
#endif
  EXPECT_EQ(UseAvx2(), cpu && !disabled);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(UseAvx2(), UseAvx2());
}

}  // namespace
}  // namespace indoorloc
