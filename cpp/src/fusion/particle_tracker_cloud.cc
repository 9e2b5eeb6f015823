// The particle tracker's cloud: storage (structure of arrays), the one-pass finish of an update
// (linear weights, log normaliser, ESS, resampling, estimate), the weighted estimate, the
// fixed-lag ring of past positions and the recorded history for the backward smoother.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>

#include "indoorloc/core/log_weights.h"
#include "indoorloc/core/validate.h"
#include "particle_tracker_impl.h"

namespace indoorloc::fusion {

namespace {
// A recorded cloud (record_history): states, floor and log-weight per particle.
constexpr double kNegInfinity = -std::numeric_limits<double>::infinity();
constexpr double kHistoryBytesPerParticle = 4 * sizeof(double) + sizeof(int) + sizeof(double);

void RequireHistoryMemory(double num_particles, double num_clouds, std::string_view name) {
  RequireSizeLimit(num_particles * num_clouds, kHistoryBytesPerParticle, name,
                   "recorded particles (num_particles x " + FormatValue(num_clouds) +
                       " recorded steps, record_history / the smoother)");
}
}  // namespace

void ParticleTracker::Impl::Resize(int count) {
  n = count;
  x.assign(n, 0.0);
  y.assign(n, 0.0);
  offset.assign(n, 0.0);
  cos_offset.assign(n, 1.0);
  sin_offset.assign(n, 0.0);
  scale.assign(n, 1.0);
  floor.assign(n, 0);
  if (corridor_mode()) {
    segment.assign(n, 0);
    direction.assign(n, 1);
    along.assign(n, 0.0);
  }
  log_w = Eigen::VectorXd::Constant(n, -std::log(static_cast<double>(n)));
  lag_ring.Reset(n, options.smoothing_lag_steps);
}

// Every state array (and the lag ring) takes the values of the particles' ancestors.
void ParticleTracker::Impl::Gather(const std::vector<int>& anc) {
  // Through one scratch array per type, swapped in: no allocation after the first resampling.
  auto gather = [&](auto& v, auto& scratch) {
    scratch.resize(v.size());
    for (int i = 0; i < n; ++i) scratch[i] = v[anc[i]];
    v.swap(scratch);
  };
  gather(x, gather_scratch);
  gather(y, gather_scratch);
  gather(offset, gather_scratch);
  gather(cos_offset, gather_scratch);
  gather(sin_offset, gather_scratch);
  gather(scale, gather_scratch);
  gather(floor, gather_scratch_int);
  if (corridor_mode()) {
    gather(segment, gather_scratch_int);
    std::vector<signed char> scratch;
    gather(direction, scratch);
    gather(along, gather_scratch);
  }
  lag_ring.Gather(anc);
}

// After an update of log_w that was normalised before it: one pass gives the linear weights
// (exp only where a weight is neither the largest nor zero), their sum (the log normaliser, the
// event's log-likelihood increment), the ESS and, in the same pass, the weighted sums of the
// estimate; resamples (from the linear weights) when ESS < threshold N, and then estimates from
// the resampled cloud. Leaves log_w normalised.
double ParticleTracker::Impl::FinishUpdate(double max_log_w, TrackerEstimate* est) {
  weights.resize(static_cast<size_t>(n));
  // exp(0) = 1 and exp(-inf) = 0 exactly: equal weights (after resampling, with walls only) and
  // dropped particles need no exp call. First pass without a branch (the dropped particles lie at
  // random in the cloud: a branch on them is mispredicted); the exp pass only if some weight
  // needs it (after a WiFi update or a fix every weight does: then its branch is predictable).
  double sum = 0.0, sum_sq = 0.0;
  bool need_exp = false;
  constexpr std::uint64_t kNegInfinityBits = 0xFFF0000000000000ULL;
  for (int i = 0; i < n; ++i) {
    // On the bits (integer compares give flags, not the two-flag FP compare that the compiler
    // turns into a branch): d is +-0 iff its bits without the sign are zero.
    const double d = log_w[i] - max_log_w;
    std::uint64_t bits;
    std::memcpy(&bits, &d, sizeof(bits));
    const bool zero = (bits << 1) == 0;
    const double w = static_cast<double>(zero);
    need_exp |= !zero & (bits != kNegInfinityBits);
    weights[i] = w;
    sum += w;
    sum_sq += w * w;
  }
  if (need_exp) {
    sum = 0.0;
    sum_sq = 0.0;
    for (int i = 0; i < n; ++i) {
      const double d = log_w[i] - max_log_w;
      if ((d != 0.0) & (d != kNegInfinity)) weights[i] = ExpOfLogDifference(d);
      sum += weights[i];
      sum_sq += weights[i] * weights[i];
    }
  }
  const CloudSums m = WeightedSums(weights.data());
  const double log_z = max_log_w + std::log(sum);
  est->ess = sum * sum / sum_sq;
  const double threshold = options.resampling.ess_threshold * n;
  est->resampled = options.resampling.ess_threshold > 0.0 && est->ess < threshold;
  ess_sum += est->ess;
  ++events;
  summary.mean_ess = ess_sum / events;
  if (est->resampled) {
    ResampleLinear(weights.data(), n, sum, options.resampling.scheme, rng, &ancestors);
    Gather(ancestors);
    log_w.setConstant(-std::log(static_cast<double>(n)));
    std::fill(weights.begin(), weights.end(), 1.0 / n);
    ++summary.resamplings;
    FillEstimate(weights, est);
    return log_z;
  }
  const double inv = 1.0 / sum;
  for (int i = 0; i < n; ++i) {
    log_w[i] -= log_z;
    weights[i] *= inv;
  }
  // The estimate from the sums (FillEstimate's quantities, normalised by the sum).
  const double ex = m.dx * inv, ey = m.dy * inv;
  est->mean_m = Eigen::Vector2d(m.rx + ex, m.ry + ey);
  const double vxx = m.dxx * inv - ex * ex, vxy = m.dxy * inv - ex * ey, vyy = m.dyy * inv - ey * ey;
  est->covariance_m2 << std::max(vxx, 0.0), vxy, vxy, std::max(vyy, 0.0);
  est->heading_offset_rad = std::atan2(m.sin * inv, m.cos * inv);
  est->scale = m.scale * inv;
  FillFloorsAndLag(weights, est);
  return log_z;
}

// The weighted sums of the estimate for linear weights w (not normalised): positions about the
// reference particle (x[0], y[0]) (one pass, without the cancellation of raw moments far from the
// origin), their products, sin and cos of the offset, the scale. Four interleaved partial sums
// per quantity (particle i into lane i mod 4, added in a fixed order at the end): independent
// chains that the compiler can keep in vector registers; the result depends on n only.
ParticleTracker::Impl::CloudSums ParticleTracker::Impl::WeightedSums(const double* w) const {
  constexpr int kLanes = 4;
  CloudSums out;
  out.rx = x[0];
  out.ry = y[0];
  double a[8][kLanes] = {};
  const int full = n - n % kLanes;
  auto add = [&](int lane, int i) {
    const double dx = x[i] - out.rx, dy = y[i] - out.ry;
    a[0][lane] += w[i] * dx;
    a[1][lane] += w[i] * dy;
    a[2][lane] += w[i] * dx * dx;
    a[3][lane] += w[i] * dx * dy;
    a[4][lane] += w[i] * dy * dy;
    a[5][lane] += w[i] * sin_offset[i];
    a[6][lane] += w[i] * cos_offset[i];
    a[7][lane] += w[i] * scale[i];
  };
  for (int i = 0; i < full; i += kLanes) {
    for (int lane = 0; lane < kLanes; ++lane) add(lane, i + lane);
  }
  for (int i = full; i < n; ++i) add(i - full, i);
  double total[8];
  for (int q = 0; q < 8; ++q) total[q] = (a[q][0] + a[q][1]) + (a[q][2] + a[q][3]);
  out.dx = total[0];
  out.dy = total[1];
  out.dxx = total[2];
  out.dxy = total[3];
  out.dyy = total[4];
  out.sin = total[5];
  out.cos = total[6];
  out.scale = total[7];
  return out;
}

// The floor probabilities, the most probable floor and the fixed-lag position from normalised
// linear weights w.
void ParticleTracker::Impl::FillFloorsAndLag(const std::vector<double>& w, TrackerEstimate* est) const {
  est->floor_probabilities = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(floors.size()));
  if (floors.size() == 1) {
    double total = 0.0;
    for (int i = 0; i < n; ++i) total += w[i];
    est->floor_probabilities[0] = total;
  } else {
    for (int i = 0; i < n; ++i) est->floor_probabilities[floor[i]] += w[i];
  }
  Eigen::Index best = 0;
  est->floor_probabilities.maxCoeff(&best);
  est->floor_index = static_cast<int>(best);
  if (lag_ring.has_lagged()) est->lagged_m = lag_ring.WeightedSum(w.data());
}

