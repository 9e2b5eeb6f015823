// Internal to the grid tracker: the double-precision row sums of GridMoments (grid_ops.h), used
// with spatial medians (the moments and the median's block sums in one pass) and in the
// smoother's underflow fallback: the portable version and the AVX2 one (core/simd_dispatch.h).
//
// Each row's additions are those of a plain loop along the row, in its order (a double reduction
// may not be reordered without changing its bits). Rows are independent, so the portable version
// runs four rows side by side in SSE2 lanes and the AVX2 version eight, four per 256-bit
// register; each lane does exactly its own row's operations in the same order (no FMA, no sum
// across lanes), so both give the plain loop's bits.
#include "grid_ops.h"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif

namespace indoorloc::fusion::grid_ops {

// out[x] = (a[x], b[x]) in double, or (a[x] wa[x], b[x] wb[x]) with weights (products in double:
// exact). SSE2: four cells per iteration (two loads, unpack, convert) instead of a scalar load
// and convert per value; the same values either way.
static void InterleaveRowPair(const float* a, const float* b, const float* wa, const float* wb, int nx, RowPair* out) {
  int x = 0;
#if defined(__SSE2__) && defined(__GNUC__)
  auto pairs = [](const float* p, const float* q, int at, __m128d d[4]) {
    const __m128 u = _mm_loadu_ps(p + at), v = _mm_loadu_ps(q + at);
    const __m128 lo = _mm_unpacklo_ps(u, v), hi = _mm_unpackhi_ps(u, v);  // (p0 q0 p1 q1), (p2 q2 p3 q3)
    d[0] = _mm_cvtps_pd(lo);
    d[1] = _mm_cvtps_pd(_mm_movehl_ps(lo, lo));
    d[2] = _mm_cvtps_pd(hi);
    d[3] = _mm_cvtps_pd(_mm_movehl_ps(hi, hi));
  };
  for (; x + 4 <= nx; x += 4) {
    __m128d d[4], e[4];
    pairs(a, b, x, d);
    if (wa) {
      pairs(wa, wb, x, e);
      for (int j = 0; j < 4; ++j) d[j] = _mm_mul_pd(d[j], e[j]);
    }
    for (int j = 0; j < 4; ++j) std::memcpy(&out[x + j], &d[j], sizeof(RowPair));
  }
#endif
  for (; x < nx; ++x) {
    out[x] = wa ? RowPair{static_cast<double>(a[x]) * wa[x], static_cast<double>(b[x]) * wb[x]}
                : RowPair{static_cast<double>(a[x]), static_cast<double>(b[x])};
  }
}

void RowGroupMomentsInDouble(const float* g, const float* weight, const FloorGrid& fg, int y0, int rows, int q,
                                    double* coarse, Moments* m) {
  const int nx = fg.nx, nqx = (nx + q - 1) / q;
  // The rows' values (the product alpha * beta in double: exact), interleaved: lo = rows 0, 1;
  // hi = rows 2, 3 (missing rows repeat row 0 and are never read back).
  thread_local std::vector<RowPair> lo, hi;
  lo.resize(static_cast<std::size_t>(nx));
  hi.resize(static_cast<std::size_t>(nx));
  const float* rp[kDoubleRows];
  const float* wp[kDoubleRows];
  for (int r = 0; r < kDoubleRows; ++r) {
    const std::size_t off = static_cast<std::size_t>(y0 + (r < rows ? r : 0)) * nx;
    rp[r] = g + off;
    wp[r] = weight ? weight + off : nullptr;
  }
  InterleaveRowPair(rp[0], rp[1], wp[0], wp[1], nx, lo.data());
  InterleaveRowPair(rp[2], rp[3], wp[2], wp[3], nx, hi.data());
  const RowPair zero = {0.0, 0.0};
  RowPair mass0 = zero, sx0 = zero, sxx0 = zero, mass1 = zero, sx1 = zero, sxx1 = zero;
  for (int bx = 0; bx < nqx; ++bx) {
    RowPair bm0 = zero, bsx0 = zero, bm1 = zero, bsx1 = zero;
    const int x_end = std::min(nx, bx * q + q);
    for (int x = bx * q; x < x_end; ++x) {
      const double xd = x;
      const RowPair xx = {xd, xd};
      // v x, shared by Σ v x, Σ v x² = Σ (v x) x and the block's Σ v x (the plain loop's products)
      const RowPair v0 = lo[x], v1 = hi[x], vx0 = v0 * xx, vx1 = v1 * xx;
      mass0 += v0;
      mass1 += v1;
      sx0 += vx0;
      sx1 += vx1;
      sxx0 += vx0 * xx;
      sxx1 += vx1 * xx;
      bm0 += v0;
      bm1 += v1;
      bsx0 += vx0;
      bsx1 += vx1;
    }
    if (coarse) {
      const double bm[kDoubleRows] = {bm0[0], bm0[1], bm1[0], bm1[1]};
      const double bsx[kDoubleRows] = {bsx0[0], bsx0[1], bsx1[0], bsx1[1]};
      for (int r = 0; r < rows; ++r) {
        const int y = y0 + r;
        double* blk = coarse + (static_cast<std::size_t>(y / q) * nqx + bx) * 3;
        blk[0] += bm[r];
        blk[1] += bsx[r];
        blk[2] += bm[r] * y;
      }
    }
  }
  const double mass[kDoubleRows] = {mass0[0], mass0[1], mass1[0], mass1[1]};
  const double sx[kDoubleRows] = {sx0[0], sx0[1], sx1[0], sx1[1]};
  const double sxx[kDoubleRows] = {sxx0[0], sxx0[1], sxx1[0], sxx1[1]};
  for (int r = 0; r < rows; ++r) AddRowMoments(mass[r], sx[r], sxx[r], y0 + r, m);
}

#if defined(__x86_64__) && defined(__GNUC__)

namespace {

// out[x] = (r0[x], r1[x], r2[x], r3[x]) in double, times (w0[x], ..., w3[x]) when weighted
// (float x float in double: exact). Four cells at a time: four loads, a 4 x 4 transpose, converts.
// `out`: 4 nx doubles, cell x at 4 x (unaligned: a std::vector of __m256d would drop the type's
// alignment).
__attribute__((target("avx2"))) void InterleaveRowQuad(const float* const* r, const float* const* w, int nx,
                                                       double* out) {
  int x = 0;
  for (; x + 4 <= nx; x += 4) {
    __m128 a = _mm_loadu_ps(r[0] + x), b = _mm_loadu_ps(r[1] + x), c = _mm_loadu_ps(r[2] + x),
           d = _mm_loadu_ps(r[3] + x);
    _MM_TRANSPOSE4_PS(a, b, c, d);  // a = column x, b = column x + 1, ...
    __m256d v[4] = {_mm256_cvtps_pd(a), _mm256_cvtps_pd(b), _mm256_cvtps_pd(c), _mm256_cvtps_pd(d)};
    if (w) {
      __m128 e = _mm_loadu_ps(w[0] + x), f = _mm_loadu_ps(w[1] + x), g = _mm_loadu_ps(w[2] + x),
             h = _mm_loadu_ps(w[3] + x);
      _MM_TRANSPOSE4_PS(e, f, g, h);
      v[0] = _mm256_mul_pd(v[0], _mm256_cvtps_pd(e));
      v[1] = _mm256_mul_pd(v[1], _mm256_cvtps_pd(f));
      v[2] = _mm256_mul_pd(v[2], _mm256_cvtps_pd(g));
      v[3] = _mm256_mul_pd(v[3], _mm256_cvtps_pd(h));
    }
    for (int j = 0; j < 4; ++j) _mm256_storeu_pd(out + 4 * (x + j), v[j]);
  }
  for (; x < nx; ++x) {
    double v[4];
    for (int j = 0; j < 4; ++j) v[j] = w ? static_cast<double>(r[j][x]) * w[j][x] : static_cast<double>(r[j][x]);
    for (int j = 0; j < 4; ++j) out[4 * x + j] = v[j];
  }
}

}  // namespace

__attribute__((target("avx2"))) void RowGroupMomentsInDoubleAvx2(const float* g, const float* weight,
                                                                 const FloorGrid& fg, int y0, int rows, int q,
                                                                 double* coarse, Moments* m) {
  const int nx = fg.nx, nqx = (nx + q - 1) / q;
  // lo: rows 0-3, hi: rows 4-7 of the group (missing rows repeat row 0 and are never read back).
  thread_local std::vector<double> lo, hi;
  lo.resize(4 * static_cast<std::size_t>(nx));
  hi.resize(4 * static_cast<std::size_t>(nx));
  const float* rp[kDoubleRowsAvx2];
  const float* wp[kDoubleRowsAvx2];
  for (int r = 0; r < kDoubleRowsAvx2; ++r) {
    const std::size_t off = static_cast<std::size_t>(y0 + (r < rows ? r : 0)) * nx;
    rp[r] = g + off;
    wp[r] = weight ? weight + off : nullptr;
  }
  InterleaveRowQuad(rp, weight ? wp : nullptr, nx, lo.data());
  InterleaveRowQuad(rp + 4, weight ? wp + 4 : nullptr, nx, hi.data());
  const __m256d zero = _mm256_setzero_pd();
  __m256d mass0 = zero, sx0 = zero, sxx0 = zero, mass1 = zero, sx1 = zero, sxx1 = zero;
  for (int bx = 0; bx < nqx; ++bx) {
    __m256d bm0 = zero, bsx0 = zero, bm1 = zero, bsx1 = zero;
    const int x_end = std::min(nx, bx * q + q);
    for (int x = bx * q; x < x_end; ++x) {
      const __m256d xx = _mm256_set1_pd(static_cast<double>(x));
      // The portable loop's operations: v x, then Σ v, Σ v x, Σ (v x) x and the block's Σ v, Σ v x.
      const __m256d v0 = _mm256_loadu_pd(lo.data() + 4 * x), v1 = _mm256_loadu_pd(hi.data() + 4 * x);
      const __m256d vx0 = _mm256_mul_pd(v0, xx), vx1 = _mm256_mul_pd(v1, xx);
      mass0 = _mm256_add_pd(mass0, v0);
      mass1 = _mm256_add_pd(mass1, v1);
      sx0 = _mm256_add_pd(sx0, vx0);
      sx1 = _mm256_add_pd(sx1, vx1);
      sxx0 = _mm256_add_pd(sxx0, _mm256_mul_pd(vx0, xx));
      sxx1 = _mm256_add_pd(sxx1, _mm256_mul_pd(vx1, xx));
      bm0 = _mm256_add_pd(bm0, v0);
      bm1 = _mm256_add_pd(bm1, v1);
      bsx0 = _mm256_add_pd(bsx0, vx0);
      bsx1 = _mm256_add_pd(bsx1, vx1);
    }
    if (coarse) {
      double bm[kDoubleRowsAvx2], bsx[kDoubleRowsAvx2];
      _mm256_storeu_pd(bm, bm0);
      _mm256_storeu_pd(bm + 4, bm1);
      _mm256_storeu_pd(bsx, bsx0);
      _mm256_storeu_pd(bsx + 4, bsx1);
      for (int r = 0; r < rows; ++r) {  // row after row, as the plain loop adds them
        const int y = y0 + r;
        double* blk = coarse + (static_cast<std::size_t>(y / q) * nqx + bx) * 3;
        blk[0] += bm[r];
        blk[1] += bsx[r];
        blk[2] += bm[r] * y;
      }
    }
  }
  double mass[kDoubleRowsAvx2], sx[kDoubleRowsAvx2], sxx[kDoubleRowsAvx2];
  _mm256_storeu_pd(mass, mass0);
  _mm256_storeu_pd(mass + 4, mass1);
  _mm256_storeu_pd(sx, sx0);
  _mm256_storeu_pd(sx + 4, sx1);
  _mm256_storeu_pd(sxx, sxx0);
  _mm256_storeu_pd(sxx + 4, sxx1);
  for (int r = 0; r < rows; ++r) AddRowMoments(mass[r], sx[r], sxx[r], y0 + r, m);
}

#else  // never called (UseAvx2() is false)

void RowGroupMomentsInDoubleAvx2(const float* g, const float* w, const FloorGrid& fg, int y0, int rows, int q,
                                 double* coarse, Moments* m) {
  for (int y = y0; y < y0 + rows; y += kDoubleRows)
    RowGroupMomentsInDouble(g, w, fg, y, std::min(kDoubleRows, y0 + rows - y), q, coarse, m);
}

#endif

}  // namespace indoorloc::fusion::grid_ops
