// The validation vocabulary of indoorloc: one wording for every rule an argument or an Options
// field must obey, so a message always names the field, the value and the rule, e.g.
// "sigma_acc_mps2 must be finite and in [1e-12, 1e+12], got inf".
//
// Two forms:
//  - Validator chains the rules inside an Options struct's IsValid(std::string* error); the first
//    broken rule wins and its message goes to *error (ValidateOptions then throws
//    std::invalid_argument "indoorloc: argument 'options': <message>").
//  - Require*() throw std::invalid_argument naming a function argument directly; bindings and
//    public functions use them at the boundary (pybind11 turns them into ValueError).
//
// Why bounds and not only "> 0": a standard deviation of 1e-300 passes "> 0" but its inverse
// square overflows to inf, and a count of 2**31 passes ">= 1" but asks for more memory or time
// than any machine has. Scales therefore live in [kMinScale, kMaxScale] and sizes are checked
// against a byte budget before anything is allocated (RequireSizeLimit).
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>

#include <Eigen/Core>

#include "indoorloc/core/check.h"

namespace indoorloc {

/// Smallest and largest accepted value of a physical scale (a standard deviation, a gain, a
/// length): their squares and inverse squares stay finite in double precision.
inline constexpr double kMinScale = 1e-12;
inline constexpr double kMaxScale = 1e12;

/// Default memory budget of one call [bytes]: asking for more is a user error, not a job
/// (a shared 2-core, 24 GB machine must survive a typo such as num_out = 2**31 - 1).
inline constexpr double kMaxBytes = 4e9;

/// A value for messages: "inf", "nan", "1e+300", "-7", "0.25".
std::string FormatValue(double value);
/// A byte count for messages: "3.2 GB", "12 kB".
std::string FormatBytes(double bytes);

/// Chains rules over Options fields; the first failure is kept.
///
///   bool FooOptions::IsValid(std::string* error) const {
///     return Validator(error).Scale(sigma_m, "sigma_m").AtLeast(iterations, 1, "iterations").ok();
///   }
class Validator {
 public:
  explicit Validator(std::string* error) : error_(error) {}

  /// finite (no NaN, no +-inf)
  Validator& Finite(double value, std::string_view name);
  /// finite and > 0
  Validator& Positive(double value, std::string_view name);
  /// finite and >= 0
  Validator& NonNegative(double value, std::string_view name);
  /// finite and in [kMinScale, kMaxScale]: standard deviations, gains, lengths
  Validator& Scale(double value, std::string_view name);
  /// 0 or a Scale (0 switches a term off)
  Validator& ZeroOrScale(double value, std::string_view name);
  /// finite and in [lo, hi]
  Validator& InRange(double value, double lo, double hi, std::string_view name);
  /// integer (any integer type) in [lo, hi]
  Validator& IntInRange(std::int64_t value, std::int64_t lo, std::int64_t hi, std::string_view name);
  /// integer >= lo
  Validator& AtLeast(std::int64_t value, std::int64_t lo, std::string_view name);
  /// a free-form rule: `ok` or "<name> <rule>"
  Validator& Check(bool ok, std::string_view name, std::string_view rule);

  bool ok() const { return ok_; }
  operator bool() const { return ok_; }  // NOLINT: lets IsValid `return Validator(...)...;`

 private:
  Validator& Fail(std::string_view name, std::string_view rule, const std::string& got);
  std::string* error_;
  bool ok_ = true;
};

/// Throwing forms for function arguments: std::invalid_argument
/// "indoorloc: argument '<name>': must be <rule>, got <value>".
void RequireFinite(double value, std::string_view name);
void RequirePositive(double value, std::string_view name);
void RequireNonNegative(double value, std::string_view name);
void RequireScale(double value, std::string_view name);
void RequireInRange(double value, double lo, double hi, std::string_view name);
/// A whole number in [lo, hi] given as a double (e.g. from a float64 array).
void RequireIntegerValued(double value, double lo, double hi, std::string_view name);
/// An integer in [lo, hi].
void RequireIntInRange(std::int64_t value, std::int64_t lo, std::int64_t hi, std::string_view name);
/// Every entry of `x` finite and in [lo, hi]; names the first entry that is not.
template <typename Derived>
void RequireAllInRange(const Eigen::DenseBase<Derived>& x, double lo, double hi, std::string_view name) {
  for (Eigen::Index j = 0; j < x.cols(); ++j) {
    for (Eigen::Index i = 0; i < x.rows(); ++i) {
      const double v = static_cast<double>(x(i, j));
      if (!(v >= lo && v <= hi)) {
        const bool is_vector = x.cols() == 1 || x.rows() == 1;
        ThrowInvalidArgument(name, (is_vector ? DescribeEntry(x.cols() == 1 ? i : j, 0, true) : DescribeEntry(i, j, false)) +
                                       " must be in [" + FormatValue(lo) + ", " + FormatValue(hi) + "], got " +
                                       FormatValue(v));
      }
    }
  }
}

/// `count` items of `bytes_per_item` bytes fit in `max_bytes`; the message gives what it would
/// take: "argument 'n': 1e+10 x 1e+10 grid would need 8e+20 B (limit 8 GB)".
void RequireSizeLimit(double count, double bytes_per_item, std::string_view name,
                      std::string_view what = "items", double max_bytes = kMaxBytes);

}  // namespace indoorloc