// The weighted estimate from normalised linear weights w: mean, covariance, circular mean
// offset, mean scale, floor probabilities and the fixed-lag position.
void ParticleTracker::Impl::FillEstimate(const std::vector<double>& w, TrackerEstimate* est) const {
  double mx = 0.0, my = 0.0, so = 0.0, co = 0.0, sc = 0.0;
  for (int i = 0; i < n; ++i) {
    mx += w[i] * x[i];
    my += w[i] * y[i];
    so += w[i] * sin_offset[i];
    co += w[i] * cos_offset[i];
    sc += w[i] * scale[i];
  }
  double cxx = 0.0, cxy = 0.0, cyy = 0.0;
  for (int i = 0; i < n; ++i) {
    const double dx = x[i] - mx, dy = y[i] - my;
    cxx += w[i] * dx * dx;
    cxy += w[i] * dx * dy;
    cyy += w[i] * dy * dy;
  }
  est->mean_m = Eigen::Vector2d(mx, my);
  est->covariance_m2 << cxx, cxy, cxy, cyy;
  est->heading_offset_rad = std::atan2(so, co);
  est->scale = sc;
  FillFloorsAndLag(w, est);
}

// Estimate from the current log-weights (outside an update).
void ParticleTracker::Impl::FillEstimate(TrackerEstimate* est) const {
  const Eigen::VectorXd w = NormalizedWeights(log_w);
  FillEstimate(std::vector<double>(w.data(), w.data() + w.size()), est);
}

