// Python bindings of the wifi subsystem: signal maps, Delaunay interpolation, the interpolated
// RSS model, the gradient tracker and maximum-likelihood fixes.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "indoorloc/core/options.h"
#include "indoorloc/core/parallel.h"
#include "indoorloc/core/random.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/wifi/delaunay_interpolator.h"
#include "indoorloc/wifi/gradient_tracker.h"
#include "indoorloc/wifi/grid_posterior.h"
#include "indoorloc/wifi/rss_model.h"
#include "indoorloc/wifi/signal_map.h"
#include "numpy_args.h"
#include "options_binding.h"

namespace indoorloc::bindings {

using wifi::DelaunayInterpolator;
using wifi::GradientTracker;
using wifi::GradientTrackerOptions;
using wifi::RssModel;
using wifi::RssModelOptions;
using wifi::SignalMap;
using wifi::SignalMapOptions;
using wifi::WifiFix;

namespace {

// Fixes of a batch as numpy arrays.
py::dict FixesToDict(const std::vector<WifiFix>& fixes) {
  const py::ssize_t n = static_cast<py::ssize_t>(fixes.size());
  py::array_t<double> pos({n, py::ssize_t{2}}), cov({n, py::ssize_t{2}, py::ssize_t{2}}), nll(n);
  py::array_t<std::int64_t> floors(n), iterations(n), fallbacks(n);
  py::array_t<bool> inside(n), relocalized(n);
  auto p = pos.mutable_unchecked<2>();
  auto c = cov.mutable_unchecked<3>();
  for (py::ssize_t i = 0; i < n; ++i) {
    const WifiFix& f = fixes[static_cast<size_t>(i)];
    p(i, 0) = f.position_m[0];
    p(i, 1) = f.position_m[1];
    for (int r = 0; r < 2; ++r)
      for (int k = 0; k < 2; ++k) c(i, r, k) = f.covariance_m2(r, k);
    nll.mutable_data()[i] = f.neg_log_likelihood;
    floors.mutable_data()[i] = f.floor;
    iterations.mutable_data()[i] = f.iterations;
    fallbacks.mutable_data()[i] = f.fallback_steps;
    inside.mutable_data()[i] = f.inside;
    relocalized.mutable_data()[i] = f.relocalized;
  }
  py::dict d;
  d["positions_m"] = pos;
  d["covariances_m2"] = cov;
  d["floors"] = floors;
  d["neg_log_likelihood"] = nll;
  d["inside"] = inside;
  d["iterations"] = iterations;
  d["fallback_steps"] = fallbacks;
  d["relocalized"] = relocalized;
  return d;
}

}  // namespace

/// Signal maps and their options.
static void BindSignalMap(py::module_& m) {
  py::class_<SignalMapOptions> signal_map_options(m, "SignalMapOptions",
                                                   "How raw scans become a signal map; fields by keyword.");
  signal_map_options
      .def_readwrite("not_heard_sentinel", &SignalMapOptions::not_heard_sentinel,
                     "RSS value that marks 'not heard' in the raw scans [dBm].")
      .def_readwrite("not_heard_dbm", &SignalMapOptions::not_heard_dbm, "RSS a not-heard AP is given [dBm].")
      .def_readwrite("variance_floor_db2", &SignalMapOptions::variance_floor_db2, "Lower bound of a variance [dB^2].")
      .def_readwrite("min_point_fraction", &SignalMapOptions::min_point_fraction,
                     "Drop APs heard at fewer than this fraction of the reference points.");
  BindOptionsProtocol(signal_map_options, "SignalMapOptions",
                      {"not_heard_sentinel", "not_heard_dbm", "variance_floor_db2", "min_point_fraction"});

  py::class_<SignalMap, std::shared_ptr<SignalMap>>(m, "SignalMap", R"doc(
Reference positions with per-AP RSS mean [dBm] and variance [dB^2] (paper 004, §5.4).)doc")
      .def(py::init([](const py::object& positions_m, const py::object& floors, const py::object& mean_dbm,
                       const py::object& variance_db2) {
             MatrixArg pos = ToMatrix(positions_m, "positions_m", -1, 2);
             MatrixArg mean = ToMatrix(mean_dbm, "mean_dbm", pos.map.rows(), -1);
             MatrixArg var = ToMatrix(variance_db2, "variance_db2", pos.map.rows(), mean.map.cols());
             const Eigen::VectorXi fl = floors.is_none() ? Eigen::VectorXi::Zero(pos.map.rows())
                                                         : ToIntVector(floors, "floors", pos.map.rows());
             return std::make_shared<SignalMap>(pos.map, fl, mean.map, var.map);
           }),
           py::arg("positions_m"), py::arg("floors"), py::arg("mean_dbm"), py::arg("variance_db2"),
           "Map from statistics: positions (N, 2) [m], floors (N,) int or None, mean (N, K), variance (N, K).")
      .def_static("from_scans", [](const py::object& scan_positions_m, const py::object& scan_floors,
                                   const py::object& rss_dbm, const SignalMapOptions& options) {
             MatrixArg rss = ToMatrix(rss_dbm, "rss_dbm", -1, -1, Finiteness::kAny);
             MatrixArg pos = ToMatrix(scan_positions_m, "scan_positions_m", rss.map.rows(), 2);
             const Eigen::VectorXi fl = scan_floors.is_none() ? Eigen::VectorXi::Zero(rss.map.rows())
                                                              : ToIntVector(scan_floors, "scan_floors", rss.map.rows());
             py::gil_scoped_release release;
             return std::make_shared<SignalMap>(SignalMap::FromScans(pos.map, fl, rss.map, options));
           },
           py::arg("scan_positions_m"), py::arg("scan_floors"), py::arg("rss_dbm"),
           py::arg("options") = SignalMapOptions(), R"doc(
Build a map from raw scans: rss_dbm (S, K_all) with a not-heard sentinel or NaN, scan positions
(S, 2) [m], scan floors (S,) or None. Scans at equal (x, y, floor) form one reference point.)doc")
      .def_static("load", &SignalMap::Load, py::arg("path"), "Read a map written by save().")
      .def("save", &SignalMap::Save, py::arg("path"), "Write the map as text (docs/wifi.md).")
      .def("prepare_scans", [](const SignalMap& map, const py::object& rss_dbm, double sentinel, double not_heard_dbm) {
             MatrixArg rss = ToMatrix(rss_dbm, "rss_dbm", -1, -1, Finiteness::kAny);
             return map.PrepareScans(rss.map, sentinel, not_heard_dbm);
           },
           py::arg("rss_dbm"), py::arg("not_heard_sentinel") = SignalMapOptions().not_heard_sentinel,
           py::arg("not_heard_dbm") = SignalMapOptions().not_heard_dbm,
           "Select the map's AP columns from raw scans (S, K_all) and apply the not-heard model.")
      .def_property_readonly("num_points", &SignalMap::num_points)
      .def_property_readonly("num_access_points", &SignalMap::num_access_points)
      .def_property_readonly("positions_m", &SignalMap::positions_m)
      .def_property_readonly("floors", &SignalMap::floors)
      .def_property_readonly("mean_dbm", &SignalMap::mean_dbm)
      .def_property_readonly("variance_db2", &SignalMap::variance_db2)
      .def_property_readonly("detection_rate", &SignalMap::detection_rate)
      .def_property_readonly("scan_counts", &SignalMap::scan_counts)
      .def_property_readonly("access_point_indices", &SignalMap::access_point_indices)
      .def("__repr__", [](const SignalMap& map) {
        return "<SignalMap " + std::to_string(map.num_points()) + " points, " +
               std::to_string(map.num_access_points()) + " APs, " +
               std::to_string(map.distinct_floors().size()) + " floor(s)>";
      });
}

/// The Delaunay interpolator of a signal map.
static void BindDelaunayInterpolator(py::module_& m) {
  py::class_<DelaunayInterpolator, std::shared_ptr<DelaunayInterpolator>>(m, "DelaunayInterpolator", R"doc(
Piecewise-linear interpolation of fields over a CGAL Delaunay triangulation, with gradients.)doc")
      .def(py::init([](const py::object& positions_m, const py::object& fields) {
             MatrixArg pos = ToMatrix(positions_m, "positions_m", -1, 2);
             MatrixArg f = ToMatrix(fields, "fields", pos.map.rows(), -1);
             py::gil_scoped_release release;
             return std::make_shared<DelaunayInterpolator>(pos.map, f.map);
           }),
           py::arg("positions_m"), py::arg("fields"), "positions (N, 2) [m], fields (N, F).")
      .def("interpolate", [](const DelaunayInterpolator& d, const py::object& queries_m, bool sequential, int num_threads) {
             MatrixArg q = ToMatrix(queries_m, "queries_m", -1, 2);
             const py::ssize_t n = static_cast<py::ssize_t>(q.map.rows());
             const py::ssize_t f = d.num_fields();
             // Results are written straight into the numpy arrays (no copy of Q x 3F doubles).
             py::array_t<double> values({n, f}), grads({n, f, py::ssize_t{2}}), at({n, py::ssize_t{2}});
             py::array_t<bool> inside(n);
             Eigen::Map<wifi::RowMatrixXd> values_map(values.mutable_data(), n, f);
             Eigen::Map<wifi::RowMatrixXd> grads_map(grads.mutable_data(), n, 2 * f);
             Eigen::Map<wifi::RowMatrixXd> at_map(at.mutable_data(), n, 2);
             Eigen::Map<Eigen::Matrix<bool, Eigen::Dynamic, 1>> inside_map(inside.mutable_data(), n);
             {
               py::gil_scoped_release release;
               d.InterpolateBatchInto(q.map, sequential, num_threads, values_map, grads_map, inside_map, at_map);
             }
             return py::make_tuple(values, grads, inside, at);
           },
           py::arg("queries_m"), py::arg("sequential") = false, py::arg("num_threads") = 1, R"doc(
Interpolate every field at queries (Q, 2) [m].

Returns (values (Q, F), gradients (Q, F, 2) [per m], inside (Q,) bool, evaluated_at_m (Q, 2)).
Outside the convex hull the nearest hull point is used. ``sequential=True`` uses the previous
query's triangle as the search hint (paths).)doc")
      .def("sibson", [](const DelaunayInterpolator& d, const py::object& queries_m) {
             MatrixArg q = ToMatrix(queries_m, "queries_m", -1, 2);
             py::gil_scoped_release release;
             return d.SibsonInterpolate(q.map);
           },
           py::arg("queries_m"), "Sibson natural-neighbour interpolation (Q, 2) -> (Q, F).")
      .def("clamp_to_hull", [](const DelaunayInterpolator& d, const Eigen::Vector2d& z) { return d.ClampToHull(z); },
           py::arg("z_m"))
      .def("triangles", &DelaunayInterpolator::Triangles, "Vertex indices (T, 3).")
      .def_property_readonly("num_points", &DelaunayInterpolator::num_points)
      .def_property_readonly("num_fields", &DelaunayInterpolator::num_fields)
      .def_property_readonly("num_triangles", &DelaunayInterpolator::num_triangles);
}

/// The Gaussian RSS model and its options.
static void BindRssModel(py::module_& m) {
  py::class_<RssModelOptions> rss_model_options(m, "RssModelOptions", "Options of the RSS model; fields by keyword.");
  rss_model_options
      .def_readwrite("variance_floor_db2", &RssModelOptions::variance_floor_db2, "Lower bound of a variance [dB^2].")
      .def_readwrite("max_term", &RssModelOptions::max_term, "Cap of each AP's residual term [nats].");
  BindOptionsProtocol(rss_model_options, "RssModelOptions", {"variance_floor_db2", "max_term"});

  py::class_<RssModel, std::shared_ptr<RssModel>>(m, "RssModel", R"doc(
The interpolated Gaussian RSS model of a signal map: l(z, v), its gradient and Fisher information.)doc")
      .def(py::init([](const SignalMap& map, const RssModelOptions& options) {
             return std::make_shared<RssModel>(map, options);
           }),
           py::arg("map"), py::arg("options") = RssModelOptions())
      .def_property_readonly("floors", &RssModel::floors)
      .def_property_readonly("num_access_points", &RssModel::num_access_points)
      .def_property_readonly("map", &RssModel::map)
      .def("interpolator", &RssModel::interpolator, py::arg("floor_index"), py::return_value_policy::reference_internal)
      .def("evaluate", [](const RssModel& model, const py::object& rss_dbm, const Eigen::Vector2d& z_m, int floor) {
             MatrixArg scans = ToMatrix(rss_dbm, "rss_dbm", -1, model.num_access_points());
             RequireAllInRange(scans.map, -1e4, 1e4, "rss_dbm");  // 1e300 dBm gave inf likelihoods
             int hint = -1;
             const wifi::RssLikelihood l = model.Evaluate(scans.map, z_m, model.FloorIndex(floor), &hint);
             return py::make_tuple(l.neg_log_likelihood, l.gradient, l.fisher, l.inside);
           },
           py::arg("rss_dbm"), py::arg("z_m"), py::arg("floor") = 0, R"doc(
l(z, v) [nats], its gradient (2,) [1/m] and the Fisher information (2, 2) [1/m^2] for scans
(n, K) all taken at z_m, and whether z_m is inside the floor's hull.)doc")
      .def("neg_log_likelihood_at", [](const RssModel& model, const py::object& rss_dbm, const py::object& points_m, int floor) {
             MatrixArg scans = ToMatrix(rss_dbm, "rss_dbm", -1, model.num_access_points());
             RequireAllInRange(scans.map, -1e4, 1e4, "rss_dbm");  // 1e300 dBm gave inf likelihoods
             MatrixArg pts = ToMatrix(points_m, "points_m", -1, 2);
             const int f = model.FloorIndex(floor);
             Eigen::VectorXd out(pts.map.rows());
             {
               py::gil_scoped_release release;
               int hint = -1;
               for (Eigen::Index i = 0; i < pts.map.rows(); ++i) {
                 out[i] = model.Evaluate(scans.map, pts.map.row(i).transpose(), f, &hint).neg_log_likelihood;
               }
             }
             return out;
           },
           py::arg("rss_dbm"), py::arg("points_m"), py::arg("floor") = 0,
           "l of scans (n, K) at each of points (Q, 2): the likelihood surface, (Q,).")
      .def("mean_and_variance", [](const RssModel& model, const py::object& points_m, int floor) {
             MatrixArg pts = ToMatrix(points_m, "points_m", -1, 2);
             const int f = model.FloorIndex(floor);
             const Eigen::Index k = model.num_access_points();
             wifi::RowMatrixXd mean(pts.map.rows(), k), var(pts.map.rows(), k);
             {
               py::gil_scoped_release release;
               int hint = -1;
               Eigen::VectorXd mu, v;
               for (Eigen::Index i = 0; i < pts.map.rows(); ++i) {
                 model.MeanAndVariance(pts.map.row(i).transpose(), f, &mu, &v, &hint);
                 mean.row(i) = mu.transpose();
                 var.row(i) = v.transpose();
               }
             }
             return py::make_tuple(mean, var);
           },
           py::arg("points_m"), py::arg("floor") = 0,
           "Interpolated mean (Q, K) [dBm] and floored variance (Q, K) [dB^2] at points (Q, 2).")
      .def("fisher_information", [](const RssModel& model, const py::object& points_m, int floor) {
             MatrixArg pts = ToMatrix(points_m, "points_m", -1, 2);
             const int f = model.FloorIndex(floor);
             py::array_t<double> out({pts.map.rows(), Eigen::Index{2}, Eigen::Index{2}});
             double* data = out.mutable_data();
             {
               py::gil_scoped_release release;
               int hint = -1;
               for (Eigen::Index i = 0; i < pts.map.rows(); ++i) {
                 const Eigen::Matrix2d fi = model.FisherInformation(pts.map.row(i).transpose(), f, &hint);
                 for (int r = 0; r < 2; ++r)
                   for (int c = 0; c < 2; ++c) data[4 * i + 2 * r + c] = fi(r, c);
               }
             }
             return out;
           },
           py::arg("points_m"), py::arg("floor") = 0,
           "Fisher information of one scan (Q, 2, 2) [1/m^2]; its inverse is the Cramér-Rao bound.")
      .def("simulate_scans", [](const RssModel& model, const py::object& points_m, int floor, std::uint64_t seed) {
             MatrixArg pts = ToMatrix(points_m, "points_m", -1, 2);
             const int f = model.FloorIndex(floor);
             const Eigen::Index k = model.num_access_points();
             wifi::RowMatrixXd out(pts.map.rows(), k);
             {
               py::gil_scoped_release release;
               RandomStream rng(seed);
               int hint = -1;
               Eigen::VectorXd mu, v;
               for (Eigen::Index i = 0; i < pts.map.rows(); ++i) {
                 model.MeanAndVariance(pts.map.row(i).transpose(), f, &mu, &v, &hint);
                 for (Eigen::Index a = 0; a < k; ++a) out(i, a) = rng.Normal(mu[a], std::sqrt(v[a]));
               }
             }
             return out;
           },
           py::arg("points_m"), py::arg("floor") = 0, py::arg("seed") = 0, R"doc(
Simulated mode (paper §5.6.1): one Gaussian RSS vector per point (Q, 2) drawn from the
interpolated model, (Q, K) [dBm]. Stream `seed` of indoorloc's generator.)doc");
}

/// The gradient tracker and its options.
static void BindGradientTracker(py::module_& m) {
  py::class_<GradientTrackerOptions> gradient_tracker_options(
      m, "GradientTrackerOptions", "Step control of the gradient tracker; fields by keyword.");
  gradient_tracker_options
      .def_readwrite("max_step_m", &GradientTrackerOptions::max_step_m)
      .def_readwrite("min_reciprocal_condition", &GradientTrackerOptions::min_reciprocal_condition)
      .def_readwrite("fallback_step_m", &GradientTrackerOptions::fallback_step_m)
      .def_readwrite("backtracking", &GradientTrackerOptions::backtracking)
      .def_readwrite("iterations_per_scan", &GradientTrackerOptions::iterations_per_scan)
      .def_readwrite("paper_mode", &GradientTrackerOptions::paper_mode)
      .def_readwrite("num_starts", &GradientTrackerOptions::num_starts)
      .def_readwrite("start_iterations", &GradientTrackerOptions::start_iterations)
      .def_readwrite("tolerance_m", &GradientTrackerOptions::tolerance_m)
      .def_readwrite("relocalize_threshold_nats", &GradientTrackerOptions::relocalize_threshold_nats);
  BindOptionsProtocol(gradient_tracker_options, "GradientTrackerOptions");

  py::class_<GradientTracker>(m, "GradientTracker", R"doc(
Streaming tracker of paper 004 (Algorithm 1, Fisher-scoring steps, no motion model).)doc")
      .def(py::init([](const std::shared_ptr<RssModel>& model, const GradientTrackerOptions& options) {
             CheckArgument(model != nullptr, "model", "is None");  // a null holder would crash
             return GradientTracker(model, options);
           }),
           py::arg("model"), py::arg("options") = GradientTrackerOptions())
      .def("update", [](GradientTracker& t, const py::object& rss_dbm) {
             VectorArg v = ToVector(rss_dbm, "rss_dbm");
             const WifiFix f = t.Update(v.map);
             return py::make_tuple(f.position_m, f.covariance_m2, f.floor, f.neg_log_likelihood);
           },
           py::arg("rss_dbm"),
           "One scan (K,) [dBm, prepared] -> (position (2,) [m], covariance (2, 2) [m^2], floor, l).")
      .def("track", [](GradientTracker& t, const py::object& rss_dbm) {
             MatrixArg scans = ToMatrix(rss_dbm, "rss_dbm");
             std::vector<WifiFix> fixes(static_cast<size_t>(scans.map.rows()));
             {
               py::gil_scoped_release release;
               for (Eigen::Index i = 0; i < scans.map.rows(); ++i) {
                 fixes[static_cast<size_t>(i)] = t.Update(scans.map.row(i).transpose());
               }
             }
             return FixesToDict(fixes);
           },
           py::arg("rss_dbm"), "Update with each row of scans (Q, K); returns a dict of arrays.")
      .def("reset", &GradientTracker::Reset)
      .def("reset_to", &GradientTracker::ResetTo, py::arg("position_m"), py::arg("floor") = 0)
      .def_property_readonly("initialized", &GradientTracker::initialized);
}

/// Grid posteriors and maximum-likelihood location.
static void BindGridPosterior(py::module_& m) {
  const wifi::GridPosteriorOptions grid_posterior;  // the keyword defaults
  py::class_<wifi::GridPosterior>(m, "GridPosterior", R"doc(
Posterior mean and covariance of the position under the interpolated likelihood, on a grid
over each floor's hull (uniform prior). ``spacing_m <= 0``: a third of the median reference spacing.)doc")
      .def(py::init([](const std::shared_ptr<RssModel>& model, double spacing_m, int max_points_per_floor) {
             CheckArgument(model != nullptr, "model", "is None");  // a null holder would crash
             wifi::GridPosteriorOptions o;
             o.spacing_m = spacing_m;
             o.max_points_per_floor = max_points_per_floor;
             py::gil_scoped_release release;
             return std::make_unique<wifi::GridPosterior>(model, o);
           }),
           py::arg("model"), py::arg("spacing_m") = grid_posterior.spacing_m,
           py::arg("max_points_per_floor") = grid_posterior.max_points_per_floor)
      .def_property_readonly("spacing_m", &wifi::GridPosterior::spacing_m)
      .def("grid", &wifi::GridPosterior::grid, py::arg("floor_index"), "Grid points (G, 2) [m] of a floor.")
      .def("locate", [](const wifi::GridPosterior& gp, const py::object& rss_dbm, int group_size, int num_threads) {
             MatrixArg scans = ToMatrix(rss_dbm, "rss_dbm");
             CheckArgument(group_size >= 1, "group_size", "must be >= 1");
             CheckArgument(scans.map.rows() % group_size == 0, "rss_dbm", "number of rows is not a multiple of group_size");
             const int groups = static_cast<int>(scans.map.rows() / group_size);
             std::vector<WifiFix> fixes(static_cast<size_t>(groups));
             {
               py::gil_scoped_release release;
               ParallelForRuns(groups, num_threads, 0, [&](int g, RandomStream&) {
                 fixes[static_cast<size_t>(g)] =
                     gp.Locate(scans.map.middleRows(static_cast<Eigen::Index>(g) * group_size, group_size));
               });
             }
             return FixesToDict(fixes);
           },
           py::arg("rss_dbm"), py::arg("group_size") = 1, py::arg("num_threads") = 1,
           "Posterior-mean fixes of blocks of group_size scans (Q, K) [dBm, prepared]; dict as locate_ml.");

  m.def("locate_ml", [](const std::shared_ptr<RssModel>& model, const py::object& rss_dbm, int group_size,
                        const GradientTrackerOptions& options, int num_threads) {
          CheckArgument(model != nullptr, "model", "is None");  // a null holder would crash
          MatrixArg scans = ToMatrix(rss_dbm, "rss_dbm", -1, model->num_access_points());
          CheckArgument(group_size >= 1, "group_size", "must be >= 1");
          CheckArgument(scans.map.rows() % group_size == 0, "rss_dbm",
                        "number of rows is not a multiple of group_size");
          ValidateOptions(options);
          const int groups = static_cast<int>(scans.map.rows() / group_size);
          std::vector<WifiFix> fixes(static_cast<size_t>(groups));
          {
            py::gil_scoped_release release;
            ParallelForRuns(groups, num_threads, 0, [&](int g, RandomStream&) {
              fixes[static_cast<size_t>(g)] = wifi::LocateMaximumLikelihood(
                  *model, scans.map.middleRows(static_cast<Eigen::Index>(g) * group_size, group_size), options);
            });
          }
          return FixesToDict(fixes);
        },
        py::arg("model"), py::arg("rss_dbm"), py::arg("group_size") = 1,
        py::arg("options") = GradientTrackerOptions(), py::arg("num_threads") = 1, R"doc(
Global maximum-likelihood fixes. Rows of rss_dbm (Q, K) [dBm, prepared] are grouped in blocks
of ``group_size`` consecutive scans taken at one position (e.g. 10 scans at a static test point).
Returns a dict: positions_m (G, 2), covariances_m2 (G, 2, 2), floors (G,), neg_log_likelihood,
inside, iterations, fallback_steps.)doc");
}

void BindWifi(py::module_& m) {
  BindSignalMap(m);
  BindDelaunayInterpolator(m);
  BindRssModel(m);
  BindGradientTracker(m);
  BindGridPosterior(m);
}

}  // namespace indoorloc::bindings
