// The (cell, mode) smoother's element-wise passes (mode_sequence_smoother_passes.h) compiled for the x86-64
// baseline and, again, for AVX2 (chosen at run time, core/simd_dispatch.h): the same bodies, so the
// same operations in the same order per entry and the same bits (-ffp-contract=off, no FMA).
#include "mode_sequence_smoother_passes.h"

namespace indoorloc::fusion::mode_ops {

#if defined(__x86_64__) && defined(__GNUC__)
#define INDOORLOC_AVX2 __attribute__((target("avx2")))
#else
#define INDOORLOC_AVX2
#endif

// One build of every pass: PREFIX the attribute, V the stencil's vector type.
#define INDOORLOC_MODE_PASSES(NAME, PREFIX, V)                                                                     \
  namespace NAME {                                                                                                \
  PREFIX void Stencil(const std::vector<Run>& runs, const std::vector<Tap>& taps, const double* lat, double* out, \
                      std::ptrdiff_t sign, const double* factor) {                                                \
    StencilBody<V>(runs, taps, lat, out, sign, factor);                                                           \
  }                                                                                                               \
  PREFIX void Mix(const std::vector<MixRow>& rows, const double* in, double* out, std::ptrdiff_t n, double* sum) { \
    MixBody(rows, in, out, n, sum);                                                                               \
  }                                                                                                               \
  PREFIX void MixIntoLattice(const MixRow& row, const double* in, const double* sum, std::ptrdiff_t n,             \
                             const std::vector<Run>& runs, double* lat) {                                         \
    MixIntoLatticeBody<V>(row, in, sum, n, runs, lat);                                                               \
  }                                                                                                               \
  PREFIX void ScatterProduct(const double* x, const double* factor, const std::vector<Run>& runs, double* lat) {  \
    ScatterProductBody(x, factor, runs, lat);                                                                     \
  }                                                                                                               \
  PREFIX void NormaliseStoreAndSum(double* a, std::ptrdiff_t m, std::ptrdiff_t n, double s, float* store,         \
                                   double* sum) {                                                                 \
    NormaliseStoreAndSumBody(a, m, n, s, store, sum);                                                             \
  }                                                                                                               \
  PREFIX void ScaleAndPosterior(double* b, std::ptrdiff_t m, std::ptrdiff_t n, double mx, const float* alpha,     \
                                double* p) {                                                                      \
    ScaleAndPosteriorBody(b, m, n, mx, alpha, p);                                                                 \
  }                                                                                                               \
  }  // namespace NAME

INDOORLOC_MODE_PASSES(portable, , V2)
INDOORLOC_MODE_PASSES(avx2, INDOORLOC_AVX2, V4)

const Passes& PortablePasses() {
  static const Passes p{portable::Stencil, portable::Mix, portable::MixIntoLattice, portable::ScatterProduct,
                        portable::NormaliseStoreAndSum, portable::ScaleAndPosterior};
  return p;
}

const Passes& Avx2Passes() {
  static const Passes p{avx2::Stencil, avx2::Mix, avx2::MixIntoLattice, avx2::ScatterProduct,
                        avx2::NormaliseStoreAndSum, avx2::ScaleAndPosterior};
  return p;
}

}  // namespace indoorloc::fusion::mode_ops
