#include "indoorloc/mapmatch/particle_map_matcher.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include <immintrin.h>

#include "indoorloc/core/check.h"
#include "indoorloc/core/log_weights.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/simd_dispatch.h"
#include "indoorloc/core/validate.h"

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

// The sums of the update pass, for the normalisation, ESS, estimate, spread and disagreement.
struct WeightSums {
  double sum = 0, sum_sq = 0, sx = 0, sy = 0, sxx = 0, syy = 0, disagreement = 0, max_w = 0;
};

// Pass 2 of a step (eq. 11): w_i <- w_i · scale · factor[2 S_i + (d_i > 0)], and the weighted
// sums. Four interleaved accumulators (particle i into lane i mod 4, lanes added pairwise at the
// end) make the AVX2 version below a plain four-wide loop; the order is fixed, so both versions
// give the same sums to the bit.
constexpr int kSumLanes = 4;

struct LaneSums {
  double sum[kSumLanes] = {}, sum_sq[kSumLanes] = {}, sx[kSumLanes] = {}, sy[kSumLanes] = {}, sxx[kSumLanes] = {},
         syy[kSumLanes] = {}, dis[kSumLanes] = {}, max_w[kSumLanes] = {};
};

struct WeighInputs {
  int n;
  const int* seg;
  const signed char* dir;
  const double* along;
  double* weight;
  double scale;
  const double* factor;
  const double* disagree;  // null: no disagreement sum (recovery off)
  const double* origin_x;
  const double* origin_y;
  const double* unit_x;
  const double* unit_y;
  const double* geometry_rows;  // M x 4: origin x, origin y, unit x, unit y
};

// Particles [begin, n), particle i into lane i mod kSumLanes (portable version).
void WeighScalar(const WeighInputs& in, int begin, LaneSums* acc) {
  for (int i = begin; i < in.n; ++i) {
    const int j = i % kSumLanes;
    const int si = in.seg[i];
    const int key = 2 * si + (in.dir[i] > 0);
    const double w = in.weight[i] * in.scale * in.factor[key];
    in.weight[i] = w;
    const double x = in.origin_x[si] + in.along[i] * in.unit_x[si];
    const double y = in.origin_y[si] + in.along[i] * in.unit_y[si];
    acc->sum[j] += w;
    acc->sum_sq[j] += w * w;
    acc->sx[j] += w * x;
    acc->sy[j] += w * y;
    acc->sxx[j] += w * x * x;
    acc->syy[j] += w * y * y;
    if (in.disagree != nullptr) acc->dis[j] += w * in.disagree[key];
    acc->max_w[j] = acc->max_w[j] > w ? acc->max_w[j] : w;
  }
}

// Whole groups of four with AVX2 (table entries loaded per particle; the same operations in the same order
// as WeighScalar, no FMA). Returns the first particle not done.
// Four table entries t[i0..i3] by scalar loads: faster than vgatherdpd on the machines measured
// (docs/performance.md), and no uninitialised-source warning from GCC's gather intrinsic.
#define INDOORLOC_GATHER4(t, i0, i1, i2, i3) _mm256_set_pd((t)[i3], (t)[i2], (t)[i1], (t)[i0])

