// Position fixes from the interpolated RSS model (paper 004): the gradient tracker of
// Algorithm 1 / eq. 17 and a global maximum-likelihood fix.
//
// The tracker moves the estimate at every scan by z <- z + R_z^{-1} ∇l(z, v) = z - I(z)^{-1}
// ∇l(z, v): a Fisher-scoring step on l (docs/wifi_derivations.md shows that this step has the
// right drift to first order; there is no motion model). Step control, beyond the paper:
//  - the step is capped at max_step_m (a walking speed bound);
//  - when I(z) is ill-conditioned (Proposition 1: all field gradients parallel), a ridge is
//    added, and if that fails a gradient step of at most fallback_step_m is taken;
//  - optional backtracking halves the step while l increases;
//  - the estimate is kept on the mesh (projected onto the floor's convex hull).
// The first fix comes from several starts: the reference points with the lowest l, each refined
// by Fisher-scoring iterations; the best refined point wins (LocateMaximumLikelihood). With
// options.paper_mode the tracker reproduces Algorithm 1 exactly (one uncapped step, no
// backtracking) after the first fix.
//
// Each fix carries the 2x2 covariance I(z)^{-1} (Cramér-Rao bound of the fix) [m^2].
#pragma once

#include <limits>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "indoorloc/wifi/rss_model.h"

namespace indoorloc::wifi {

struct GradientTrackerOptions {
  /// Largest move per step [m] (also per refinement iteration).
  double max_step_m = 1.0;
  /// Reciprocal condition number of I below which a ridge (then a gradient step) is used.
  double min_reciprocal_condition = 1e-6;
  /// Length cap of the fallback gradient step [m].
  double fallback_step_m = 0.3;
  /// Halve the step (up to 6 times) while l increases.
  bool backtracking = true;
  /// Fisher-scoring iterations per scan while tracking (the paper takes 1).
  int iterations_per_scan = 1;
  /// Reproduce Algorithm 1: 1 uncapped step per scan, no backtracking (fallback still guards
  /// a singular I).
  bool paper_mode = false;
  /// Number of starting points of a global fix.
  int num_starts = 5;
  /// Fisher-scoring iterations from each start of a global fix.
  int start_iterations = 25;
  /// Stop refining when a step is shorter than this [m].
  double tolerance_m = 1e-4;
  /// Re-localisation (beyond the paper): after each tracking step, also compute the global ML
  /// fix of the scan; if l at the tracked estimate exceeds the global optimum's by more than
  /// this many nats, jump to the global fix. A local Fisher step cannot leave a local minimum of
  /// a bumpy (shadowed) field; this test can. +inf disables it (the paper's behaviour).
  double relocalize_threshold_nats = std::numeric_limits<double>::infinity();

  bool IsValid(std::string* error) const;
};

/// A position fix.
struct WifiFix {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  Eigen::Matrix2d covariance_m2 = Eigen::Matrix2d::Identity();  ///< I(z)^{-1}; large if singular
  int floor = 0;                ///< floor number (not index)
  double neg_log_likelihood = 0.0;
  bool inside = true;           ///< the raw step landed inside the hull (before projection)
  int iterations = 0;
  int fallback_steps = 0;       ///< steps where I was too ill-conditioned for Fisher scoring
  bool relocalized = false;     ///< the tracker jumped to the global fix at this scan
};

/// Global maximum-likelihood fix for scans (n x K, prepared) all taken at one position, over
/// every floor (or only floor_index >= 0): best `num_starts` reference points by l, refined.
WifiFix LocateMaximumLikelihood(const RssModel& model, const Eigen::Ref<const RowMatrixXd>& rss_dbm,
                                const GradientTrackerOptions& options, int floor_index = -1);

/// Streaming tracker (paper Algorithm 1 with step control). Not thread-safe; use one per track.
class GradientTracker {
 public:
  GradientTracker(std::shared_ptr<const RssModel> model, GradientTrackerOptions options);

  /// Processes one scan (K values, prepared). The first scan after construction or Reset()
  /// gives a global fix; later scans move the estimate by Fisher-scoring steps.
  WifiFix Update(const Eigen::Ref<const Eigen::VectorXd>& rss_dbm);

  /// Forgets the estimate: the next Update makes a global fix.
  void Reset();
  /// Starts tracking from a known position and floor number.
  void ResetTo(const Eigen::Vector2d& position_m, int floor);

  bool initialized() const { return initialized_; }
  const WifiFix& last_fix() const { return last_; }

 private:
  std::shared_ptr<const RssModel> model_;
  GradientTrackerOptions options_;
  bool initialized_ = false;
  int floor_index_ = 0;
  int hint_ = -1;
  WifiFix last_;
  RowMatrixXd scan_;  // 1 x K buffer
};

}  // namespace indoorloc::wifi
