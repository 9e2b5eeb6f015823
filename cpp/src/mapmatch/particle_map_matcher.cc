#include "indoorloc/mapmatch/particle_map_matcher.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "indoorloc/core/check.h"
#include "indoorloc/core/log_weights.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "move_and_weigh.h"

namespace indoorloc::mapmatch {
namespace {

// The options validated before the motion model is built from them (so that an invalid field
// is reported by the filter's own validation).
// The distances of a step, v Δt - b Δt + η with η ~ U(-a, a) (eq. 8-9), the odometer bias b
// first taking its random-walk step when it is estimated; every draw from the random lanes.
void DrawDistances(const FilterOptions& options, double mean_distance, double dt_s, int n, RandomLanes& lanes,
                   double* bias, double* uniform, double* distance) {
  const double a = options.noise_halfwidth_m;
  const double two_a = 2.0 * a;
  const bool estimate_bias = options.estimate_speed_bias;
  const double jitter = options.bias_jitter_mps * std::sqrt(3.0);  // uniform with that sd
  if (estimate_bias && jitter > 0) {
    lanes.FillUniform01(uniform, n);
    for (int i = 0; i < n; ++i) bias[i] += -jitter + 2.0 * jitter * uniform[i];
  }
  if (a > 0 && !estimate_bias) {  // the common case: one pass, the distances written by the lanes
    lanes.FillCentred(distance, n, mean_distance, a);
    return;
  }
  if (a > 0) lanes.FillUniform01(uniform, n);
  for (int i = 0; i < n; ++i) {
    const double mean = estimate_bias ? mean_distance - bias[i] * dt_s : mean_distance;
    distance[i] = a > 0 ? mean + (two_a * uniform[i] - a) : mean;
  }
}

// Stream family of the per-particle uniform draws (the junction choices and resampling use
// stream 0, rng_).
constexpr std::uint64_t kNoiseLanesStream = 1;

CorridorMotionOptions ValidatedMotionOptions(const FilterOptions& options) {
  ValidateOptions(options);
  return options.corridor_motion();
}

}  // namespace

bool FilterOptions::IsValid(std::string* error) const {
  Validator v(error);
  v.AtLeast(num_particles, 1, "num_particles").IntInRange(num_particles, 1, 100000000, "num_particles");
  if (!v) return false;
  // kappa and junction_kappa: the corridor model's limits (κ <= 300 keeps every likelihood factor
  // e^{κ (d cos - 1)} >= e^{-600} representable in this filter's linear weights).
  if (!corridor_motion().IsValid(error)) return false;
  v.InRange(noise_halfwidth_m, 0.0, 1e6, "noise_halfwidth_m");
  if (!v) return false;
  std::string inner;
  if (!resampling.IsValid(&inner)) {
    if (error) *error = "resampling." + inner;
    return false;
  }
  return v.InRange(bias_halfwidth_mps, 0.0, 1e6, "bias_halfwidth_mps")
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
    : network_(network), options_(options), motion_(network, ValidatedMotionOptions(options)) {
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
    limit_[i] = network_.lengths_m()[s];
    direction_[i] = (k % 2 == 0) ? 1 : -1;
    bias_[i] = options_.estimate_speed_bias ? rng_.Uniform(-options_.bias_halfwidth_mps, options_.bias_halfwidth_mps) : 0.0;
  }
}

void ParticleMapMatcher::Reset() {
  const int n = options_.num_particles;
  rng_ = RandomStream(options_.seed);
  lanes_ = RandomLanes(options_.seed, kNoiseLanesStream);
  segment_.assign(static_cast<size_t>(n), 0);
  direction_.assign(static_cast<size_t>(n), 1);
  along_.assign(static_cast<size_t>(n), 0.0);
  limit_.assign(static_cast<size_t>(n), 0.0);
  bias_.assign(static_cast<size_t>(n), 0.0);
  Spread(0, n, 0.5);
  weights_.assign(static_cast<size_t>(n), 1.0);
  weight_scale_ = 1.0;
  weight_sum_ = n;
  factor_.assign(static_cast<size_t>(2 * network_.num_segments()), 1.0);
  disagree_.assign(static_cast<size_t>(2 * network_.num_segments()), 0.0);
  disagreement_window_.clear();
  window_pos_ = 0;
  window_filled_ = 0;
  lag_ring_.Reset(n, options_.smoothing_lag_steps);
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
  for (size_t i = 0; i < n; ++i) limit_[i] = network_.lengths_m()[segments[i]];
  std::fill(weights_.begin(), weights_.end(), 1.0);
  weight_scale_ = 1.0;
  weight_sum_ = static_cast<double>(n);
}

void ParticleMapMatcher::TakeAncestorsStates(int n) {
  segment_tmp_.resize(static_cast<size_t>(n));
  direction_tmp_.resize(static_cast<size_t>(n));
  along_tmp_.resize(static_cast<size_t>(n));
  limit_tmp_.resize(static_cast<size_t>(n));
  bias_tmp_.resize(static_cast<size_t>(n));
  {
    // Local restrict pointers: the stores into one vector's data must not force reloads of
    // the others' data pointers (they did: a third of this loop's time).
    const int* __restrict anc = ancestors_.data();
    const int* __restrict seg_in = segment_.data();
    const signed char* __restrict dir_in = direction_.data();
    const double* __restrict along_in = along_.data();
    const double* __restrict limit_in = limit_.data();
    int* __restrict seg_out = segment_tmp_.data();
    signed char* __restrict dir_out = direction_tmp_.data();
    double* __restrict along_out = along_tmp_.data();
    double* __restrict limit_out = limit_tmp_.data();
    for (int i = 0; i < n; ++i) {
      const int a = anc[i];
      seg_out[i] = seg_in[a];
      dir_out[i] = dir_in[a];
      along_out[i] = along_in[a];
      limit_out[i] = limit_in[a];
    }
  }
  segment_.swap(segment_tmp_);
  direction_.swap(direction_tmp_);
  along_.swap(along_tmp_);
  limit_.swap(limit_tmp_);
  if (options_.estimate_speed_bias) {  // otherwise every bias is 0
    for (int i = 0; i < n; ++i) bias_tmp_[static_cast<size_t>(i)] = bias_[static_cast<size_t>(ancestors_[static_cast<size_t>(i)])];
    bias_.swap(bias_tmp_);
  }
}

StepEstimate ParticleMapMatcher::Step(double speed_mps, double heading_rad, double dt_s) {
  CheckArgument(std::isfinite(speed_mps), "speed_mps", "is not finite");
  CheckArgument(std::isfinite(heading_rad), "heading_rad", "is not finite");
  RequireScale(dt_s, "dt_s");  // recovery_window_s / dt_s sizes a buffer: 1e-290 asked for 1e290 slots
  WallTimer timer;
  const int n = options_.num_particles;
  StepEstimate est;

  // Per-step tables over the 2M (segment, direction) pairs: the von Mises factor of eq. 11
  // relative to its maximum, exp(κ (d cos(φ - β_s) - 1)) in [e^{-2κ}, 1], and the
  // disagreement 1 - d cos(φ - β_s) used by the recovery rule.
  const double kappa = options_.kappa;
  motion_.HeadingTables(heading_rad, factor_.data(), disagree_.data());

  // Prediction (eq. 8-10), then the update (eq. 11) with the sums needed for the normalisation
  // (eq. 12), the ESS (eq. 14), the estimate (eq. 13), its spread and the disagreement. A
  // negative step v Δt + η moves a particle back within its segment (eq. 8-9 have no floor: a
  // floor at 0 biases the move forward by E[max(0, X)] - E[X], 5 % of the speed at 10 Hz with
  // a = 0.27 m); it stops at the end behind it.
  const double* origin_x = motion_.origin_x_m();
  const double* origin_y = motion_.origin_y_m();
  const double* unit_x = motion_.unit_x();
  const double* unit_y = motion_.unit_y();
  int* seg = segment_.data();
  signed char* dir = direction_.data();
  double* along = along_.data();
  // Pass 1: the distances of the prediction (eq. 8-9) from the random lanes (vectorised).
  uniform_.resize(static_cast<size_t>(n));
  distance_.resize(static_cast<size_t>(n));
  DrawDistances(options_, speed_mps * dt_s, dt_s, n, lanes_, bias_.data(), uniform_.data(), distance_.data());
  // Pass 2: the move (corridor model, junction choices in particle order) and the update
  // (eq. 11) with the sums, one fused pass (move_and_weigh.h).
  const bool recovery = options_.recovery_disagreement > 0.0;  // the only user of the disagreement
  const detail::WeightSums sums = detail::MoveAndWeigh(
      motion_, {n, distance_.data(), seg, dir, along, limit_.data(), weights_.data(), weight_scale_, factor_.data(),
                recovery ? disagree_.data() : nullptr, heading_rad},
      lanes_, rng_);
  const double sum = sums.sum, sum_sq = sums.sum_sq, sx = sums.sx, sy = sums.sy, sxx = sums.sxx, syy = sums.syy;
  double disagreement = sums.disagreement;
  const double max_w = sums.max_w;
  const double scale = weight_scale_;
  if (lag_ring_.enabled()) {
    for (int i = 0; i < n; ++i) {
      const int si = seg[i];
      lag_ring_.Record(i, origin_x[si] + along[i] * unit_x[si], origin_y[si] + along[i] * unit_y[si]);
    }
  }
  // The particle that had weight 1 before the step keeps at least e^{-2κ} >= e^{-600} (κ <= 300),
  // so the sum never underflows to zero and no weight becomes NaN.
  CheckArgument(sum > 0.0 && std::isfinite(sum), "heading_rad", "gives zero likelihood to every particle");
  est.ess = sum * sum / sum_sq;
  // log p(φ_k | φ_{1:k-1}) = log(Σ w_new / Σ w_old) + κ - log(2π I0(κ)); the old sum includes the
  // pending rescale.
  est.log_likelihood = std::log(sum / (weight_sum_ * scale)) + kappa - motion_.log_normaliser();
  const double inv = 1.0 / sum;
  est.weighted_mean_m = Eigen::Vector2d(sx * inv, sy * inv);
  est.spread_m = std::sqrt(std::max(0.0, sxx * inv - sx * sx * inv * inv + syy * inv - sy * sy * inv * inv));
  disagreement *= inv;
  const Projection p = network_.Nearest(est.weighted_mean_m);
  est.position_m = p.point_m;
  est.segment = p.segment;
  est.tracking = est.spread_m < options_.tracking_spread_m;
  if (lag_ring_.enabled()) {
    lag_ring_.Advance();
    if (lag_ring_.has_lagged()) est.smoothed_m = network_.Nearest(lag_ring_.WeightedSum(weights_.data()) * inv).point_m;
  }

  // Resampling (eq. 14) when N_eff < N_T, from the linear weights (core ResampleLinear).
  const ResamplingOptions& ro = options_.resampling;
  const bool resample = est.ess < ro.ess_threshold * n && est.ess < n * (1.0 - 1e-12);
  if (resample) {
    ResampleLinear(weights_.data(), n, sum, ro.scheme, rng_, &ancestors_);
    TakeAncestorsStates(n);
    lag_ring_.Gather(ancestors_);
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
