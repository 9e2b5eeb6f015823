#include "indoorloc/network/linear_ins_ceres.h"

#include <cmath>
#include <memory>
#include <stdexcept>
#include <vector>

#include <ceres/ceres.h>

#include "indoorloc/core/options.h"

namespace indoorloc::network {
namespace {

constexpr int kP = 18;

// r = A_0 x_0 + ... + A_{m-1} x_{m-1} - b, every A_a whitened (rows x 18), x_a blocks of 18.
class LinearResidual final : public ceres::CostFunction {
 public:
  LinearResidual(std::vector<Eigen::MatrixXd> A, Eigen::VectorXd b) : A_(std::move(A)), b_(std::move(b)) {
    set_num_residuals(static_cast<int>(b_.size()));
    for (size_t a = 0; a < A_.size(); ++a) mutable_parameter_block_sizes()->push_back(kP);
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    Eigen::Map<Eigen::VectorXd> r(residuals, b_.size());
    r = -b_;
    for (size_t a = 0; a < A_.size(); ++a) {
      r.noalias() += A_[a] * Eigen::Map<const Eigen::Matrix<double, kP, 1>>(parameters[a]);
      if (jacobians != nullptr && jacobians[a] != nullptr) {
        Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, kP, Eigen::RowMajor>>(jacobians[a], b_.size(), kP) = A_[a];
      }
    }
    return true;
  }

 private:
  std::vector<Eigen::MatrixXd> A_;
  Eigen::VectorXd b_;
};

// Rows `first .. first + width - 1` of one epoch observed directly: W^{1/2} (x[first..] - l).
ceres::CostFunction* DirectObservation(int first, int width, const Eigen::VectorXd& l, double sigma) {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(width, kP);
  for (int k = 0; k < width; ++k) A(k, first + k) = 1.0 / sigma;
  return new LinearResidual({A}, l / sigma);
}

}  // namespace

LinearInsCeresResult SolveLinearInsNetworkWithCeres(const LinearInsNetworkOptions& options, bool one_gauss_newton_step) {
  LinearInsCeresResult result;
  result.size = LinearInsNetworkSize(options);  // validates the options
  WallTimer build;
  const LinearInsEquations eq = LinearInsNetworkEquations(options);
  const long long E = eq.imu_epochs;
  result.x = Eigen::MatrixXd::Zero(E, kP);  // column-major E x 18: copy per epoch below
  std::vector<double> x(static_cast<size_t>(E) * kP, 0.0);

  ceres::Problem problem;
  const Eigen::VectorXd inv_sigma = eq.row_sigma.cwiseInverse();
  std::vector<Eigen::MatrixXd> whitened;
  for (const Eigen::MatrixXd& J : eq.J) whitened.push_back(inv_sigma.asDiagonal() * J);
  for (size_t i = 0; i < eq.centres.size(); ++i) {
    std::vector<double*> blocks;
    for (int o : eq.offsets) blocks.push_back(&x[static_cast<size_t>(eq.centres[i] + o) * kP]);
    const Eigen::VectorXd l = eq.dynamic_l.row(static_cast<Eigen::Index>(i)).transpose().cwiseProduct(inv_sigma);
    problem.AddResidualBlock(new LinearResidual(whitened, l), nullptr, blocks);
  }
  for (size_t k = 0; k < eq.gps_epochs.size(); ++k)
    problem.AddResidualBlock(DirectObservation(0, 3, eq.gps_l.row(static_cast<Eigen::Index>(k)).transpose(), eq.sigma_gps),
                             nullptr, &x[static_cast<size_t>(eq.gps_epochs[k]) * kP]);
  for (Eigen::Index n = 0; n < eq.prior_l.rows(); ++n)
    problem.AddResidualBlock(DirectObservation(0, kP, eq.prior_l.row(n).transpose(), eq.sigma_prior), nullptr,
                             &x[static_cast<size_t>(n) * kP]);
  for (size_t k = 0; k < eq.gupt_epochs.size(); ++k)
    problem.AddResidualBlock(DirectObservation(15, 3, eq.gupt_l.row(static_cast<Eigen::Index>(k)).transpose(), eq.sigma_gupt),
                             nullptr, &x[static_cast<size_t>(eq.gupt_epochs[k]) * kP]);
  result.build_seconds = build.ElapsedSeconds();

  ceres::Solver::Options so;  // Ceres' defaults (LM, SPARSE_NORMAL_CHOLESKY when SuiteSparse is there)
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  if (one_gauss_newton_step) {
    // LM regularises with 1/radius: a huge radius makes the first step the Gauss-Newton step,
    // which solves a linear problem exactly.
    so.initial_trust_region_radius = 1e16;
    so.max_trust_region_radius = 1e32;
    so.max_num_iterations = 1;
  }
  std::string error;
  if (!so.IsValid(&error)) throw std::runtime_error("indoorloc: Ceres options: " + error);
  ceres::Solver::Summary summary;
  WallTimer solve;
  ceres::Solve(so, &problem, &summary);
  result.solve_seconds = solve.ElapsedSeconds();
  if (summary.termination_type == ceres::FAILURE || summary.termination_type == ceres::USER_FAILURE) {
    throw std::runtime_error("indoorloc: Ceres failed on the linearised network: " + summary.message);
  }
  // summary.iterations holds iteration 0 (the evaluation at the start) and then one entry per step.
  result.iterations = static_cast<int>(summary.iterations.size()) - 1;
  result.converged = summary.termination_type == ceres::CONVERGENCE;
  result.linear_solver = std::string(ceres::LinearSolverTypeToString(summary.linear_solver_type_used)) + " (" +
                         ceres::SparseLinearAlgebraLibraryTypeToString(so.sparse_linear_algebra_library_type) + ")";
  result.report = summary.BriefReport();
  for (long long n = 0; n < E; ++n) {
    result.x.row(n) = Eigen::Map<const Eigen::Matrix<double, 1, kP>>(&x[static_cast<size_t>(n) * kP]);
    result.max_abs_error = std::max(result.max_abs_error,
                                    (result.x.row(n).transpose() - LinearInsTruth(n, options.imu_rate_hz)).cwiseAbs().maxCoeff());
  }
  return result;
}

}  // namespace indoorloc::network