template <bool kDisagreement>
__attribute__((target("avx2"))) int WeighAvx2(const WeighInputs& in, LaneSums* acc) {
  // Locals (restrict) so that the weight stores do not force reloads of the inputs.
  const int n = in.n;
  const int* __restrict seg = in.seg;
  const signed char* __restrict dir = in.dir;
  const double* __restrict along_m = in.along;
  double* __restrict weight = in.weight;
  const double* __restrict factor = in.factor;
  const double* __restrict disagree = in.disagree;
  const double* __restrict geometry = in.geometry_rows;
  __m256d sum = _mm256_setzero_pd(), sum_sq = sum, sx = sum, sy = sum, sxx = sum, syy = sum, dis = sum, max_w = sum;
  const __m256d scale = _mm256_set1_pd(in.scale);
  int i = 0;
  for (; i + kSumLanes <= n; i += kSumLanes) {
    const int s0 = seg[i], s1 = seg[i + 1], s2 = seg[i + 2], s3 = seg[i + 3];
    const int k0 = 2 * s0 + (dir[i] > 0), k1 = 2 * s1 + (dir[i + 1] > 0), k2 = 2 * s2 + (dir[i + 2] > 0),
              k3 = 2 * s3 + (dir[i + 3] > 0);
    const __m256d w =
        _mm256_mul_pd(_mm256_mul_pd(_mm256_loadu_pd(weight + i), scale), INDOORLOC_GATHER4(factor, k0, k1, k2, k3));
    _mm256_storeu_pd(weight + i, w);
    const __m256d along = _mm256_loadu_pd(along_m + i);
    // The four particles' geometry rows, transposed: 4 vector loads and 8 shuffles instead of 16
    // scalar loads.
    const __m256d r0 = _mm256_loadu_pd(geometry + 4 * s0), r1 = _mm256_loadu_pd(geometry + 4 * s1);
    const __m256d r2 = _mm256_loadu_pd(geometry + 4 * s2), r3 = _mm256_loadu_pd(geometry + 4 * s3);
    const __m256d t0 = _mm256_unpacklo_pd(r0, r1), t1 = _mm256_unpackhi_pd(r0, r1);  // ox oy / ux uy of 0, 1
    const __m256d t2 = _mm256_unpacklo_pd(r2, r3), t3 = _mm256_unpackhi_pd(r2, r3);
    const __m256d origin_x = _mm256_permute2f128_pd(t0, t2, 0x20), unit_x = _mm256_permute2f128_pd(t0, t2, 0x31);
    const __m256d origin_y = _mm256_permute2f128_pd(t1, t3, 0x20), unit_y = _mm256_permute2f128_pd(t1, t3, 0x31);
    const __m256d x = _mm256_add_pd(origin_x, _mm256_mul_pd(along, unit_x));
    const __m256d y = _mm256_add_pd(origin_y, _mm256_mul_pd(along, unit_y));
    const __m256d wx = _mm256_mul_pd(w, x), wy = _mm256_mul_pd(w, y);
    sum = _mm256_add_pd(sum, w);
    sum_sq = _mm256_add_pd(sum_sq, _mm256_mul_pd(w, w));
    sx = _mm256_add_pd(sx, wx);
    sy = _mm256_add_pd(sy, wy);
    sxx = _mm256_add_pd(sxx, _mm256_mul_pd(wx, x));
    syy = _mm256_add_pd(syy, _mm256_mul_pd(wy, y));
    if (kDisagreement) dis = _mm256_add_pd(dis, _mm256_mul_pd(w, INDOORLOC_GATHER4(disagree, k0, k1, k2, k3)));
    max_w = _mm256_max_pd(max_w, w);  // max_w > w ? max_w : w, as the portable version
  }
  _mm256_storeu_pd(acc->sum, sum);
  _mm256_storeu_pd(acc->sum_sq, sum_sq);
  _mm256_storeu_pd(acc->sx, sx);
  _mm256_storeu_pd(acc->sy, sy);
  _mm256_storeu_pd(acc->sxx, sxx);
  _mm256_storeu_pd(acc->syy, syy);
  _mm256_storeu_pd(acc->dis, dis);
  _mm256_storeu_pd(acc->max_w, max_w);
  return i;
}
#undef INDOORLOC_GATHER4

WeightSums WeighAndSum(const WeighInputs& in) {
  LaneSums acc;
  int done = 0;
  if (UseAvx2()) done = in.disagree != nullptr ? WeighAvx2<true>(in, &acc) : WeighAvx2<false>(in, &acc);
  WeighScalar(in, done, &acc);
  auto reduce = [](const double* v) { return (v[0] + v[1]) + (v[2] + v[3]); };
  WeightSums out;
  out.sum = reduce(acc.sum);
  out.sum_sq = reduce(acc.sum_sq);
  out.sx = reduce(acc.sx);
  out.sy = reduce(acc.sy);
  out.sxx = reduce(acc.sxx);
  out.syy = reduce(acc.syy);
  out.disagreement = reduce(acc.dis);
  out.max_w = std::max(std::max(acc.max_w[0], acc.max_w[1]), std::max(acc.max_w[2], acc.max_w[3]));
  return out;
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
  std::fill(weights_.begin(), weights_.end(), 1.0);
  weight_scale_ = 1.0;
  weight_sum_ = static_cast<double>(n);
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
  // Pass 1, prediction (eq. 8-10): the distances from the random lanes (vectorised), then the
  // corridor model's batch move (in-segment moves vectorised, junction choices afterwards, in
  // particle order).
  uniform_.resize(static_cast<size_t>(n));
  distance_.resize(static_cast<size_t>(n));
  DrawDistances(options_, speed_mps * dt_s, dt_s, n, lanes_, bias_.data(), uniform_.data(), distance_.data());
  motion_.MoveAll(n, distance_.data(), seg, dir, along, heading_rad, lanes_, rng_, weights_.data(), &move_scratch_);
  // Pass 2, update (eq. 11) with the sums.
  const bool recovery = options_.recovery_disagreement > 0.0;  // the only user of the disagreement
  const WeightSums sums = WeighAndSum({n, seg, dir, along, weights_.data(), weight_scale_, factor_.data(),
                                       recovery ? disagree_.data() : nullptr, origin_x, origin_y, unit_x, unit_y,
                                       motion_.geometry_rows()});
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
    segment_tmp_.resize(static_cast<size_t>(n));
    direction_tmp_.resize(static_cast<size_t>(n));
    along_tmp_.resize(static_cast<size_t>(n));
    bias_tmp_.resize(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) {
      const size_t anc = static_cast<size_t>(ancestors_[static_cast<size_t>(i)]);
      segment_tmp_[static_cast<size_t>(i)] = segment_[anc];
      direction_tmp_[static_cast<size_t>(i)] = direction_[anc];
      along_tmp_[static_cast<size_t>(i)] = along_[anc];
    }
    segment_.swap(segment_tmp_);
    direction_.swap(direction_tmp_);
    along_.swap(along_tmp_);
    if (options_.estimate_speed_bias) {  // otherwise every bias is 0
      for (int i = 0; i < n; ++i) bias_tmp_[static_cast<size_t>(i)] = bias_[static_cast<size_t>(ancestors_[static_cast<size_t>(i)])];
      bias_.swap(bias_tmp_);
    }
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
