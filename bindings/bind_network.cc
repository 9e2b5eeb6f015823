// Python bindings of the network subsystem (paper 003): INS/GPS network adjustment, the Kalman
// smoother baseline, the cross-over finder and normal gravity. Arrays in and out as numpy; the
// GIL is released around the solves; bad input raises ValueError naming the argument.
#include <cmath>
#include <iterator>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/network/gravity.h"
#include "indoorloc/network/kalman_smoother.h"
#include "indoorloc/network/network_adjustment.h"
#include "numpy_args.h"
#include "options_binding.h"

namespace indoorloc::bindings {

namespace {

using network::NetworkObservations;
using network::NetworkState;

Eigen::VectorXi ToIndices(const py::object& obj, const char* name) {
  if (obj.is_none()) return Eigen::VectorXi(0);
  VectorArg v = ToVector(obj, name);
  Eigen::VectorXi out(v.map.size());
  for (Eigen::Index i = 0; i < v.map.size(); ++i) {
    const double x = v.map[i];
    CheckArgument(x == std::floor(x) && std::abs(x) < 2e9, name, "entry " + std::to_string(i) + " is not an integer epoch");
    out[i] = static_cast<int>(x);
  }
  return out;
}

NetworkObservations MakeObservations(const py::object& imu_time_s, const py::object& acc, const py::object& gyro,
                                     const py::object& gps_time_s, const py::object& gps_position_m,
                                     const py::object& zupt_epochs, const py::object& gupt_epochs,
                                     const py::object& gupt_gravity_mps2, const py::object& xover_epochs,
                                     const py::object& vupt_epochs = py::none(),
                                     const py::object& vupt_velocity_mps = py::none(),
                                     const py::object& vupt_sd_mps = py::none(),
                                     const py::object& sgupt_epochs = py::none()) {
  NetworkObservations o;
  VectorArg t = ToVector(imu_time_s, "imu_time_s");
  o.imu_time_s = t.map;
  o.acc_body_mps2 = ToMatrix(acc, "acc_body_mps2", t.map.size(), 3).map;
  o.gyro_body_radps = ToMatrix(gyro, "gyro_body_radps", t.map.size(), 3).map;
  VectorArg gt = ToVector(gps_time_s, "gps_time_s");
  o.gps_time_s = gt.map;
  o.gps_position_m = ToMatrix(gps_position_m, "gps_position_m", gt.map.size(), 3).map;
  o.zupt_epochs = ToIndices(zupt_epochs, "zupt_epochs");
  o.gupt_epochs = ToIndices(gupt_epochs, "gupt_epochs");
  if (gupt_gravity_mps2.is_none()) {
    o.gupt_gravity_mps2.resize(0);
  } else {
    o.gupt_gravity_mps2 = ToVector(gupt_gravity_mps2, "gupt_gravity_mps2", o.gupt_epochs.size()).map;
    // Known gravity [m/s^2]: -1e300 passed the finiteness check and the filter's attitude became NaN.
    RequireAllInRange(o.gupt_gravity_mps2, -100.0, 100.0, "gupt_gravity_mps2");
  }
  CheckArgument(o.gupt_gravity_mps2.size() == o.gupt_epochs.size(), "gupt_gravity_mps2",
                "needs one value per entry of gupt_epochs");
  o.xover_epochs.resize(0, 2);
  if (!xover_epochs.is_none()) {
    DoubleArray a = ToDoubleArray(xover_epochs, "xover_epochs");
    if (a.size() > 0) {
      MatrixArg x = ToMatrix(xover_epochs, "xover_epochs", -1, 2);
      o.xover_epochs.resize(x.map.rows(), 2);
      for (Eigen::Index i = 0; i < x.map.rows(); ++i)
        for (int k = 0; k < 2; ++k) {
          const double v = x.map(i, k);
          CheckArgument(v == std::floor(v) && std::abs(v) < 2e9, "xover_epochs",
                        "row " + std::to_string(i) + " is not a pair of integer epochs");
          o.xover_epochs(i, k) = static_cast<int>(v);
        }
    }
  }
  o.vupt_epochs = ToIndices(vupt_epochs, "vupt_epochs");
  const Eigen::Index nv = o.vupt_epochs.size();
  if (vupt_velocity_mps.is_none()) {
    CheckArgument(nv == 0, "vupt_velocity_mps", "needs one row per entry of vupt_epochs");
    o.vupt_velocity_mps.resize(0, 3);
  } else {
    o.vupt_velocity_mps = ToMatrix(vupt_velocity_mps, "vupt_velocity_mps", nv, 3).map;
  }
  if (!vupt_sd_mps.is_none()) o.vupt_sd_mps = ToVector(vupt_sd_mps, "vupt_sd_mps", nv).map;
  o.sgupt_epochs = ToIndices(sgupt_epochs, "sgupt_epochs");
  return o;
}

NetworkState MakeState(const py::dict& d, Eigen::Index rows) {
  auto get = [&](const char* key) -> py::object {
    if (!d.contains(key)) ThrowInvalidArgument("initial", std::string("missing key '") + key + "'");
    return d[key];
  };
  NetworkState s;
  s.position_m = ToMatrix(get("position_m"), "initial.position_m", rows, 3).map;
  s.velocity_mps = ToMatrix(get("velocity_mps"), "initial.velocity_mps", rows, 3).map;
  s.attitude_wxyz = ToMatrix(get("attitude_wxyz"), "initial.attitude_wxyz", rows, 4).map;
  s.acc_bias_mps2 = ToMatrix(get("acc_bias_mps2"), "initial.acc_bias_mps2", rows, 3).map;
  s.gyro_bias_radps = ToMatrix(get("gyro_bias_radps"), "initial.gyro_bias_radps", rows, 3).map;
  s.gravity_disturbance_mps2 = ToVector(get("gravity_disturbance_mps2"), "initial.gravity_disturbance_mps2", rows).map;
  return s;
}

py::dict StateDict(const NetworkState& s) {
  py::dict d;
  d["position_m"] = s.position_m;
  d["velocity_mps"] = s.velocity_mps;
  d["attitude_wxyz"] = s.attitude_wxyz;
  d["acc_bias_mps2"] = s.acc_bias_mps2;
  d["gyro_bias_radps"] = s.gyro_bias_radps;
  d["gravity_disturbance_mps2"] = s.gravity_disturbance_mps2;
  if (s.gravity_disturbance_sd_mps2.size() > 0) d["gravity_disturbance_sd_mps2"] = s.gravity_disturbance_sd_mps2;
  return d;
}

constexpr const char* kObservationsDoc = R"doc(
imu_time_s : (N,) uniformly sampled, strictly increasing [s]
acc_body_mps2, gyro_body_radps : (N, 3) specific force [m/s^2] and angular rate [rad/s], body frame
gps_time_s : (M,) inside the IMU span [s]; gps_position_m : (M, 3) ENU [m]
zupt_epochs : (Z,) int epochs with zero velocity, or None
gupt_epochs : (G,) int epochs with known gravity; gupt_gravity_mps2 : (G,) total gravity [m/s^2]
xover_epochs : (K, 2) int epoch pairs with equal gravity disturbance (see find_crossovers), or None)doc";

constexpr const char* kStaticDoc = R"doc(
vupt_epochs : (V,) int epochs with known velocity (VUPT), or None
vupt_velocity_mps : (V, 3) known ENU velocities v0 [m/s] (required with vupt_epochs)
vupt_sd_mps : (V,) sd per axis [m/s] (> 0), or None: options.sigma_vupt_mps
sgupt_epochs : (S,) int static epochs with constant gravity (SGUPT, paper §3.2), strictly
    increasing; each must carry a ZUPT or a VUPT with zero velocity; each run of consecutive
    epochs is one static period, tied delta_g[n] = delta_g[n0] to its first epoch. Or None)doc";

