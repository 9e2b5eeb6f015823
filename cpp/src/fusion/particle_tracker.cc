#include "indoorloc/fusion/particle_tracker.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "indoorloc/core/check.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/core/log_weights.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/parallel.h"

namespace indoorloc::fusion {

namespace {
constexpr double kNegInf = -std::numeric_limits<double>::infinity();

double WrapAngle(double a) { return std::remainder(a, 2.0 * M_PI); }

// Systematic resampling stream ids of the tracker's own stream family: the per-event block
// streams use DeriveSeed(seed, event) instead, so the two never overlap.
constexpr std::uint64_t kTrackerStream = 0x7f3a5c11ULL;

// Memory of the particle state, checked before it is allocated: per particle six doubles of
// state, the floor, log-weight, linear weight, ancestor and the temporaries of an update and of
// resampling (96 B; corridor mode 16 B more), and the fixed-lag ring of (lag + 1) positions with
// its copy at resampling (32 B per slot).
void RequireParticleMemory(double num_particles, const TrackerOptions& options, bool corridor_mode,
                           std::string_view name) {
  const double lag = options.smoothing_lag_steps;
  const double per_particle = 96.0 + (corridor_mode ? 16.0 : 0.0) + (lag > 0 ? 32.0 * (lag + 1.0) : 0.0);
  RequireSizeLimit(num_particles, per_particle, name,
                   "particles (with smoothing_lag_steps = " + std::to_string(options.smoothing_lag_steps) + ")");
}

// A recorded cloud (record_history): states, floor and log-weight per particle.
constexpr double kHistoryBytesPerParticle = 4 * sizeof(double) + sizeof(int) + sizeof(double);

// Plan and particle coordinates are bounded like the floor plan's (+-1e7 m).
constexpr double kMaxCoordinate = 1e7;

void RequireHistoryMemory(double num_particles, double num_clouds, std::string_view name) {
  RequireSizeLimit(num_particles * num_clouds, kHistoryBytesPerParticle, name,
                   "recorded particles (num_particles x " + FormatValue(num_clouds) +
                       " recorded steps, record_history / the smoother)");
}
}  // namespace

bool TrackerOptions::IsValid(std::string* error) const {
  // Nested options are reported by the flattened names of the Python TrackerOptions (the motion,
  // WiFi and resampling fields keep their names; the fix fields carry a "fix_" prefix).
  auto nested = [&](bool ok, const std::string& prefix, const std::string& sub) {
    if (!ok && error) *error = prefix + sub;
    return ok;
  };
  Validator v(error);
  v.IntInRange(num_particles, 1, 50000000, "num_particles");
  if (!v) return false;
  std::string sub;
  if (!nested(motion.IsValid(&sub), "", sub)) return false;
  if (!nested(wifi.IsValid(&sub), "", sub)) return false;
  if (!nested(fix.IsValid(&sub), "fix_", sub)) return false;
  if (!nested(resampling.IsValid(&sub), "", sub)) return false;
  const double inf = std::numeric_limits<double>::infinity();
  return v
      .Check(wall_log_penalty <= 0.0, "wall_log_penalty",
             "must be <= 0 (-inf drops the particle), got " + FormatValue(wall_log_penalty))
      .IntInRange(respread_after_blocked_steps, 1, 1000000, "respread_after_blocked_steps")
      .Scale(respread_sd_m, "respread_sd_m")
      .ZeroOrScale(start_position_sd_m, "start_position_sd_m")
      .InRange(start_heading_offset_sd_rad, 0.0, 1e3, "start_heading_offset_sd_rad")
      .InRange(start_scale_sd, 0.0, 100.0, "start_scale_sd")
      .Check(unknown_start_heading_sd_rad >= 0.0 && (unknown_start_heading_sd_rad <= 1e3 ||
                                                     unknown_start_heading_sd_rad == inf),
             "unknown_start_heading_sd_rad",
             "must be in [0, 1000] or +inf (uniform on the circle), got " + FormatValue(unknown_start_heading_sd_rad))
      .InRange(candidate_spacing_m, 0.05, 1000.0, "candidate_spacing_m")
      .InRange(recovery_log_ratio, -1e6, 1e6, "recovery_log_ratio")
      .IntInRange(recovery_scans, 1, 1000000, "recovery_scans")
      .Check(recovery_fraction > 0.0 && recovery_fraction <= 1.0, "recovery_fraction",
             "must be in (0, 1], got " + FormatValue(recovery_fraction))
      .InRange(floor_change_probability, 0.0, 1.0, "floor_change_probability")
      .InRange(corridor_kappa, 0.0, 500.0, "corridor_kappa")
      .IntInRange(smoothing_lag_steps, 0, 10000, "smoothing_lag_steps")
      .IntInRange(num_threads, 0, 1024, "num_threads");
}

std::string TrackerSummary::BriefReport() const {
  std::ostringstream out;
  out << steps << " steps, " << wifi_updates << " WiFi updates (" << empty_wifi_updates << " empty), " << fix_updates
      << " fixes, " << resamplings
      << " resamplings, " << recoveries << " recoveries, " << all_blocked_steps << " all-blocked steps, " << respreads
      << " re-spreads, mean ESS " << std::round(mean_ess * 10.0) / 10.0 << ", log-lik " << total_log_likelihood
      << ", " << seconds << " s";
  return out.str();
}

struct ParticleTracker::Impl {
  const FloorPlan* plan = nullptr;
  const wifi::RssModel* model = nullptr;
  const mapmatch::RoadNetwork* corridors = nullptr;
  TrackerOptions options;
  std::unique_ptr<WifiLikelihood> wifi;

