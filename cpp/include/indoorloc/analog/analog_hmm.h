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

/// Where the transition from state s_i through its analog a_j goes.
enum class SuccessorRule {
  /// The analog's own successor s_{F(j)} (eq. 4 of the paper).
  kCatalog,
  /// The "locally incremental" analog operator of the AnDA literature (Lguensat et al., MWR 2017,
  /// "locally-incremental" analog forecasting) made discrete: the catalog state nearest to
  /// s_i + (s_{F(j)} - a_j), i.e. the analog's increment applied to the state itself.
  /// Analogs on the state's own trajectory (s_{i±1}, s_{i±2}) then all lead to s_{i+1} instead
  /// of s_{i-1} .. s_{i+3}, which removes the phase diffusion along the own trajectory, while
  /// analogs on other passes still carry their increments. Targets that coincide are merged
  /// (weights summed; the spare slots keep the target with probability 0).
  kIncremental,
};

/// K nearest analogs of every catalog state (exact kNN on a kd-tree built once) and the
/// transition probabilities of eq. 4 with σ_i = sigma_scale · std(K distances of state i).
/// sigma_scale = 1 is the paper's adaptive σ; smaller values concentrate the transition on the
/// nearest analogs' successors (see AnalogHmmOptions::sigma_scale). `rule` chooses the target
/// of each analog (kCatalog = the paper; kIncremental costs M·K extra 1-NN queries).
SparseTransitions BuildKnnTransitions(const Catalog& catalog, int k, double sigma_scale = 1.0,
                                      SuccessorRule rule = SuccessorRule::kCatalog);

/// Exact kNN of arbitrary query points among the catalog's analogs: indices (into the analog
/// list) and squared distances, K per query, nearest first.
void KnnAnalogs(const Catalog& catalog, const Eigen::Ref<const RowMatrixXd>& queries, int k,
                Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>* indices, RowMatrixXd* squared_distances);

struct AnalogHmmOptions {
  int k = 10;                      ///< neighbours per state (paper: 5-15)
  std::vector<int> observed;       ///< state components observed (default: the first one)
  Eigen::MatrixXd R;               ///< observation covariance (m x m, symmetric positive definite)
  /// Multiplier of the adaptive kernel width of eq. 4 (σ_i = sigma_scale · std of the K
  /// distances). 1 = the paper. The paper leaves σ to cross-validation ("a scale parameter");
  /// on a catalog of consecutive states a narrower kernel keeps the chain from drifting in time
  /// along its own trajectory (docs/analog.md). Must be > 0.
  double sigma_scale = 1.0;
  /// Target of each analog's transition (kCatalog = the paper's eq. 4; see SuccessorRule).
  SuccessorRule successor_rule = SuccessorRule::kCatalog;
  bool IsValid(std::string* error) const;
};

/// How the forward-backward of AnalogHMM::Smooth truncates (paper §2.3 and the options beyond it).
struct SmoothOptions {
  int beam = 0;                    ///< N of the truncated algorithm; 0 = exact
  int beam_unobserved = 0;         ///< beam at steps without any observation (0: same as beam)
  double max_dropped_mass = 1.0;   ///< mass-adaptive beam: widen until at most this mass is dropped (1: off)
  int beam_max = 0;                ///< cap of the adaptive beam (0: none)
  /// Prior P(X_1) over the catalog states (num_states weights, non-negative, not all zero; need
  /// not sum to 1). Empty = uniform, which the paper implies. A prior centred on a known start
  /// (AnDA's smoothers start from N(x_0, 0.1 I)) keeps a fixed-N truncation from cutting blindly
  /// at t = 1 (docs/analog.md, "Why the paper's fixed N = 1000 did not lose the truth").
  Eigen::VectorXd initial;
  bool IsValid(std::string* error) const;
};

struct SmoothingOutput {
  RowMatrixXd mean;               ///< T x D posterior mean E[X_t | y_1:T]
  RowMatrixXd mpm;                ///< T x D maximum posterior mode
  RowMatrixXd filtering_mean;     ///< T x D E[X_t | y_1:t]
  RowMatrixXd std;                ///< T x D posterior standard deviation sqrt(Var[X_t | y_1:T]) per component
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
  SmoothingOutput Smooth(const Eigen::Ref<const RowMatrixXd>& observations, const SmoothOptions& options) const;
  SmoothingOutput Smooth(const Eigen::Ref<const RowMatrixXd>& observations, int beam, int beam_unobserved = 0) const {
    SmoothOptions o;
    o.beam = beam;
    o.beam_unobserved = beam_unobserved;
    return Smooth(observations, o);
  }
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