/// The arguments of a solver that are not observations (the rest of a former call is).
bool IsSolverArgument(const std::string& name) { return name == "initial" || name == "options" || name == "model"; }

/// The former call form of a solver that took the observation arrays one by one (`old_order`:
/// its positional order): warns, gathers them into a NetworkObservations and calls the new form.
py::object CallWithGatheredObservations(const py::module_& m, const char* function,
                                        const std::vector<const char*>& old_order, const py::args& args,
                                        const py::kwargs& kwargs) {
  // A call of the new form that reached here has an argument of the wrong type: say so, as
  // pybind11 would, instead of reading the observations as the first former argument.
  if ((args.size() > 0 && py::isinstance(args[0], m.attr("NetworkObservations"))) || kwargs.contains("observations")) {
    std::string got;
    for (const py::handle a : args) got += (got.empty() ? "" : ", ") + std::string(py::str(py::type::of(a).attr("__name__")));
    for (const auto& [key, v] : kwargs)
      got += (got.empty() ? "" : ", ") + std::string(py::str(key)) + "=" + std::string(py::str(py::type::of(v).attr("__name__")));
    throw py::type_error(std::string(function) + "(): incompatible function arguments; see help(" + function +
                         ") for the types of observations, initial and the options. Invoked with: " + got);
  }
  const std::string message = std::string("indoorloc: ") + function +
                              "(imu_time_s, acc_body_mps2, ..., zupt_epochs=...) with the observation arrays one by "
                              "one is deprecated since house (issue 27): pass " + function +
                              "(NetworkObservations(imu_time_s, acc_body_mps2, ...), initial, ...)";
  if (PyErr_WarnEx(PyExc_DeprecationWarning, message.c_str(), 1) != 0) throw py::error_already_set();
  if (args.size() > old_order.size())
    throw py::type_error(std::string(function) + " takes at most " + std::to_string(old_order.size()) + " positional arguments");
  py::dict observations, rest;
  for (std::size_t i = 0; i < args.size(); ++i) (IsSolverArgument(old_order[i]) ? rest : observations)[old_order[i]] = args[i];
  for (const auto& [key, v] : kwargs) {
    py::dict& into = IsSolverArgument(py::str(key)) ? rest : observations;
    if (into.contains(key)) throw py::type_error(std::string(function) + " got multiple values for argument '" + std::string(py::str(key)) + "'");
    into[key] = v;
  }
  return m.attr(function)(m.attr("NetworkObservations")(**observations), **rest);
}

}  // namespace

