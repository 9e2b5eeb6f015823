// Internal to the grid tracker (not installed): eight float lanes for the grid's reductions.
// A row's sums are kept in eight partial sums (lane j: the cells x with x % 8 == j) so that the
// loops run on SIMD registers; the lanes are added in one fixed order at the end, so a result
// depends neither on the vector width (SSE2: two registers; AVX: one) nor on the compiler's
// choices. GCC and Clang: two 4-float vectors of their vector extension; others: a plain array.
#pragma once
#include <cstring>

namespace indoorloc::fusion::grid_ops {

#if defined(__GNUC__)
// Two 4-float vectors (one SSE / NEON register each): lanes 0-3 and 4-7.
typedef float Quad __attribute__((vector_size(16)));  // NOLINT
struct Lanes {
  Quad lo, hi;
  float operator[](int i) const { return i < 4 ? lo[i] : hi[i - 4]; }
  void Add(int i, float v) {
    if (i < 4) {
      lo[i] += v;
    } else {
      hi[i - 4] += v;
    }
  }
};
inline Lanes operator+(Lanes a, Lanes b) { return Lanes{a.lo + b.lo, a.hi + b.hi}; }
inline Lanes operator*(Lanes a, Lanes b) { return Lanes{a.lo * b.lo, a.hi * b.hi}; }
inline Lanes LanesOf(float v) { return Lanes{Quad{v, v, v, v}, Quad{v, v, v, v}}; }
inline Lanes Iota() { return Lanes{Quad{0, 1, 2, 3}, Quad{4, 5, 6, 7}}; }
inline Lanes MaxLanes(Lanes a, Lanes b) { return Lanes{a.lo > b.lo ? a.lo : b.lo, a.hi > b.hi ? a.hi : b.hi}; }
#else
struct Lanes {
  float v[8];
  float operator[](int i) const { return v[i]; }
  void Add(int i, float x) { v[i] += x; }
};
inline Lanes operator+(Lanes a, Lanes b) {
  for (int i = 0; i < 8; ++i) a.v[i] += b.v[i];
  return a;
}
inline Lanes operator*(Lanes a, Lanes b) {
  for (int i = 0; i < 8; ++i) a.v[i] *= b.v[i];
  return a;
}
inline Lanes LanesOf(float x) { return Lanes{{x, x, x, x, x, x, x, x}}; }
inline Lanes Iota() { return Lanes{{0, 1, 2, 3, 4, 5, 6, 7}}; }
inline Lanes MaxLanes(Lanes a, Lanes b) {
  for (int i = 0; i < 8; ++i) a.v[i] = a.v[i] > b.v[i] ? a.v[i] : b.v[i];
  return a;
}
#endif
inline Lanes& operator+=(Lanes& a, Lanes b) { return a = a + b; }

// Two double lanes, one per grid row: the double sums of rows run side by side, each lane doing
// exactly the additions of its own row (no sum crosses lanes), so results do not depend on the
// vector width either. (One SSE2 register: 32-byte vectors without AVX are kept in memory by GCC.)
#if defined(__GNUC__)
typedef double RowPair __attribute__((vector_size(16)));  // NOLINT
#else
struct RowPair {
  double v[2];
  double operator[](int i) const { return v[i]; }
};
inline RowPair operator+(RowPair a, RowPair b) { return RowPair{{a.v[0] + b.v[0], a.v[1] + b.v[1]}}; }
inline RowPair operator*(RowPair a, RowPair b) { return RowPair{{a.v[0] * b.v[0], a.v[1] * b.v[1]}}; }
inline RowPair& operator+=(RowPair& a, RowPair b) { return a = a + b; }
#endif
constexpr int kLanes = 8;

inline Lanes LoadLanes(const float* p) {
  Lanes v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}
inline void StoreLanes(float* p, Lanes v) { std::memcpy(p, &v, sizeof(v)); }

// The lanes' total in double, in a fixed order.
inline double LaneTotal(Lanes a) {
  return ((static_cast<double>(a[0]) + a[4]) + (static_cast<double>(a[1]) + a[5])) +
         ((static_cast<double>(a[2]) + a[6]) + (static_cast<double>(a[3]) + a[7]));
}

}  // namespace indoorloc::fusion::grid_ops
