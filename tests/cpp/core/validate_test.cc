// The validation vocabulary (core/validate.h) and cooperative interruption (core/interrupt.h).
#include "indoorloc/core/validate.h"

#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "indoorloc/core/interrupt.h"
#include "indoorloc/core/parallel.h"

namespace indoorloc {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string MessageOf(void (*fn)()) {
  try {
    fn();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(Validator, FirstBrokenRuleIsReportedWithNameValueAndRule) {
  std::string error;
  const bool ok = Validator(&error)
                      .Positive(1.0, "a_m")
                      .Scale(kInf, "sigma_m")
                      .AtLeast(0, 1, "iterations")  // also broken, but reported second
                      .ok();
  EXPECT_FALSE(ok);
  EXPECT_EQ(error, "sigma_m must be finite and in [1e-12, 1e+12], got inf");
}

TEST(Validator, EveryRuleRejectsNaNAndInfinityAndAcceptsValidValues) {
  const double nan = std::nan("");
  for (const double bad : {nan, kInf, -kInf}) {
    std::string e;
    EXPECT_FALSE(Validator(&e).Finite(bad, "x")) << bad;
    EXPECT_FALSE(Validator(&e).Positive(bad, "x")) << bad;
    EXPECT_FALSE(Validator(&e).NonNegative(bad, "x")) << bad;
    EXPECT_FALSE(Validator(&e).Scale(bad, "x")) << bad;
    EXPECT_FALSE(Validator(&e).ZeroOrScale(bad, "x")) << bad;
    EXPECT_FALSE(Validator(&e).InRange(bad, -1.0, 1.0, "x")) << bad;
  }
  std::string e;
  EXPECT_FALSE(Validator(&e).Scale(1e-300, "sigma"));  // passes "> 0", overflows 1/sigma^2
  EXPECT_NE(e.find("got 1e-300"), std::string::npos);
  EXPECT_FALSE(Validator(&e).IntInRange(2147483647, 1, 10000, "iterations_per_scan"));
  EXPECT_EQ(e, "iterations_per_scan must be in [1, 10000], got 2147483647");
  EXPECT_TRUE(Validator(nullptr).Finite(0.0, "x").Positive(2.0, "x").NonNegative(0.0, "x").Scale(1.0, "x")
                  .ZeroOrScale(0.0, "x").InRange(1.0, 1.0, 1.0, "x").IntInRange(3, 3, 3, "n").AtLeast(5, 1, "n")
                  .Check(true, "x", "is fine"));
}

TEST(Require, ThrowingFormsNameTheArgumentValueAndRule) {
  EXPECT_EQ(MessageOf([] { RequirePositive(kInf, "rate_hz"); }),
            "indoorloc: argument 'rate_hz': must be finite and > 0, got inf");
  EXPECT_EQ(MessageOf([] { RequireFinite(std::nan(""), "mu_rad"); }),
            "indoorloc: argument 'mu_rad': must be finite, got nan");
  EXPECT_EQ(MessageOf([] { RequireIntegerValued(2.5, 0, 10, "segment"); }),
            "indoorloc: argument 'segment': must be a whole number in [0, 10], got 2.5");
  EXPECT_EQ(MessageOf([] { RequireIntInRange(-2, -1, 100, "num_out"); }),
            "indoorloc: argument 'num_out': must be in [-1, 100], got -2");
  EXPECT_EQ(MessageOf([] { RequireSizeLimit(1e10, 8.0, "size", "draws"); }),
            "indoorloc: argument 'size': 1e+10 draws would need 80 GB (limit 4 GB)");
  EXPECT_NO_THROW(RequireSizeLimit(1e6, 8.0, "size"));
  EXPECT_NO_THROW(RequireScale(1.0, "x"));
  EXPECT_NO_THROW(RequireNonNegative(0.0, "x"));
  EXPECT_NO_THROW(RequireInRange(0.5, 0.0, 1.0, "x"));
}

std::atomic<int> g_polls{0};
bool StopAfterThreePolls() { return ++g_polls >= 3; }

TEST(Interrupt, AHookStopsParallelRunsOnOneAndTwoThreads) {
  for (const int threads : {1, 2}) {
    g_polls = 0;
    SetInterruptHook(&StopAfterThreePolls);
    std::atomic<int> ran{0};
    // Each run waits long enough for the 20 ms poll interval to pass several times.
    EXPECT_THROW(ParallelForRuns(100000, threads, 1,
                                 [&](int, RandomStream&) {
                                   ++ran;
                                   const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(5);
                                   while (std::chrono::steady_clock::now() < until) CheckInterrupt();
                                 }),
                 Interrupted)
        << threads;
    EXPECT_LT(ran.load(), 1000) << threads;
    SetInterruptHook(nullptr);
    ClearInterrupt();
    // Without a hook nothing stops.
    std::atomic<int> all{0};
    ParallelForRuns(50, threads, 1, [&](int, RandomStream&) { ++all; CheckInterrupt(); });
    EXPECT_EQ(all.load(), 50);
  }
}

std::atomic<int> g_late_polls{0};
bool StopAtTheSecondPoll() { return ++g_late_polls == 2; }

// The waiting thread sees the stop after the workers' last check (they never check again): the
// call must still end with Interrupted, and the next call must run undisturbed (the stop used to
// stay pending and interrupt it).
TEST(Interrupt, AStopSeenAfterTheWorkersLastCheckEndsThisCallNotTheNext) {
  g_late_polls = 0;
  SetInterruptHook(&StopAtTheSecondPoll);
  EXPECT_THROW(ParallelForRuns(2, 2, 1,
                               [&](int, RandomStream&) {
                                 std::this_thread::sleep_for(std::chrono::milliseconds(150));  // no check inside
                               }),
               Interrupted);
  SetInterruptHook(nullptr);
  ClearInterrupt();
  std::atomic<int> all{0};
  EXPECT_NO_THROW(ParallelForRuns(4, 2, 1, [&](int, RandomStream&) { ++all; CheckInterrupt(); }));
  EXPECT_EQ(all.load(), 4);
}

}  // namespace
}  // namespace indoorloc
