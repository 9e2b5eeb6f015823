#include "indoorloc/fusion/backward_smoother.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "indoorloc/core/check.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/core/log_weights.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/parallel.h"
#include "indoorloc/core/resampling.h"

namespace indoorloc::fusion {

bool SmootherOptions::IsValid(std::string* error) const {
  // The backward kernel holds num_trajectories x max_particles log-weights per step.
  return Validator(error)
      .IntInRange(num_trajectories, 1, 100000, "num_trajectories")
      .IntInRange(max_particles, 1, 50000000, "max_particles")
      .Check(static_cast<double>(num_trajectories) * max_particles * 8.0 <= kMaxBytes, "max_particles",
             "x num_trajectories x 8 B must be <= " + FormatBytes(kMaxBytes) + ", got " +
                 FormatBytes(static_cast<double>(num_trajectories) * max_particles * 8.0))
      .IntInRange(num_threads, 0, 1024, "num_threads");
}

namespace {
constexpr double kNegInf = -std::numeric_limits<double>::infinity();

// One recorded cloud, thinned to at most max_particles (systematic resampling: equal weights).
struct Cloud {
  RowMatrixXd states;
  Eigen::VectorXi floors;
  Eigen::VectorXd log_w;
};

Cloud Thin(const RowMatrixXd& states, const Eigen::VectorXi& floors, const Eigen::VectorXd& log_w, int max_particles,
           RandomStream& rng) {
  Cloud c;
  if (states.rows() <= max_particles) {
    c.states = states;
    c.floors = floors;
    c.log_w = log_w;
    return c;
  }
  const std::vector<int> picks = Resample(log_w, ResamplingScheme::kSystematic, rng, max_particles);
  c.states.resize(max_particles, 4);
  c.floors.resize(max_particles);
  for (int i = 0; i < max_particles; ++i) {
    c.states.row(i) = states.row(picks[i]);
    c.floors[i] = floors[picks[i]];
  }
  c.log_w = Eigen::VectorXd::Constant(max_particles, -std::log(static_cast<double>(max_particles)));
  return c;
}

// Index drawn from unnormalised log-weights (at least one finite).
int Draw(const std::vector<double>& lw, double max_lw, RandomStream& rng, std::vector<double>* cumulative) {
  cumulative->resize(lw.size());
  double total = 0.0;
  for (size_t i = 0; i < lw.size(); ++i) {
    total += lw[i] > kNegInf ? ExpOfLogDifference(lw[i] - max_lw) : 0.0;
    (*cumulative)[i] = total;
  }
  const double u = rng.Uniform01() * total;
  const auto it = std::upper_bound(cumulative->begin(), cumulative->end(), u);
  return static_cast<int>(std::min<std::ptrdiff_t>(it - cumulative->begin(), static_cast<std::ptrdiff_t>(lw.size()) - 1));
}

// Draw's distribution kept between draws from the same log-weights: the weights exp(lw - max)
// and their running sums. After an entry is ruled out (set to -inf: a predecessor behind a wall)
// only the running sums are redone while the maximum stays, so each draw sees the values Draw
// would compute from scratch, without n exps per draw.
class BackwardKernel {
 public:
  void Set(const std::vector<double>& lw, double max_lw) {
    max_ = max_lw;
    weight_.resize(lw.size());
    for (size_t i = 0; i < lw.size(); ++i) weight_[i] = lw[i] > kNegInf ? ExpOfLogDifference(lw[i] - max_lw) : 0.0;
    Accumulate();
  }
  // lw[i] was set to -inf; max_lw is the new maximum of lw.
  void RuleOut(const std::vector<double>& lw, int i, double max_lw) {
    if (max_lw != max_) {
      Set(lw, max_lw);
      return;
    }
    weight_[static_cast<size_t>(i)] = 0.0;
    Accumulate();
  }
  int Draw(RandomStream& rng) const {
    const double u = rng.Uniform01() * total_;
    const auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), u);
    return static_cast<int>(
        std::min<std::ptrdiff_t>(it - cumulative_.begin(), static_cast<std::ptrdiff_t>(cumulative_.size()) - 1));
  }

