// Deterministic parallel Monte Carlo runs.
//
// ParallelForRuns(n_runs, n_threads, seed, fn) calls fn(run, rng) once for every run in
// [0, n_runs), on up to n_threads threads. The stream given to run r is RandomStream(seed, r),
// whatever thread executes it, so results depend on the seed only, never on the thread count or
// the scheduling. fn must write its result into a slot owned by `run` (no shared mutable state).
#pragma once

#include <cstdint>
#include <functional>

#include "indoorloc/core/random.h"

namespace indoorloc {

/// Number of threads to use when the caller asks for `requested` (<= 0: all hardware threads).
int ResolveThreadCount(int requested);

/// Runs fn(run, rng) for run = 0..n_runs-1 on min(n_threads, n_runs) threads. The first
/// exception thrown by any run is rethrown in the caller after all threads have stopped; runs not
/// yet started are then skipped.
void ParallelForRuns(int n_runs, int n_threads, std::uint64_t seed,
                     const std::function<void(int run, RandomStream& rng)>& fn);

}  // namespace indoorloc
