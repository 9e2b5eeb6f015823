// The analog HMM (paper 001, §2.2): states = the catalog's states, transitions = the successors of
// each state's K nearest analogs (eq. 4, Gaussian kernel with σ adapted per state to the standard
// deviation of its K distances; σ = 0 gives equal weights), Gaussian observations of selected
// components with covariance R (eq. 5), missing values (NaN) per component, and the exact or
// truncated forward-backward (§2.3) with posterior mean, MPM and Viterbi MAP.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/analog/catalog.h"
#include "indoorloc/analog/forward_backward.h"

namespace indoorloc::analog {

/// K nearest analogs of every catalog state (exact kNN on a kd-tree built once) and the
/// transition probabilities of eq. 4.
SparseTransitions BuildKnnTransitions(const Catalog& catalog, int k);

/// Exact kNN of arbitrary query points among the catalog's analogs: indices (into the analog
/// list) and squared distances, K per query, nearest first.
void KnnAnalogs(const Catalog& catalog, const Eigen::Ref<const RowMatrixXd>& queries, int k,
                Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>* indices, RowMatrixXd* squared_distances);

struct AnalogHmmOptions {
  int k = 10;                      ///< neighbours per state (paper: 5-15)
  std::vector<int> observed;       ///< state components observed (default: the first one)
  Eigen::MatrixXd R;               ///< observation covariance (m x m, symmetric positive definite)
  bool IsValid(std::string* error) const;
};

struct SmoothingOutput {
  RowMatrixXd mean;               ///< T x D posterior mean E[X_t | y_1:T]
  RowMatrixXd mpm;                ///< T x D maximum posterior mode
  RowMatrixXd filtering_mean;     ///< T x D E[X_t | y_1:t]
  double log_likelihood = 0.0;
  Eigen::VectorXd dropped_mass;   ///< T
  Eigen::VectorXi support_size;   ///< T: states with non-zero smoothing posterior
  double seconds = 0.0;
};

class AnalogHMM {
 public:
  AnalogHMM(std::shared_ptr<const Catalog> catalog, const AnalogHmmOptions& options);

  const Catalog& catalog() const { return *catalog_; }
  const SparseTransitions& transitions() const { return transitions_; }
  const AnalogHmmOptions& options() const { return options_; }

  /// observations: T x m (m = observed.size()), NaN = missing component, a row of NaN = no
  /// observation. beam: 0 exact, else N of the truncated algorithm; beam_unobserved: the beam at
  /// steps without any observation (0: same as beam).
  SmoothingOutput Smooth(const Eigen::Ref<const RowMatrixXd>& observations, int beam, int beam_unobserved = 0) const;
  /// MAP sequence (Viterbi): T x D states and their indices.
  ViterbiResult MapSequence(const Eigen::Ref<const RowMatrixXd>& observations, int beam) const;

  /// log b_j(y_t) for the given states (the emission callback used above).
  LogEmission Emission(const Eigen::Ref<const RowMatrixXd>& observations) const;

 private:
  std::shared_ptr<const Catalog> catalog_;
  AnalogHmmOptions options_;
  SparseTransitions transitions_;
};

}  // namespace indoorloc::analog
