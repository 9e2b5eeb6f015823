// Internal to the (cell, mode) smoother (mode_sequence_smoother.cc; not installed): its two
// element-wise passes, the lattice moves and the mode mixing, written once and compiled twice
// (portable x86-64 baseline here, AVX2 in mode_sequence_smoother_passes.cc, chosen at run time by
// core/simd_dispatch.h). Each output entry is computed by the same IEEE operations in the same
// order in both builds (no FMA: both files are compiled with -ffp-contract=off and the avx2 target
// has none), so the bits do not depend on the machine.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <vector>

#if defined(__GNUC__)
#define INDOORLOC_MODE_PASS inline __attribute__((always_inline))
#else
#define INDOORLOC_MODE_PASS inline
#endif

// V4 values are only ever made inside the AVX2 build's functions (always inlined there): GCC's
// note that passing them without AVX would change the ABI does not apply.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif

namespace indoorloc::fusion::mode_ops {

// A run of lattice cells in one row whose states are consecutive: cells pad .. pad+length-1 of the
// zero-padded lattice hold states state .. state+length-1.
struct Run {
  std::ptrdiff_t pad;
  int state;
  int length;
};

// One stencil entry: the padded-lattice shift (dy W + dx) and its weight.
struct Tap {
  std::ptrdiff_t delta;
  double weight;
};

// One output mode of the mixing: out = base · Σ_m in_m + Σ_terms weight · in_from. `base` is the
// smallest entry of the transition's column (forward) or row (backward), so every term's weight is
// >= 0 (no cancellation) and a transition with a uniform part costs a few terms, not M.
struct MixTerm {
  int from;
  double weight;
};
struct MixRow {
  double base;
  std::vector<MixTerm> terms;
};

// Vectors of doubles (GCC vector extension): V2 for the portable build (SSE2), V4 for the AVX2
// build; the same per-lane operations in both. Written out because the compiler, left to itself,
// vectorised the stencil over its taps (gathers) instead of over the cells.
typedef double V2 __attribute__((vector_size(16)));
typedef double V4 __attribute__((vector_size(32)));

template <typename V>
INDOORLOC_MODE_PASS V LoadV(const double* p) {
  V v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

template <typename V>
INDOORLOC_MODE_PASS void StoreV(double* p, V v) {
  std::memcpy(p, &v, sizeof v);
}

// out[j] = Σ_taps w · lat[pad(j) + sign · delta] for every state j of every run: the gather form of
// a move (forward, sign -1: the mass arriving at j; backward, sign +1: the expectation over j's
// moves). Taps in their order, from 0, for each entry; eight entries at a time kept in registers
// (eight / lanes vectors V). `factor` (or null): each entry then multiplied by factor[j] (the
// forward pass's emission).
template <typename V>
INDOORLOC_MODE_PASS void StencilBody(const std::vector<Run>& runs, const std::vector<Tap>& taps, const double* lat,
                                     double* out, std::ptrdiff_t sign, const double* factor) {
  constexpr int kLanes = static_cast<int>(sizeof(V) / sizeof(double));
  constexpr int kVectors = 8 / kLanes;
  for (const Run& run : runs) {
    double* o = out + run.state;
    const double* base = lat + run.pad;
    int t0 = 0;
    for (; t0 + 8 <= run.length; t0 += 8) {
      V acc[kVectors] = {};
      for (const Tap& tap : taps) {
        const double* src = base + t0 + sign * tap.delta;
        V w;
        for (int l = 0; l < kLanes; ++l) w[l] = tap.weight;
        for (int v = 0; v < kVectors; ++v) acc[v] += w * LoadV<V>(src + v * kLanes);
      }
      if (factor != nullptr) {
        for (int v = 0; v < kVectors; ++v) acc[v] *= LoadV<V>(factor + run.state + t0 + v * kLanes);
      }
      for (int v = 0; v < kVectors; ++v) StoreV<V>(o + t0 + v * kLanes, acc[v]);
    }
    for (int t = t0; t < run.length; ++t) {
      double acc = 0.0;
      for (const Tap& tap : taps) acc += tap.weight * base[t + sign * tap.delta];
      o[t] = factor != nullptr ? acc * factor[run.state + t] : acc;
    }
  }
}

constexpr std::ptrdiff_t kMixBlock = 256;  // columns per block: the block's M rows stay in L1

// out (M x n, row-major) from in (M x n): row r = rows[r].base · Σ_m in_m + Σ_terms weight · in_from,
// the sum over m in order, then the terms in order. sum: scratch of kMixBlock doubles.
INDOORLOC_MODE_PASS void MixBody(const std::vector<MixRow>& rows, const double* in, double* out, std::ptrdiff_t n,
                                 double* sum) {
  const std::ptrdiff_t m = static_cast<std::ptrdiff_t>(rows.size());
  for (std::ptrdiff_t j0 = 0; j0 < n; j0 += kMixBlock) {
    const std::ptrdiff_t len = std::min(kMixBlock, n - j0);
    std::copy(in + j0, in + j0 + len, sum);
    for (std::ptrdiff_t r = 1; r < m; ++r) {
      const double* x = in + r * n + j0;
      for (std::ptrdiff_t t = 0; t < len; ++t) sum[t] += x[t];
    }
    for (std::ptrdiff_t r = 0; r < m; ++r) {
      double* o = out + r * n + j0;
      const double b = rows[static_cast<std::size_t>(r)].base;
      for (std::ptrdiff_t t = 0; t < len; ++t) o[t] = b * sum[t];
      for (const MixTerm& term : rows[static_cast<std::size_t>(r)].terms) {
        const double* x = in + term.from * n + j0;
        const double w = term.weight;
        for (std::ptrdiff_t t = 0; t < len; ++t) o[t] += w * x[t];
      }
    }
  }
}

// The forward pass's mixing of one mode m', written straight into the states' cells of the
// padded lattice: lat[pad(j)] = row.base · sum[j] + Σ_terms weight · in[from][j] (in: M x n
// row-major, sum[j] = Σ_m in[m][j]); eight entries at a time kept in registers, as the stencil.
template <typename V>
INDOORLOC_MODE_PASS void MixIntoLatticeBody(const MixRow& row, const double* in, const double* sum, std::ptrdiff_t n,
                                            const std::vector<Run>& runs, double* lat) {
  constexpr int kLanes = static_cast<int>(sizeof(V) / sizeof(double));
  constexpr int kVectors = 8 / kLanes;
  V b;
  for (int l = 0; l < kLanes; ++l) b[l] = row.base;
  for (const Run& run : runs) {
    double* o = lat + run.pad;
    const double* sm = sum + run.state;
    int t0 = 0;
    for (; t0 + 8 <= run.length; t0 += 8) {
      V acc[kVectors];
      for (int v = 0; v < kVectors; ++v) acc[v] = b * LoadV<V>(sm + t0 + v * kLanes);
      for (const MixTerm& term : row.terms) {
        const double* x = in + term.from * n + run.state + t0;
        V w;
        for (int l = 0; l < kLanes; ++l) w[l] = term.weight;
        for (int v = 0; v < kVectors; ++v) acc[v] += w * LoadV<V>(x + v * kLanes);
      }
      for (int v = 0; v < kVectors; ++v) StoreV<V>(o + t0 + v * kLanes, acc[v]);
    }
    for (int t = t0; t < run.length; ++t) {
      double acc = row.base * sm[t];
      for (const MixTerm& term : row.terms) acc += term.weight * in[term.from * n + run.state + t];
      o[t] = acc;
    }
  }
}

// lat[pad(j)] = x[j] · factor[j] for the states' cells (the backward pass's β ⊙ e).
INDOORLOC_MODE_PASS void ScatterProductBody(const double* x, const double* factor, const std::vector<Run>& runs,
                                            double* lat) {
  for (const Run& run : runs) {
    double* o = lat + run.pad;
    const double* a = x + run.state;
    const double* f = factor + run.state;
    for (int t = 0; t < run.length; ++t) o[t] = a[t] * f[t];
  }
}

// The forward pass's tick end, in place: a[m][j] *= 1 / s (a multiply: a division per entry cost
// as much as the rest of the pass), store[m][j] = float(a[m][j]), and
// sum[j] = Σ_m a[m][j] (modes in order), the next tick's mixing input.
INDOORLOC_MODE_PASS void NormaliseStoreAndSumBody(double* a, std::ptrdiff_t m, std::ptrdiff_t n, double s, float* store,
                                                  double* sum) {
  const double inv_s = 1.0 / s;
  for (std::ptrdiff_t j0 = 0; j0 < n; j0 += kMixBlock) {
    const std::ptrdiff_t len = std::min(kMixBlock, n - j0);
    for (std::ptrdiff_t r = 0; r < m; ++r) {
      double* x = a + r * n + j0;
      float* f = store + r * n + j0;
      double* sm = sum + j0;
      for (std::ptrdiff_t t = 0; t < len; ++t) {
        x[t] = x[t] * inv_s;
        f[t] = static_cast<float>(x[t]);
      }
      if (r == 0) {
        for (std::ptrdiff_t t = 0; t < len; ++t) sm[t] = x[t];
      } else {
        for (std::ptrdiff_t t = 0; t < len; ++t) sm[t] += x[t];
      }
    }
  }
}

// The backward pass's tick end: b[m][j] *= 1 / mx (in place; mx > 0, else b kept), and the unnormalised
// posterior p[j] = Σ_m float alpha[m][j] · b[m][j] (modes in order).
INDOORLOC_MODE_PASS void ScaleAndPosteriorBody(double* b, std::ptrdiff_t m, std::ptrdiff_t n, double mx,
                                               const float* alpha, double* p) {
  const double inv_mx = mx > 0.0 ? 1.0 / mx : 1.0;
  for (std::ptrdiff_t j0 = 0; j0 < n; j0 += kMixBlock) {
    const std::ptrdiff_t len = std::min(kMixBlock, n - j0);
    for (std::ptrdiff_t r = 0; r < m; ++r) {
      double* x = b + r * n + j0;
      const float* f = alpha + r * n + j0;
      double* pp = p + j0;
      if (mx > 0.0) {
        for (std::ptrdiff_t t = 0; t < len; ++t) x[t] = x[t] * inv_mx;
      }
      if (r == 0) {
        for (std::ptrdiff_t t = 0; t < len; ++t) pp[t] = static_cast<double>(f[t]) * x[t];
      } else {
        for (std::ptrdiff_t t = 0; t < len; ++t) pp[t] += static_cast<double>(f[t]) * x[t];
      }
    }
  }
}

// The passes of one build (portable or AVX2), chosen once per smoother.
struct Passes {
  void (*stencil)(const std::vector<Run>& runs, const std::vector<Tap>& taps, const double* lat, double* out,
                  std::ptrdiff_t sign, const double* factor);
  void (*mix)(const std::vector<MixRow>& rows, const double* in, double* out, std::ptrdiff_t n, double* sum);
  void (*mix_into_lattice)(const MixRow& row, const double* in, const double* sum, std::ptrdiff_t n,
                           const std::vector<Run>& runs, double* lat);
  void (*scatter_product)(const double* x, const double* factor, const std::vector<Run>& runs, double* lat);
  void (*normalise_store_and_sum)(double* a, std::ptrdiff_t m, std::ptrdiff_t n, double s, float* store, double* sum);
  void (*scale_and_posterior)(double* b, std::ptrdiff_t m, std::ptrdiff_t n, double mx, const float* alpha, double* p);
};

const Passes& PortablePasses();
const Passes& Avx2Passes();

}  // namespace indoorloc::fusion::mode_ops
