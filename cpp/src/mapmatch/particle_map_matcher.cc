#include "indoorloc/mapmatch/particle_map_matcher.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "indoorloc/core/check.h"
#include "indoorloc/core/log_weights.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/mapmatch/trajectory_simulator.h"

namespace indoorloc::mapmatch {
namespace {

constexpr double kPi = 3.14159265358979323846;

// log(2π I0(κ)) computed without overflow: I0(κ) = e^κ I0e(κ).
double LogVonMisesNormaliser(double kappa) {
  return std::log(2.0 * kPi) + kappa + std::log(std::cyl_bessel_i(0.0, kappa) * std::exp(-kappa));
}

}  // namespace

bool FilterOptions::IsValid(std::string* error) const {
  Validator v(error);
  // κ <= 300 keeps every likelihood factor e^{κ (d cos - 1)} >= e^{-600} representable; the
  // junction weights use the same form (1e300 used to surface as "'heading_rad' gives zero
  // likelihood").
  v.AtLeast(num_particles, 1, "num_particles")
      .IntInRange(num_particles, 1, 100000000, "num_particles")
      .InRange(kappa, 0.0, 300.0, "kappa")
      .InRange(noise_halfwidth_m, 0.0, 1e6, "noise_halfwidth_m");
  if (!v) return false;
  std::string inner;
  if (!resampling.IsValid(&inner)) {
    if (error) *error = "resampling." + inner;
    return false;
  }
  return v.InRange(junction_kappa, 0.0, 300.0, "junction_kappa")
      .InRange(bias_halfwidth_mps, 0.0, 1e6, "bias_halfwidth_mps")
      .InRange(bias_jitter_mps, 0.0, 1e6, "bias_jitter_mps")
      .Scale(tracking_spread_m, "tracking_spread_m")
      .Scale(recovery_window_s, "recovery_window_s")
      .Check(recovery_fraction > 0.0 && recovery_fraction <= 1.0, "recovery_fraction",
             "must be in (0, 1], got " + FormatValue(recovery_fraction))
      .IntInRange(smoothing_lag_steps, 0, 10000, "smoothing_lag_steps");
}

std::string FilterSummary::BriefReport() const {
  char buffer[200];
  std::snprintf(buffer, sizeof(buffer), "%d steps, %d resamplings, %d recoveries, mean ESS %.1f, log-lik %.2f, %.3f s",
                steps, resamplings, recoveries, mean_ess, total_log_likelihood, seconds);
  return buffer;
}

ParticleMapMatcher::ParticleMapMatcher(const RoadNetwork& network, const FilterOptions& options)
    : network_(network), options_(options) {
  ValidateOptions(options_);
  log_normaliser_ = LogVonMisesNormaliser(options_.kappa);
  Reset();
}

void ParticleMapMatcher::Spread(int first, int count, double offset_fraction) {
  // Equal spacing over the whole network length; alternate directions so that both travel
  // directions of every corridor are represented (unknown start and heading).
  if (count <= 0) return;
  const double spacing = network_.total_length_m() / std::max(1, (count + 1) / 2);
  int s = 0;
  double start_of_segment = 0.0;
  for (int k = 0; k < count; ++k) {
    const double position = (k / 2 + offset_fraction) * spacing;
    while (s + 1 < network_.num_segments() && position > start_of_segment + network_.lengths_m()[s]) {
      start_of_segment += network_.lengths_m()[s++];
    }
    const size_t i = static_cast<size_t>(first + k);
    segment_[i] = s;
    along_[i] = std::clamp(position - start_of_segment, 0.0, network_.lengths_m()[s]);
    direction_[i] = (k % 2 == 0) ? 1 : -1;
    bias_[i] = options_.estimate_speed_bias ? rng_.Uniform(-options_.bias_halfwidth_mps, options_.bias_halfwidth_mps) : 0.0;
  }
}

void ParticleMapMatcher::Reset() {
  const int n = options_.num_particles;
  rng_ = RandomStream(options_.seed);
  segment_.assign(static_cast<size_t>(n), 0);
  direction_.assign(static_cast<size_t>(n), 1);
  along_.assign(static_cast<size_t>(n), 0.0);
  bias_.assign(static_cast<size_t>(n), 0.0);
  Spread(0, n, 0.5);
  weights_.assign(static_cast<size_t>(n), 1.0);
  weight_scale_ = 1.0;
  weight_sum_ = n;
  factor_.assign(static_cast<size_t>(2 * network_.num_segments()), 1.0);
  // Segment geometry as flat arrays: x = origin + along * unit direction.
  const int m = network_.num_segments();
  lengths_.resize(static_cast<size_t>(m));
  origin_x_.resize(static_cast<size_t>(m));
  origin_y_.resize(static_cast<size_t>(m));
  unit_x_.resize(static_cast<size_t>(m));
  unit_y_.resize(static_cast<size_t>(m));
  for (int k = 0; k < m; ++k) {
    const double len = network_.lengths_m()[k];
    lengths_[static_cast<size_t>(k)] = len;
    origin_x_[static_cast<size_t>(k)] = network_.segments_m()(k, 0);
    origin_y_[static_cast<size_t>(k)] = network_.segments_m()(k, 1);
    unit_x_[static_cast<size_t>(k)] = (network_.segments_m()(k, 2) - network_.segments_m()(k, 0)) / len;
    unit_y_[static_cast<size_t>(k)] = (network_.segments_m()(k, 3) - network_.segments_m()(k, 1)) / len;
  }
  disagree_.assign(static_cast<size_t>(2 * network_.num_segments()), 0.0);
  disagreement_window_.clear();
  window_pos_ = 0;
  window_filled_ = 0;
  const int slots = options_.smoothing_lag_steps > 0 ? options_.smoothing_lag_steps + 1 : 0;
  history_.assign(static_cast<size_t>(n) * static_cast<size_t>(slots) * 2, 0.0);
  history_steps_ = 0;
  summary_ = FilterSummary();
  was_tracking_ = false;
}

void ParticleMapMatcher::SetParticles(const std::vector<int>& segments, const std::vector<signed char>& directions,
                                      const std::vector<double>& along_m) {
  const size_t n = static_cast<size_t>(options_.num_particles);
  CheckArgument(segments.size() == n && directions.size() == n && along_m.size() == n, "segments",
                "segments, directions and along_m need one entry per particle (" + std::to_string(n) + ")");
  for (size_t i = 0; i < n; ++i) {
    CheckArgument(segments[i] >= 0 && segments[i] < network_.num_segments(), "segments",
                  "entry " + std::to_string(i) + " is not a segment index");
    CheckArgument(directions[i] == 1 || directions[i] == -1, "directions", "entries must be +1 or -1");
    CheckArgument(along_m[i] >= 0.0 && along_m[i] <= network_.lengths_m()[segments[i]], "along_m",
                  "entry " + std::to_string(i) + " is outside its segment");
  }
  segment_ = segments;
  direction_ = directions;
  along_ = along_m;
  std::fill(weights_.begin(), weights_.end(), 1.0);
  weight_scale_ = 1.0;
  weight_sum_ = static_cast<double>(n);
}

double ParticleMapMatcher::Move(int i, double distance, double heading_rad, RandomStream& rng) {
  const Eigen::VectorXd& lengths = network_.lengths_m();
  int s = segment_[static_cast<size_t>(i)];
  int d = direction_[static_cast<size_t>(i)];
  double u = along_[static_cast<size_t>(i)] + d * distance;
  double importance = 1.0;
  for (int guard = 0; guard < 100000; ++guard) {
    int end;
    double leftover;
    if (u > lengths[s]) {
      end = 1;
      leftover = u - lengths[s];
    } else if (u < 0.0) {
      end = 0;
      leftover = -u;
    } else {
      break;
    }
    // A negative step (v Δt + η < 0: eq. 8-9 have no floor) moves the particle back, but not
    // over the end behind it: it stops there. Backing onto a continuation chosen at random would
    // put it on a branch it never came from (the filter keeps no history), which cost 7 m of
    // error at κ_P = 5 in the §III experiment (docs/mapmatch.md).
    if ((end == 1) != (d > 0)) {
      u = end == 1 ? lengths[s] : 0.0;
      break;
    }
    const std::vector<Continuation>& choices = network_.continuations(s, end);
    size_t pick = 0;
    if (choices.size() > 1) {
      if (options_.junction_policy == JunctionPolicy::kUniform) {
        pick = static_cast<size_t>(rng.UniformInt(choices.size()));
      } else {
        // Proposal q_j ∝ exp(κ_J cos(φ - heading_j)); the weight is multiplied by
        // prior / proposal = (1 / n_choices) / q_j, so the posterior is unchanged.
        q_.resize(choices.size());
        double total = 0.0;
        for (size_t j = 0; j < choices.size(); ++j) {
          const double h = TravelHeading(network_, choices[j].segment, choices[j].enter_end == 0 ? 1 : -1);
          q_[j] = std::exp(options_.junction_kappa * (std::cos(heading_rad - h) - 1.0));
          total += q_[j];
        }
        double r = rng.Uniform01() * total;
        while (pick + 1 < choices.size() && r >= q_[pick]) r -= q_[pick++];
        importance *= (total / q_[pick]) / static_cast<double>(choices.size());
      }
    }
    const Continuation& c = choices[pick];
    s = c.segment;
    d = c.enter_end == 0 ? 1 : -1;
    u = c.enter_end == 0 ? leftover : lengths[s] - leftover;
  }
  segment_[static_cast<size_t>(i)] = s;
  direction_[static_cast<size_t>(i)] = static_cast<signed char>(d);
  along_[static_cast<size_t>(i)] = std::clamp(u, 0.0, lengths[s]);
  return importance;
}

StepEstimate ParticleMapMatcher::Step(double speed_mps, double heading_rad, double dt_s) {
  CheckArgument(std::isfinite(speed_mps), "speed_mps", "is not finite");
  CheckArgument(std::isfinite(heading_rad), "heading_rad", "is not finite");
  RequireScale(dt_s, "dt_s");  // recovery_window_s / dt_s sizes a buffer: 1e-290 asked for 1e290 slots
  WallTimer timer;
  const int n = options_.num_particles;
  const int num_segments = network_.num_segments();
  StepEstimate est;

  // Per-step tables over the 2M (segment, direction) pairs: the von Mises factor of eq. 11
  // relative to its maximum, exp(κ (d cos(φ - β_s) - 1)) in [e^{-2κ}, 1], and the
  // disagreement 1 - d cos(φ - β_s) used by the recovery rule.
  const Eigen::VectorXd& beta = network_.headings_rad();
  const double kappa = options_.kappa;
  for (int s = 0; s < num_segments; ++s) {
    const double c = std::cos(heading_rad - beta[s]);
    factor_[static_cast<size_t>(2 * s + 1)] = std::exp(kappa * (c - 1.0));
    factor_[static_cast<size_t>(2 * s)] = std::exp(kappa * (-c - 1.0));
    disagree_[static_cast<size_t>(2 * s + 1)] = 1.0 - c;
    disagree_[static_cast<size_t>(2 * s)] = 1.0 + c;
  }

  // Prediction (eq. 8-10) and update (eq. 11) fused in one pass, with the sums needed for the
  // normalisation (eq. 12), the ESS (eq. 14), the estimate (eq. 13), its spread and the
  // disagreement. A negative step v Δt + η moves a particle back within its segment (eq. 8-9
  // have no floor: a floor at 0 biases the move forward by E[max(0, X)] - E[X], 5 % of the speed
  // at 10 Hz with a = 0.27 m); it stops at the end behind it.
  // Hoisted into locals so that the compiler keeps them in registers (the loop writes through
  // several pointers, which would otherwise force reloads of every member).
  const double a = options_.noise_halfwidth_m;
  const double two_a = 2.0 * a;
  const double mean_distance = speed_mps * dt_s;
  const bool estimate_bias = options_.estimate_speed_bias;
  const double jitter = options_.bias_jitter_mps * std::sqrt(3.0);  // uniform with that sd
  const double* length = lengths_.data();
  const double* origin_x = origin_x_.data();
  const double* origin_y = origin_y_.data();
  const double* unit_x = unit_x_.data();
  const double* unit_y = unit_y_.data();
  const double* factor = factor_.data();
  const double* disagree = disagree_.data();
  int* seg = segment_.data();
  signed char* dir = direction_.data();
  double* along = along_.data();
  double* weight = weights_.data();
  double* bias = bias_.data();
  double sum = 0, sum_sq = 0, sx = 0, sy = 0, sxx = 0, syy = 0, disagreement = 0, max_w = 0;
  const int slots = options_.smoothing_lag_steps > 0 ? options_.smoothing_lag_steps + 1 : 0;
  const int slot = slots > 0 ? history_steps_ % slots : 0;
  const double scale = weight_scale_;
  // A local copy of the stream keeps its state in registers (stores through the particle arrays
  // could alias a member); it is written back after the pass.
  RandomStream rng = rng_;
  // Pass 1, prediction (eq. 8-10): random moves and junction choices. Kept apart from the
  // weighting pass so that the accumulators there stay in registers (no calls in that loop).
  for (int i = 0; i < n; ++i) {
    double distance = mean_distance;
    if (estimate_bias) {
      if (jitter > 0) bias[i] += rng.Uniform(-jitter, jitter);
      distance -= bias[i] * dt_s;
    }
    if (a > 0) distance += two_a * rng.Uniform01() - a;
    const double u = along[i] + dir[i] * distance;
    if (u >= 0.0 && u <= length[seg[i]]) {
      along[i] = u;  // fast path: no junction
    } else {
      const double importance = Move(i, distance, heading_rad, rng);
      if (importance != 1.0) weight[i] *= importance;
    }
  }
  rng_ = rng;
  // Pass 2, update (eq. 11) with the sums for normalisation (eq. 12), ESS (eq. 14), estimate
  // (eq. 13), spread and disagreement.
  for (int i = 0; i < n; ++i) {
    const int si = seg[i];
    const int key = 2 * si + (dir[i] > 0);
    const double w = weight[i] * scale * factor[key];
    weight[i] = w;
    const double x = origin_x[si] + along[i] * unit_x[si];
    const double y = origin_y[si] + along[i] * unit_y[si];
    sum += w;
    sum_sq += w * w;
    sx += w * x;
    sy += w * y;
    sxx += w * x * x;
    syy += w * y * y;
    disagreement += w * disagree[key];
    max_w = std::max(max_w, w);
  }
  if (slots > 0) {
    for (int i = 0; i < n; ++i) {
      const int si = seg[i];
      const size_t base = (static_cast<size_t>(i) * static_cast<size_t>(slots) + static_cast<size_t>(slot)) * 2;
      history_[base] = origin_x[si] + along[i] * unit_x[si];
      history_[base + 1] = origin_y[si] + along[i] * unit_y[si];
    }
  }
  // The particle that had weight 1 before the step keeps at least e^{-2κ} >= e^{-600} (κ <= 300),
  // so the sum never underflows to zero and no weight becomes NaN.
  CheckArgument(sum > 0.0 && std::isfinite(sum), "heading_rad", "gives zero likelihood to every particle");
  est.ess = sum * sum / sum_sq;
  // log p(φ_k | φ_{1:k-1}) = log(Σ w_new / Σ w_old) + κ - log(2π I0(κ)); the old sum includes the
  // pending rescale.
  est.log_likelihood = std::log(sum / (weight_sum_ * scale)) + kappa - log_normaliser_;
  const double inv = 1.0 / sum;
  est.weighted_mean_m = Eigen::Vector2d(sx * inv, sy * inv);
  est.spread_m = std::sqrt(std::max(0.0, sxx * inv - sx * sx * inv * inv + syy * inv - sy * sy * inv * inv));
  disagreement *= inv;
  const Projection p = network_.Nearest(est.weighted_mean_m);
  est.position_m = p.point_m;
  est.segment = p.segment;
  est.tracking = est.spread_m < options_.tracking_spread_m;
  if (slots > 0) {
    ++history_steps_;
    if (history_steps_ >= slots) {
      const int oldest = history_steps_ % slots;  // the slot written `lag` steps ago
      double mx = 0, my = 0;
      for (int i = 0; i < n; ++i) {
        const size_t base = (static_cast<size_t>(i) * static_cast<size_t>(slots) + static_cast<size_t>(oldest)) * 2;
        mx += weights_[static_cast<size_t>(i)] * history_[base];
        my += weights_[static_cast<size_t>(i)] * history_[base + 1];
      }
      est.smoothed_m = network_.Nearest(Eigen::Vector2d(mx * inv, my * inv)).point_m;
    }
  }

  // Resampling (eq. 14) when N_eff < N_T, from the linear weights (core ResampleLinear).
  const ResamplingOptions& ro = options_.resampling;
  const bool resample = est.ess < ro.ess_threshold * n && est.ess < n * (1.0 - 1e-12);
  if (resample) {
    ResampleLinear(weights_.data(), n, sum, ro.scheme, rng_, &ancestors_);
    segment_tmp_.resize(static_cast<size_t>(n));
    direction_tmp_.resize(static_cast<size_t>(n));
    along_tmp_.resize(static_cast<size_t>(n));
    bias_tmp_.resize(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) {
      const size_t anc = static_cast<size_t>(ancestors_[static_cast<size_t>(i)]);
      segment_tmp_[static_cast<size_t>(i)] = segment_[anc];
      direction_tmp_[static_cast<size_t>(i)] = direction_[anc];
      along_tmp_[static_cast<size_t>(i)] = along_[anc];
      bias_tmp_[static_cast<size_t>(i)] = bias_[anc];
    }
    segment_.swap(segment_tmp_);
    direction_.swap(direction_tmp_);
    along_.swap(along_tmp_);
    bias_.swap(bias_tmp_);
    if (slots > 0) {
      std::vector<double> gathered(history_.size());
      const size_t row = static_cast<size_t>(slots) * 2;
      for (int i = 0; i < n; ++i) {
        std::copy_n(history_.begin() + static_cast<std::ptrdiff_t>(static_cast<size_t>(ancestors_[static_cast<size_t>(i)]) * row),
                    row, gathered.begin() + static_cast<std::ptrdiff_t>(static_cast<size_t>(i) * row));
      }
      history_.swap(gathered);
    }
    std::fill(weights_.begin(), weights_.end(), 1.0);
    weight_scale_ = 1.0;
    weight_sum_ = n;
    est.resampled = true;
    ++summary_.resamplings;
  } else {
    weight_scale_ = 1.0 / max_w;  // applied at the next update: keeps the largest weight at 1
    weight_sum_ = sum;
  }

  // Recovery ("switch back to the seeking phase"): only once the filter has tracked, when the
  // posterior's heading has disagreed with the compass for a whole window.
  if (est.tracking) was_tracking_ = true;
  if (options_.recovery_disagreement > 0.0) {
    const double slots = options_.recovery_window_s / dt_s;
    RequireSizeLimit(slots, sizeof(double), "dt_s", "recovery-window slots (recovery_window_s / dt_s)", 1e9);
    const size_t window = std::max<size_t>(1, static_cast<size_t>(std::lround(slots)));
    if (disagreement_window_.size() != window) {
      disagreement_window_.assign(window, 0.0);
      window_pos_ = 0;
      window_filled_ = 0;
    }
    disagreement_window_[window_pos_] = disagreement;
    window_pos_ = (window_pos_ + 1) % window;
    window_filled_ = std::min(window_filled_ + 1, window);
    const double mean = std::accumulate(disagreement_window_.begin(), disagreement_window_.end(), 0.0) /
                        static_cast<double>(window);
    if (was_tracking_ && window_filled_ == window && mean > options_.recovery_disagreement) {
      const int count = std::max(1, static_cast<int>(std::lround(options_.recovery_fraction * n)));
      Spread(n - count, count, rng_.Uniform01());
      std::fill(weights_.begin(), weights_.end(), 1.0);
      weight_scale_ = 1.0;
      weight_sum_ = n;
      was_tracking_ = false;
      window_filled_ = 0;
      est.recovered = true;
      ++summary_.recoveries;
    }
  }

  ++summary_.steps;
  summary_.total_log_likelihood += est.log_likelihood;
  summary_.mean_ess += (est.ess - summary_.mean_ess) / summary_.steps;
  summary_.seconds += timer.ElapsedSeconds();
  return est;
}

Eigen::VectorXd ParticleMapMatcher::SegmentPosterior() const {
  Eigen::VectorXd p = Eigen::VectorXd::Zero(network_.num_segments());
  for (int i = 0; i < options_.num_particles; ++i) p[segment_[static_cast<size_t>(i)]] += weights_[static_cast<size_t>(i)];
  return p / p.sum();
}

RowMatrixXd ParticleMapMatcher::ParticlePositions() const {
  RowMatrixXd out(options_.num_particles, 2);
  for (int i = 0; i < options_.num_particles; ++i) {
    out.row(i) = network_.point_at(segment_[static_cast<size_t>(i)], along_[static_cast<size_t>(i)]).transpose();
  }
  return out;
}

Eigen::VectorXd ParticleMapMatcher::ParticleWeights() const {
  const Eigen::Map<const Eigen::VectorXd> w(weights_.data(), static_cast<Eigen::Index>(weights_.size()));
  return w / w.sum();
}

std::vector<StepEstimate> RunFilter(ParticleMapMatcher& filter, const Eigen::Ref<const Eigen::VectorXd>& speed_mps,
                                    const Eigen::Ref<const Eigen::VectorXd>& heading_rad, double dt_s) {
  CheckArgument(speed_mps.size() == heading_rad.size(), "heading_rad",
                "must have as many samples as speed_mps");
  CheckFinite(speed_mps, "speed_mps");
  CheckFinite(heading_rad, "heading_rad");
  CheckArgument(std::isfinite(dt_s) && dt_s > 0.0, "dt_s", "must be finite and > 0");
  std::vector<StepEstimate> out;
  out.reserve(static_cast<size_t>(speed_mps.size()));
  for (Eigen::Index k = 0; k < speed_mps.size(); ++k) out.push_back(filter.Step(speed_mps[k], heading_rad[k], dt_s));
  return out;
}

}  // namespace indoorloc::mapmatch
