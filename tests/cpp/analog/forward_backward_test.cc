#include "indoorloc/analog/forward_backward.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "indoorloc/core/random.h"

namespace indoorloc::analog {
namespace {

struct TinyHmm {
  SparseTransitions tr;
  Eigen::VectorXd initial;
  Eigen::MatrixXd log_b;  // T x M
};

// M states, K successors each (random, distinct), random emissions; some steps unobserved.
TinyHmm MakeHmm(int m, int k, int steps, std::uint64_t seed) {
  RandomStream rng(seed);
  TinyHmm h;
  h.tr.num_states = m;
  h.tr.k = k;
  for (int i = 0; i < m; ++i) {
    std::vector<int> pool(static_cast<size_t>(m));
    for (int j = 0; j < m; ++j) pool[static_cast<size_t>(j)] = j;
    double total = 0;
    std::vector<double> w;
    for (int j = 0; j < k; ++j) {
      const size_t pick = static_cast<size_t>(j) + static_cast<size_t>(rng.UniformInt(static_cast<std::uint64_t>(m - j)));
      std::swap(pool[static_cast<size_t>(j)], pool[pick]);
      h.tr.next.push_back(pool[static_cast<size_t>(j)]);
      w.push_back(rng.Uniform(0.1, 1.0));
      total += w.back();
    }
    for (double x : w) h.tr.prob.push_back(x / total);
  }
  h.initial = Eigen::VectorXd::Ones(m);
  h.log_b.resize(steps, m);
  for (int t = 0; t < steps; ++t)
    for (int j = 0; j < m; ++j) h.log_b(t, j) = (t == 2) ? 0.0 : -rng.Uniform(0.0, 30.0);  // t = 2: no observation
  return h;
}

LogEmission FromMatrix(const Eigen::MatrixXd& log_b) {
  return [log_b](int t, const int* s, int n, double* out) {
    for (int i = 0; i < n; ++i) out[i] = log_b(t, s[i]);
  };
}

double TransitionProb(const SparseTransitions& tr, int i, int j) {
  double p = 0;
  for (int k = 0; k < tr.k; ++k) {
    if (tr.next[static_cast<size_t>(i * tr.k + k)] == j) p += tr.prob[static_cast<size_t>(i * tr.k + k)];
  }
  return p;
}

// Exhaustive enumeration of all M^T paths: smoothing posteriors, log-likelihood, MAP path.
void BruteForce(const TinyHmm& h, Eigen::MatrixXd* posterior, double* log_likelihood, std::vector<int>* map_path) {
  const int m = h.tr.num_states, steps = static_cast<int>(h.log_b.rows());
  *posterior = Eigen::MatrixXd::Zero(steps, m);
  double total = 0, best = -1;
  std::vector<int> path(static_cast<size_t>(steps), 0);
  long count = 1;
  for (int t = 0; t < steps; ++t) count *= m;
  for (long code = 0; code < count; ++code) {
    long c = code;
    for (int t = 0; t < steps; ++t) {
      path[static_cast<size_t>(t)] = static_cast<int>(c % m);
      c /= m;
    }
    double p = h.initial[path[0]] / h.initial.sum() * std::exp(h.log_b(0, path[0]));
    for (int t = 1; t < steps && p > 0; ++t) {
      p *= TransitionProb(h.tr, path[static_cast<size_t>(t - 1)], path[static_cast<size_t>(t)]) * std::exp(h.log_b(t, path[static_cast<size_t>(t)]));
    }
    total += p;
    for (int t = 0; t < steps; ++t) (*posterior)(t, path[static_cast<size_t>(t)]) += p;
    if (p > best) {
      best = p;
      *map_path = path;
    }
  }
  *posterior /= total;
  *log_likelihood = std::log(total);
}

class ForwardBackwardBruteForce : public ::testing::TestWithParam<std::uint64_t> {};

TEST_P(ForwardBackwardBruteForce, ExactAndFullBeamMatchEnumeration) {
  const TinyHmm h = MakeHmm(5, 3, 6, GetParam());
  Eigen::MatrixXd expected;
  double expected_ll;
  std::vector<int> expected_map;
  BruteForce(h, &expected, &expected_ll, &expected_map);
  for (int beam : {0, 5, 100}) {
    ForwardBackwardOptions o;
    o.beam = beam;
    const ForwardBackwardResult r = ForwardBackward(h.tr, h.initial, 6, FromMatrix(h.log_b), o);
    EXPECT_NEAR(r.log_likelihood, expected_ll, 1e-9);
    for (int t = 0; t < 6; ++t) {
      Eigen::VectorXd got = Eigen::VectorXd::Zero(5);
      double sum = 0;
      for (size_t i = 0; i < r.smoothing.states[t].size(); ++i) {
        got[r.smoothing.states[t][i]] = r.smoothing.probabilities[t][i];
        sum += r.smoothing.probabilities[t][i];
      }
      EXPECT_NEAR(sum, 1.0, 1e-12);
      EXPECT_LT((got - expected.row(t).transpose()).cwiseAbs().maxCoeff(), 1e-10) << "beam " << beam << " t " << t;
      EXPECT_EQ(r.dropped_mass[t], 0.0);
    }
    const ViterbiResult v = Viterbi(h.tr, h.initial, 6, FromMatrix(h.log_b), o);
    EXPECT_EQ(v.states, expected_map) << "beam " << beam;
  }
}

INSTANTIATE_TEST_SUITE_P(Seeds, ForwardBackwardBruteForce, ::testing::Values(1u, 2u, 3u, 4u, 5u));

TEST(ForwardBackward, TruncationDropsMassAndStillNormalises) {
  const TinyHmm h = MakeHmm(40, 4, 30, 9);
  ForwardBackwardOptions o;
  o.beam = 5;
  const ForwardBackwardResult r = ForwardBackward(h.tr, h.initial, 30, FromMatrix(h.log_b), o);
  double dropped = 0;
  for (int t = 0; t < 30; ++t) {
    EXPECT_LE(r.filtering.states[t].size(), 5u);
    double sum = 0;
    for (double p : r.smoothing.probabilities[t]) sum += p;
    EXPECT_NEAR(sum, 1.0, 1e-12);
    dropped += r.dropped_mass[t];
  }
  EXPECT_GT(dropped, 0.0);
}

TEST(ForwardBackward, MassAdaptiveBeamBoundsTheDroppedMass) {
  const TinyHmm h = MakeHmm(40, 4, 30, 9);
  for (double tolerance : {0.2, 0.01}) {
    ForwardBackwardOptions o;
    o.beam = 2;
    o.max_dropped_mass = tolerance;
    const ForwardBackwardResult r = ForwardBackward(h.tr, h.initial, 30, FromMatrix(h.log_b), o);
    bool widened = false;
    for (int t = 0; t < 30; ++t) {
      EXPECT_LE(r.dropped_mass[t], tolerance + 1e-12) << "t " << t;
      widened = widened || r.filtering.states[t].size() > 2u;
    }
    EXPECT_TRUE(widened);
  }
  // Tolerance 0 keeps every state with non-zero mass: the exact posteriors.
  ForwardBackwardOptions tight;
  tight.beam = 1;
  tight.max_dropped_mass = 0.0;
  const ForwardBackwardResult exact = ForwardBackward(h.tr, h.initial, 30, FromMatrix(h.log_b));
  const ForwardBackwardResult r = ForwardBackward(h.tr, h.initial, 30, FromMatrix(h.log_b), tight);
  EXPECT_NEAR(r.log_likelihood, exact.log_likelihood, 1e-9);
  for (int t = 0; t < 30; ++t) {
    Eigen::VectorXd a = Eigen::VectorXd::Zero(40), b = Eigen::VectorXd::Zero(40);
    for (size_t i = 0; i < exact.smoothing.states[t].size(); ++i) a[exact.smoothing.states[t][i]] = exact.smoothing.probabilities[t][i];
    for (size_t i = 0; i < r.smoothing.states[t].size(); ++i) b[r.smoothing.states[t][i]] = r.smoothing.probabilities[t][i];
    EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-10) << "t " << t;
  }
  // The cap wins over the tolerance.
  ForwardBackwardOptions capped;
  capped.beam = 2;
  capped.max_dropped_mass = 0.0;
  capped.beam_max = 3;
  const ForwardBackwardResult c = ForwardBackward(h.tr, h.initial, 30, FromMatrix(h.log_b), capped);
  for (int t = 0; t < 30; ++t) EXPECT_LE(c.filtering.states[t].size(), 3u);
}

TEST(ForwardBackward, ExtremeEmissionsDoNotUnderflow) {
  TinyHmm h = MakeHmm(6, 2, 5, 11);
  h.log_b.array() -= 5000.0;  // every likelihood underflows in linear space
  const ForwardBackwardResult r = ForwardBackward(h.tr, h.initial, 5, FromMatrix(h.log_b));
  EXPECT_TRUE(std::isfinite(r.log_likelihood));
  for (const auto& p : r.smoothing.probabilities)
    for (double x : p) EXPECT_TRUE(std::isfinite(x));
}

TEST(ForwardBackward, BadInputGivesClearErrors) {
  TinyHmm h = MakeHmm(4, 2, 3, 1);
  EXPECT_THROW(ForwardBackward(h.tr, Eigen::VectorXd::Ones(3), 3, FromMatrix(h.log_b)), std::invalid_argument);
  EXPECT_THROW(ForwardBackward(h.tr, h.initial, 0, FromMatrix(h.log_b)), std::invalid_argument);
  h.tr.prob[0] += 0.5;  // row no longer sums to 1
  EXPECT_THROW(ForwardBackward(h.tr, h.initial, 3, FromMatrix(h.log_b)), std::invalid_argument);
  ForwardBackwardOptions o;
  o.beam = -1;
  EXPECT_THROW(ForwardBackward(MakeHmm(4, 2, 3, 1).tr, h.initial, 3, FromMatrix(h.log_b), o), std::invalid_argument);
  o.beam = 2;
  o.max_dropped_mass = 1.5;
  EXPECT_THROW(ForwardBackward(MakeHmm(4, 2, 3, 1).tr, h.initial, 3, FromMatrix(h.log_b), o), std::invalid_argument);
}

}  // namespace
}  // namespace indoorloc::analog
