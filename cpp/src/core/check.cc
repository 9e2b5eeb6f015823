#include "indoorloc/core/check.h"

#include <sstream>
#include <stdexcept>

namespace indoorloc {

void ThrowInvalidArgument(std::string_view argument, std::string_view problem) {
  std::string message = "indoorloc: argument '";
  message.append(argument);
  message.append("': ");
  message.append(problem);
  throw std::invalid_argument(message);
}

std::string DescribeEntry(Eigen::Index row, Eigen::Index col, bool is_vector) {
  if (is_vector) return "entry " + std::to_string(row);
  return "entry (" + std::to_string(row) + ", " + std::to_string(col) + ")";
}

namespace {
std::string FormatValue(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}
}  // namespace

void CheckPositive(double value, std::string_view argument) {
  if (!(std::isfinite(value) && value > 0.0)) {
    ThrowInvalidArgument(argument, "must be finite and > 0, got " + FormatValue(value));
  }
}

void CheckNonNegative(double value, std::string_view argument) {
  if (!(std::isfinite(value) && value >= 0.0)) {
    ThrowInvalidArgument(argument, "must be finite and >= 0, got " + FormatValue(value));
  }
}

void CheckInRange(double value, double lo, double hi, std::string_view argument) {
  if (!(value >= lo && value <= hi)) {
    ThrowInvalidArgument(argument, "must be in [" + FormatValue(lo) + ", " + FormatValue(hi) +
                                       "], got " + FormatValue(value));
  }
}

}  // namespace indoorloc
