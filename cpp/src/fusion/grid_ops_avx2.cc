// Internal to the grid tracker: the AVX2 builds of the grid's float passes (grid_ops.h), chosen
// at run time (core/simd_dispatch.h). The library is compiled for the x86-64 baseline (SSE2), so
// these are the same bodies compiled again for 256-bit vectors: Blur, NormaliseAndFlush,
// MultiplyAndSum, Multiply, MaxOf and NormaliseMomentsAndStore (INDOORLOC_GRID_PASS, always inlined
// here). They are element-wise float operations and reductions kept in eight fixed lanes
// (grid_lanes.h); no FMA (the avx2 target does not include it, and this file is compiled with
// -ffp-contract=off), so the bits are the portable build's. (The double row sums of GridMoments:
// grid_moments_double.cc.)
#include "grid_ops.h"

namespace indoorloc::fusion::grid_ops {

#if defined(__x86_64__) && defined(__GNUC__)

#define INDOORLOC_AVX2 __attribute__((target("avx2")))

INDOORLOC_AVX2 void BlurAvx2(std::vector<float>& g, std::vector<float>& scratch, int nx, int ny, double var_cells2,
                             const CellWindow& win) {
  BlurBody(g, scratch, nx, ny, var_cells2, win);
}
INDOORLOC_AVX2 void NormaliseAndFlushAvx2(std::vector<float>& g, double scale, int nx, const CellWindow* win) {
  NormaliseAndFlushBody(g, scale, nx, win);
}
INDOORLOC_AVX2 double MultiplyAndSumAvx2(std::vector<float>& g, const std::vector<float>& wall, const float* fix,
                                         int nx, const CellWindow& win) {
  return MultiplyAndSumBody(g, wall, fix, nx, win);
}
INDOORLOC_AVX2 void MultiplyAvx2(std::vector<float>& g, const std::vector<float>& wall, const float* fix) {
  MultiplyBody(g, wall, fix);
}
INDOORLOC_AVX2 float MaxOfAvx2(const std::vector<float>& g) { return MaxOfBody(g); }
INDOORLOC_AVX2 Moments NormaliseMomentsAndStoreAvx2(std::vector<float>& g, double scale, const FloorGrid& fg,
                                                    double cell, float* store, const CellWindow& win) {
  return NormaliseMomentsAndStoreBody(g, scale, fg, cell, store, win);
}

#else  // never called (UseAvx2() is false): the portable bodies

void BlurAvx2(std::vector<float>& g, std::vector<float>& scratch, int nx, int ny, double v, const CellWindow& win) {
  BlurBody(g, scratch, nx, ny, v, win);
}
void NormaliseAndFlushAvx2(std::vector<float>& g, double scale, int nx, const CellWindow* win) {
  NormaliseAndFlushBody(g, scale, nx, win);
}
double MultiplyAndSumAvx2(std::vector<float>& g, const std::vector<float>& wall, const float* fix, int nx,
                          const CellWindow& win) {
  return MultiplyAndSumBody(g, wall, fix, nx, win);
}
void MultiplyAvx2(std::vector<float>& g, const std::vector<float>& wall, const float* fix) {
  MultiplyBody(g, wall, fix);
}
float MaxOfAvx2(const std::vector<float>& g) { return MaxOfBody(g); }
Moments NormaliseMomentsAndStoreAvx2(std::vector<float>& g, double scale, const FloorGrid& fg, double cell,
                                     float* store, const CellWindow& win) {
  return NormaliseMomentsAndStoreBody(g, scale, fg, cell, store, win);
}
#endif

}  // namespace indoorloc::fusion::grid_ops
