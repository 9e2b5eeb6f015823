// Python bindings of the mapmatch subsystem: road networks, trajectories, the circular particle
// filter and the Monte Carlo runner of paper 000.
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/mapmatch/monte_carlo.h"
#include "indoorloc/mapmatch/particle_map_matcher.h"
#include "indoorloc/mapmatch/road_network.h"
#include "indoorloc/mapmatch/trajectory_simulator.h"
#include "numpy_args.h"
#include "options_binding.h"

namespace indoorloc::bindings {

using namespace indoorloc::mapmatch;  // NOLINT: binding file

namespace {

template <typename T>
py::array_t<T> ToArray(const std::vector<T>& v) {
  py::array_t<T> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

JunctionPolicy ParsePolicy(const std::string& name) {
  if (name == "uniform") return JunctionPolicy::kUniform;
  if (name == "heading_aware") return JunctionPolicy::kHeadingAware;
  ThrowInvalidArgument("junction_policy", "unknown policy '" + name + "' (uniform or heading_aware)");
}

py::dict TrajectoryToDict(const Trajectory& t) {
  py::dict d;
  d["positions_m"] = t.positions_m;
  d["segments"] = t.segments;
  d["heading_true_rad"] = t.heading_true_rad;
  d["speed_mps"] = t.speed_mps;
  d["heading_rad"] = t.heading_rad;
  d["speed_bias_mps"] = t.speed_bias_mps;
  d["start_m"] = t.start_m;
  return d;
}

py::dict EstimatesToDict(const std::vector<StepEstimate>& e) {
  const py::ssize_t n = static_cast<py::ssize_t>(e.size());
  RowMatrixXd pos(n, 2), mean(n, 2), smoothed(n, 2);
  std::vector<std::int64_t> segment(e.size());
  std::vector<double> spread(e.size()), ess(e.size()), loglik(e.size());
  std::vector<bool> tracking(e.size()), resampled(e.size()), recovered(e.size());
  for (size_t k = 0; k < e.size(); ++k) {
    pos.row(static_cast<Eigen::Index>(k)) = e[k].position_m.transpose();
    mean.row(static_cast<Eigen::Index>(k)) = e[k].weighted_mean_m.transpose();
    smoothed.row(static_cast<Eigen::Index>(k)) = e[k].smoothed_m.transpose();
    segment[k] = e[k].segment;
    spread[k] = e[k].spread_m;
    ess[k] = e[k].ess;
    loglik[k] = e[k].log_likelihood;
    tracking[k] = e[k].tracking;
    resampled[k] = e[k].resampled;
    recovered[k] = e[k].recovered;
  }
  auto bools = [](const std::vector<bool>& v) {
    py::array_t<bool> out(static_cast<py::ssize_t>(v.size()));
    for (size_t k = 0; k < v.size(); ++k) out.mutable_data()[k] = v[k];
    return out;
  };
  py::dict d;
  d["positions_m"] = pos;
  d["weighted_mean_m"] = mean;
  d["smoothed_m"] = smoothed;
  d["segments"] = ToArray(segment);
  d["spread_m"] = ToArray(spread);
  d["ess"] = ToArray(ess);
  d["log_likelihood"] = ToArray(loglik);
  d["tracking"] = bools(tracking);
  d["resampled"] = bools(resampled);
  d["recovered"] = bools(recovered);
  return d;
}

}  // namespace

/// The road network.
static void BindRoadNetwork(py::module_& m) {
  const RoadNetworkOptions road_network;  // the keyword defaults
  py::class_<RoadNetwork, std::shared_ptr<RoadNetwork>>(m, "RoadNetwork", R"doc(
Straight segments with connectivity at their ends (paper 000 §II.B) and a spatial index.

Parameters
----------
segments_m : (M, 4) float array
    x_A, y_A, x_B, y_B of each segment [m].
ids : (M,) int array or None
    Unique segment ids (default 1..M).
snap_tolerance_m : float
    Ends closer than this form one junction [m].
split_at_intersections : bool
    Split segments at crossings and T-junctions first.)doc")
      .def(py::init([](const py::object& segments_m, const py::object& ids, double snap_tolerance_m,
                       bool split_at_intersections) {
             MatrixArg seg = ToMatrix(segments_m, "segments_m", -1, 4);
             Eigen::VectorXi id;
             if (!ids.is_none()) id = ToIntVector(ids, "ids", seg.map.rows());  // 32-bit ids: no wrap-around
             RoadNetworkOptions o;
             o.snap_tolerance_m = snap_tolerance_m;
             o.split_at_intersections = split_at_intersections;
             return std::make_shared<RoadNetwork>(seg.map, id, o);
           }),
           py::arg("segments_m"), py::arg("ids") = py::none(), py::arg("snap_tolerance_m") = road_network.snap_tolerance_m,
           py::arg("split_at_intersections") = road_network.split_at_intersections)
      .def_property_readonly("num_segments", &RoadNetwork::num_segments)
      .def_property_readonly("segments_m", &RoadNetwork::segments_m)
      .def_property_readonly("ids", &RoadNetwork::ids)
      .def_property_readonly("headings_rad", &RoadNetwork::headings_rad)
      .def_property_readonly("lengths_m", &RoadNetwork::lengths_m)
      .def_property_readonly("total_length_m", &RoadNetwork::total_length_m)
      .def_property_readonly("components", &RoadNetwork::components)
      .def_property_readonly("num_components", &RoadNetwork::num_components)
      .def_property_readonly("dangling_ends", [](const RoadNetwork& n) {
        const auto d = n.dangling_ends();
        py::array_t<std::int64_t> out({static_cast<py::ssize_t>(d.size()), py::ssize_t{2}});
        for (size_t k = 0; k < d.size(); ++k) {
          out.mutable_data()[2 * k] = d[k].first;
          out.mutable_data()[2 * k + 1] = d[k].second;
        }
        return out;
      }, "(n, 2) int array of (segment index, end) with only a U-turn (0 = A, 1 = B).")
      .def("continuations", [](const RoadNetwork& n, int segment, int end) {
             CheckArgument(segment >= 0 && segment < n.num_segments(), "segment", "out of range");
             CheckArgument(end == 0 || end == 1, "end", "must be 0 (A) or 1 (B)");
             std::vector<std::pair<int, int>> out;
             for (const Continuation& c : n.continuations(segment, end)) out.emplace_back(c.segment, c.enter_end);
             return out;
           },
           py::arg("segment"), py::arg("end"), "[(segment, enter_end), ...] reachable from an end.")
      .def("nearest", [](const RoadNetwork& n, const py::object& points_m) {
             MatrixArg p = ToMatrix(points_m, "points_m", -1, 2);
             RequireAllInRange(p.map, -1e12, 1e12, "points_m");  // squared distances stay finite
             const Eigen::Index q = p.map.rows();
             std::vector<std::int64_t> seg(static_cast<size_t>(q));
             RowMatrixXd proj(q, 2);
             Eigen::VectorXd dist(q), along(q);
             {
               py::gil_scoped_release release;
               for (Eigen::Index i = 0; i < q; ++i) {
                 const Projection pr = n.Nearest(p.map.row(i).transpose());
                 seg[static_cast<size_t>(i)] = pr.segment;
                 proj.row(i) = pr.point_m.transpose();
                 dist[i] = pr.distance_m;
                 along[i] = pr.along_m;
               }
             }
             return py::make_tuple(ToArray(seg), proj, dist, along);
           },
           py::arg("points_m"), "Nearest segment of points (Q, 2): (segments, projections (Q, 2), distances, along_m).")
      .def("point_at", [](const RoadNetwork& n, int segment, double along_m) {
             RequireIntInRange(segment, 0, n.num_segments() - 1, "segment");
             RequireFinite(along_m, "along_m");
             return n.point_at(segment, along_m);
           }, py::arg("segment"), py::arg("along_m"))
      .def("report", &RoadNetwork::Report, "Validation report: sizes, components, dangling ends.")
      .def("__repr__", [](const RoadNetwork& n) { return "<RoadNetwork " + n.Report() + ">"; });
}

/// Simulated vehicle runs.
static void BindTrajectorySimulation(py::module_& m) {
  py::class_<TrajectoryOptions> trajectory_options(m, "TrajectoryOptions",
                                                    "Simulated vehicle runs (paper 000 §III); fields by keyword.");
  trajectory_options.def_readwrite("duration_s", &TrajectoryOptions::duration_s, "Run length [s].")
      .def_readwrite("dt_s", &TrajectoryOptions::dt_s, "Sample period of both sensors [s].")
      .def_readwrite("speed_mps", &TrajectoryOptions::speed_mps, "True constant speed [m/s].")
      .def_readwrite("speed_noise_sd_mps", &TrajectoryOptions::speed_noise_sd_mps, "Odometer noise sd [m/s].")
      .def_readwrite("speed_bias_halfwidth_mps", &TrajectoryOptions::speed_bias_halfwidth_mps,
                     "Per-run odometer bias ~ U(-h, h) [m/s].")
      .def_readwrite("heading_kappa", &TrajectoryOptions::heading_kappa, "Compass von Mises concentration.")
      .def_readwrite("allow_straight", &TrajectoryOptions::allow_straight,
                     "Whether the vehicle may go straight on at a junction.");
  BindOptionsProtocol(trajectory_options, "TrajectoryOptions",
                      {"duration_s", "dt_s", "speed_mps", "speed_noise_sd_mps", "speed_bias_halfwidth_mps",
                       "heading_kappa", "allow_straight"});

  m.def("simulate_trajectory", [](const RoadNetwork& n, const TrajectoryOptions& o, std::uint64_t seed, std::uint64_t stream) {
          RandomStream rng(seed, stream);
          return TrajectoryToDict(SimulateTrajectory(n, o, rng));
        },
        py::arg("network"), py::arg("options") = TrajectoryOptions(), py::arg("seed") = 0, py::arg("stream") = 0, R"doc(
One simulated run: dict with positions_m (T, 2), segments (T,), heading_true_rad, speed_mps
(odometer), heading_rad (compass), speed_bias_mps, start_m. Sample k is at time (k + 1) dt.)doc");
}

/// The circular particle filter, its options and the Monte Carlo study.
static void BindParticleMapMatcher(py::module_& m) {
  py::class_<FilterOptions> filter_options(
      m, "FilterOptions", "Options of the circular particle filter (see docs/mapmatch.md); fields by keyword.");
  filter_options.def_readwrite("num_particles", &FilterOptions::num_particles)
      .def_readwrite("kappa", &FilterOptions::kappa, "κ of the von Mises heading weight.")
      .def_readwrite("noise_halfwidth_m", &FilterOptions::noise_halfwidth_m, "Uniform along-track noise half-width [m].")
      .def_property("resampling", [](const FilterOptions& o) { return std::string(ToString(o.resampling.scheme)); },
                    [](FilterOptions& o, const std::string& v) { o.resampling.scheme = ParseResamplingScheme(v, "resampling"); })
      .def_property("ess_threshold", [](const FilterOptions& o) { return o.resampling.ess_threshold; },
                    [](FilterOptions& o, double v) { o.resampling.ess_threshold = v; })
      .def_property("junction_policy",
                    [](const FilterOptions& o) { return o.junction_policy == JunctionPolicy::kUniform ? "uniform" : "heading_aware"; },
                    [](FilterOptions& o, const std::string& s) { o.junction_policy = ParsePolicy(s); },
                    "'uniform' or 'heading_aware'.")
      .def_readwrite("junction_kappa", &FilterOptions::junction_kappa)
      .def_readwrite("estimate_speed_bias", &FilterOptions::estimate_speed_bias)
      .def_readwrite("bias_halfwidth_mps", &FilterOptions::bias_halfwidth_mps)
      .def_readwrite("bias_jitter_mps", &FilterOptions::bias_jitter_mps)
      .def_readwrite("tracking_spread_m", &FilterOptions::tracking_spread_m)
      .def_readwrite("recovery_disagreement", &FilterOptions::recovery_disagreement)
      .def_readwrite("recovery_window_s", &FilterOptions::recovery_window_s)
      .def_readwrite("recovery_fraction", &FilterOptions::recovery_fraction)
      .def_readwrite("smoothing_lag_steps", &FilterOptions::smoothing_lag_steps)
      .def_readwrite("seed", &FilterOptions::seed);
  BindOptionsProtocol(filter_options, "FilterOptions",
                      {"num_particles", "kappa", "noise_halfwidth_m", "resampling", "ess_threshold", "junction_policy",
                       "junction_kappa", "estimate_speed_bias", "bias_halfwidth_mps", "bias_jitter_mps",
                       "tracking_spread_m", "recovery_disagreement", "recovery_window_s", "recovery_fraction",
                       "smoothing_lag_steps", "seed"});

  py::class_<ParticleMapMatcher>(m, "ParticleMapMatcher", R"doc(
Circular particle filter on a road network (paper 000 Algorithm 1). Keeps a reference to the
network.)doc")
      .def(py::init<const RoadNetwork&, const FilterOptions&>(), py::arg("network"), py::arg("options") = FilterOptions(),
           py::keep_alive<1, 2>())
      .def("reset", &ParticleMapMatcher::Reset)
      .def("step", [](ParticleMapMatcher& f, double speed_mps, double heading_rad, double dt_s) {
             return EstimatesToDict({f.Step(speed_mps, heading_rad, dt_s)});
           },
           py::arg("speed_mps"), py::arg("heading_rad"), py::arg("dt_s"), "One step; dict of length-1 arrays.")
      .def("run", [](ParticleMapMatcher& f, const py::object& speed_mps, const py::object& heading_rad, double dt_s) {
             VectorArg v = ToVector(speed_mps, "speed_mps");
             VectorArg h = ToVector(heading_rad, "heading_rad", v.map.size());
             std::vector<StepEstimate> e;
             {
               py::gil_scoped_release release;
               e = RunFilter(f, v.map, h.map, dt_s);
             }
             return EstimatesToDict(e);
           },
           py::arg("speed_mps"), py::arg("heading_rad"), py::arg("dt_s"), R"doc(
Filter odometer speeds (T,) [m/s] and compass headings (T,) [rad] sampled every dt_s [s],
continuing from the filter's current particles (call reset() first to start again from the
initial grid and seed: a second run without reset() starts where the first ended).
Returns a dict of arrays: positions_m (T, 2) (projected estimate), weighted_mean_m, smoothed_m
(fixed-lag, NaN when off), segments (T,), spread_m, ess, log_likelihood, tracking, resampled,
recovered.)doc")
      .def("set_particles", [](ParticleMapMatcher& f, const py::object& segments, const py::object& directions,
                               const py::object& along_m) {
             // Whole numbers only: 2.7 is not a segment index and -7 is not a direction.
             const Eigen::VectorXi s = ToIntVector(segments, "segments");
             const Eigen::VectorXi d = ToIntVector(directions, "directions", s.size());
             VectorArg u = ToVector(along_m, "along_m", s.size());
             std::vector<int> seg(s.data(), s.data() + s.size());
             std::vector<signed char> dir(seg.size());
             std::vector<double> along(seg.size());
             for (size_t i = 0; i < seg.size(); ++i) {
               const int di = d[static_cast<Eigen::Index>(i)];
               if (di != 1 && di != -1)
                 ThrowInvalidArgument("directions", DescribeEntry(static_cast<Eigen::Index>(i), 0, true) +
                                                        " must be +1 or -1, got " + std::to_string(di));
               dir[i] = static_cast<signed char>(di);
               along[i] = u.map[static_cast<Eigen::Index>(i)];
             }
             f.SetParticles(seg, dir, along);
           },
           py::arg("segments"), py::arg("directions"), py::arg("along_m"),
           "Replace the particles (a prior): segment indices (N,), directions ±1 (N,), along_m (N,) [m].")
      .def("segment_posterior", &ParticleMapMatcher::SegmentPosterior, "Probability of each segment (M,).")
      .def("particle_positions", &ParticleMapMatcher::ParticlePositions, "(N, 2) [m].")
      .def("particle_weights", &ParticleMapMatcher::ParticleWeights, "(N,) normalised.")
      .def("particle_states", [](const ParticleMapMatcher& f) {
        std::vector<std::int64_t> seg(f.particle_segments().begin(), f.particle_segments().end());
        std::vector<std::int64_t> dir(f.particle_directions().begin(), f.particle_directions().end());
        return py::make_tuple(ToArray(seg), ToArray(dir), ToArray(f.particle_along_m()));
      }, "(segments (N,), directions (N,) ±1, along_m (N,)).")
      .def_property_readonly("summary_report", [](const ParticleMapMatcher& f) { return f.summary().BriefReport(); })
      .def_property_readonly("recoveries", [](const ParticleMapMatcher& f) { return f.summary().recoveries; });

