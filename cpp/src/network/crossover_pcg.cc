#include "indoorloc/network/crossover_pcg.h"

#include <cmath>
#include <sstream>

#include "indoorloc/core/check.h"
#include "indoorloc/core/interrupt.h"
#include "indoorloc/core/validate.h"

namespace indoorloc::network {
namespace {

using Eigen::VectorXd;

// y += Σ w (x_a - x_b)(e_a - e_b).
void AddTies(const std::vector<Tie>& ties, const VectorXd& x, VectorXd* y) {
  for (const Tie& t : ties) {
    const double d = t.weight * (x[t.a] - x[t.b]);
    (*y)[t.a] += d;
    (*y)[t.b] -= d;
  }
}

}  // namespace

bool TiedSolveOptions::IsValid(std::string* error) const {
  // Each PCG iteration is one banded solve: an upper bound keeps a typo from running for hours.
  return Validator(error)
      .IntInRange(max_iterations, 1, 1000000, "max_iterations")
      .Check(relative_tolerance > 0.0 && relative_tolerance < 1.0, "relative_tolerance",
             "must be in (0, 1), got " + FormatValue(relative_tolerance));
}

std::string TiedSolveSummary::BriefReport() const {
  std::ostringstream s;
  s << "PCG with the banded factor: " << ToString(termination) << " after " << iterations << " iterations, relative residual "
    << relative_residual << ", " << seconds << " s";
  return s.str();
}

TiedSolution SolveWithTies(const BlockTridiagonalFactor& band, const VectorXd& band_rhs, const std::vector<Tie>& ties,
                           const TiedSolveOptions& options) {
  ValidateOptions(options);
  const long long n = static_cast<long long>(band.num_blocks()) * band.block_size();
  CheckArgument(band_rhs.size() == n, "band_rhs", "must have one entry per unknown (" + std::to_string(n) + ")");
  CheckFinite(band_rhs, "band_rhs");
  for (size_t i = 0; i < ties.size(); ++i) {
    const Tie& t = ties[i];
    if (t.a < 0 || t.a >= n || t.b < 0 || t.b >= n || t.a == t.b) {
      ThrowInvalidArgument("ties", "tie " + std::to_string(i) + " joins unknowns " + std::to_string(t.a) + " and " +
                                       std::to_string(t.b) + ": outside 0.." + std::to_string(n - 1) + " or equal");
    }
    if (!(std::isfinite(t.weight) && t.weight > 0.0) || !std::isfinite(t.value)) {
      ThrowInvalidArgument("ties", "tie " + std::to_string(i) + " has a non-positive weight or a non-finite value");
    }
  }
  WallTimer timer;
  VectorXd b = band_rhs;
  for (const Tie& t : ties) {
    b[t.a] += t.weight * t.value;
    b[t.b] -= t.weight * t.value;
  }
  // Convergence in the preconditioner's norm: ‖r‖_{A^{-1}} = √(rᵀ A^{-1} r) against the same norm
  // of b. The plain ‖r‖ is dominated by the stiffest rows (weights up to 1e13 here) and stalls
  // near 1e-6 while the solution is already exact to 1e-9.
  const VectorXd b_pre = band.Solve(b);
  const double b_norm = std::sqrt(std::max(b.dot(b_pre), 1e-300));
  auto apply = [&](const VectorXd& x) {
    VectorXd y = band.Multiply(x);
    AddTies(ties, x, &y);
    return y;
  };
  TiedSolution out;
  out.x = b_pre;  // the band-only solution: exact when there are no ties
  VectorXd r = b - apply(out.x);
  VectorXd z = band.Solve(r);
  double rz = r.dot(z);
  out.summary.relative_residual = std::sqrt(std::max(rz, 0.0)) / b_norm;
  if (ties.empty() || out.summary.relative_residual <= options.relative_tolerance) {
    out.summary.termination = Termination::kConverged;
    out.summary.seconds = timer.ElapsedSeconds();
    return out;
  }
  VectorXd p = z;
  out.summary.termination = Termination::kMaxIterations;
  for (int it = 1; it <= options.max_iterations; ++it) {
    CheckInterrupt();  // one banded solve per iteration
    const VectorXd q = apply(p);
    const double pq = p.dot(q);
    if (!(pq > 0.0)) {
      out.summary.termination = Termination::kFailure;  // the tied matrix is not positive definite numerically
      break;
    }
    const double alpha = rz / pq;
    out.x.noalias() += alpha * p;
    r.noalias() -= alpha * q;
    out.summary.iterations = it;
    z = band.Solve(r);
    const double rz_new = r.dot(z);
    out.summary.relative_residual = std::sqrt(std::max(rz_new, 0.0)) / b_norm;
    if (out.summary.relative_residual <= options.relative_tolerance) {
      out.summary.termination = Termination::kConverged;
      break;
    }
    p = z + (rz_new / rz) * p;
    rz = rz_new;
  }
  out.summary.seconds = timer.ElapsedSeconds();
  return out;
}

}  // namespace indoorloc::network