  std::vector<int> floors;            // tracker floor numbers
  std::vector<int> plan_floor;        // tracker floor index -> plan floor index (or -1)
  std::vector<int> model_floor;       // tracker floor index -> model floor index (or -1)
  std::vector<RowMatrixXd> candidates;  // per tracker floor: candidate points (unknown start, recovery)
  std::vector<double> floor_area;       // per tracker floor: walkable area [m²]
  double total_area = 0.0;              // over all floors: the outlier density of a fix is ε / total_area

  int n = 0;
  std::vector<double> x, y, offset, scale;
  std::vector<double> cos_offset, sin_offset;  // of `offset`, kept for the estimates (no trig there)
  std::vector<double> weights;                 // normalised linear weights of the last update
  std::vector<int> floor;
  std::vector<int> segment;
  std::vector<signed char> direction;
  std::vector<double> along;
  Eigen::VectorXd log_w;
  std::vector<double> lag_ring;  // n x (L + 1) x 2
  int lag_len = 0;

  RandomStream rng;
  std::uint64_t event = 0;
  bool initialized = false;
  bool awaiting_first_fix = false;
  double last_time = -std::numeric_limits<double>::infinity();
  int consecutive_blocked = 0;
  int consecutive_disagreement = 0;
  double ess_sum = 0.0;
  int events = 0;
  ParticleHistory history;
  TrackerSummary summary;
  std::vector<int> ancestors;

  bool corridor_mode() const { return corridors != nullptr; }

  // Every event (step, WiFi observation, fix) at or after the previous one (or the start).
  void CheckTime(double time_s, const char* name) const {
    if (time_s < last_time) {
      ThrowInvalidArgument(name, FormatValue(time_s) + " s is before the previous event or the start (" +
                                     FormatValue(last_time) + " s): negative time step (events must not go back in time)");
    }
  }

  // Runs fn(begin, end, rng) over fixed particle blocks; the stream of block b depends only on
  // (seed, event, b), never on the thread count.
  template <typename Fn>
  void ForBlocks(int count, const Fn& fn) {
    const int blocks = (count + kBlockSize - 1) / kBlockSize;
    const std::uint64_t seed = DeriveSeed(options.seed, ++event);
    ParallelForRuns(blocks, options.num_threads, seed, [&](int b, RandomStream& block_rng) {
      const int begin = b * kBlockSize;
      const int end = std::min(count, begin + kBlockSize);
      fn(b, begin, end, block_rng);
    });
  }

  void Resize(int count) {
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
    lag_len = options.smoothing_lag_steps;
    lag_ring.assign(lag_len > 0 ? static_cast<size_t>(n) * (lag_len + 1) * 2 : 0, std::numeric_limits<double>::quiet_NaN());
  }

  bool Walkable(double px, double py, int f) const {
    if (!plan) return true;
    return plan->IsWalkable(px, py, plan_floor[f]);
  }
  bool Blocked(double x0, double y0, double x1, double y1, int f) const {
    if (!plan) return false;
    return plan->CrossesWall(x0, y0, x1, y1, plan_floor[f]);
  }

  void BuildCandidates() {
    const double h = options.candidate_spacing_m;
    candidates.assign(floors.size(), RowMatrixXd());
    for (size_t f = 0; f < floors.size(); ++f) {
      std::vector<double> pts;
      if (plan) {
        const Eigen::Vector4d b = plan->Bounds(plan_floor[f]);
        const int nx = static_cast<int>(std::floor((b[2] - b[0]) / h)) + 1;
        const int ny = static_cast<int>(std::floor((b[3] - b[1]) / h)) + 1;
        CheckArgument(static_cast<double>(nx) * ny <= 2e7, "options.candidate_spacing_m",
                      "gives more than 2e7 candidate points on floor " + std::to_string(floors[f]) + ": use a larger spacing");
        for (int j = 0; j < ny; ++j) {
          for (int i = 0; i < nx; ++i) {
            const double px = b[0] + (i + 0.5) * h, py = b[1] + (j + 0.5) * h;
            if (px <= b[2] && py <= b[3] && plan->IsWalkable(px, py, plan_floor[f])) {
              pts.push_back(px);
              pts.push_back(py);
            }
          }
        }
      } else if (model) {
        const int mf = model_floor[f];
        for (int row : model->points_on_floor(mf)) {
          pts.push_back(model->map().positions_m()(row, 0));
          pts.push_back(model->map().positions_m()(row, 1));
        }
      }
      candidates[f] = Eigen::Map<RowMatrixXd>(pts.data(), static_cast<Eigen::Index>(pts.size() / 2), 2);
    }
  }

  // Log-likelihood point_ll(x, y, tracker floor) at every candidate of every floor (concatenated).
  template <typename PointLL>
  Eigen::VectorXd CandidateLogLikelihoods(const PointLL& point_ll, std::vector<int>* candidate_floor,
                                          std::vector<int>* candidate_row) {
    int total = 0;
    for (const auto& c : candidates) total += static_cast<int>(c.rows());
    candidate_floor->resize(total);
    candidate_row->resize(total);
    int k = 0;
    for (size_t f = 0; f < candidates.size(); ++f) {
      for (Eigen::Index r = 0; r < candidates[f].rows(); ++r, ++k) {
        (*candidate_floor)[k] = static_cast<int>(f);
        (*candidate_row)[k] = static_cast<int>(r);
      }
    }
    Eigen::VectorXd ll(total);
    ForBlocks(total, [&](int, int begin, int end, RandomStream&) {
      for (int i = begin; i < end; ++i) {
        const int f = (*candidate_floor)[i];
        ll[i] = point_ll(candidates[f]((*candidate_row)[i], 0), candidates[f]((*candidate_row)[i], 1), f);
      }
    });
    return ll;
  }

