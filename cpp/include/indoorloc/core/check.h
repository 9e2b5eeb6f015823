// Argument checks at the public boundary of indoorloc.
//
// These checks are always on (also in Release builds): every public function validates what the
// caller passed and throws std::invalid_argument with a message that names the argument and the
// problem, e.g. "indoorloc: argument 'log_weights': entry 3 is NaN". pybind11 turns
// std::invalid_argument into Python's ValueError, so a Python user sees the same message and the
// interpreter survives. Internal invariants use assert() (debug builds only) instead.
#pragma once

#include <cmath>
#include <string>
#include <string_view>

#include <Eigen/Core>

namespace indoorloc {

/// Throws std::invalid_argument("indoorloc: argument '<argument>': <problem>").
[[noreturn]] void ThrowInvalidArgument(std::string_view argument, std::string_view problem);

/// Throws std::invalid_argument naming `argument` unless `condition` holds.
inline void CheckArgument(bool condition, std::string_view argument, std::string_view problem) {
  if (!condition) ThrowInvalidArgument(argument, problem);
}

/// Formats a (row, col) or flat index of a matrix for error messages: "entry 3" or "entry (2, 1)".
std::string DescribeEntry(Eigen::Index row, Eigen::Index col, bool is_vector);

/// Throws unless every entry of `x` is finite (no NaN, no +-inf). Names the first bad entry.
template <typename Derived>
void CheckFinite(const Eigen::DenseBase<Derived>& x, std::string_view argument) {
  for (Eigen::Index j = 0; j < x.cols(); ++j) {
    for (Eigen::Index i = 0; i < x.rows(); ++i) {
      const double v = static_cast<double>(x(i, j));
      if (!std::isfinite(v)) {
        const bool is_vector = x.cols() == 1 || x.rows() == 1;
        const Eigen::Index flat = x.cols() == 1 ? i : (x.rows() == 1 ? j : 0);
        ThrowInvalidArgument(argument, (is_vector ? DescribeEntry(flat, 0, true)
                                                  : DescribeEntry(i, j, false)) +
                                           (std::isnan(v) ? " is NaN" : " is infinite"));
      }
    }
  }
}

/// Throws unless `x` has `rows` rows and `cols` columns; pass -1 for "any".
template <typename Derived>
void CheckShape(const Eigen::DenseBase<Derived>& x, Eigen::Index rows, Eigen::Index cols,
                std::string_view argument) {
  const bool rows_ok = rows < 0 || x.rows() == rows;
  const bool cols_ok = cols < 0 || x.cols() == cols;
  if (!rows_ok || !cols_ok) {
    auto dim = [](Eigen::Index n) { return n < 0 ? std::string("any") : std::to_string(n); };
    ThrowInvalidArgument(argument, "expected shape (" + dim(rows) + ", " + dim(cols) +
                                       "), got (" + std::to_string(x.rows()) + ", " +
                                       std::to_string(x.cols()) + ")");
  }
}

/// Throws unless `value` is finite and strictly positive.
void CheckPositive(double value, std::string_view argument);

/// Throws unless `value` is finite and >= 0.
void CheckNonNegative(double value, std::string_view argument);

/// Throws unless lo <= value <= hi (and value is not NaN).
void CheckInRange(double value, double lo, double hi, std::string_view argument);

}  // namespace indoorloc
