// Resampling of weighted particles, on log-weights.
//
// Four schemes (Douc, Cappé & Moulines 2005; Hol, Schön & Gustafsson 2006), each unbiased: the
// expected number of copies of particle i is N_out * w_i. They differ in variance:
// multinomial > residual, stratified > systematic (usually). All run in O(N + N_out) time and
// return ancestor indices in non-decreasing order (so copies of one particle are contiguous).
//
// ResampleIfNeeded() is the adaptive rule used by particle filters: resample only when the
// effective sample size falls below a fraction of N (paper 000, eq. 14: N_eff < N_T).
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/core/random.h"

namespace indoorloc {

enum class ResamplingScheme { kMultinomial, kStratified, kSystematic, kResidual };

/// "multinomial", "stratified", "systematic" or "residual".
std::string_view ToString(ResamplingScheme scheme);
/// Inverse of ToString; throws std::invalid_argument naming `argument` for an unknown name.
ResamplingScheme ParseResamplingScheme(std::string_view name,
                                       std::string_view argument = "scheme");

/// Draws `num_out` ancestor indices (num_out < 0: as many as there are weights) according to the
/// normalised exp(log_weights). The weights need not be normalised. Output is sorted.
/// Throws std::invalid_argument on empty input, NaN/+inf, or all weights zero.
void Resample(const Eigen::Ref<const Eigen::VectorXd>& log_weights, ResamplingScheme scheme,
              RandomStream& rng, std::vector<int>* ancestors, int num_out = -1);

/// As Resample, from n linear weights (finite, >= 0) whose sum is `total` (> 0): for filters
/// that keep linear weights rescaled every step, avoiding an exp() per particle.
void ResampleLinear(const double* weights, int n, double total, ResamplingScheme scheme,
                    RandomStream& rng, std::vector<int>* ancestors, int num_out = -1);

/// Convenience overload returning the ancestors.
std::vector<int> Resample(const Eigen::Ref<const Eigen::VectorXd>& log_weights,
                          ResamplingScheme scheme, RandomStream& rng, int num_out = -1);

/// Options of the adaptive resampling step.
struct ResamplingOptions {
  /// Scheme used when resampling happens.
  ResamplingScheme scheme = ResamplingScheme::kSystematic;
  /// Resample when ESS < ess_threshold * N. 1.0 resamples at every step whose weights are not
  /// all equal; 0.0 never resamples. Must be in [0, 1].
  double ess_threshold = 0.5;

  /// True if the options are usable; otherwise false with the reason in *error.
  bool IsValid(std::string* error) const;
};

/// What one adaptive resampling step did.
struct ResamplingSummary {
  bool resampled = false;
  int num_particles = 0;
  /// ESS of the incoming weights, in [1, N].
  double ess_before = 0.0;
  /// log of the sum of the incoming (unnormalised) weights: the log-likelihood increment.
  double log_normalizer = 0.0;
  /// Number of distinct ancestors kept (N when no resampling happened).
  int num_unique_ancestors = 0;

  /// One line, e.g. "resampled (systematic): ESS 312.4 / 1000, 287 unique, log Z -3.21".
  std::string BriefReport() const;
};

/// Normalises `log_weights` in place and, if ESS < options.ess_threshold * N, resamples: then
/// *ancestors holds the chosen indices and log_weights is reset to uniform (-log N). Otherwise
/// *ancestors is the identity 0..N-1. The caller gathers its particle states with *ancestors.
ResamplingSummary ResampleIfNeeded(Eigen::Ref<Eigen::VectorXd> log_weights,
                                   const ResamplingOptions& options, RandomStream& rng,
                                   std::vector<int>* ancestors);

}  // namespace indoorloc