  // Replaces the particles in `slots` by draws from the candidates' likelihood point_ll (with
  // uniform jitter within a candidate cell, kept walkable), heading offsets as UnknownOffset.
  template <typename PointLL>
  void DrawFromCandidates(const PointLL& point_ll, const std::vector<int>& slots) {
    std::vector<int> cf, cr;
    const Eigen::VectorXd ll = CandidateLogLikelihoods(point_ll, &cf, &cr);
    if (ll.size() == 0) ThrowInvalidArgument("plan", "has no candidate point (walkable area smaller than the candidate grid)");
    std::vector<int> picks;
    Resample(ll, ResamplingScheme::kSystematic, rng, &picks, static_cast<int>(slots.size()));
    const double h = options.candidate_spacing_m;
    for (size_t j = 0; j < slots.size(); ++j) {
      const int c = picks[j];
      const int f = cf[c];
      const double cx = candidates[f](cr[c], 0), cy = candidates[f](cr[c], 1);
      double px = cx, py = cy;
      if (plan) {
        for (int attempt = 0; attempt < 20; ++attempt) {
          const double qx = cx + rng.Uniform(-0.5 * h, 0.5 * h), qy = cy + rng.Uniform(-0.5 * h, 0.5 * h);
          if (plan->IsWalkable(qx, qy, plan_floor[f])) {
            px = qx;
            py = qy;
            break;
          }
        }
      } else {
        px += rng.Uniform(-0.5 * h, 0.5 * h);
        py += rng.Uniform(-0.5 * h, 0.5 * h);
      }
      PlaceFree(slots[j], px, py, f, UnknownOffset());
    }
  }

  // One absolute observation (WiFi scan or position fix) given by its log-likelihood point_ll(x,
  // y, tracker floor): places the cloud of an unknown start that is still waiting for one, else
  // weights the particles, resamples, and runs the recovery test. `informative`: the observation
  // says something about the position (a scan with heard readings, a fix with components).
  template <typename PointLL>
  TrackerEstimate Observe(double time_s, bool informative, const PointLL& point_ll) {
    TrackerEstimate est;
    est.time_s = time_s;
    if (awaiting_first_fix && informative) {
      // Unknown start: the first informative observation places the cloud (the seeking phase).
      std::vector<int> all(static_cast<size_t>(n));
      for (int i = 0; i < n; ++i) all[i] = i;
      DrawFromCandidates(point_ll, all);
      log_w.setConstant(-std::log(static_cast<double>(n)));
      awaiting_first_fix = false;
      est.recovered = true;
      FillEstimate(&est);
      est.ess = n;
      Snapshot(true);
      return est;
    }
    Eigen::VectorXd ll(n);
    ForBlocks(n, [&](int, int begin, int end, RandomStream&) {
      for (int i = begin; i < end; ++i) ll[i] = point_ll(x[i], y[i], floor[i]);
    });
    log_w += ll;
    // log p(observation | past), tempered (log_w was normalised before the update).
    const double predictive = FinishUpdate(log_w.maxCoeff(), &est);
    est.log_likelihood = predictive;
    summary.total_log_likelihood += predictive;

    // Recovery: the observation fits the best candidate far better than the cloud, several in a row.
    if (options.recovery_log_ratio > 0.0 && informative) {
      std::vector<int> cf, cr;
      const Eigen::VectorXd cll = CandidateLogLikelihoods(point_ll, &cf, &cr);
      const double best = cll.size() > 0 ? cll.maxCoeff() : kNegInf;
      if (predictive < best - options.recovery_log_ratio) {
        ++consecutive_disagreement;
      } else {
        consecutive_disagreement = 0;
      }
      if (consecutive_disagreement >= options.recovery_scans) {
        if (!est.resampled) {  // equal weights first, so that replacing a subset is unbiased
          Resample(log_w, options.resampling.scheme, rng, &ancestors);
          Gather(ancestors);
          log_w.setConstant(-std::log(static_cast<double>(n)));
        }
        const int every = std::max(1, static_cast<int>(std::lround(1.0 / options.recovery_fraction)));
        std::vector<int> slots;
        for (int i = 0; i < n; i += every) slots.push_back(i);
        DrawFromCandidates(point_ll, slots);
        consecutive_disagreement = 0;
        est.recovered = true;
        ++summary.recoveries;
        FillEstimate(&est);
      }
    }
    Snapshot(true);
    return est;
  }

  // The WiFi likelihood as a point function of tracker floors.
  auto WifiPointLL(const WifiObservation& obs) const {
    return [this, &obs](double px, double py, int f) { return wifi->LogLikelihood(px, py, model_floor[f], obs); };
  }

  // Heading offset of a particle placed without a known start.
  double UnknownOffset() {
    const double sd = options.unknown_start_heading_sd_rad;
    return std::isinf(sd) ? rng.Uniform(-M_PI, M_PI) : sd * rng.Normal();
  }

