#include "indoorloc/analog/analog_hmm.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <map>
#include <utility>

#include <Eigen/Cholesky>
#include <nanoflann.hpp>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"

namespace indoorloc::analog {
namespace {

constexpr double kLog2Pi = 1.8378770664093453;

// nanoflann dataset adaptor over the analog rows of the catalog's state matrix.
struct AnalogCloud {
  const RowMatrixXd& states;
  const std::vector<int>& rows;
  size_t kdtree_get_point_count() const { return rows.size(); }
  double kdtree_get_pt(size_t idx, size_t dim) const {
    return states(rows[idx], static_cast<Eigen::Index>(dim));
  }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const { return false; }
};

using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, AnalogCloud>, AnalogCloud, -1, size_t>;

}  // namespace

void KnnAnalogs(const Catalog& catalog, const Eigen::Ref<const RowMatrixXd>& queries, int k,
                Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>* indices, RowMatrixXd* squared_distances) {
  CheckArgument(k >= 1, "k", "must be >= 1, got " + std::to_string(k));
  CheckArgument(catalog.num_analogs() >= k, "k",
                "the catalog has " + std::to_string(catalog.num_analogs()) + " analogs, fewer than K = " + std::to_string(k));
  CheckShape(queries, -1, catalog.dim(), "queries");
  CheckFinite(queries, "queries");
  const AnalogCloud cloud{catalog.states(), catalog.analogs()};
  KdTree tree(static_cast<size_t>(catalog.dim()), cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();
  indices->resize(queries.rows(), k);
  squared_distances->resize(queries.rows(), k);
  std::vector<size_t> idx(static_cast<size_t>(k));
  std::vector<double> dist(static_cast<size_t>(k));
  for (Eigen::Index q = 0; q < queries.rows(); ++q) {
    const size_t found = tree.knnSearch(queries.row(q).data(), static_cast<size_t>(k), idx.data(), dist.data());
    CheckArgument(found == static_cast<size_t>(k), "queries", "kNN search returned too few neighbours");
    for (int j = 0; j < k; ++j) {
      (*indices)(q, j) = static_cast<int>(idx[static_cast<size_t>(j)]);
      (*squared_distances)(q, j) = dist[static_cast<size_t>(j)];
    }
  }
}

namespace {

// nanoflann dataset adaptor over every row of the catalog's state matrix (targets of the
// incremental rule may be any state, also one without a successor).
struct StateCloud {
  const RowMatrixXd& states;
  size_t kdtree_get_point_count() const { return static_cast<size_t>(states.rows()); }
  double kdtree_get_pt(size_t idx, size_t dim) const {
    return states(static_cast<Eigen::Index>(idx), static_cast<Eigen::Index>(dim));
  }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const { return false; }
};

using StateTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, StateCloud>, StateCloud, -1, size_t>;

// SuccessorRule::kIncremental: replace each target s_{F(j)} of state i by the state nearest to
// s_i + (s_{F(j)} - a_j); merge equal targets of a row (weights summed, first occurrence keeps
// the mass, later ones keep the same target with probability 0 so that K stays fixed).
void ApplyIncrementalRule(const Catalog& catalog, const Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>& nn,
                          SparseTransitions* tr) {
  const RowMatrixXd& states = catalog.states();
  const StateCloud cloud{states};
  StateTree tree(static_cast<size_t>(catalog.dim()), cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();
  const int k = tr->k;
  Eigen::VectorXd query(catalog.dim());
  for (int i = 0; i < tr->num_states; ++i) {
    const size_t base = static_cast<size_t>(i) * static_cast<size_t>(k);
    for (int j = 0; j < k; ++j) {
      const size_t a = static_cast<size_t>(nn(i, j));
      const int analog = catalog.analogs()[a], successor = catalog.successors()[a];
      query = states.row(i).transpose() + (states.row(successor) - states.row(analog)).transpose();
      size_t target = 0;
      double d2 = 0.0;
      tree.knnSearch(query.data(), 1, &target, &d2);
      tr->next[base + static_cast<size_t>(j)] = static_cast<int>(target);
    }
    for (int j = 1; j < k; ++j) {
      for (int l = 0; l < j; ++l) {
        if (tr->next[base + static_cast<size_t>(l)] == tr->next[base + static_cast<size_t>(j)]) {
          tr->prob[base + static_cast<size_t>(l)] += tr->prob[base + static_cast<size_t>(j)];
          tr->prob[base + static_cast<size_t>(j)] = 0.0;
          break;
        }
      }
    }
  }
}

}  // namespace

SparseTransitions BuildKnnTransitions(const Catalog& catalog, int k, double sigma_scale, SuccessorRule rule) {
  CheckArgument(std::isfinite(sigma_scale) && sigma_scale > 0.0, "sigma_scale", "must be finite and > 0, got " + std::to_string(sigma_scale));
  Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> nn;
  RowMatrixXd d2;
  KnnAnalogs(catalog, catalog.states(), k, &nn, &d2);
  SparseTransitions tr;
  tr.num_states = catalog.num_states();
  tr.k = k;
  tr.next.resize(static_cast<size_t>(tr.num_states) * static_cast<size_t>(k));
  tr.prob.resize(tr.next.size());
  for (int i = 0; i < tr.num_states; ++i) {
    // Eq. 4 with σ adapted per state: the standard deviation of its K distances (σ = 0: equal).
    double mean = 0.0, mean_sq = 0.0;
    for (int j = 0; j < k; ++j) {
      const double d = std::sqrt(d2(i, j));
      mean += d / k;
      mean_sq += d * d / k;
    }
    const double sigma = sigma_scale * std::sqrt(std::max(0.0, mean_sq - mean * mean));
    double total = 0.0;
    const size_t base = static_cast<size_t>(i) * static_cast<size_t>(k);
    // Shifted by the nearest distance (the weights are normalised anyway), so that the nearest
    // neighbour has weight 1 and a tiny σ can never underflow every weight to 0/0.
    const double d2_min = d2(i, 0);
    for (int j = 0; j < k; ++j) {
      const double w = sigma > 1e-12 * std::max(1.0, mean) ? std::exp(-(d2(i, j) - d2_min) / (2.0 * sigma * sigma)) : 1.0;
      tr.next[base + static_cast<size_t>(j)] = catalog.successors()[static_cast<size_t>(nn(i, j))];
      tr.prob[base + static_cast<size_t>(j)] = w;
      total += w;
    }
    for (int j = 0; j < k; ++j) tr.prob[base + static_cast<size_t>(j)] /= total;
  }
  if (rule == SuccessorRule::kIncremental) ApplyIncrementalRule(catalog, nn, &tr);
  return tr;
}

bool AnalogHmmOptions::IsValid(std::string* error) const {
  if (k < 1) {
    *error = "k must be >= 1";
    return false;
  }
  if (!(std::isfinite(sigma_scale) && sigma_scale > 0.0)) {
    *error = "sigma_scale must be finite and > 0";
    return false;
  }
  if (successor_rule != SuccessorRule::kCatalog && successor_rule != SuccessorRule::kIncremental) {
    *error = "successor_rule must be kCatalog or kIncremental";
    return false;
  }
  return true;
}

AnalogHMM::AnalogHMM(std::shared_ptr<const Catalog> catalog, const AnalogHmmOptions& options)
    : catalog_(std::move(catalog)), options_(options) {
  CheckArgument(catalog_ != nullptr, "catalog", "is null");
  ValidateOptions(options_);
  if (options_.observed.empty()) options_.observed = {0};
  for (int c : options_.observed) {
    CheckArgument(c >= 0 && c < catalog_->dim(), "observed",
                  "component " + std::to_string(c) + " is outside the state dimension " + std::to_string(catalog_->dim()));
  }
  CheckArgument(options_.observed.size() <= 63, "observed", "at most 63 observed components");
  const Eigen::Index m = static_cast<Eigen::Index>(options_.observed.size());
  CheckArgument(options_.R.rows() == m && options_.R.cols() == m, "R",
                "expected shape (" + std::to_string(m) + ", " + std::to_string(m) + "), got (" +
                    std::to_string(options_.R.rows()) + ", " + std::to_string(options_.R.cols()) + ")");
  CheckFinite(options_.R, "R");
  CheckArgument((options_.R - options_.R.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * std::max(1.0, options_.R.cwiseAbs().maxCoeff()),
                "R", "is not symmetric");
  Eigen::LLT<Eigen::MatrixXd> llt(options_.R);
  CheckArgument(llt.info() == Eigen::Success, "R", "is not positive definite");
  // K + 1 in 64 bits: k = INT_MAX overflowed int (UBSan, found by the property suite under ASan).
  const std::int64_t analogs_needed = static_cast<std::int64_t>(options_.k) + 1;
  CheckArgument(static_cast<std::int64_t>(catalog_->num_analogs()) >= analogs_needed, "k",
                "k = " + std::to_string(options_.k) + " needs at least K + 1 = " + std::to_string(analogs_needed) +
                    " analogs, argument 'catalog' has " + std::to_string(catalog_->num_analogs()));
  transitions_ = BuildKnnTransitions(*catalog_, options_.k, options_.sigma_scale, options_.successor_rule);
}

LogEmission AnalogHMM::Emission(const Eigen::Ref<const RowMatrixXd>& observations) const {
  const Eigen::Index m = static_cast<Eigen::Index>(options_.observed.size());
  CheckArgument(observations.cols() == m, "observations",
                "has " + std::to_string(observations.cols()) + " columns, the model observes " + std::to_string(m) + " components");
  for (Eigen::Index t = 0; t < observations.rows(); ++t) {
    for (Eigen::Index c = 0; c < m; ++c) {
      if (std::isinf(observations(t, c))) ThrowInvalidArgument("observations", DescribeEntry(t, c, false) + " is infinite");
      // Squared residuals must stay finite (1e300 gave -inf emissions for every state).
      if (std::abs(observations(t, c)) > 1e100)
        ThrowInvalidArgument("observations", DescribeEntry(t, c, false) + " = " + FormatValue(observations(t, c)) +
                                                 " is beyond +-1e100");
    }
  }
  // Per distinct missingness pattern: the observed sub-covariance's inverse and log-determinant.
  struct Pattern {
    std::vector<int> comps;      // indices into `observed`
    Eigen::MatrixXd inverse;
    double log_norm = 0.0;       // ½ log det(2π R_oo)
  };
  auto patterns = std::make_shared<std::map<std::uint64_t, Pattern>>();
  auto mask_of = std::make_shared<std::vector<std::uint64_t>>(static_cast<size_t>(observations.rows()));
  for (Eigen::Index t = 0; t < observations.rows(); ++t) {
    std::uint64_t mask = 0;
    for (Eigen::Index c = 0; c < m; ++c) {
      if (!std::isnan(observations(t, c))) mask |= std::uint64_t{1} << c;
    }
    (*mask_of)[static_cast<size_t>(t)] = mask;
    if (mask == 0 || patterns->count(mask)) continue;
    Pattern p;
    for (Eigen::Index c = 0; c < m; ++c) {
      if (mask >> c & 1) p.comps.push_back(static_cast<int>(c));
    }
    Eigen::MatrixXd sub(p.comps.size(), p.comps.size());
    for (size_t a = 0; a < p.comps.size(); ++a)
      for (size_t b = 0; b < p.comps.size(); ++b) sub(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) = options_.R(p.comps[a], p.comps[b]);
    Eigen::LLT<Eigen::MatrixXd> llt(sub);
    p.inverse = llt.solve(Eigen::MatrixXd::Identity(sub.rows(), sub.cols()));
    p.log_norm = 0.5 * static_cast<double>(p.comps.size()) * kLog2Pi +
                 llt.matrixLLT().diagonal().array().log().sum();
    patterns->emplace(mask, std::move(p));
  }
  const RowMatrixXd obs = observations;  // owned copy: the callback may outlive the caller's view
  const std::vector<int> observed = options_.observed;
  const Catalog* catalog = catalog_.get();
  return [patterns, mask_of, obs, observed, catalog](int t, const int* states, int count, double* out) {
    const std::uint64_t mask = (*mask_of)[static_cast<size_t>(t)];
    if (mask == 0) {
      std::fill(out, out + count, 0.0);
      return;
    }
    const Pattern& p = patterns->at(mask);
    const size_t n = p.comps.size();
    Eigen::VectorXd r(static_cast<Eigen::Index>(n));
    for (int s = 0; s < count; ++s) {
      const auto row = catalog->states().row(states[s]);
      for (size_t a = 0; a < n; ++a) {
        const int c = p.comps[a];
        r[static_cast<Eigen::Index>(a)] = obs(t, c) - row(observed[static_cast<size_t>(c)]);
      }
      out[s] = -0.5 * r.dot(p.inverse * r) - p.log_norm;
    }
  };
}

bool SmoothOptions::IsValid(std::string* error) const {
  if (beam < 0 || beam_unobserved < 0 || beam_max < 0) {
    *error = "beam, beam_unobserved and beam_max must be >= 0";
    return false;
  }
  if (!(max_dropped_mass >= 0.0 && max_dropped_mass <= 1.0)) {
    *error = "max_dropped_mass must be in [0, 1]";
    return false;
  }
  return true;
}

SmoothingOutput AnalogHMM::Smooth(const Eigen::Ref<const RowMatrixXd>& observations, const SmoothOptions& options) const {
  ValidateOptions(options);
  CheckArgument(observations.rows() >= 1, "observations", "has no time step");
  const int beam = options.beam, beam_unobserved = options.beam_unobserved;
  const LogEmission emission = Emission(observations);
  ForwardBackwardOptions fb;
  fb.beam = beam;
  fb.emission_argument = "observations";
  fb.max_dropped_mass = options.max_dropped_mass;
  fb.beam_max = options.beam_max;
  if (beam > 0 && beam_unobserved > 0) {
    fb.beam_per_step.resize(static_cast<size_t>(observations.rows()));
    for (Eigen::Index t = 0; t < observations.rows(); ++t) {
      const bool observed = !observations.row(t).array().isNaN().all();
      fb.beam_per_step[static_cast<size_t>(t)] = observed ? beam : beam_unobserved;
    }
  }
  if (options.initial.size() != 0) {
    CheckArgument(options.initial.size() == catalog_->num_states(), "initial",
                  "expected " + std::to_string(catalog_->num_states()) + " weights (one per catalog state), got " +
                      std::to_string(options.initial.size()));
  }
  // Uniform prior unless given (ForwardBackward checks non-negative, finite, positive sum).
  const Eigen::VectorXd initial =
      options.initial.size() != 0 ? options.initial : Eigen::VectorXd::Ones(catalog_->num_states());
  const ForwardBackwardResult r = ForwardBackward(transitions_, initial, static_cast<int>(observations.rows()), emission, fb);
  const Eigen::Index steps = observations.rows();
  const RowMatrixXd& states = catalog_->states();
  SmoothingOutput out;
  out.mean = RowMatrixXd::Zero(steps, catalog_->dim());
  out.filtering_mean = RowMatrixXd::Zero(steps, catalog_->dim());
  out.std = RowMatrixXd::Zero(steps, catalog_->dim());
  out.mpm.resize(steps, catalog_->dim());
  out.support_size.resize(steps);
  for (Eigen::Index t = 0; t < steps; ++t) {
    const auto& s = r.smoothing.states[static_cast<size_t>(t)];
    const auto& g = r.smoothing.probabilities[static_cast<size_t>(t)];
    const auto& f = r.filtering.probabilities[static_cast<size_t>(t)];
    size_t arg = 0;
    int support = 0;
    for (size_t i = 0; i < s.size(); ++i) {
      out.mean.row(t) += g[i] * states.row(s[i]);
      out.filtering_mean.row(t) += f[i] * states.row(s[i]);
      if (g[i] > g[arg]) arg = i;
      support += g[i] > 0.0;
    }
    for (size_t i = 0; i < s.size(); ++i) {
      out.std.row(t) += g[i] * (states.row(s[i]) - out.mean.row(t)).array().square().matrix();
    }
    out.std.row(t) = out.std.row(t).array().sqrt().matrix();
    out.mpm.row(t) = states.row(s[arg]);
    out.support_size[t] = support;
  }
  out.log_likelihood = r.log_likelihood;
  out.dropped_mass = r.dropped_mass;
  out.seconds = r.seconds;
  return out;
}

ViterbiResult AnalogHMM::MapSequence(const Eigen::Ref<const RowMatrixXd>& observations, int beam) const {
  CheckArgument(observations.rows() >= 1, "observations", "has no time step");
  const LogEmission emission = Emission(observations);
  ForwardBackwardOptions fb;
  fb.beam = beam;
  fb.emission_argument = "observations";
  return Viterbi(transitions_, Eigen::VectorXd::Ones(catalog_->num_states()), static_cast<int>(observations.rows()), emission, fb);
}

}  // namespace indoorloc::analog