/// Options of the network adjustment and of the Kalman smoother baseline.
static void BindNetworkOptions(py::module_& m) {
  py::class_<network::NetworkOptions> network_options(m, "NetworkOptions", R"doc(
Options of the network adjustment (see cpp/include/indoorloc/network/network_adjustment.h).
discretization: "leapfrog" (paper §3.3; decouples even and odd epochs) or "trapezoidal".
Noise densities: acc_noise_mps2_rthz [m/s^2/sqrt(Hz)], gyro_noise_radps_rthz [rad/s/sqrt(Hz)],
random walks acc_bias_walk_mps2_rts, gyro_bias_walk_radps_rts, gravity_walk_mps2_rts [unit/sqrt(s)];
sigmas of VEL, CUPT, ZUPT, GUPT, XOVER, VUPT, SGUPT; slow_parameter_stride (paper §4); solver
tolerances; check_datum. Set fields by keyword (``NetworkOptions(sigma_gps_m=0.5)``); ``replace``,
``to_dict``, equality and pickling as for every Options class.)doc");
  network_options
      .def_property(
          "discretization",
          [](const network::NetworkOptions& o) {
            return std::string(o.discretization == network::Discretization::kLeapFrog ? "leapfrog" : "trapezoidal");
          },
          [](network::NetworkOptions& o, const std::string& v) {
            if (v == "leapfrog") o.discretization = network::Discretization::kLeapFrog;
            else if (v == "trapezoidal") o.discretization = network::Discretization::kTrapezoidal;
            else ThrowInvalidArgument("discretization", "expected 'leapfrog' or 'trapezoidal', got '" + v + "'");
          })
      .def_readwrite("latitude_rad", &network::NetworkOptions::latitude_rad)
      .def_readwrite("origin_height_m", &network::NetworkOptions::origin_height_m)
      .def_readwrite("earth_rate_radps", &network::NetworkOptions::earth_rate_radps)
      .def_readwrite("acc_noise_mps2_rthz", &network::NetworkOptions::acc_noise_mps2_rthz)
      .def_readwrite("gyro_noise_radps_rthz", &network::NetworkOptions::gyro_noise_radps_rthz)
      .def_readwrite("acc_bias_walk_mps2_rts", &network::NetworkOptions::acc_bias_walk_mps2_rts)
      .def_readwrite("gyro_bias_walk_radps_rts", &network::NetworkOptions::gyro_bias_walk_radps_rts)
      .def_readwrite("gravity_walk_mps2_rts", &network::NetworkOptions::gravity_walk_mps2_rts)
      .def_readwrite("acc_bias_correlation_time_s", &network::NetworkOptions::acc_bias_correlation_time_s,
                     "0: random-walk accelerometer bias; > 0: first-order Gauss-Markov with this time [s].")
      .def_readwrite("gyro_bias_correlation_time_s", &network::NetworkOptions::gyro_bias_correlation_time_s,
                     "0: random-walk gyro bias; > 0: first-order Gauss-Markov with this time [s].")
      .def_readwrite("sigma_vel_mps", &network::NetworkOptions::sigma_vel_mps)
      .def_readwrite("sigma_gps_m", &network::NetworkOptions::sigma_gps_m)
      .def_readwrite("sigma_zupt_mps", &network::NetworkOptions::sigma_zupt_mps)
      .def_readwrite("sigma_gupt_mps2", &network::NetworkOptions::sigma_gupt_mps2)
      .def_readwrite("sigma_xover_mps2", &network::NetworkOptions::sigma_xover_mps2)
      .def_readwrite("sigma_vupt_mps", &network::NetworkOptions::sigma_vupt_mps,
                     "VUPT sd per axis [m/s] for observations without their own vupt_sd_mps (default 0.01).")
      .def_readwrite("sigma_sgupt_mps2", &network::NetworkOptions::sigma_sgupt_mps2,
                     "SGUPT sd [m/s^2] of each tie delta_g[n] - delta_g[n0] in a static period (default 1e-6 = 0.1 mGal).")
      .def_readwrite("slow_parameter_stride", &network::NetworkOptions::slow_parameter_stride,
                     "Slow parameters (paper §4): one accelerometer-bias, gyro-bias and delta_g block per this many "
                     "IMU epochs (piecewise constant; 1 = every epoch, the default; e.g. IMU rate / GPS rate). "
                     "Unknowns 9 N + 7 ceil(N / stride) instead of 16 N.")
      .def_readwrite("gps_huber_threshold", &network::NetworkOptions::gps_huber_threshold)
      .def_readwrite("max_iterations", &network::NetworkOptions::max_iterations)
      .def_readwrite("initial_trust_region_radius", &network::NetworkOptions::initial_trust_region_radius)
      .def_readwrite("function_tolerance", &network::NetworkOptions::function_tolerance)
      .def_readwrite("gradient_tolerance", &network::NetworkOptions::gradient_tolerance)
      .def_readwrite("parameter_tolerance", &network::NetworkOptions::parameter_tolerance)
      .def_readwrite("num_threads", &network::NetworkOptions::num_threads)
      .def_readwrite("check_datum", &network::NetworkOptions::check_datum)
      .def_readwrite("datum_pivot_tolerance", &network::NetworkOptions::datum_pivot_tolerance)
      .def_property(
          "gravity_covariance",
          [](const network::NetworkOptions& o) {
            switch (o.gravity_covariance) {
              case network::NetworkOptions::Covariance::kCeres: return std::string("ceres");
              case network::NetworkOptions::Covariance::kDense: return std::string("dense");
              default: return std::string("none");
            }
          },
          [](network::NetworkOptions& o, const std::string& v) {
            if (v == "none") o.gravity_covariance = network::NetworkOptions::Covariance::kNone;
            else if (v == "ceres") o.gravity_covariance = network::NetworkOptions::Covariance::kCeres;
            else if (v == "dense") o.gravity_covariance = network::NetworkOptions::Covariance::kDense;
            else ThrowInvalidArgument("gravity_covariance", "expected 'none', 'ceres' or 'dense', got '" + v + "'");
          },
          "Standard deviations of every δg: 'none', 'ceres' (ceres::Covariance, SPARSE_QR) or 'dense' (reference, <= 8,000 unknowns).")
      .def_readwrite("variance_components", &network::NetworkOptions::variance_components,
                     "Variance factors of the acc, gyro and GPS groups in the summary (dense: <= 8,000 unknowns).")
      .def("is_valid", [](const network::NetworkOptions& o) {
        std::string e;
        return o.IsValid(&e) ? std::string() : e;
      }, "'' when valid, else the reason.");
  BindOptionsProtocol(network_options, "NetworkOptions");

  py::class_<network::KalmanSmootherOptions> kalman_smoother_options(
      m, "KalmanSmootherOptions", "Initial standard deviations of the SSA filter and whether to smooth; fields by keyword.");
  kalman_smoother_options
      .def_readwrite("init_sigma_position_m", &network::KalmanSmootherOptions::init_sigma_position_m)
      .def_readwrite("init_sigma_velocity_mps", &network::KalmanSmootherOptions::init_sigma_velocity_mps)
      .def_readwrite("init_sigma_level_rad", &network::KalmanSmootherOptions::init_sigma_level_rad)
      .def_readwrite("init_sigma_heading_rad", &network::KalmanSmootherOptions::init_sigma_heading_rad)
      .def_readwrite("init_sigma_acc_bias_mps2", &network::KalmanSmootherOptions::init_sigma_acc_bias_mps2)
      .def_readwrite("init_sigma_gyro_bias_radps", &network::KalmanSmootherOptions::init_sigma_gyro_bias_radps)
      .def_readwrite("init_sigma_gravity_mps2", &network::KalmanSmootherOptions::init_sigma_gravity_mps2)
      .def_readwrite("smooth", &network::KalmanSmootherOptions::smooth);
  BindOptionsProtocol(kalman_smoother_options, "KalmanSmootherOptions");
}

