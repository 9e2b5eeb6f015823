// The particle tracker's private state (ParticleTracker::Impl) and the map of where each part
// of the filter lives. Private header: only the particle_tracker*.cc files include it.
//
//   particle_tracker.cc             public API: options check, construction, the event entry
//                                   points (Step, Wifi, Fix, starts), particle access
//   particle_tracker_free_space.cc  free-space mode: motion, wall test, floor change, re-spread
//   particle_tracker_corridor.cc    corridor mode: the shared corridor motion model
//                                   (mapmatch/corridor_motion.h: network move + von Mises heading
//                                   weight, paper 000 eq. 8-11) driven by the sampled steps
//   particle_tracker_seeking.cc     placing particles without a known start: candidate grid,
//                                   draws from an observation's likelihood, uniform cloud
//   particle_tracker_observation.cc absolute observations (WiFi scan, fix) and recovery
//   particle_tracker_cloud.cc       the cloud: storage, weights + ESS + resampling in one pass,
//                                   the estimate, the fixed-lag ring, the recorded history
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/core/fixed_lag_ring.h"
#include "indoorloc/core/parallel.h"
#include "indoorloc/core/random.h"
#include "indoorloc/fusion/particle_tracker.h"
#include "indoorloc/mapmatch/corridor_motion.h"

namespace indoorloc::fusion {

/// Log-likelihood of an absolute observation at a point: (x [m], y [m], tracker floor index).
using PointLogLikelihood = std::function<double(double, double, int)>;

namespace tracker_detail {
constexpr double kNegInf = -std::numeric_limits<double>::infinity();
/// Plan and particle coordinates are bounded like the floor plan's (+-1e7 m).
constexpr double kMaxCoordinate = 1e7;
/// Systematic resampling stream id of the tracker's own stream family: the per-event block
/// streams use DeriveSeed(seed, event) instead, so the two never overlap.
constexpr std::uint64_t kTrackerStream = 0x7f3a5c11ULL;
/// Stream id of the motion's random lanes (RandomLanes(block stream's first draw, this)).
constexpr std::uint64_t kMotionLanesStream = 0x5eed1a7eULL;

/// Angle wrapped to [-pi, pi] [rad].
inline double WrapAngle(double a) { return std::remainder(a, 2.0 * M_PI); }
}  // namespace tracker_detail

struct ParticleTracker::Impl {
  // ---- sources and options (fixed after construction)
  const FloorPlan* plan = nullptr;
  const wifi::RssModel* model = nullptr;
  const mapmatch::RoadNetwork* corridors = nullptr;
  TrackerOptions options;
  std::unique_ptr<WifiLikelihood> wifi;

  std::vector<int> floors;              // tracker floor numbers
  std::vector<int> plan_floor;          // tracker floor index -> plan floor index (or -1)
  std::vector<int> model_floor;         // tracker floor index -> model floor index (or -1)
  std::vector<RowMatrixXd> candidates;  // per tracker floor: candidate points (unknown start, recovery)
  std::vector<double> floor_area;       // per tracker floor: walkable area [m²]
  double total_area = 0.0;              // over all floors: the outlier density of a fix is ε / total_area

  // ---- the cloud (structure of arrays)
  int n = 0;
  std::vector<double> x, y, offset, scale;
  std::vector<double> cos_offset, sin_offset;  // of `offset`, kept for the estimates (no trig there)
  std::vector<double> weights;                 // normalised linear weights of the last update
  std::vector<int> floor;
  std::vector<int> segment;                    // corridor mode: network segment,
  std::vector<signed char> direction;          //   direction of travel (+1 / -1),
  std::vector<double> along;                   //   distance along the segment [m]
  Eigen::VectorXd log_w;
  FixedLagRing lag_ring;  // the last L + 1 positions of every particle

  // ---- filter state
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
  std::vector<double> gather_scratch;   // Gather's temporaries (kept: no allocation per resampling)
  std::vector<int> gather_scratch_int;
  Eigen::VectorXd step_start_log_w;     // Step: the log-weights before the step (all-blocked restore)

  // Corridor mode: the network move and heading weight shared with mapmatch (null otherwise).
  std::unique_ptr<mapmatch::CorridorMotion> corridor_motion;

  bool corridor_mode() const { return corridors != nullptr; }

  // Every event (step, WiFi observation, fix) at or after the previous one (or the start).
  void CheckTime(double time_s, const char* name) const;

  // Runs fn(block, begin, end, rng) over fixed particle blocks; the stream of block b depends
  // only on (seed, event, b), never on the thread count.
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

  // Particle i's step drawn from the motion model (StepMotion::Sample): its heading offset and
  // scale move on; returns its displacement in the map frame [m]. Both modes move one particle so.
  Eigen::Vector2d SampleStep(const StepMotion& motion, int i, RandomStream& stream) {
    double o, sc;
    Eigen::Vector2d delta;
    motion.Sample(offset[i], &cos_offset[i], &sin_offset[i], scale[i], stream, &o, &sc, &delta);
    offset[i] = o;
    scale[i] = sc;
    return delta;
  }

  bool Walkable(double px, double py, int f) const {
    if (!plan) return true;
    return plan->IsWalkable(px, py, plan_floor[f]);
  }
  bool Blocked(double x0, double y0, double x1, double y1, int f) const {
    if (!plan) return false;
    return plan->CrossesWall(x0, y0, x1, y1, plan_floor[f]);
  }

  // ---- the cloud (particle_tracker_cloud.cc)
  void Resize(int count);
  void Gather(const std::vector<int>& anc);
  double FinishUpdate(double max_log_w, TrackerEstimate* est);
  void FillEstimate(const std::vector<double>& w, TrackerEstimate* est) const;
  void FillEstimate(TrackerEstimate* est) const;
  void FillFloorsAndLag(const std::vector<double>& w, TrackerEstimate* est) const;
  struct CloudSums {
    double rx = 0, ry = 0;                  // the reference particle's position [m]
    double dx = 0, dy = 0, dxx = 0, dxy = 0, dyy = 0;  // Σ w d, Σ w d dᵀ, d = p - reference [m, m²]
    double sin = 0, cos = 0, scale = 0;     // Σ w sin o, Σ w cos o, Σ w s
  };
  CloudSums WeightedSums(const double* w) const;
  void PushLag();
  void Snapshot(bool replace_last);

  // ---- free-space mode (particle_tracker_free_space.cc)
  void MoveFreeSpace(const StepMotion& motion, std::vector<double>* blocked_mass);
  void MoveFreeSpaceChangingFloors(const StepMotion& motion, std::vector<double>* blocked_mass);
  void Respread();

  // ---- corridor mode (particle_tracker_corridor.cc)
  void MoveAlongCorridors(const StepMotion& motion);
  void PlaceOnCorridors(int i, double px, double py);
  Eigen::Vector2d UniformOnCorridors();

  // ---- placing particles without a known start (particle_tracker_seeking.cc)
  void BuildCandidates();
  Eigen::VectorXd CandidateLogLikelihoods(const PointLogLikelihood& point_ll, std::vector<int>* candidate_floor,
                                          std::vector<int>* candidate_row);
  void DrawFromCandidates(const PointLogLikelihood& point_ll, const std::vector<int>& slots);
  double UnknownOffset();
  void PlaceFree(int i, double px, double py, int f, double o);
  void UniformCloud();

  // ---- absolute observations and recovery (particle_tracker_observation.cc)
  TrackerEstimate Observe(double time_s, bool informative, const PointLogLikelihood& point_ll);
  PointLogLikelihood WifiPointLL(const WifiObservation& obs) const;
};

}  // namespace indoorloc::fusion