  // Sets particle i at (px, py) on tracker floor f with offset o and a scale from the prior.
  void PlaceFree(int i, double px, double py, int f, double o) {
    x[i] = px;
    y[i] = py;
    floor[i] = f;
    offset[i] = WrapAngle(o);
    cos_offset[i] = std::cos(offset[i]);
    sin_offset[i] = std::sin(offset[i]);
    scale[i] = std::clamp(1.0 + options.start_scale_sd * rng.Normal(), options.motion.min_scale, options.motion.max_scale);
    if (corridor_mode()) {
      const mapmatch::Projection p = corridors->Nearest(Eigen::Vector2d(px, py));
      segment[i] = p.segment;
      along[i] = p.along_m;
      direction[i] = rng.Uniform01() < 0.5 ? 1 : -1;
      const Eigen::Vector2d q = corridors->point_at(segment[i], along[i]);
      x[i] = q.x();
      y[i] = q.y();
    }
  }

  void UniformCloud() {
    // Floor chosen in proportion to the walkable area (or candidate count without a plan).
    std::vector<double> mass(floors.size());
    for (size_t f = 0; f < floors.size(); ++f) {
      mass[f] = plan ? plan->WalkableArea(plan_floor[f]) : static_cast<double>(candidates[f].rows());
    }
    double total = 0.0;
    for (double m : mass) total += m;
    CheckArgument(total > 0.0, "plan", "no walkable area or candidate point to start from");
    for (int i = 0; i < n; ++i) {
      double u = rng.Uniform01() * total;
      size_t f = 0;
      while (f + 1 < mass.size() && u >= mass[f]) u -= mass[f++];
      double px, py;
      if (corridor_mode()) {
        // Uniform along the network.
        double s = rng.Uniform01() * corridors->total_length_m();
        int seg = 0;
        while (seg + 1 < corridors->num_segments() && s >= corridors->lengths_m()[seg]) s -= corridors->lengths_m()[seg++];
        const Eigen::Vector2d q = corridors->point_at(seg, s);
        px = q.x();
        py = q.y();
      } else if (plan) {
        const RowMatrixXd p = plan->SampleWalkable(1, plan_floor[f], rng);
        px = p(0, 0);
        py = p(0, 1);
      } else {
        const int r = static_cast<int>(rng.UniformInt(static_cast<std::uint64_t>(candidates[f].rows())));
        px = candidates[f](r, 0) + rng.Uniform(-0.5, 0.5) * options.candidate_spacing_m;
        py = candidates[f](r, 1) + rng.Uniform(-0.5, 0.5) * options.candidate_spacing_m;
      }
      PlaceFree(i, px, py, static_cast<int>(f), UnknownOffset());
    }
    log_w.setConstant(-std::log(static_cast<double>(n)));
  }

  void Gather(const std::vector<int>& anc) {
    auto gather = [&](auto& v) {
      auto tmp = v;
      for (int i = 0; i < n; ++i) v[i] = tmp[anc[i]];
    };
    gather(x);
    gather(y);
    gather(offset);
    gather(cos_offset);
    gather(sin_offset);
    gather(scale);
    gather(floor);
    if (corridor_mode()) {
      gather(segment);
      gather(direction);
      gather(along);
    }
    if (lag_len > 0) {
      const size_t stride = static_cast<size_t>(lag_len + 1) * 2;
      std::vector<double> tmp = lag_ring;
      for (int i = 0; i < n; ++i) {
        std::copy_n(tmp.begin() + static_cast<std::ptrdiff_t>(anc[i] * stride), stride,
                    lag_ring.begin() + static_cast<std::ptrdiff_t>(i * stride));
      }
    }
  }

  // After an update of log_w that was normalised before it: one pass of exp() gives the linear
  // weights, the log normaliser (the event's log-likelihood increment), the ESS and the estimate;
  // resamples (from the linear weights) when ESS < threshold N. Leaves log_w normalised.
  double FinishUpdate(double max_log_w, TrackerEstimate* est) {
    weights.resize(static_cast<size_t>(n));
    double sum = 0.0, sum_sq = 0.0;
    for (int i = 0; i < n; ++i) {
      const double w = std::exp(log_w[i] - max_log_w);
      weights[i] = w;
      sum += w;
      sum_sq += w * w;
    }
    const double log_z = max_log_w + std::log(sum);
    est->ess = sum * sum / sum_sq;
    const double threshold = options.resampling.ess_threshold * n;
    est->resampled = options.resampling.ess_threshold > 0.0 && est->ess < threshold;
    if (est->resampled) {
      ResampleLinear(weights.data(), n, sum, options.resampling.scheme, rng, &ancestors);
      Gather(ancestors);
      log_w.setConstant(-std::log(static_cast<double>(n)));
      std::fill(weights.begin(), weights.end(), 1.0 / n);
      ++summary.resamplings;
    } else {
      log_w.array() -= log_z;
      const double inv = 1.0 / sum;
      for (double& w : weights) w *= inv;
    }
    ess_sum += est->ess;
    ++events;
    summary.mean_ess = ess_sum / events;
    FillEstimate(weights, est);
    return log_z;
  }

