#include "indoorloc/core/validate.h"

#include <cmath>
#include <sstream>

#include "indoorloc/core/check.h"

namespace indoorloc {

std::string FormatValue(double value) {
  std::ostringstream out;
  out.precision(6);
  out << value;
  return out.str();
}

std::string FormatBytes(double bytes) {
  const char* units[] = {"B", "kB", "MB", "GB", "TB"};
  int u = 0;
  while (bytes >= 1000.0 && u < 4) {
    bytes /= 1000.0;
    ++u;
  }
  std::ostringstream out;
  out.precision(3);
  out << bytes << " " << units[u];
  return out.str();
}

namespace {
std::string Range(double lo, double hi) { return "[" + FormatValue(lo) + ", " + FormatValue(hi) + "]"; }
}  // namespace

Validator& Validator::Fail(std::string_view name, std::string_view rule, const std::string& got) {
  if (!ok_) return *this;  // the first broken rule is the one reported
  ok_ = false;
  if (error_) {
    std::string m(name);
    m.append(" ").append(rule);
    if (!got.empty()) m.append(", got ").append(got);
    *error_ = m;
  }
  return *this;
}

Validator& Validator::Finite(double value, std::string_view name) {
  return std::isfinite(value) ? *this : Fail(name, "must be finite", FormatValue(value));
}
Validator& Validator::Positive(double value, std::string_view name) {
  return std::isfinite(value) && value > 0.0 ? *this : Fail(name, "must be finite and > 0", FormatValue(value));
}
Validator& Validator::NonNegative(double value, std::string_view name) {
  return std::isfinite(value) && value >= 0.0 ? *this
                                              : Fail(name, "must be finite and >= 0", FormatValue(value));
}
Validator& Validator::Scale(double value, std::string_view name) {
  return value >= kMinScale && value <= kMaxScale
             ? *this
             : Fail(name, "must be finite and in " + Range(kMinScale, kMaxScale), FormatValue(value));
}
Validator& Validator::ZeroOrScale(double value, std::string_view name) {
  return value == 0.0 || (value >= kMinScale && value <= kMaxScale)
             ? *this
             : Fail(name, "must be 0 or in " + Range(kMinScale, kMaxScale), FormatValue(value));
}
Validator& Validator::InRange(double value, double lo, double hi, std::string_view name) {
  return value >= lo && value <= hi ? *this : Fail(name, "must be in " + Range(lo, hi), FormatValue(value));
}
Validator& Validator::IntInRange(std::int64_t value, std::int64_t lo, std::int64_t hi, std::string_view name) {
  return value >= lo && value <= hi
             ? *this
             : Fail(name, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]",
                    std::to_string(value));
}
Validator& Validator::AtLeast(std::int64_t value, std::int64_t lo, std::string_view name) {
  return value >= lo ? *this : Fail(name, "must be >= " + std::to_string(lo), std::to_string(value));
}
Validator& Validator::Check(bool ok, std::string_view name, std::string_view rule) {
  return ok ? *this : Fail(name, rule, "");
}

namespace {
[[noreturn]] void Throw(std::string_view name, const std::string& rule, double value) {
  ThrowInvalidArgument(name, rule + ", got " + FormatValue(value));
}
}  // namespace

void RequireFinite(double value, std::string_view name) {
  if (!std::isfinite(value)) Throw(name, "must be finite", value);
}
void RequirePositive(double value, std::string_view name) {
  if (!(std::isfinite(value) && value > 0.0)) Throw(name, "must be finite and > 0", value);
}
void RequireNonNegative(double value, std::string_view name) {
  if (!(std::isfinite(value) && value >= 0.0)) Throw(name, "must be finite and >= 0", value);
}
void RequireScale(double value, std::string_view name) {
  if (!(value >= kMinScale && value <= kMaxScale))
    Throw(name, "must be finite and in " + Range(kMinScale, kMaxScale), value);
}
void RequireInRange(double value, double lo, double hi, std::string_view name) {
  if (!(value >= lo && value <= hi)) Throw(name, "must be in " + Range(lo, hi), value);
}
void RequireIntegerValued(double value, double lo, double hi, std::string_view name) {
  if (!(value >= lo && value <= hi && value == std::floor(value)))
    Throw(name, "must be a whole number in " + Range(lo, hi), value);
}
void RequireIntInRange(std::int64_t value, std::int64_t lo, std::int64_t hi, std::string_view name) {
  if (value < lo || value > hi)
    ThrowInvalidArgument(name, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
                                   std::to_string(value));
}
void RequireSizeLimit(double count, double bytes_per_item, std::string_view name, std::string_view what,
                      double max_bytes) {
  const double bytes = count * bytes_per_item;
  if (!(bytes <= max_bytes)) {
    ThrowInvalidArgument(name, FormatValue(count) + " " + std::string(what) + " would need " + FormatBytes(bytes) +
                                   " (limit " + FormatBytes(max_bytes) + ")");
  }
}

}  // namespace indoorloc
