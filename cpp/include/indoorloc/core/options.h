// The Options / Summary pattern shared by every indoorloc algorithm (after Ceres'
// Solver::Options and Solver::Summary).
//
//  - Every algorithm takes an `XxxOptions` struct whose members have documented defaults and
//    which has `bool IsValid(std::string* error) const`.
//  - The algorithm calls ValidateOptions(options) first: invalid options throw
//    std::invalid_argument (Python: ValueError) before any work is done.
//  - It returns (or fills) an `XxxSummary` with the termination reason, iteration counts,
//    timings and method diagnostics (ESS, log-likelihood, ...) and a one-line BriefReport().
#pragma once

#include <chrono>
#include <string>
#include <string_view>

#include "indoorloc/core/check.h"

namespace indoorloc {

/// Throws std::invalid_argument("indoorloc: argument 'options': <reason>") unless
/// options.IsValid(&reason).
template <typename Options>
void ValidateOptions(const Options& options, std::string_view argument = "options") {
  std::string error;
  if (!options.IsValid(&error)) ThrowInvalidArgument(argument, error);
}

/// Why an iterative algorithm stopped.
enum class Termination {
  kCompleted,      ///< a non-iterative algorithm ran to the end
  kConverged,      ///< a convergence tolerance was met
  kMaxIterations,  ///< the iteration budget ran out
  kNoProgress,     ///< a step made no progress (line search, singular system)
  kFailure,        ///< numerical failure; see the Summary's message
};

/// "completed", "converged", "max_iterations", "no_progress" or "failure".
std::string_view ToString(Termination termination);

/// Wall-clock stopwatch for the timings in Summaries, in seconds.
class WallTimer {
 public:
  WallTimer() : start_(std::chrono::steady_clock::now()) {}
  /// Seconds since construction or the last Reset().
  double ElapsedSeconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  void Reset() { start_ = std::chrono::steady_clock::now(); }

 private:
  std::chrono::steady_clock::time_point start_;
};

}  // namespace indoorloc