  void FillEstimate(const std::vector<double>& w, TrackerEstimate* est) const {
    double mx = 0.0, my = 0.0, so = 0.0, co = 0.0, sc = 0.0;
    est->floor_probabilities = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(floors.size()));
    for (int i = 0; i < n; ++i) {
      mx += w[i] * x[i];
      my += w[i] * y[i];
      so += w[i] * sin_offset[i];
      co += w[i] * cos_offset[i];
      sc += w[i] * scale[i];
      est->floor_probabilities[floor[i]] += w[i];
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
    Eigen::Index best = 0;
    est->floor_probabilities.maxCoeff(&best);
    est->floor_index = static_cast<int>(best);
    if (lag_len > 0 && summary.steps > lag_len) {
      const int slot = (summary.steps - 1 - lag_len) % (lag_len + 1);
      const size_t stride = static_cast<size_t>(lag_len + 1) * 2;
      Eigen::Vector2d lagged = Eigen::Vector2d::Zero();
      for (int i = 0; i < n; ++i) {
        const double* p = &lag_ring[i * stride + static_cast<size_t>(slot) * 2];
        lagged += w[i] * Eigen::Vector2d(p[0], p[1]);
      }
      est->lagged_m = lagged;
    }
  }

  // Estimate from the current log-weights (outside an update).
  void FillEstimate(TrackerEstimate* est) const {
    const Eigen::VectorXd w = NormalizedWeights(log_w);
    FillEstimate(std::vector<double>(w.data(), w.data() + w.size()), est);
  }

  void PushLag() {
    if (lag_len <= 0) return;
    const int slot = (summary.steps - 1) % (lag_len + 1);
    const size_t stride = static_cast<size_t>(lag_len + 1) * 2;
    for (int i = 0; i < n; ++i) {
      lag_ring[i * stride + static_cast<size_t>(slot) * 2] = x[i];
      lag_ring[i * stride + static_cast<size_t>(slot) * 2 + 1] = y[i];
    }
  }