  m.def("monte_carlo", [](const RoadNetwork& n, const TrajectoryOptions& t, const FilterOptions& f, int n_runs,
                          std::uint64_t seed, int n_threads) {
          RequireIntInRange(n_runs, 1, 100000000, "n_runs");
          ValidateOptions(t, "trajectory");
          // The (R, T) result arrays (and each run's history) must fit in memory: refuse before
          // running for hours. The loops poll Ctrl-C (KeyboardInterrupt) between steps.
          RequireSizeLimit(static_cast<double>(n_runs) * std::floor(t.duration_s / t.dt_s + 1.0), 5 * sizeof(double),
                           "n_runs", "run-steps (n_runs x duration_s / dt_s)");
          std::vector<RunResult> r;
          {
            py::gil_scoped_release release;
            r = RunMonteCarlo(n, t, f, n_runs, seed, n_threads);
          }
          const Eigen::Index steps = r[0].error_m.size();
          RowMatrixXd err(n_runs, steps), smoothed(n_runs, steps);
          Eigen::Matrix<std::int64_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> correct(n_runs, steps), tracking(n_runs, steps);
          Eigen::VectorXd bias(n_runs), seconds(n_runs), recoveries(n_runs);
          for (int i = 0; i < n_runs; ++i) {
            err.row(i) = r[static_cast<size_t>(i)].error_m.transpose();
            smoothed.row(i) = r[static_cast<size_t>(i)].smoothed_error_m.transpose();
            correct.row(i) = r[static_cast<size_t>(i)].correct_segment.cast<std::int64_t>().transpose();
            tracking.row(i) = r[static_cast<size_t>(i)].tracking.cast<std::int64_t>().transpose();
            bias[i] = r[static_cast<size_t>(i)].speed_bias_mps;
            seconds[i] = r[static_cast<size_t>(i)].summary.seconds;
            recoveries[i] = r[static_cast<size_t>(i)].summary.recoveries;
          }
          py::dict d;
          d["error_m"] = err;
          d["smoothed_error_m"] = smoothed;
          d["correct_segment"] = correct;
          d["tracking"] = tracking;
          d["speed_bias_mps"] = bias;
          d["filter_seconds"] = seconds;
          d["recoveries"] = recoveries;
          return d;
        },
        py::arg("network"), py::arg("trajectory"), py::arg("filter"), py::arg("n_runs") = 100, py::arg("seed") = 0,
        py::arg("n_threads") = 0, R"doc(
Paper 000 §III Monte Carlo: n_runs simulated runs, each filtered; run r uses streams (seed, 2r)
and (seed, 2r + 1), so results do not depend on n_threads (0 = all cores). Returns a dict of
(R, T) arrays error_m, smoothed_error_m, correct_segment, tracking and (R,) speed_bias_mps,
filter_seconds, recoveries.)doc");
}

void BindMapmatch(py::module_& m) {
  BindRoadNetwork(m);
  BindTrajectorySimulation(m);
  BindParticleMapMatcher(m);
}

}  // namespace indoorloc::bindings
