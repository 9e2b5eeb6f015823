// Forward-backward and Viterbi on HMMs with sparse transitions (K successors per state), exact or
// truncated to a beam of the N most likely states (paper 001, §2.3).
//
// Numerics: messages are kept linear and renormalised at every step (scaling); emissions are
// taken in log space and shifted by their maximum before exp(), so observations far from every
// state never underflow to 0/0. The log-likelihood is the sum of the log normalisers.
//
// Truncation (beam N > 0): after each forward step only the N most likely states of the
// filtering posterior P(X_t | y_1:t) are kept and renormalised; the mass dropped is reported per
// step; optionally the beam widens until the dropped mass is below a tolerance (mass-adaptive
// beam, `max_dropped_mass`). The backward recursion runs on the forward supports (the smoothing posterior is
// α_t β_t, so β is needed only where α_t > 0): with N >= M this is the exact algorithm.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace indoorloc::analog {

/// Row-sparse transition matrix: state i moves to next[i*K + k] with probability prob[i*K + k].
struct SparseTransitions {
  int num_states = 0;
  int k = 0;
  std::vector<int> next;
  std::vector<double> prob;

  /// Throws std::invalid_argument on bad sizes, indices out of range, negative probabilities or
  /// rows that do not sum to 1 (within 1e-9).
  void Validate() const;
};

/// log b_j(y_t) for the `count` states in `states` at time t, written to `out`.
using LogEmission = std::function<void(int t, const int* states, int count, double* out)>;

struct ForwardBackwardOptions {
  /// N of the truncated algorithm; 0 = exact.
  int beam = 0;
  /// Optional per-step beams (size T) overriding `beam`, e.g. a wider beam at steps without an
  /// observation, where the predicted mass is spread evenly and a narrow cut drops states at
  /// random (0 in an entry: no truncation at that step).
  std::vector<int> beam_per_step;
  /// Mass-adaptive beam (off at 1): when keeping the N most likely states would drop more than
  /// this filtering mass, keep more states, most likely first, until the dropped mass is at most
  /// `max_dropped_mass` or `beam_max` states are kept. It widens the beam exactly where a fixed
  /// N cuts blindly: at the start, where a uniform prior and one scalar observation leave a wide
  /// slab of equally likely states (docs/analog.md). In [0, 1].
  double max_dropped_mass = 1.0;
  /// Cap of the adaptive beam (0: no cap, up to every candidate).
  int beam_max = 0;
  /// The argument named when the emissions give every state zero likelihood at a step (the
  /// caller's name for what produced them: "log_emission", or "observations" for AnalogHMM).
  const char* emission_argument = "log_emission";
  bool IsValid(std::string* error) const;
};

/// Sparse posteriors per time step.
struct SparsePosteriors {
  std::vector<std::vector<int>> states;
  std::vector<std::vector<double>> probabilities;  ///< sum to 1 at each t
};

struct ForwardBackwardResult {
  SparsePosteriors filtering;  ///< P(X_t | y_1:t) on the forward support
  SparsePosteriors smoothing;  ///< P(X_t | y_1:T)
  double log_likelihood = 0.0;  ///< log p(y_1:T) (of the truncated model when beam > 0)
  Eigen::VectorXd dropped_mass; ///< T: filtering mass removed by the truncation at each step
  double seconds = 0.0;
};

/// initial: P(X_1) (M, non-negative, not all zero). T steps; emissions from `log_emission`.
ForwardBackwardResult ForwardBackward(const SparseTransitions& transitions, const Eigen::VectorXd& initial,
                                      int num_steps, const LogEmission& log_emission,
                                      const ForwardBackwardOptions& options = ForwardBackwardOptions());

struct ViterbiResult {
  std::vector<int> states;      ///< T: the MAP state sequence
  double log_probability = 0.0; ///< log p(x_1:T, y_1:T) of that sequence
};

/// Most likely state sequence (max-product in log space); beam > 0 keeps the N best partial
/// paths per step (exact when N >= M).
ViterbiResult Viterbi(const SparseTransitions& transitions, const Eigen::VectorXd& initial, int num_steps,
                      const LogEmission& log_emission, const ForwardBackwardOptions& options = ForwardBackwardOptions());

}  // namespace indoorloc::analog
