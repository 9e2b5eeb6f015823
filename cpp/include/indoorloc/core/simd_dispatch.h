// Run-time choice between the AVX2 and the portable version of a hot loop.
//
// The library is compiled for the x86-64 baseline (no -march=native: Eigen's ABI must match
// Debian's Ceres), so a loop that needs AVX2 (gathers, 4 x 64-bit integer lanes) is written
// twice, once with __attribute__((target("avx2"))) intrinsics and once in portable C++, and
// chosen here. Both versions perform the same IEEE operations in the same order (no FMA), so
// results are bit-identical whichever runs: a test runs both (INDOORLOC_DISABLE_AVX2=1).
#pragma once

namespace indoorloc {

/// True when the CPU has AVX2 and the environment variable INDOORLOC_DISABLE_AVX2 is unset or
/// "0" (read once, at the first call).
bool UseAvx2();

}  // namespace indoorloc
