// Catalog of an analog (exemplar-based) HMM (paper 001, §2.2, eq. 2 and 6): every state of the
// historical trajectories, and for each state that has one, its successor in time.
//
// With a time-lag embedding δ (eq. 6) the state at time t of a trajectory is the concatenation
// (x_t, x_{t-1}, ..., x_{t-δ+1}), so the first δ - 1 samples of each trajectory form no state.
// With a stride s the successor of the state at t is the state at t + s. The state set S holds
// every embedded state (M of them); the analogs D_a are the states with a successor (the last s
// states of each trajectory have none, but they can still be successors).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace indoorloc::analog {

using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct CatalogOptions {
  int lag = 1;     ///< δ of eq. 6 (1: no embedding)
  int stride = 1;  ///< successor = state `stride` samples later

  bool IsValid(std::string* error) const;
};

class Catalog {
 public:
  /// trajectories: one (T_i x d) array per trajectory, all with the same d, finite values.
  Catalog(const std::vector<RowMatrixXd>& trajectories, const CatalogOptions& options = CatalogOptions());

  int num_states() const { return static_cast<int>(states_.rows()); }
  int num_analogs() const { return static_cast<int>(analogs_.size()); }
  /// Dimension of an embedded state, d * lag.
  int dim() const { return static_cast<int>(states_.cols()); }
  /// Dimension of one sample, d.
  int base_dim() const { return base_dim_; }
  const CatalogOptions& options() const { return options_; }
  /// All states (M x d*lag).
  const RowMatrixXd& states() const { return states_; }
  /// Indices (into states) of the analogs, and of their successors (same length).
  const std::vector<int>& analogs() const { return analogs_; }
  const std::vector<int>& successors() const { return successors_; }

 private:
  CatalogOptions options_;
  int base_dim_ = 0;
  RowMatrixXd states_;
  std::vector<int> analogs_, successors_;
};

}  // namespace indoorloc::analog
