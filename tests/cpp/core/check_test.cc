#include "indoorloc/core/check.h"

#include <limits>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "invalid_argument_message.h"

#include "indoorloc/core/options.h"

namespace indoorloc {
namespace {

TEST(Check, MessageNamesArgumentAndProblem) {
  EXPECT_EQ(MessageOf([] { ThrowInvalidArgument("speed_mps", "must be >= 0"); }),
            "indoorloc: argument 'speed_mps': must be >= 0");
}

TEST(Check, CheckFiniteNamesFirstBadEntry) {
  Eigen::VectorXd v(4);
  v << 1, 2, std::numeric_limits<double>::quiet_NaN(), 4;
  EXPECT_EQ(MessageOf([&] { CheckFinite(v, "x"); }), "indoorloc: argument 'x': entry 2 is NaN");
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(3, 2);
  m(1, 1) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(MessageOf([&] { CheckFinite(m, "m"); }),
            "indoorloc: argument 'm': entry (1, 1) is infinite");
  EXPECT_NO_THROW(CheckFinite(Eigen::MatrixXd::Ones(2, 2), "ok"));
}

TEST(Check, CheckShape) {
  Eigen::MatrixXd m(3, 2);
  EXPECT_NO_THROW(CheckShape(m, 3, 2, "m"));
  EXPECT_NO_THROW(CheckShape(m, -1, 2, "m"));
  EXPECT_EQ(MessageOf([&] { CheckShape(m, -1, 3, "positions_m"); }),
            "indoorloc: argument 'positions_m': expected shape (any, 3), got (3, 2)");
}

TEST(Check, ScalarChecks) {
  EXPECT_NO_THROW(CheckPositive(1e-9, "a"));
  EXPECT_THROW(CheckPositive(0.0, "a"), std::invalid_argument);
  EXPECT_THROW(CheckPositive(std::nan(""), "a"), std::invalid_argument);
  EXPECT_NO_THROW(CheckNonNegative(0.0, "a"));
  EXPECT_THROW(CheckNonNegative(-1.0, "a"), std::invalid_argument);
  EXPECT_NO_THROW(CheckInRange(0.5, 0, 1, "a"));
  EXPECT_THROW(CheckInRange(std::nan(""), 0, 1, "a"), std::invalid_argument);
  EXPECT_THROW(CheckInRange(1.5, 0, 1, "a"), std::invalid_argument);
}

struct ToyOptions {
  int iterations = 10;
  bool IsValid(std::string* error) const {
    if (iterations <= 0) {
      *error = "iterations must be > 0";
      return false;
    }
    return true;
  }
};

TEST(Options, ValidateOptionsThrowsWithReason) {
  ToyOptions options;
  EXPECT_NO_THROW(ValidateOptions(options));
  options.iterations = 0;
  EXPECT_EQ(MessageOf([&] { ValidateOptions(options); }),
            "indoorloc: argument 'options': iterations must be > 0");
  EXPECT_EQ(ToString(Termination::kConverged), "converged");
}

TEST(Options, WallTimerIsMonotone) {
  WallTimer timer;
  const double a = timer.ElapsedSeconds();
  const double b = timer.ElapsedSeconds();
  EXPECT_GE(a, 0.0);
  EXPECT_GE(b, a);
}

}  // namespace
}  // namespace indoorloc
