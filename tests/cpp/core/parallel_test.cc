#include "indoorloc/core/parallel.h"

#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace indoorloc {
namespace {

std::vector<double> RunMany(int n_threads) {
  std::vector<double> results(64);
  ParallelForRuns(64, n_threads, 1234, [&](int run, RandomStream& rng) {
    double s = 0.0;
    for (int k = 0; k < 1000; ++k) s += rng.Normal();
    results[run] = s;
  });
  return results;
}

TEST(ParallelForRuns, ResultsDoNotDependOnThreadCount) {
  const std::vector<double> one = RunMany(1);
  EXPECT_EQ(one, RunMany(2));
  EXPECT_EQ(one, RunMany(7));
  EXPECT_EQ(one, RunMany(0));
}

TEST(ParallelForRuns, EveryRunExactlyOnce) {
  std::vector<int> hits(100, 0);
  ParallelForRuns(100, 4, 0, [&](int run, RandomStream&) { ++hits[run]; });
  for (int h : hits) EXPECT_EQ(h, 1);
  EXPECT_NO_THROW(ParallelForRuns(0, 4, 0, [](int, RandomStream&) {}));
  EXPECT_THROW(ParallelForRuns(-1, 4, 0, [](int, RandomStream&) {}), std::invalid_argument);
}

TEST(ParallelForRuns, RethrowsTheFirstError) {
  EXPECT_THROW(ParallelForRuns(50, 3, 0,
                               [](int run, RandomStream&) {
                                 if (run == 10) throw std::runtime_error("run 10 failed");
                               }),
               std::runtime_error);
}

}  // namespace
}  // namespace indoorloc
