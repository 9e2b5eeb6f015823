// Log-space weights: the representation of every probability vector in indoorloc.
//
// Particle weights and HMM messages underflow in linear space after a few hundred likelihood
// factors, so they are kept as natural logarithms. -inf is a valid log-weight (weight zero);
// NaN and +inf are not. Follows the `particles` library's resampling.py helpers.
#pragma once

#include <cmath>

#include <Eigen/Core>

namespace indoorloc {

/// The largest log-weight, after checking the vector: throws std::invalid_argument naming the
/// first NaN or +inf entry, if the vector is empty, or if every entry is -inf (all weights
/// zero). Vectorised; the building block of every function below.
double CheckedMaxLogWeight(const Eigen::Ref<const Eigen::VectorXd>& log_weights);

/// log(sum_i exp(log_weights_i)), computed stably (shift by the maximum). Returns -inf when every
/// entry is -inf or the vector is empty. Throws std::invalid_argument on NaN or +inf.
double LogSumExp(const Eigen::Ref<const Eigen::VectorXd>& log_weights);

/// Normalises in place so that sum_i exp(log_weights_i) = 1 and returns the log normaliser
/// (the log of the old sum, i.e. the log-likelihood increment in a particle filter).
/// Throws std::invalid_argument if the vector is empty, holds NaN or +inf, or is all -inf.
double NormalizeLogWeights(Eigen::Ref<Eigen::VectorXd> log_weights);

/// exp() of the normalised log-weights: linear weights summing to one.
Eigen::VectorXd NormalizedWeights(const Eigen::Ref<const Eigen::VectorXd>& log_weights);

/// Effective sample size (sum w)^2 / sum w^2, in [1, N]. The weights need not be normalised.
double EffectiveSampleSize(const Eigen::Ref<const Eigen::VectorXd>& log_weights);

/// exp(d) of a log-weight difference d: 0 without the library call for d < -746, where exp
/// underflows to 0 anyway (the same value; the library's underflow path is slow).
inline double ExpOfLogDifference(double d) { return d < -746.0 ? 0.0 : std::exp(d); }

}  // namespace indoorloc
