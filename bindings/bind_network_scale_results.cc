// Python bindings of the network scale path's results: typed read-only objects
// (LinearInsNetworkResult, FoldedNetworkResult, CrossoverNetworkResult, LinearInsCeresResult,
// LinearInsEquations) bound once by result_binding.h. They replace the dicts the scale functions
// used to copy field by field; reading them as those dicts still works for one release with a
// DeprecationWarning (docs/api_changes.md). The fields several results share (the network's
// size, the block-tridiagonal solver's summary, the error against the noise-free truth, the
// gravity disturbance) are declared once below; the stub (network.pyi) mirrors these groups. The functions returning them are bound in
// bind_network_scale.cc, which calls BindNetworkScaleResults first.
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "indoorloc/core/options.h"
#include "indoorloc/network/folded_network.h"
#include "indoorloc/network/linear_ins_ceres.h"
#include "indoorloc/network/linear_ins_network.h"
#include "result_binding.h"

namespace indoorloc::bindings {

namespace {

constexpr const char* kSince = "house (issue 27)";

/// imu_epochs, gps_epochs, unknowns of the network solved (result.size).
template <typename R>
void SizeFields(ResultBinder<R>& b) {
  b.Field("imu_epochs", [](const R& r) { return r.size.imu_epochs; })
      .Field("gps_epochs", [](const R& r) { return r.size.gps_epochs; })
      .Field("unknowns", [](const R& r) { return r.size.unknowns; }, "18 per IMU epoch.");
}

/// The block-tridiagonal solver's summary (result.solver): timings [s], memory, the smallest pivot.
template <typename R>
void SolverFields(ResultBinder<R>& b) {
  b.Field("factor_seconds", [](const R& r) { return r.solver.factor_seconds; })
      .Field("backward_seconds", [](const R& r) { return r.solver.backward_seconds; })
      .Field("total_seconds", [](const R& r) { return r.total_seconds; })
      .Field("stored_factor_bytes", [](const R& r) { return r.solver.stored_factor_bytes; })
      .Field("min_relative_pivot", [](const R& r) { return r.solver.min_relative_pivot; });
}

/// The error against the noise-free truth: over every unknown, and of δg.
template <typename R>
void TruthFields(ResultBinder<R>& b) {
  b.Field("max_abs_error", [](const R& r) { return r.max_abs_error; }, "max |x - x*| over every unknown.")
      .Field("gravity_rmse", [](const R& r) { return r.gravity_rmse; }, "δg error RMSE [m/s²].");
}

/// The gravity disturbance δg with its sigma per epoch.
template <typename R>
void GravityFields(ResultBinder<R>& b) {
  b.Field("gravity_sigma", [](const R& r) { return Eigen::MatrixXd(r.gravity_sigma); },
          "(E, 3) sqrt of the diagonal of Σ_δg per epoch [m/s²].")
      .Field("gravity_estimate", [](const R& r) { return Eigen::MatrixXd(r.gravity_estimate); },
             "(E, 3) δg estimate [m/s²]; empty unless keep_gravity_estimate.");
}

void BindLinearInsNetworkResult(py::module_& m) {
  using R = network::LinearInsNetworkResult;
  ResultBinder<R> b(m, "LinearInsNetworkResult", "The linearised INS/GPS network solved by solve_linear_ins_network.");
  SizeFields(b);
  b.Field("equations", [](const R& r) { return r.size.equations; })
      .Field("block_size", [](const R& r) { return r.size.block_size; })
      .Field("num_blocks", [](const R& r) { return r.size.num_blocks; })
      .Field("assembler_calls", [](const R& r) { return r.solver.assembler_calls; });
  SolverFields(b);
  b.Field("min_relative_pivot_block", [](const R& r) { return r.solver.min_relative_pivot_block; })
      .Field("min_relative_pivot_unknown", [](const R& r) { return r.solver.min_relative_pivot_unknown; });
  TruthFields(b);
  b.Field("max_abs_error_by_unknown", [](const R& r) { return Eigen::VectorXd(r.max_abs_error_by_unknown); },
          "(18,) max |x - x*| per unknown of an epoch, each in its own unit.")
      .Field("max_abs_error_epoch", [](const R& r) { return r.max_abs_error_epoch; });
  GravityFields(b);
  b.Field("report", [](const R& r) { return r.solver.BriefReport(); }).MappingDeprecated(kSince).Finish();
}

void BindFoldedNetworkResult(py::module_& m) {
  using R = network::FoldedNetworkResult;
  ResultBinder<R> b(m, "FoldedNetworkResult", "The repeated-pass network solved by solve_folded_linear_ins_network.");
  SizeFields(b);
  b.Field("ties", [](const R& r) { return r.ties; }, "XOVER equations.")
      .Field("gupts", [](const R& r) { return r.gupts; }, "GUPT equations.")
      .Field("equations", [](const R& r) { return r.equations; })
      .Field("folded_blocks", [](const R& r) { return r.folded_blocks; })
      .Field("folded_block_size", [](const R& r) { return r.folded_block_size; });
  SolverFields(b);
  TruthFields(b);
  GravityFields(b);
  b.Field("report", [](const R& r) { return r.BriefReport(); }).MappingDeprecated(kSince).Finish();
}

void BindCrossoverNetworkResult(py::module_& m) {
  using R = network::CrossoverNetworkResult;
  ResultBinder<R> b(m, "CrossoverNetworkResult",
                    "The grid survey network with cross-over ties solved by solve_linear_ins_network_with_crossovers.");
  SizeFields(b);
  b.Field("equations", [](const R& r) { return r.size.equations + r.ties; }, "The network's rows and the ties.")
      .Field("crossings", [](const R& r) { return r.crossings; })
      .Field("ties", [](const R& r) { return r.ties; })
      .Field("factor_seconds", [](const R& r) { return r.factor_seconds; })
      .Field("factor_bytes", [](const R& r) { return r.factor_bytes; })
      .Field("pcg_iterations", [](const R& r) { return r.pcg.iterations; })
      .Field("pcg_seconds", [](const R& r) { return r.pcg.seconds; })
      .Field("pcg_relative_residual", [](const R& r) { return r.pcg.relative_residual; })
      .Field("pcg_converged", [](const R& r) { return r.pcg.termination == Termination::kConverged; });
  TruthFields(b);
  b.Field("total_seconds", [](const R& r) { return r.total_seconds; })
      .Field("report", [](const R& r) { return r.pcg.BriefReport(); })
      .MappingDeprecated(kSince)
      .Finish();
}

void BindLinearInsCeresResult(py::module_& m) {
  using R = network::LinearInsCeresResult;
  ResultBinder<R>(m, "LinearInsCeresResult", "The linearised network solved by Ceres (solve_linear_ins_network_ceres).")
      .Field("imu_epochs", [](const R& r) { return r.size.imu_epochs; })
      .Field("unknowns", [](const R& r) { return r.size.unknowns; })
      .Field("x", [](const R& r) { return Eigen::MatrixXd(r.x); },
             "(E, 18) [δr m, δv m/s, ψ rad, a m/s², ω rad/s, δg m/s²].")
      .Field("build_seconds", [](const R& r) { return r.build_seconds; })
      .Field("solve_seconds", [](const R& r) { return r.solve_seconds; })
      .Field("iterations", [](const R& r) { return r.iterations; })
      .Field("converged", [](const R& r) { return r.converged; })
      .Field("max_abs_error", [](const R& r) { return r.max_abs_error; }, "max |x - x*| over every unknown.")
      .Field("linear_solver", [](const R& r) { return r.linear_solver; })
      .Field("report", [](const R& r) { return r.report; })
      .MappingDeprecated(kSince)
      .Finish();
}

void BindLinearInsEquations(py::module_& m) {
  using R = network::LinearInsEquations;
  ResultBinder<R>(m, "LinearInsEquations",
                  "The observation equations of the linearised network (linear_ins_equations): equation i "
                  "centred at centres[i] reads sum_a J[a] x[centres[i] + offsets[a]] = dynamic_l[i].")
      .Field("offsets", [](const R& e) { return e.offsets; })
      .Field("J", [](const R& e) { return e.J; }, "list of (18, 18).")
      .Field("row_sigma", [](const R& e) { return Eigen::VectorXd(e.row_sigma); }, "(18,).")
      .Field("centres", [](const R& e) { return e.centres; })
      .Field("dynamic_l", [](const R& e) { return Eigen::MatrixXd(e.dynamic_l); }, "(len(centres), 18).")
      .Field("gps_epochs", [](const R& e) { return e.gps_epochs; })
      .Field("gps_l", [](const R& e) { return Eigen::MatrixXd(e.gps_l); }, "CUPT on δr, (len(gps_epochs), 3).")
      .Field("prior_l", [](const R& e) { return Eigen::MatrixXd(e.prior_l); }, "(prior_epochs, 18).")
      .Field("gupt_epochs", [](const R& e) { return e.gupt_epochs; })
      .Field("gupt_l", [](const R& e) { return Eigen::MatrixXd(e.gupt_l); }, "δg, (len(gupt_epochs), 3).")
      .Field("sigma_gps", [](const R& e) { return e.sigma_gps; })
      .Field("sigma_prior", [](const R& e) { return e.sigma_prior; })
      .Field("sigma_gupt", [](const R& e) { return e.sigma_gupt; })
      .Field("imu_epochs", [](const R& e) { return e.imu_epochs; })
      .MappingDeprecated(kSince)
      .Finish();
}

}  // namespace

void BindNetworkScaleResults(py::module_& m) {
  BindLinearInsNetworkResult(m);
  BindFoldedNetworkResult(m);
  BindCrossoverNetworkResult(m);
  BindLinearInsCeresResult(m);
  BindLinearInsEquations(m);
}

}  // namespace indoorloc::bindings