 private:
  void Accumulate() {
    cumulative_.resize(weight_.size());
    double total = 0.0;
    for (size_t i = 0; i < weight_.size(); ++i) {
      total += weight_[i];
      cumulative_[i] = total;
    }
    total_ = total;
  }
  double max_ = 0, total_ = 0;
  std::vector<double> weight_, cumulative_;
};
}  // namespace

SmoothedTrack SmoothBackward(const ParticleHistory& history, const FloorPlan* plan,
                             const TrackerOptions& tracker_options, const SmootherOptions& options) {
  ValidateOptions(options, "smoother_options");
  ValidateOptions(tracker_options, "tracker_options");
  WallTimer timer;
  const int num_steps = static_cast<int>(history.states.size());
  CheckArgument(num_steps > 0, "history", "is empty (record_history off, or no step taken)");
  CheckArgument(history.steps.size() == history.states.size() && history.log_weights.size() == history.states.size() &&
                    history.floor_indices.size() == history.states.size(),
                "history", "has inconsistent lengths");
  const int m = options.num_trajectories;
  {
    // Thinned clouds (44 B per particle), the trajectories (x, y, floor) and the output, per step.
    double largest = 0.0;
    for (const auto& c : history.states) largest = std::max(largest, static_cast<double>(c.rows()));
    const double per_step = std::min(largest, static_cast<double>(options.max_particles)) * 44.0 + m * 40.0;
    RequireSizeLimit(static_cast<double>(num_steps), per_step, "smoother_options",
                     "recorded steps (max_particles x 44 B + num_trajectories x 40 B each)");
  }

  RandomStream thin_rng(options.seed, 0x5eedULL);
  std::vector<Cloud> clouds(static_cast<size_t>(num_steps));
  for (int k = 0; k < num_steps; ++k) {
    clouds[k] = Thin(history.states[k], history.floor_indices[k], history.log_weights[k], options.max_particles, thin_rng);
  }
  std::vector<StepMotion> motions;
  motions.reserve(static_cast<size_t>(num_steps));
  for (int k = 0; k < num_steps; ++k) motions.emplace_back(history.steps[k], tracker_options.motion);
  int num_floors = 1;
  for (const auto& c : clouds) num_floors = std::max(num_floors, c.floors.size() ? c.floors.maxCoeff() + 1 : 1);
  if (plan) num_floors = std::max(num_floors, plan->num_floors());
  const double p_change = num_floors > 1 ? tracker_options.floor_change_probability : 0.0;
  const double log_stay = std::log1p(-p_change);
  const double log_change = p_change > 0.0 ? std::log(p_change / (num_floors - 1)) : kNegInf;
  const double penalty = tracker_options.wall_log_penalty;

  // trajectory j: (x, y, floor) per step.
  std::vector<RowMatrixXd> paths(static_cast<size_t>(m), RowMatrixXd(num_steps, 3));
  ParallelForRuns(m, options.num_threads, DeriveSeed(options.seed, 0x6a11ULL), [&](int j, RandomStream& rng) {
    std::vector<double> lw, cumulative;
    BackwardKernel kernel;
    RowMatrixXd& path = paths[j];
    const Cloud& last = clouds[num_steps - 1];
    lw.assign(last.log_w.data(), last.log_w.data() + last.log_w.size());
    int idx = Draw(lw, last.log_w.maxCoeff(), rng, &cumulative);
    Eigen::Vector4d succ = last.states.row(idx).transpose();
    int succ_floor = last.floors[idx];
    path.row(num_steps - 1) << succ[0], succ[1], succ_floor;
    for (int k = num_steps - 2; k >= 0; --k) {
      const Cloud& c = clouds[k];
      const StepMotion& motion = motions[k + 1];
      const int n = static_cast<int>(c.states.rows());
      lw.resize(n);
      double max_lw = kNegInf;
      // cos and sin of the successor's offset once for the n predecessors (same bits).
      const StepMotion::Successor to = StepMotion::SuccessorOf(succ.head<2>(), succ[2], succ[3]);
      for (int i = 0; i < n; ++i) {
        double v = c.log_w[i];
        if (c.floors[i] != succ_floor) {
          v += log_change;
        } else {
          v += log_stay;
        }
        if (v > kNegInf) {
          v += motion.TransitionLogDensity(Eigen::Vector2d(c.states(i, 0), c.states(i, 1)), c.states(i, 2), c.states(i, 3),
                                           to);
        }
        lw[i] = v;
        max_lw = std::max(max_lw, v);
      }
      int pick = -1;
      // Draw, then test the wall only for the drawn predecessor (rejection: a few wall tests per
      // step instead of n).
      if (max_lw > kNegInf) kernel.Set(lw, max_lw);
      for (int attempt = 0; attempt < 32 && max_lw > kNegInf; ++attempt) {
        const int i = kernel.Draw(rng);
        const bool same_floor = c.floors[i] == succ_floor;
        const bool blocked = plan && same_floor &&
                             plan->CrossesWall(c.states(i, 0), c.states(i, 1), succ[0], succ[1], c.floors[i]);
        if (!blocked) {
          pick = i;
          break;
        }
        if (std::isinf(penalty)) {
          lw[i] = kNegInf;
          max_lw = *std::max_element(lw.begin(), lw.end());
          if (max_lw > kNegInf) kernel.RuleOut(lw, i, max_lw);
        } else {
          // Accept with probability exp(penalty) (the wall factor of the density); lw is
          // unchanged, so is the kernel.
          if (rng.Uniform01() < std::exp(penalty)) {
            pick = i;
            break;
          }
        }
      }
      if (pick < 0) {
        // No predecessor explains the successor (a recovery or re-spread happened in between):
        // fall back to the filtering weights.
        lw.assign(c.log_w.data(), c.log_w.data() + n);
        pick = Draw(lw, c.log_w.maxCoeff(), rng, &cumulative);
      }
      succ = c.states.row(pick).transpose();
      succ_floor = c.floors[pick];
      path.row(k) << succ[0], succ[1], succ_floor;
    }
  });

  SmoothedTrack out;
  out.positions_m = RowMatrixXd::Zero(num_steps, 2);
  out.covariances_m2 = RowMatrixXd::Zero(num_steps, 3);
  out.floor_indices = Eigen::VectorXi::Zero(num_steps);
  out.trajectories_m.resize(num_steps, 2 * m);
  for (int k = 0; k < num_steps; ++k) {
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    std::vector<int> votes(static_cast<size_t>(num_floors), 0);
    for (int j = 0; j < m; ++j) {
      mean += paths[j].row(k).head<2>().transpose();
      out.trajectories_m(k, 2 * j) = paths[j](k, 0);
      out.trajectories_m(k, 2 * j + 1) = paths[j](k, 1);
      ++votes[static_cast<size_t>(paths[j](k, 2))];
    }
    mean /= m;
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    for (int j = 0; j < m; ++j) {
      const Eigen::Vector2d d = paths[j].row(k).head<2>().transpose() - mean;
      cov += d * d.transpose();
    }
    cov /= m;
    out.positions_m.row(k) = mean.transpose();
    out.covariances_m2.row(k) << cov(0, 0), cov(0, 1), cov(1, 1);
    out.floor_indices[k] = static_cast<int>(std::max_element(votes.begin(), votes.end()) - votes.begin());
  }
  out.seconds = timer.ElapsedSeconds();
  return out;
}

}  // namespace indoorloc::fusion