/// The observations of a flight, gathered and checked once for both solvers.
static void BindNetworkObservations(py::module_& m) {
  py::class_<NetworkObservations>(m, "NetworkObservations", (std::string(R"doc(
The observations of a flight for solve_network and kalman_smoother, checked once (ValueError
naming the argument): NetworkObservations(imu_time_s, acc_body_mps2, gyro_body_radps, gps_time_s,
gps_position_m, zupt_epochs=None, gupt_epochs=None, gupt_gravity_mps2=None, xover_epochs=None,
vupt_epochs=None, vupt_velocity_mps=None, vupt_sd_mps=None, sgupt_epochs=None).
)doc") + kObservationsDoc + kStaticDoc).c_str())
      .def(py::init(&MakeObservations), py::arg("imu_time_s"), py::arg("acc_body_mps2"), py::arg("gyro_body_radps"),
           py::arg("gps_time_s"), py::arg("gps_position_m"), py::arg("zupt_epochs") = py::none(),
           py::arg("gupt_epochs") = py::none(), py::arg("gupt_gravity_mps2") = py::none(),
           py::arg("xover_epochs") = py::none(), py::arg("vupt_epochs") = py::none(),
           py::arg("vupt_velocity_mps") = py::none(), py::arg("vupt_sd_mps") = py::none(),
           py::arg("sgupt_epochs") = py::none())
      .def_property_readonly("num_imu_epochs", [](const NetworkObservations& o) { return o.imu_time_s.size(); })
      .def_property_readonly("num_gps_epochs", [](const NetworkObservations& o) { return o.gps_time_s.size(); })
      .def("__repr__", [](const NetworkObservations& o) {
        return "NetworkObservations(" + std::to_string(o.imu_time_s.size()) + " IMU epochs, " +
               std::to_string(o.gps_time_s.size()) + " GPS fixes, " + std::to_string(o.zupt_epochs.size()) + " ZUPT, " +
               std::to_string(o.gupt_epochs.size()) + " GUPT, " + std::to_string(o.xover_epochs.rows()) + " XOVER, " +
               std::to_string(o.vupt_epochs.size()) + " VUPT, " + std::to_string(o.sgupt_epochs.size()) + " SGUPT)";
      });
}

/// solve_network and the kalman_smoother baseline.
static void BindNetworkSolvers(py::module_& m) {
  m.def("solve_network",
        [](const NetworkObservations& obs, const py::dict& initial, const network::NetworkOptions& options) {
          ValidateOptions(options);
          const NetworkState init = MakeState(initial, obs.imu_time_s.size());
          network::NetworkSummary s;
          NetworkState out;
          {
            py::gil_scoped_release release;
            out = network::SolveNetwork(obs, init, options, &s);
          }
          py::dict summary;
          summary["termination"] = std::string(ToString(s.termination));
          summary["iterations"] = s.iterations;
          summary["initial_cost"] = s.initial_cost;
          summary["final_cost"] = s.final_cost;
          summary["seconds_total"] = s.seconds_total;
          summary["seconds_solve"] = s.seconds_solve;
          summary["seconds_datum_check"] = s.seconds_datum_check;
          summary["num_epochs"] = s.num_epochs;
          summary["num_parameters"] = s.num_parameters;
          summary["num_residuals"] = s.num_residuals;
          summary["num_xover"] = s.num_xover;
          summary["num_slow_nodes"] = s.num_slow_nodes;
          summary["num_vupt"] = s.num_vupt;
          summary["num_sgupt"] = s.num_sgupt;
          summary["min_pivot_ratio"] = s.min_pivot_ratio;
          summary["variance_factor"] = s.variance_factor;
          summary["variance_factor_acc"] = s.variance_factor_acc;
          summary["variance_factor_gyro"] = s.variance_factor_gyro;
          summary["variance_factor_gps"] = s.variance_factor_gps;
          summary["redundancy_acc"] = s.redundancy_acc;
          summary["redundancy_gyro"] = s.redundancy_gyro;
          summary["redundancy_gps"] = s.redundancy_gps;
          summary["seconds_covariance"] = s.seconds_covariance;
          summary["message"] = s.message;
          summary["brief_report"] = s.BriefReport();
          return py::make_tuple(StateDict(out), summary);
        },
        py::arg("observations"), py::arg("initial"), py::arg("options") = network::NetworkOptions(),
        R"doc(
INS/GPS network adjustment (paper 003): every epoch's position, velocity, attitude, biases and
vertical gravity disturbance from one sparse least-squares network (Ceres, SuiteSparse).
observations : NetworkObservations (IMU, GPS and the update epochs, checked once)
initial : dict of initial values, keys position_m (N, 3), velocity_mps (N, 3), attitude_wxyz (N, 4),
          acc_bias_mps2 (N, 3), gyro_bias_radps (N, 3), gravity_disturbance_mps2 (N,)
          (with options.slow_parameter_stride > 1 the biases and delta_g are averaged per interval)
Returns (state dict with the same keys, one row per IMU epoch: with slow parameters the epochs of
an interval share the values; summary dict with num_parameters, num_slow_nodes, num_xover,
num_vupt, num_sgupt, timings, ...). Raises ValueError naming the argument for bad input and for
datum defects (rank-deficient networks). The former form with the observation arrays as
arguments (solve_network(imu_time_s, ..., initial, ...)) still works and warns (deprecated).)doc");
  m.def("solve_network", [m](const py::args& args, const py::kwargs& kwargs) {
    return CallWithGatheredObservations(
        m, "solve_network",
        {"imu_time_s", "acc_body_mps2", "gyro_body_radps", "gps_time_s", "gps_position_m", "initial", "zupt_epochs",
         "gupt_epochs", "gupt_gravity_mps2", "xover_epochs", "options", "vupt_epochs", "vupt_velocity_mps",
         "vupt_sd_mps", "sgupt_epochs"},
        args, kwargs);
  });

  m.def("kalman_smoother",
        [](const NetworkObservations& obs, const py::dict& initial, const network::NetworkOptions& model,
           const network::KalmanSmootherOptions& options) {
          ValidateOptions(model, "model");
          ValidateOptions(options);
          const NetworkState init = MakeState(initial, 1);
          network::KalmanSmootherSummary s;
          NetworkState out, filtered;
          {
            py::gil_scoped_release release;
            out = network::RunKalmanSmoother(obs, init, model, options, &s, &filtered);
          }
          py::dict summary;
          summary["num_epochs"] = s.num_epochs;
          summary["num_updates"] = s.num_updates;
          summary["num_xover_ignored"] = s.num_xover_ignored;
          summary["seconds_filter"] = s.seconds_filter;
          summary["seconds_smoother"] = s.seconds_smoother;
          summary["brief_report"] = s.BriefReport();
          return py::make_tuple(StateDict(out), StateDict(filtered), summary);
        },
        py::arg("observations"), py::arg("initial"), py::arg("model") = network::NetworkOptions(),
        py::arg("options") = network::KalmanSmootherOptions(), R"doc(
State-space baseline (SSA): error-state EKF + RTS smoother with the model and noise densities of
`model`. Same observations as solve_network (NetworkObservations); XOVER cannot enter a filter
and is only counted; VUPT and SGUPT are not used.
initial : dict with the keys of solve_network, shape (1, .) or (N, .): only row 0 is used.
Returns (smoothed state dict, filtered state dict, summary dict). The former form with the
observation arrays as arguments still works and warns (deprecated).)doc");
  m.def("kalman_smoother", [m](const py::args& args, const py::kwargs& kwargs) {
    return CallWithGatheredObservations(
        m, "kalman_smoother",
        {"imu_time_s", "acc_body_mps2", "gyro_body_radps", "gps_time_s", "gps_position_m", "initial", "zupt_epochs",
         "gupt_epochs", "gupt_gravity_mps2", "xover_epochs", "model", "options"},
        args, kwargs);
  });
}

/// Cross-overs of a trajectory, normal gravity and the earth rate.
static void BindNetworkGeodesy(py::module_& m) {
  m.def("find_crossovers",
        [](const py::object& time_s, const py::object& position_m, double radius_m, double max_dh, double min_sep) {
          VectorArg t = ToVector(time_s, "time_s");
          MatrixArg p = ToMatrix(position_m, "position_m", t.map.size(), 3);
          network::CrossoverOptions o;
          o.radius_m = radius_m;
          o.max_height_difference_m = max_dh;
          o.min_separation_s = min_sep;
          network::RowMatrixX2i x;
          {
            py::gil_scoped_release release;
            x = network::FindCrossovers(t.map, p.map, o);
          }
          return Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor>(x);
        },
        py::arg("time_s"), py::arg("position_m"), py::arg("radius_m") = network::CrossoverOptions().radius_m,
        py::arg("max_height_difference_m") = network::CrossoverOptions().max_height_difference_m,
        py::arg("min_separation_s") = network::CrossoverOptions().min_separation_s, R"doc(
Cross-overs of a trajectory: (K, 2) int epoch pairs (n < k) at most radius_m apart horizontally,
|dh| <= max_height_difference_m, at least min_separation_s apart in time; one (the closest) per
crossing of two passes. time_s (N,) [s], position_m (N, 3) ENU [m].)doc");

  m.def("normal_gravity",
        [](double latitude_rad, const py::object& height_m) {
          VectorArg h = ToVector(height_m, "height_m");
          RequireInRange(latitude_rad, -1.5707963267948966, 1.5707963267948966, "latitude_rad");
          // The height term is quadratic: beyond ±1e7 m (far outside the model's validity) it overflows.
          RequireAllInRange(h.map, -1e7, 1e7, "height_m");
          Eigen::VectorXd g(h.map.size());
          for (Eigen::Index i = 0; i < g.size(); ++i) g[i] = network::NormalGravity(latitude_rad, h.map[i]);
          return ToNumpy(g);
        },
        py::arg("latitude_rad"), py::arg("height_m"),
        "GRS80 normal gravity (Somigliana + second-order height term) [m/s^2] at heights (H,) [m].");
  m.def("earth_rate_enu", [](double latitude_rad) {
          RequireInRange(latitude_rad, -1.5707963267948966, 1.5707963267948966, "latitude_rad");
          return Eigen::Vector3d(network::EarthRateEnu(latitude_rad));
        },
        py::arg("latitude_rad"), "Earth rotation vector (3,) in the local ENU frame [rad/s].");
}

void BindNetwork(py::module_& m) {
  BindNetworkOptions(m);
  BindNetworkObservations(m);
  BindNetworkSolvers(m);
  BindNetworkGeodesy(m);
}

}  // namespace indoorloc::bindings
