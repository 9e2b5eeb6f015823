// Bindings of the network subsystem's scale path: the streaming block-tridiagonal solver on the
// linearised INS/GPS network (indoorloc/network/linear_ins_network.h), for the Table 2 benchmark.
// Every function takes the network first (LinearInsNetworkOptions, bound once here: its size and
// noise model; DefOnNetwork, which also keeps the former form with the fields as arguments) and
// returns a typed result (bind_network_scale_results.cc).
#include <optional>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "indoorloc/core/check.h"
#include "indoorloc/core/interrupt.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/network/linear_ins_ceres.h"
#include "indoorloc/network/folded_network.h"
#include "indoorloc/network/linear_ins_network.h"
#include "options_binding.h"

namespace py = pybind11;

namespace indoorloc::bindings {

namespace {

/// The name the `rule` field gives a discretisation.
std::string RuleName(network::Discretisation rule) {
  return rule == network::Discretisation::kLeapFrog ? "leapfrog" : "trapezoidal";
}

/// A benchmark scenario's own network size (its IMU and GPS rates and duration); the rest are
/// the struct's defaults.
network::LinearInsNetworkOptions Scenario(double imu_rate_hz, double duration_s, double gps_rate_hz) {
  network::LinearInsNetworkOptions o;
  o.imu_rate_hz = imu_rate_hz;
  o.duration_s = duration_s;
  o.gps_rate_hz = gps_rate_hz;
  return o;
}

/// The former call form of a scale function, whose network fields (imu_rate_hz, duration_s,
/// gps_rate_hz, rule, and prior_epochs or sigma_gupt_mps2 for some) were arguments of their own
/// (`old_order`: its positional order): warns, gathers them into a LinearInsNetworkOptions
/// starting from `base` (the function's default network) and calls the new form.
py::object CallWithGatheredNetwork(const py::module_& m, const char* function, const std::vector<const char*>& old_order,
                                   const network::LinearInsNetworkOptions& base, const py::args& args,
                                   const py::kwargs& kwargs) {
  const py::object network_type = m.attr("LinearInsNetworkOptions");
  if ((args.size() > 0 && py::isinstance(args[0], network_type)) || kwargs.contains("network")) {
    throw py::type_error(std::string(function) + "(): incompatible function arguments; see help(" + function +
                         ") for the types of network and the other arguments");
  }
  const std::string message = std::string("indoorloc: ") + function +
                              "(imu_rate_hz, duration_s, gps_rate_hz, rule, ...) with the network's fields as "
                              "arguments is deprecated since house (issue 27): pass " + function +
                              "(LinearInsNetworkOptions(imu_rate_hz=..., ...), ...)";
  if (PyErr_WarnEx(PyExc_DeprecationWarning, message.c_str(), 1) != 0) throw py::error_already_set();
  if (args.size() > old_order.size())
    throw py::type_error(std::string(function) + " takes at most " + std::to_string(old_order.size()) + " positional arguments");
  const py::object fields = py::cast(base).attr("to_dict")();
  py::dict network_fields, rest;
  const auto put = [&](const py::str& key, const py::handle& value) {
    py::dict& into = fields.contains(key) ? network_fields : rest;
    if (into.contains(key)) throw py::type_error(std::string(function) + " got multiple values for argument '" + std::string(key) + "'");
    into[key] = value;
  };
  for (std::size_t i = 0; i < args.size(); ++i) put(py::str(old_order[i]), args[i]);
  for (const auto& [key, value] : kwargs) put(py::str(key), value);
  return m.attr(function)(py::cast(base).attr("replace")(**network_fields), **rest);
}

/// Binds `f(network, ...)` as `name`, the network (LinearInsNetworkOptions, default `base`) first
/// and then `extra` (the function's own py::arg, its docstring); and the former form, the
/// network's fields as arguments in `old_order`, which warns (CallWithGatheredNetwork).
template <typename F, typename... Extra>
void DefOnNetwork(py::module_& m, const char* name, F&& f, const network::LinearInsNetworkOptions& base,
                  std::vector<const char*> old_order, Extra&&... extra) {
  m.def(name, std::forward<F>(f), py::arg("network") = base, std::forward<Extra>(extra)...);
  m.def(name, [m, name, old_order, base](const py::args& args, const py::kwargs& kwargs) {
    return CallWithGatheredNetwork(m, name, old_order, base, args, kwargs);
  });
}

/// The network's size and noise model, bound once: its defaults are the C++ struct's.
void BindLinearInsNetworkOptions(py::module_& m) {
  using O = network::LinearInsNetworkOptions;
  py::class_<O> cls(m, "LinearInsNetworkOptions", R"doc(
The linearised INS/GPS network of the scale path (linear_ins_network.h): its size (imu_rate_hz,
duration_s, gps_rate_hz, rule "leapfrog" or "trapezoidal", prior_epochs) and noise model (the
densities of the dynamic equation groups, sigma_gps_m, sigma_prior, gupt_end_epochs,
sigma_gupt_mps2, specific_force_mps2). Fields by keyword; defaults: the C++ struct's
(``LinearInsNetworkOptions().to_dict()``).)doc");
  cls.def_readwrite("imu_rate_hz", &O::imu_rate_hz, "[Hz]")
      .def_readwrite("duration_s", &O::duration_s, "[s]; epochs = round(duration_s * imu_rate_hz) + 1.")
      .def_readwrite("gps_rate_hz", &O::gps_rate_hz, "CUPT rate [Hz].")
      .def_property("rule", [](const O& o) { return RuleName(o.rule); },
                    [](O& o, const std::string& v) {
                      CheckArgument(v == "leapfrog" || v == "trapezoidal", "rule",
                                    "must be 'leapfrog' or 'trapezoidal', got '" + v + "'");
                      o.rule = v == "leapfrog" ? network::Discretisation::kLeapFrog : network::Discretisation::kTrapezoidal;
                    }, "'leapfrog' or 'trapezoidal'.")
      .def_readwrite("prior_epochs", &O::prior_epochs, "Epochs at the start with an alignment prior on every unknown.")
      .def_property("specific_force_mps2",
                    [](const O& o) { return std::vector<double>(o.specific_force_mps2, o.specific_force_mps2 + 3); },
                    [](O& o, const std::vector<double>& f) {
                      CheckArgument(f.size() == 3, "specific_force_mps2", "needs 3 values, got " + std::to_string(f.size()));
                      for (int k = 0; k < 3; ++k) o.specific_force_mps2[k] = f[k];
                    },
                    "[x, y, z] [m/s²] (a list: equality and to_dict stay plain).")
      .def_readwrite("velocity_density", &O::velocity_density, "[m/s/√Hz]")
      .def_readwrite("accel_density", &O::accel_density, "[m/s²/√Hz]")
      .def_readwrite("gyro_density", &O::gyro_density, "[rad/s/√Hz]")
      .def_readwrite("accel_bias_density", &O::accel_bias_density, "[m/s³/√Hz]")
      .def_readwrite("gyro_bias_density", &O::gyro_bias_density, "[rad/s²/√Hz]")
      .def_readwrite("gravity_density", &O::gravity_density, "[m/s³/√Hz]")
      .def_readwrite("sigma_gps_m", &O::sigma_gps_m, "CUPT [m].")
      .def_readwrite("sigma_prior", &O::sigma_prior, "Alignment prior (all units).")
      .def_readwrite("gupt_end_epochs", &O::gupt_end_epochs, "GUPT on the last epochs.")
      .def_readwrite("sigma_gupt_mps2", &O::sigma_gupt_mps2, "[m/s²]");
  BindOptionsProtocol(cls, "LinearInsNetworkOptions");
}

}  // namespace

void BindNetworkScaleResults(py::module_& m);

/// The folded repeated-pass network (block-tridiagonal elimination with checkpoints).
static void BindFoldedNetwork(py::module_& m) {
  const network::LinearInsNetworkOptions linear;
  const network::FoldedNetworkOptions folded;
  DefOnNetwork(
      m, "solve_folded_linear_ins_network",
      [](network::LinearInsNetworkOptions o, long long num_ties, long long num_gupts, double sigma_xover_mps2,
         int checkpoint_interval, bool gravity_covariance, bool keep_gravity_estimate, int num_threads) {
        ValidateOptions(o, "network");  // before any layout or allocation sized by rate x duration
        const double sigma_gupt_mps2 = o.sigma_gupt_mps2;
        o.gupt_end_epochs = 0;  // every GUPT comes from the layout, so the count is num_gupts
        // Tie and GUPT sds enter as 1/sigma^2 next to the IMU densities (about 1e-5): beyond
        // [1e-9, 1e3] the weights leave double precision's range ('ties'/'assemble' errors).
        RequireInRange(sigma_xover_mps2, 1e-9, 1e3, "sigma_xover_mps2");
        RequireInRange(sigma_gupt_mps2, 1e-9, 1e3, "sigma_gupt_mps2");
        network::FoldedNetworkOptions fo;
        fo.checkpoint_interval = checkpoint_interval;
        fo.gravity_covariance = gravity_covariance;
        fo.keep_gravity_estimate = keep_gravity_estimate;
        fo.num_threads = num_threads;
        ValidateOptions(fo);
        network::FoldedNetworkResult r;
        {
          py::gil_scoped_release release;
          const network::RepeatedPassLayout layout =
              network::MakeRepeatedPassLayout(o, num_ties, num_gupts, sigma_xover_mps2, sigma_gupt_mps2);
          r = network::SolveFoldedLinearInsNetwork(o, layout.ties, layout.gupts, fo);
        }
        return r;
      },
      Scenario(50.0, 60.0, 2.0),
      {"imu_rate_hz", "duration_s", "gps_rate_hz", "rule", "num_ties", "num_gupts", "sigma_xover_mps2", "sigma_gupt_mps2",
       "checkpoint_interval", "gravity_covariance", "keep_gravity_estimate", "num_threads"},
      py::arg("num_ties") = 1000, py::arg("num_gupts") = 10,
      py::arg("sigma_xover_mps2") = 1e-5, py::arg("checkpoint_interval") = folded.checkpoint_interval,
      py::arg("gravity_covariance") = folded.gravity_covariance, py::arg("keep_gravity_estimate") = folded.keep_gravity_estimate, py::arg("num_threads") = folded.num_threads, R"doc(
The linearised INS/GPS network of a survey re-flown in reverse over its own track, with
cross-over ties between the two passes and GUPTs, solved exactly (no iteration) by the
block-tridiagonal Cholesky in the folded order (super-block k = base blocks m-1-k and m+k,
block size 72 for leap-frog), with the covariance of every δg (selected inversion).
Paper Table 2 case 4: network=LinearInsNetworkOptions(imu_rate_hz=50, duration_s=565049/50,
gps_rate_hz=2) (565,050 epochs), num_ties=332150, num_gupts=1907.

Parameters
----------
network : LinearInsNetworkOptions
    Size [Hz, s, Hz]; epochs = round(duration_s * imu_rate_hz) + 1 (leap-frog: even); rule;
    network.sigma_gupt_mps2 is the GUPTs' sd. Default: 50 Hz, 60 s, 2 Hz GPS.
num_ties : int
    Scalar XOVER ties δg_z[t] - δg_z[E-1-t] (every mirror pair first, then ties to the
    mirror's neighbour E-2-t), at most ⌊E/2⌋ + ⌊(E-1)/2⌋.
num_gupts : int
    Scalar GUPTs on δg_z evenly spread over the flight (no other GUPT).
sigma_xover_mps2 : float
    Standard deviation of a tie [m/s²] (1e-5 = 1 mGal).
checkpoint_interval : int
    0 keeps the whole factor (2 K 72² doubles); k > 0 one checkpoint every k super-blocks.
gravity_covariance, keep_gravity_estimate : bool
num_threads : int
    Threads for the two chains of the twisted elimination (1 or 2; <= 0: all cores). The
    results are bit-identical on any count.

Returns
-------
FoldedNetworkResult (read-only attributes; reading it as the former dict is deprecated):
imu_epochs, gps_epochs, unknowns, ties, gupts, equations, folded_blocks,
folded_block_size, factor_seconds, backward_seconds, total_seconds [s], stored_factor_bytes,
min_relative_pivot, max_abs_error (every unknown, against the noise-free truth), gravity_rmse
[m/s²], gravity_sigma (E, 3) [m/s²], gravity_estimate (E, 3) [m/s²] or empty, report.)doc");
}

/// The survey network with cross-over ties, solved by PCG.
static void BindCrossoverNetwork(py::module_& m) {
  const network::LinearInsNetworkOptions linear;
  const network::TiedSolveOptions tied_solve;
  DefOnNetwork(
      m, "solve_linear_ins_network_with_crossovers",
      [](const network::LinearInsNetworkOptions& o, int lines, int cross_lines, double sigma_xover_mps2, int max_iterations,
         double relative_tolerance) {
        ValidateOptions(o, "network");
        RequireInRange(sigma_xover_mps2, 1e-9, 1e3, "sigma_xover_mps2");
        // 2**31 - 1 lines overflowed lines + cross_lines (an int) and ended in std::bad_alloc.
        RequireIntInRange(lines, 1, 1000000, "lines");
        RequireIntInRange(cross_lines, 1, 1000000, "cross_lines");
        // The PCG keeps the whole banded factor (two b x b blocks per block row). Budget: 16 GB,
        // which holds Table 2 case 4 (about 6 GB); 1.6e8 epochs used to allocate until the
        // machine ran out of memory.
        const network::NetworkSize size = network::LinearInsNetworkSize(o);
        RequireSizeLimit(static_cast<double>(size.num_blocks), 2.0 * size.block_size * size.block_size * 8.0,
                         "duration_s", "block rows of the stored factor (duration_s x imu_rate_hz)", 16e9);
        network::TiedSolveOptions pcg;
        pcg.max_iterations = max_iterations;
        pcg.relative_tolerance = relative_tolerance;
        network::CrossoverNetworkResult r;
        {
          py::gil_scoped_release release;
          r = network::SolveLinearInsNetworkWithCrossovers(o, lines, cross_lines, sigma_xover_mps2, pcg);
        }
        return r;
      },
      Scenario(50.0, 600.0, 2.0),
      {"imu_rate_hz", "duration_s", "gps_rate_hz", "rule", "lines", "cross_lines", "sigma_xover_mps2", "max_iterations",
       "relative_tolerance"},
      py::arg("lines") = 10, py::arg("cross_lines") = 10,
      py::arg("sigma_xover_mps2") = 1e-5, py::arg("max_iterations") = tied_solve.max_iterations, py::arg("relative_tolerance") = tied_solve.relative_tolerance, R"doc(
The linearised INS/GPS network with cross-over ties of a grid survey (`lines` East-West lines,
then `cross_lines` North-South lines; each crossing ties the three δg unknowns), solved by
conjugate gradients preconditioned with the stored banded factor. Paper Table 2 case 4:
50 Hz x 11,301 s, 2 Hz GPS, 332,150 cross-overs (576 x 577 lines gives 332,352).

Returns a CrossoverNetworkResult (attributes; reading it as the former dict is deprecated):
sizes, crossings, ties, factor_seconds, factor_bytes, pcg_iterations,
pcg_seconds, pcg_relative_residual, pcg_converged, max_abs_error and gravity_rmse [m/s²]
against the noise-free truth, total_seconds, report.)doc");
}

/// The linear INS network through Ceres, its equations and its normal blocks.
static void BindLinearInsNetworkParts(py::module_& m) {
  const network::LinearInsNetworkOptions linear;
  DefOnNetwork(
      m, "solve_linear_ins_network_ceres",
      [](const network::LinearInsNetworkOptions& o, bool one_gauss_newton_step) {
        ValidateOptions(o, "network");
        // Ceres cannot be interrupted inside its sparse factorisation: the peer is bounded to the
        // benchmark's sizes (50 Hz x 2400 s = 2.16e6 unknowns) instead of running for hours.
        const long long unknowns = network::LinearInsNetworkSize(o).unknowns;
        CheckArgument(unknowns <= 2'200'000, "duration_s",
                      "duration_s x imu_rate_hz gives " + std::to_string(unknowns) +
                          " unknowns; the Ceres peer is meant for the benchmark's sizes (<= 2.2e6 unknowns)");
        network::LinearInsCeresResult r;
        {
          py::gil_scoped_release release;
          r = network::SolveLinearInsNetworkWithCeres(o, one_gauss_newton_step);
        }
        return r;
      },
      linear, {"imu_rate_hz", "duration_s", "gps_rate_hz", "rule", "prior_epochs", "one_gauss_newton_step"},
      py::arg("one_gauss_newton_step") = false, R"doc(
The linearised INS/GPS network (same equations as solve_linear_ins_network) solved by Ceres
(SPARSE_NORMAL_CHOLESKY with SuiteSparse, single thread): the peer of the benchmark, in process.
With one_gauss_newton_step=False Ceres runs with its default Solver::Options (Levenberg-
Marquardt from x = 0); with True, one Gauss-Newton step (exact for this linear problem).

Returns a LinearInsCeresResult (attributes; reading it as the former dict is deprecated):
imu_epochs, unknowns, x (E, 18) [δr m, δv m/s, ψ rad, a m/s², ω rad/s, δg m/s²],
build_seconds, solve_seconds, iterations, converged, max_abs_error (against the noise-free
truth), linear_solver, report.)doc");

  DefOnNetwork(
      m, "linear_ins_equations",
      [](const network::LinearInsNetworkOptions& o) {
        ValidateOptions(o, "network");
        CheckArgument(network::LinearInsNetworkSize(o).unknowns <= 20'000'000, "duration_s",
                      "duration_s x imu_rate_hz: this export is meant for peers at moderate sizes (<= 2e7 unknowns)");
        // About three 18-wide equation rows of doubles per unknown (J blocks, observations).
        RequireSizeLimit(static_cast<double>(network::LinearInsNetworkSize(o).unknowns), 3.0 * 18.0 * 8.0,
                         "duration_s", "unknowns' equations");
        network::LinearInsEquations e;
        {
          py::gil_scoped_release release;
          e = network::LinearInsNetworkEquations(o);
        }
        return e;
      },
      linear, {"imu_rate_hz", "duration_s", "gps_rate_hz", "rule", "prior_epochs"}, R"doc(
The observation equations of the linearised INS/GPS network (for building it in other solvers):
a LinearInsEquations (attributes; reading it as the former dict is deprecated) with offsets, J (list of 18x18: equation centred at n reads sum_a J[a] x[n + offsets[a]] =
dynamic_l[i]), row_sigma (18,), centres, dynamic_l, gps_epochs, gps_l (CUPT on δr), prior_l
(every unknown of the first epochs), gupt_epochs, gupt_l (δg), sigma_gps, sigma_prior,
sigma_gupt, imu_epochs. Unknowns per epoch: δr, δv, ψ, accelerometer bias, gyro bias, δg.)doc");

  DefOnNetwork(
      m, "linear_ins_normal_blocks",
      [](const network::LinearInsNetworkOptions& o) {
        ValidateOptions(o, "network");
        const network::NetworkSize size = network::LinearInsNetworkSize(o);
        CheckArgument(size.unknowns <= 20'000'000, "duration_s", "duration_s x imu_rate_hz: this dense-block export is meant for peers at moderate sizes (<= 2e7 unknowns)");
        // Three dense b x b blocks per block row: 2e7 unknowns asked numpy for 34 GB.
        RequireSizeLimit(static_cast<double>(size.num_blocks), (2.0 * size.block_size + 1.0) * size.block_size * 8.0,
                         "duration_s", "normal-equation block rows");
        const py::ssize_t n = size.num_blocks, b = size.block_size;
        py::array_t<double> diagonal({n, b, b}), lower({n, b, b}), rhs({n, b});
        {
          double* pd = diagonal.mutable_data();
          double* pl = lower.mutable_data();
          double* pr = rhs.mutable_data();
          py::gil_scoped_release release;
          const network::BlockRowAssembler assemble = network::LinearInsAssembler(o);
          Eigen::MatrixXd D(b, b), L(b, b);
          Eigen::VectorXd r(b);
          for (py::ssize_t j = 0; j < n; ++j) {
            D.setZero();
            L.setZero();
            r.setZero();
            if ((j & 1023) == 0) CheckInterrupt();
            assemble(static_cast<int>(j), &D, &L, &r);
            // Row-major copies (numpy's layout).
            for (py::ssize_t i = 0; i < b; ++i)
              for (py::ssize_t k = 0; k < b; ++k) {
                pd[(j * b + i) * b + k] = D(i, k);
                pl[(j * b + i) * b + k] = L(i, k);
              }
            for (py::ssize_t i = 0; i < b; ++i) pr[j * b + i] = r[i];
          }
        }
        return py::make_tuple(diagonal, lower, rhs);
      },
      linear, {"imu_rate_hz", "duration_s", "gps_rate_hz", "rule", "prior_epochs"}, R"doc(
The normal equations of the linearised INS/GPS network as dense blocks, for solving it with other
libraries: diagonal (n, b, b) = A_ii, lower (n, b, b) = A_{i,i-1} (lower[0] is zero), rhs (n, b).)doc");
}

/// The linear INS network solved directly (Cholesky or QR).
static void BindLinearInsNetworkSolve(py::module_& m) {
  const network::LinearInsNetworkOptions linear;
  const network::FoldedNetworkOptions folded;
  DefOnNetwork(
      m, "solve_linear_ins_network",
      [](const network::LinearInsNetworkOptions& o, bool gravity_covariance, int checkpoint_interval,
         bool keep_gravity_estimate, int num_threads, std::optional<double> pivot_tolerance, const std::string& method) {
        CheckArgument(method == "cholesky" || method == "qr", "method", "must be 'cholesky' or 'qr', got '" + method + "'");
        if (pivot_tolerance) {  // checked here so the message names the argument, whichever solver runs
          CheckArgument(*pivot_tolerance >= 0.0 && *pivot_tolerance < 1.0, "pivot_tolerance",
                        "must be in [0, 1), got " + FormatValue(*pivot_tolerance));
        }
        ValidateOptions(o, "network");
        CheckArgument(checkpoint_interval >= 0, "checkpoint_interval", "must be >= 0");
        // Without checkpoints the whole factor is kept (two b x b blocks per block row): the same
        // 16 GB budget as the crossover solver (1.6e8 epochs ended in std::bad_alloc).
        const network::NetworkSize size = network::LinearInsNetworkSize(o);
        const double per_row = checkpoint_interval == 0 ? 2.0 * size.block_size * size.block_size * 8.0
                                                        : 4.0 * size.block_size * 8.0;
        RequireSizeLimit(static_cast<double>(size.num_blocks), per_row, "duration_s",
                         "block rows (duration_s x imu_rate_hz)", 16e9);
        network::LinearInsNetworkResult r;
        {
          py::gil_scoped_release release;
          if (method == "qr") {
            r = network::SolveLinearInsNetworkQr(o, gravity_covariance, checkpoint_interval, keep_gravity_estimate,
                                                 pivot_tolerance.value_or(1e-20));
          } else {
            r = network::SolveLinearInsNetwork(o, gravity_covariance, checkpoint_interval, keep_gravity_estimate,
                                               num_threads, pivot_tolerance.value_or(1e-12));
          }
        }
        return r;
      },
      linear,
      {"imu_rate_hz", "duration_s", "gps_rate_hz", "rule", "gravity_covariance", "checkpoint_interval", "prior_epochs",
       "keep_gravity_estimate", "num_threads", "pivot_tolerance", "method"},
      py::arg("gravity_covariance") = folded.gravity_covariance, py::arg("checkpoint_interval") = 0,
      py::arg("keep_gravity_estimate") = folded.keep_gravity_estimate, py::arg("num_threads") = folded.num_threads,
      py::arg("pivot_tolerance") = py::none(), py::arg("method") = "cholesky", R"doc(
Builds the linearised strapdown INS/GPS network (18 unknowns per IMU epoch, leap-frog or
trapezoidal dynamic equations, CUPT at the GPS epochs, alignment prior, GUPT at the end) block by
block and solves it with the streaming block-tridiagonal Cholesky, with the covariances of every
gravity-disturbance unknown (selected inversion).

Parameters
----------
network : LinearInsNetworkOptions
    Size (paper Table 2 case 1: 200 Hz x 10,800 s), rule, prior_epochs (1 with leap-frog leaves
    the odd chain without datum: RuntimeError naming the block) and noise model.
gravity_covariance : bool
    Also return sqrt(diag Σ_δg) per epoch [m/s²].
checkpoint_interval : int
    0 keeps the whole factor; k > 0 keeps one checkpoint every k blocks (memory independent of
    the size, about 1.5x the time).
keep_gravity_estimate : bool
    Return the δg estimate (E, 3) too.
num_threads : int
    Threads for the two chains of the twisted elimination (blocks 0.. and ..n-1 meeting in the
    middle; 1 or 2; <= 0: all cores). The results are bit-identical on any count. The QR runs
    on one thread.
pivot_tolerance : float or None
    Rank test on the relative pivot (pivot² / A_kk; QR: R_kk² / A_kk), in [0, 1). None: 1e-12
    for the Cholesky, 1e-20 for the QR (a datum defect gives about 1e-30 there).
method : "cholesky" or "qr"
    "cholesky": the normal equations, twisted order (fast). "qr": Householder QR of the whitened
    observation equations, one way (about 2.5-3.3x slower), which does not square the condition:
    Table 2 case 3 (200 Hz x 4 h, 5 Hz GPS) needs it (docs/network_scale.md, "Case 3").

Returns
-------
LinearInsNetworkResult (attributes; reading it as the former dict is deprecated): sizes (imu_epochs, gps_epochs, unknowns, equations, block_size, num_blocks), timings
[s], stored_factor_bytes, min_relative_pivot with min_relative_pivot_block and
min_relative_pivot_unknown (where it was seen), max_abs_error against the noise-free truth with
max_abs_error_by_unknown (18,) and max_abs_error_epoch, gravity_rmse [m/s²], gravity_sigma (E, 3)
[m/s²], gravity_estimate, report.)doc");
}

void BindNetworkScale(py::module_& m) {
  BindLinearInsNetworkOptions(m);
  BindNetworkScaleResults(m);
  // Keyword defaults equal to a struct's default are read from it (the struct is the one place a
  // default is written); the scenario sizes of the folded and crossover benchmarks (50 Hz, 2 Hz
  // GPS, their durations) are those scenarios' own and stay literal.
  BindFoldedNetwork(m);
  BindCrossoverNetwork(m);
  BindLinearInsNetworkParts(m);
  BindLinearInsNetworkSolve(m);
}

}  // namespace indoorloc::bindings