// Fixed-lag ring: the positions after the current step.
void ParticleTracker::Impl::PushLag() {
  if (!lag_ring.enabled()) return;
  for (int i = 0; i < n; ++i) lag_ring.Record(i, x[i], y[i]);
  lag_ring.Advance();
}

// record_history: the cloud after a step (replace_last: after an observation following it).
void ParticleTracker::Impl::Snapshot(bool replace_last) {
  if (!options.record_history || summary.steps == 0) return;
  if (!(replace_last && !history.states.empty())) {
    RequireHistoryMemory(n, static_cast<double>(history.states.size() + 1), "options.record_history");
  }
  RowMatrixXd states(n, 4);
  Eigen::VectorXi fl(n);
  for (int i = 0; i < n; ++i) {
    states(i, 0) = x[i];
    states(i, 1) = y[i];
    states(i, 2) = offset[i];
    states(i, 3) = scale[i];
    fl[i] = floor[i];
  }
  Eigen::VectorXd lw = log_w;
  NormalizeLogWeights(lw);
  if (replace_last && !history.states.empty()) {
    history.states.back() = std::move(states);
    history.floor_indices.back() = std::move(fl);
    history.log_weights.back() = std::move(lw);
  } else {
    history.states.push_back(std::move(states));
    history.floor_indices.push_back(std::move(fl));
    history.log_weights.push_back(std::move(lw));
  }
}

}  // namespace indoorloc::fusion