  void Snapshot(bool replace_last) {
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

  void Respread() {
    TrackerEstimate est;
    FillEstimate(&est);
    const int f = est.floor_index;
    for (int i = 0; i < n; ++i) {
      double px = est.mean_m.x(), py = est.mean_m.y();
      for (int attempt = 0; attempt < 50; ++attempt) {
        const double qx = est.mean_m.x() + options.respread_sd_m * rng.Normal();
        const double qy = est.mean_m.y() + options.respread_sd_m * rng.Normal();
        if (Walkable(qx, qy, f)) {
          px = qx;
          py = qy;
          break;
        }
      }
      int pf = f;
      if (!Walkable(px, py, f)) {  // the mean itself is inside an obstacle: keep the particle
        px = x[i];
        py = y[i];
        pf = floor[i];
      }
      const double o = offset[i];
      const double s = scale[i];
      PlaceFree(i, px, py, pf, o);
      scale[i] = s;
    }
    log_w.setConstant(-std::log(static_cast<double>(n)));
    ++summary.respreads;
  }
};

ParticleTracker::ParticleTracker(const FloorPlan* plan, const wifi::RssModel* wifi_model,
                                 const mapmatch::RoadNetwork* corridors, const TrackerOptions& options)
    : impl_(std::make_unique<Impl>()) {
  ValidateOptions(options, "options");
  Impl& s = *impl_;
  s.plan = plan;
  s.model = wifi_model;
  s.corridors = corridors;
  s.options = options;
  s.rng = RandomStream(options.seed, kTrackerStream);
  if (plan) {
    s.floors = plan->floors();
  } else if (wifi_model) {
    s.floors = wifi_model->floors();
  } else {
    s.floors = {0};
  }
  s.plan_floor.assign(s.floors.size(), -1);
  s.model_floor.assign(s.floors.size(), -1);
  for (size_t f = 0; f < s.floors.size(); ++f) {
    if (plan) s.plan_floor[f] = static_cast<int>(f);
    if (wifi_model) {
      const auto& mf = wifi_model->floors();
      const auto it = std::find(mf.begin(), mf.end(), s.floors[f]);
      if (it == mf.end()) {
        ThrowInvalidArgument("wifi_model", "the signal map has no reference point on floor " + std::to_string(s.floors[f]) +
                                               " of the floor plan (the map's floors must be the plan's floors)");
      }
      s.model_floor[f] = static_cast<int>(it - mf.begin());
    }
  }
  if (plan && wifi_model) {
    for (int mf : wifi_model->floors()) {
      if (std::find(s.floors.begin(), s.floors.end(), mf) == s.floors.end()) {
        ThrowInvalidArgument("wifi_model", "the signal map has floor " + std::to_string(mf) +
                                               ", which the floor plan does not have");
      }
    }
  }
  if (corridors) {
    CheckArgument(s.floors.size() == 1, "corridors", "corridor mode supports one floor only (the plan or map has " +
                                                         std::to_string(s.floors.size()) + ")");
    CheckArgument(corridors->num_segments() > 0 && corridors->total_length_m() > 0.0, "corridors", "is empty");
  }
  if (wifi_model) s.wifi = std::make_unique<WifiLikelihood>(*wifi_model, options.wifi);
  if (plan || wifi_model) s.BuildCandidates();
  s.floor_area.assign(s.floors.size(), 1e4);
  for (size_t f = 0; f < s.floors.size(); ++f) {
    if (plan) {
      s.floor_area[f] = plan->WalkableArea(s.plan_floor[f]);
    } else if (wifi_model && s.candidates[f].rows() > 0) {
      s.floor_area[f] = static_cast<double>(s.candidates[f].rows()) * options.candidate_spacing_m * options.candidate_spacing_m;
    }
  }
  for (double a : s.floor_area) s.total_area += a;
  RequireParticleMemory(options.num_particles, options, corridors != nullptr, "options");
  s.Resize(options.num_particles);
}

ParticleTracker::~ParticleTracker() = default;
ParticleTracker::ParticleTracker(ParticleTracker&&) noexcept = default;
ParticleTracker& ParticleTracker::operator=(ParticleTracker&&) noexcept = default;

const std::vector<int>& ParticleTracker::floors() const { return impl_->floors; }
bool ParticleTracker::initialized() const { return impl_->initialized; }
const ParticleHistory& ParticleTracker::history() const { return impl_->history; }
const TrackerSummary& ParticleTracker::summary() const { return impl_->summary; }
const TrackerOptions& ParticleTracker::options() const { return impl_->options; }

void ParticleTracker::InitializeKnown(double time_s, const Eigen::Vector2d& position_m, int floor_number,
                                      double heading_offset_rad) {
  Impl& s = *impl_;
  CheckArgument(std::isfinite(time_s), "time_s", "must be finite");
  CheckFinite(position_m, "position_m");
  CheckArgument(std::isfinite(heading_offset_rad), "heading_offset_rad", "must be finite");
  const auto it = std::find(s.floors.begin(), s.floors.end(), floor_number);
  if (it == s.floors.end()) ThrowInvalidArgument("floor", "the tracker has no floor " + std::to_string(floor_number));
  const int f = static_cast<int>(it - s.floors.begin());
  // With soft walls (a finite wall_log_penalty) obstacles are only unlikely, not forbidden: a start
  // inside one (a shop without a door in the plan) is accepted and the prior is not truncated.
  const bool hard_walls = std::isinf(s.options.wall_log_penalty);
  if (hard_walls && !s.Walkable(position_m.x(), position_m.y(), f)) {
    ThrowInvalidArgument("position_m", "(" + std::to_string(position_m.x()) + ", " + std::to_string(position_m.y()) +
                                           ") is not walkable on floor " + std::to_string(floor_number) +
                                           " (outside the outline or inside an obstacle)");
  }
  const TrackerOptions& o = s.options;
  for (int i = 0; i < s.n; ++i) {
    double px = position_m.x(), py = position_m.y();
    for (int attempt = 0; attempt < 50 && o.start_position_sd_m > 0.0; ++attempt) {
      const double qx = position_m.x() + o.start_position_sd_m * s.rng.Normal();
      const double qy = position_m.y() + o.start_position_sd_m * s.rng.Normal();
      // Behind a wall from the known start is not a possible start.
      if (!hard_walls || (s.Walkable(qx, qy, f) && !s.Blocked(position_m.x(), position_m.y(), qx, qy, f))) {
        px = qx;
        py = qy;
        break;
      }
    }
    s.PlaceFree(i, px, py, f, heading_offset_rad + o.start_heading_offset_sd_rad * s.rng.Normal());
  }
  s.log_w.setConstant(-std::log(static_cast<double>(s.n)));
  s.initialized = true;
  s.awaiting_first_fix = false;
  s.last_time = time_s;
}

void ParticleTracker::InitializeUnknown(const WifiObservation& observation) {
  Impl& s = *impl_;
  CheckArgument(s.plan || s.model || s.corridors, "plan", "an unknown start needs a floor plan, a signal map or corridors");
  if (s.model) s.wifi->CheckObservation(observation, "observation");
  if (observation.empty() || !s.model) {
    s.UniformCloud();
    // The first scan with readings, or the first fix, places the cloud.
    s.awaiting_first_fix = true;
  } else {
    std::vector<int> all(static_cast<size_t>(s.n));
    for (int i = 0; i < s.n; ++i) all[i] = i;
    s.DrawFromCandidates(s.WifiPointLL(observation), all);
    s.log_w.setConstant(-std::log(static_cast<double>(s.n)));
    s.awaiting_first_fix = false;
  }
  s.initialized = true;
  s.last_time = observation.time_s;
}

TrackerEstimate ParticleTracker::Step(const StepInput& step) {
  Impl& s = *impl_;
  WallTimer timer;
  CheckArgument(s.initialized, "step", "the tracker is not initialised (InitializeKnown or InitializeUnknown first)");
  CheckStepInput(step, "step");
  s.CheckTime(step.time_s, "step.time_s");
  s.last_time = step.time_s;
  const StepMotion motion(step, s.options.motion);
  const Eigen::VectorXd old_log_w = s.log_w;  // normalised (the invariant between events)
  const double penalty = s.options.wall_log_penalty;
  const int num_floors = static_cast<int>(s.floors.size());
  const double p_change = num_floors > 1 ? s.options.floor_change_probability : 0.0;
  const double kappa = s.options.corridor_kappa;
  const double log_vm_norm = s.corridor_mode() ? std::log(2.0 * M_PI * std::cyl_bessel_i(0.0, kappa)) : 0.0;
  const int blocks = (s.n + kBlockSize - 1) / kBlockSize;
  std::vector<double> blocked_mass(static_cast<size_t>(blocks), 0.0);
  s.ForBlocks(s.n, [&](int b, int begin, int end, RandomStream& rng) {
    double blocked = 0.0;
    for (int i = begin; i < end; ++i) {
      double o, sc;
      Eigen::Vector2d delta;
      motion.Sample(s.offset[i], &s.cos_offset[i], &s.sin_offset[i], s.scale[i], rng, &o, &sc, &delta);
      s.offset[i] = o;
      s.scale[i] = sc;
      if (s.corridor_mode()) {
        // Paper 000 eq. 8-10 with the step's length, eq. 11 with the step's heading.
        const double length = delta.norm();
        const double heading = std::atan2(delta.y(), delta.x());
        const Eigen::VectorXd& lengths = s.corridors->lengths_m();
        int seg = s.segment[i];
        int d = s.direction[i];
        double u = s.along[i] + d * length;
        for (int guard = 0; guard < 10000; ++guard) {
          int e;
          double left;
          if (d > 0 && u > lengths[seg]) {
            e = 1;
            left = u - lengths[seg];
          } else if (d < 0 && u < 0.0) {
            e = 0;
            left = -u;
          } else {
            break;
          }
          const auto& choices = s.corridors->continuations(seg, e);
          const auto& c = choices[choices.size() > 1 ? rng.UniformInt(choices.size()) : 0];
          seg = c.segment;
          d = c.enter_end == 0 ? 1 : -1;
          u = c.enter_end == 0 ? left : lengths[seg] - left;
        }
        u = std::clamp(u, 0.0, lengths[seg]);
        s.segment[i] = seg;
        s.direction[i] = static_cast<signed char>(d);
        s.along[i] = u;
        const Eigen::Vector2d q = s.corridors->point_at(seg, u);
        s.x[i] = q.x();
        s.y[i] = q.y();
        const double beta = s.corridors->headings_rad()[seg] + (d > 0 ? 0.0 : M_PI);
        if (length > 1e-9) s.log_w[i] += kappa * std::cos(heading - beta) - log_vm_norm;
        continue;
      }
      const double qx = s.x[i] + delta.x(), qy = s.y[i] + delta.y();
      int f = s.floor[i];
      bool is_blocked;
      if (p_change > 0.0 && rng.Uniform01() < p_change) {
        int g = static_cast<int>(rng.UniformInt(static_cast<std::uint64_t>(num_floors - 1)));
        if (g >= f) ++g;
        f = g;
        is_blocked = !s.Walkable(qx, qy, f);
      } else {
        is_blocked = s.Blocked(s.x[i], s.y[i], qx, qy, f);
      }
      if (is_blocked) {
        blocked += std::exp(s.log_w[i]);
        s.log_w[i] += penalty;
        if (std::isinf(penalty)) continue;  // dropped: stays where it was
      }
      s.x[i] = qx;
      s.y[i] = qy;
      s.floor[i] = f;
    }
    blocked_mass[b] = blocked;
  });

  ++s.summary.steps;
  TrackerEstimate est;
  est.time_s = step.time_s;
  double blocked_total = 0.0;
  for (double m : blocked_mass) blocked_total += m;
  est.blocked_fraction = std::min(1.0, blocked_total);
  const double max_log_w = s.log_w.maxCoeff();
  if (!(max_log_w > kNegInf)) {
    // Every particle blocked: the step contradicts the plan (an unmapped door, a wrong heading
    // offset). Ignore it rather than lose the cloud (a dropped particle stayed where it was);
    // re-spread if it keeps happening.
    s.log_w = old_log_w;
    ++s.summary.all_blocked_steps;
    if (++s.consecutive_blocked >= s.options.respread_after_blocked_steps) {
      s.Respread();
      s.consecutive_blocked = 0;
    }
    est.ess = EffectiveSampleSize(s.log_w);
    est.log_likelihood = 0.0;
    s.PushLag();
    s.FillEstimate(&est);
  } else {
    s.consecutive_blocked = 0;
    s.PushLag();
    // log-likelihood increment: log Σ w_old,i · (wall factor), the old weights normalised.
    est.log_likelihood = s.FinishUpdate(max_log_w, &est);
    s.summary.total_log_likelihood += est.log_likelihood;
  }
  if (s.options.record_history) {
    s.history.times_s.push_back(step.time_s);
    s.history.steps.push_back(step);
    s.Snapshot(false);
  }
  s.summary.seconds += timer.ElapsedSeconds();
  return est;
}

TrackerEstimate ParticleTracker::Wifi(const WifiObservation& observation) {
  Impl& s = *impl_;
  WallTimer timer;
  CheckArgument(s.model != nullptr, "observation", "the tracker has no signal map (wifi_model is None)");
  s.wifi->CheckObservation(observation, "observation");
  if (!s.initialized) {
    InitializeUnknown(observation);
    TrackerEstimate est = Estimate();
    est.time_s = observation.time_s;
    return est;
  }
  // Events go forward in time, whatever their kind (a reading re-timed to its own time is
  // placed in time order by MakeWifiObservations and Track).
  s.CheckTime(observation.time_s, "observation.time_s");
  s.last_time = observation.time_s;
  if (observation.empty()) {
    TrackerEstimate est;
    est.time_s = observation.time_s;
    ++s.summary.empty_wifi_updates;
    s.FillEstimate(&est);
    est.ess = EffectiveSampleSize(s.log_w);
    return est;
  }
  ++s.summary.wifi_updates;
  TrackerEstimate est = s.Observe(observation.time_s, observation.num_heard > 0, s.WifiPointLL(observation));
  s.summary.seconds += timer.ElapsedSeconds();
  return est;
}

TrackerEstimate ParticleTracker::Fix(const PositionFix& fix) {
  Impl& s = *impl_;
  WallTimer timer;
  CheckPositionFix(fix, "fix");
  if (s.initialized) {
    s.CheckTime(fix.time_s, "fix.time_s");
    s.last_time = fix.time_s;
  } else {
    CheckArgument(s.plan || s.model || s.corridors, "fix", "an unknown start needs a floor plan, a signal map or corridors");
    s.UniformCloud();
    s.initialized = true;
    s.awaiting_first_fix = true;
    s.last_time = fix.time_s;
  }

  if (fix.empty()) {
    TrackerEstimate est;
    est.time_s = fix.time_s;
    s.FillEstimate(&est);
    est.ess = EffectiveSampleSize(s.log_w);
    return est;
  }
  ++s.summary.fix_updates;
  const FixLikelihood likelihood(fix, s.options.fix);
  TrackerEstimate est = s.Observe(fix.time_s, true, [&](double px, double py, int f) {
    return likelihood.LogLikelihood(px, py, s.floors[f], s.total_area);
  });
  s.summary.seconds += timer.ElapsedSeconds();
  return est;
}

const std::vector<double>& ParticleTracker::floor_areas_m2() const { return impl_->floor_area; }

TrackerEstimate ParticleTracker::Estimate() const {
  if (!impl_->initialized) {
    throw std::runtime_error(
        "indoorloc: ParticleTracker.estimate: the tracker is not initialised (no start, step, scan, fix or "
        "set_particles yet)");
  }
  TrackerEstimate est;
  est.time_s = impl_->last_time;
  impl_->FillEstimate(&est);
  est.ess = EffectiveSampleSize(impl_->log_w);
  return est;
}

RowMatrixXd ParticleTracker::ParticleStates() const {
  const Impl& s = *impl_;
  RowMatrixXd out(s.n, 4);
  for (int i = 0; i < s.n; ++i) out.row(i) << s.x[i], s.y[i], s.offset[i], s.scale[i];
  return out;
}

Eigen::VectorXi ParticleTracker::ParticleFloorIndices() const {
  return Eigen::Map<const Eigen::VectorXi>(impl_->floor.data(), impl_->n);
}

Eigen::VectorXd ParticleTracker::ParticleWeights() const { return NormalizedWeights(impl_->log_w); }

void ParticleTracker::SetParticles(const Eigen::Ref<const RowMatrixXd>& states,
                                   const Eigen::Ref<const Eigen::VectorXi>& floor_indices) {
  Impl& s = *impl_;
  CheckShape(states, -1, 4, "states");
  CheckArgument(states.rows() > 0, "states", "has no particle");
  CheckShape(floor_indices, states.rows(), 1, "floor_indices");
  CheckFinite(states, "states");
  CheckArgument(!s.corridor_mode(), "states", "SetParticles is not available in corridor mode");
  const int num_floors = static_cast<int>(s.floors.size());
  for (Eigen::Index i = 0; i < states.rows(); ++i) {
    const int f = floor_indices[i];
    if (f < 0 || f >= num_floors) {
      ThrowInvalidArgument("floor_indices", "entry " + std::to_string(i) + " = " + std::to_string(f) +
                                                " is not a floor index (0.." + std::to_string(num_floors - 1) + ")");
    }
    for (int c = 0; c < 2; ++c) {
      if (!(std::abs(states(i, c)) <= kMaxCoordinate)) {
        ThrowInvalidArgument("states", DescribeEntry(i, c, false) + std::string(c == 0 ? " (x" : " (y") +
                                           ") must be in [-1e+07, 1e+07] m, got " + FormatValue(states(i, c)));
      }
    }
    if (!(std::abs(states(i, 2)) <= 1e6)) {
      ThrowInvalidArgument("states", DescribeEntry(i, 2, false) + " (heading offset) must be in [-1e+06, 1e+06] rad, got " +
                                         FormatValue(states(i, 2)));
    }
    const double lo = s.options.motion.min_scale, hi = s.options.motion.max_scale;
    if (!(states(i, 3) >= lo && states(i, 3) <= hi)) {
      ThrowInvalidArgument("states", DescribeEntry(i, 3, false) + " (scale) must be in [min_scale, max_scale] = [" +
                                         FormatValue(lo) + ", " + FormatValue(hi) + "], got " + FormatValue(states(i, 3)));
    }
    // With hard walls no particle may stand outside walkable space (the filter's invariant: a
    // step never ends inside an obstacle); with soft walls it is only unlikely.
    if (s.plan && std::isinf(s.options.wall_log_penalty) &&
        !s.plan->IsWalkable(states(i, 0), states(i, 1), s.plan_floor[static_cast<size_t>(f)])) {
      ThrowInvalidArgument("states", "row " + std::to_string(i) + ": (" + FormatValue(states(i, 0)) + ", " +
                                         FormatValue(states(i, 1)) + ") is not walkable on floor " +
                                         std::to_string(s.floors[static_cast<size_t>(f)]) +
                                         " (hard walls: wall_log_penalty = -inf)");
    }
  }
  RequireParticleMemory(static_cast<double>(states.rows()), s.options, false, "states");
  s.options.num_particles = static_cast<int>(states.rows());
  s.Resize(static_cast<int>(states.rows()));
  for (int i = 0; i < s.n; ++i) {
    s.x[i] = states(i, 0);
    s.y[i] = states(i, 1);
    s.offset[i] = WrapAngle(states(i, 2));
    s.cos_offset[i] = std::cos(s.offset[i]);
    s.sin_offset[i] = std::sin(s.offset[i]);
    s.scale[i] = states(i, 3);
    s.floor[i] = floor_indices[i];
  }
  s.initialized = true;
  s.awaiting_first_fix = false;
}

}  // namespace indoorloc::fusion
