#include "indoorloc/analog/forward_backward.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <functional>
#include <limits>
#include <numeric>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"

namespace indoorloc::analog {
namespace {

constexpr double kMinusInf = -std::numeric_limits<double>::infinity();

// Number of states to keep: `beam`, or more (most likely first) until the dropped mass is at most
// `max_dropped` (capped at `beam_max` when > 0). `values` are normalised probabilities.
size_t KeptCount(const std::vector<double>& values, int beam, double max_dropped, int beam_max) {
  const size_t n = values.size();
  if (beam <= 0 || n <= static_cast<size_t>(beam)) return n;
  if (!(max_dropped < 1.0)) return static_cast<size_t>(beam);
  const size_t cap = beam_max > 0 ? std::min(n, static_cast<size_t>(std::max(beam_max, beam))) : n;
  std::vector<double> sorted(values);
  std::sort(sorted.begin(), sorted.end(), std::greater<double>());
  double kept = 0.0;
  size_t count = 0;
  for (; count < cap; ++count) {
    if (count >= static_cast<size_t>(beam) && 1.0 - kept <= max_dropped) break;
    kept += sorted[count];
  }
  return count;
}

// Keeps the `count` largest entries of (states, values) (ties: smaller state index first);
// returns the mass removed (values are normalised probabilities) and renormalises the rest.
double Truncate(std::vector<int>* states, std::vector<double>* values, size_t count) {
  const size_t n = states->size();
  if (n <= count) return 0.0;
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(count), order.end(),
                   [&](size_t a, size_t b) { return (*values)[a] > (*values)[b] || ((*values)[a] == (*values)[b] && (*states)[a] < (*states)[b]); });
  order.resize(count);
  std::sort(order.begin(), order.end());  // keep the original (deterministic) order
  std::vector<int> s;
  std::vector<double> v;
  s.reserve(order.size());
  v.reserve(order.size());
  double kept = 0.0;
  for (size_t i : order) {
    s.push_back((*states)[i]);
    v.push_back((*values)[i]);
    kept += (*values)[i];
  }
  for (double& x : v) x /= kept;
  states->swap(s);
  values->swap(v);
  return 1.0 - kept;
}

void CheckInputs(const SparseTransitions& transitions, const Eigen::VectorXd& initial, int num_steps) {
  transitions.Validate();
  CheckArgument(initial.size() == transitions.num_states, "initial",
                "expected " + std::to_string(transitions.num_states) + " entries, got " + std::to_string(initial.size()));
  CheckFinite(initial, "initial");
  CheckArgument((initial.array() >= 0.0).all() && initial.sum() > 0.0, "initial",
                "must be non-negative with a positive sum");
  CheckArgument(num_steps >= 1, "num_steps", "must be >= 1");
}

}  // namespace

void SparseTransitions::Validate() const {
  CheckArgument(num_states > 0, "transitions", "no states");
  CheckArgument(k > 0, "transitions", "k must be >= 1");
  const size_t size = static_cast<size_t>(num_states) * static_cast<size_t>(k);
  CheckArgument(next.size() == size && prob.size() == size, "transitions", "next/prob must have num_states * k entries");
  for (int i = 0; i < num_states; ++i) {
    double row = 0.0;
    for (int j = 0; j < k; ++j) {
      const size_t e = static_cast<size_t>(i) * static_cast<size_t>(k) + static_cast<size_t>(j);
      if (next[e] < 0 || next[e] >= num_states) ThrowInvalidArgument("transitions", "next index out of range in row " + std::to_string(i));
      if (!(prob[e] >= 0.0) || !std::isfinite(prob[e])) ThrowInvalidArgument("transitions", "negative or non-finite probability in row " + std::to_string(i));
      row += prob[e];
    }
    if (std::abs(row - 1.0) > 1e-9) ThrowInvalidArgument("transitions", "row " + std::to_string(i) + " does not sum to 1");
  }
}

bool ForwardBackwardOptions::IsValid(std::string* error) const {
  if (beam < 0) {
    *error = "beam must be >= 0 (0: exact)";
    return false;
  }
  for (int b : beam_per_step) {
    if (b < 0) {
      *error = "beam_per_step entries must be >= 0";
      return false;
    }
  }
  if (!(max_dropped_mass >= 0.0 && max_dropped_mass <= 1.0)) {
    *error = "max_dropped_mass must be in [0, 1]";
    return false;
  }
  if (beam_max < 0) {
    *error = "beam_max must be >= 0 (0: no cap)";
    return false;
  }
  return true;
}

ForwardBackwardResult ForwardBackward(const SparseTransitions& tr, const Eigen::VectorXd& initial, int num_steps,
                                      const LogEmission& log_emission, const ForwardBackwardOptions& options) {
  ValidateOptions(options);
  CheckInputs(tr, initial, num_steps);
  CheckArgument(options.beam_per_step.empty() || options.beam_per_step.size() == static_cast<size_t>(num_steps),
                "beam_per_step", "must be empty or have one entry per step");
  const auto start = std::chrono::steady_clock::now();
  const int m = tr.num_states, k = tr.k;
  const size_t steps = static_cast<size_t>(num_steps);
  ForwardBackwardResult out;
  out.filtering.states.resize(steps);
  out.filtering.probabilities.resize(steps);
  out.dropped_mass = Eigen::VectorXd::Zero(num_steps);
  std::vector<std::vector<double>> emission(steps);  // linear b_j(y_t) / max, on the support
  std::vector<double> log_b;
  std::vector<double> predicted(static_cast<size_t>(m), 0.0);
  std::vector<char> touched(static_cast<size_t>(m), 0);

  // Forward with scaling. Per step: predicted prior p_j (scatter over the K successors of the
  // support), emissions b_j = exp(log b_j - max log b) (one exp per candidate, no log), then
  // α_j ∝ p_j b_j and log-likelihood increment max log b + log Σ p_j b_j.
  std::vector<int> cand;
  std::vector<double> prior;
  cand.reserve(static_cast<size_t>(m));
  prior.reserve(static_cast<size_t>(m));
  for (size_t t = 0; t < steps; ++t) {
    cand.clear();
    prior.clear();
    if (t == 0) {
      const double total = initial.sum();
      for (int j = 0; j < m; ++j) {
        if (initial[j] > 0.0) {
          cand.push_back(j);
          prior.push_back(initial[j] / total);
        }
      }
    } else {
      const std::vector<int>& s = out.filtering.states[t - 1];
      const std::vector<double>& a = out.filtering.probabilities[t - 1];
      for (size_t i = 0; i < s.size(); ++i) {
        const size_t base = static_cast<size_t>(s[i]) * static_cast<size_t>(k);
        const double ai = a[i];
        for (int j = 0; j < k; ++j) {
          const size_t nxt = static_cast<size_t>(tr.next[base + static_cast<size_t>(j)]);
          if (!touched[nxt]) {
            touched[nxt] = 1;
            cand.push_back(static_cast<int>(nxt));
          }
          predicted[nxt] += ai * tr.prob[base + static_cast<size_t>(j)];
        }
      }
      prior.resize(cand.size());
      for (size_t c = 0; c < cand.size(); ++c) {
        const size_t j = static_cast<size_t>(cand[c]);
        prior[c] = predicted[j];
        predicted[j] = 0.0;
        touched[j] = 0;
      }
    }
    log_b.resize(cand.size());
    log_emission(static_cast<int>(t), cand.data(), static_cast<int>(cand.size()), log_b.data());
    double bmax = kMinusInf;
    for (double v : log_b) bmax = std::max(bmax, v);
    if (bmax == kMinusInf) ThrowInvalidArgument(options.emission_argument, "every candidate state has zero likelihood (-inf) at step " + std::to_string(t));
    std::vector<double> b(cand.size());
    std::vector<double> alpha(cand.size());
    double sum = 0.0;
    for (size_t c = 0; c < cand.size(); ++c) {
      b[c] = std::exp(log_b[c] - bmax);
      sum += (alpha[c] = prior[c] * b[c]);
    }
    if (!(sum > 0.0)) ThrowInvalidArgument(options.emission_argument, "the observations have zero likelihood under every predicted state at step " + std::to_string(t));
    out.log_likelihood += bmax + std::log(sum);
    const double inv = 1.0 / sum;
    for (double& v : alpha) v *= inv;
    // Truncate (carrying b along).
    const int beam = options.beam_per_step.empty() ? options.beam : options.beam_per_step[t];
    const size_t keep = KeptCount(alpha, beam, options.max_dropped_mass, options.beam_max);
    if (keep < cand.size()) {
      std::vector<int> states(cand.size());
      std::iota(states.begin(), states.end(), 0);
      out.dropped_mass[static_cast<Eigen::Index>(t)] = Truncate(&states, &alpha, keep);
      std::vector<int> kept_states(states.size());
      std::vector<double> kept_b(states.size());
      for (size_t c = 0; c < states.size(); ++c) {
        kept_states[c] = cand[static_cast<size_t>(states[c])];
        kept_b[c] = b[static_cast<size_t>(states[c])];
      }
      out.filtering.states[t] = std::move(kept_states);
      out.filtering.probabilities[t] = std::move(alpha);
      emission[t] = std::move(kept_b);
    } else {
      out.filtering.states[t] = cand;
      out.filtering.probabilities[t] = std::move(alpha);
      emission[t] = std::move(b);
    }
  }

  // Backward on the forward supports, rescaled every step.
  out.smoothing.states = out.filtering.states;
  out.smoothing.probabilities.resize(steps);
  std::vector<double> beta_next;  // β_{t+1} · b_{t+1} on supp_{t+1}, scattered into a dense scratch
  std::vector<double> weight(static_cast<size_t>(m), 0.0);
  std::vector<double> beta(out.filtering.states[steps - 1].size(), 1.0);
  for (size_t t = steps; t-- > 0;) {
    const std::vector<int>& s = out.filtering.states[t];
    const std::vector<double>& a = out.filtering.probabilities[t];
    if (t + 1 < steps) {
      const std::vector<int>& s1 = out.filtering.states[t + 1];
      for (size_t j = 0; j < s1.size(); ++j) weight[static_cast<size_t>(s1[j])] = beta_next[j] * emission[t + 1][j];
      beta.assign(s.size(), 0.0);
      double bmax = 0.0;
      for (size_t i = 0; i < s.size(); ++i) {
        const size_t base = static_cast<size_t>(s[i]) * static_cast<size_t>(k);
        double acc = 0.0;
        for (int j = 0; j < k; ++j) acc += tr.prob[base + static_cast<size_t>(j)] * weight[static_cast<size_t>(tr.next[base + static_cast<size_t>(j)])];
        beta[i] = acc;
        bmax = std::max(bmax, acc);
      }
      for (size_t j = 0; j < s1.size(); ++j) weight[static_cast<size_t>(s1[j])] = 0.0;
      if (bmax > 0.0) {
        for (double& v : beta) v /= bmax;
      }
    }
    std::vector<double> gamma(s.size());
    double total = 0.0;
    for (size_t i = 0; i < s.size(); ++i) total += (gamma[i] = a[i] * beta[i]);
    if (total > 0.0) {
      for (double& g : gamma) g /= total;
    } else {
      gamma = a;  // the truncated backward lost every path: fall back to filtering
    }
    out.smoothing.probabilities[t] = std::move(gamma);
    beta_next = beta;
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

ViterbiResult Viterbi(const SparseTransitions& tr, const Eigen::VectorXd& initial, int num_steps,
                      const LogEmission& log_emission, const ForwardBackwardOptions& options) {
  ValidateOptions(options);
  CheckInputs(tr, initial, num_steps);
  const int m = tr.num_states, k = tr.k;
  const size_t steps = static_cast<size_t>(num_steps);
  std::vector<std::vector<int>> support(steps), back(steps);
  std::vector<double> score;  // δ on the current support (log)
  std::vector<double> best(static_cast<size_t>(m), kMinusInf);
  std::vector<int> from(static_cast<size_t>(m), -1);
  std::vector<double> log_b;
  for (size_t t = 0; t < steps; ++t) {
    std::vector<int> cand;
    std::vector<double> val;
    std::vector<int> bp;
    if (t == 0) {
      for (int j = 0; j < m; ++j) {
        if (initial[j] > 0.0) {
          cand.push_back(j);
          val.push_back(std::log(initial[j] / initial.sum()));
          bp.push_back(-1);
        }
      }
    } else {
      const std::vector<int>& s = support[t - 1];
      for (size_t i = 0; i < s.size(); ++i) {
        const size_t base = static_cast<size_t>(s[i]) * static_cast<size_t>(k);
        for (int j = 0; j < k; ++j) {
          const double p = tr.prob[base + static_cast<size_t>(j)];
          if (p <= 0.0) continue;
          const int nxt = tr.next[base + static_cast<size_t>(j)];
          const double v = score[i] + std::log(p);
          if (best[static_cast<size_t>(nxt)] == kMinusInf) cand.push_back(nxt);
          // Ties go to the smaller predecessor index: deterministic and equal to exhaustive search.
          if (v > best[static_cast<size_t>(nxt)] ||
              (v == best[static_cast<size_t>(nxt)] && s[i] < from[static_cast<size_t>(nxt)])) {
            best[static_cast<size_t>(nxt)] = v;
            from[static_cast<size_t>(nxt)] = s[i];
          }
        }
      }
      val.resize(cand.size());
      bp.resize(cand.size());
      for (size_t c = 0; c < cand.size(); ++c) {
        val[c] = best[static_cast<size_t>(cand[c])];
        bp[c] = from[static_cast<size_t>(cand[c])];
        best[static_cast<size_t>(cand[c])] = kMinusInf;
        from[static_cast<size_t>(cand[c])] = -1;
      }
    }
    log_b.resize(cand.size());
    log_emission(static_cast<int>(t), cand.data(), static_cast<int>(cand.size()), log_b.data());
    for (size_t c = 0; c < cand.size(); ++c) val[c] += log_b[c];
    // No path left: backtracking would follow -1 pointers (it crashed on observations of 1e300).
    if (std::none_of(val.begin(), val.end(), [](double v) { return v > kMinusInf; })) {
      ThrowInvalidArgument(options.emission_argument,
                           "every candidate state has zero likelihood (-inf) at step " + std::to_string(t));
    }
    if (options.beam > 0 && cand.size() > static_cast<size_t>(options.beam)) {
      std::vector<size_t> order(cand.size());
      std::iota(order.begin(), order.end(), 0);
      std::nth_element(order.begin(), order.begin() + options.beam, order.end(),
                       [&](size_t a, size_t b) { return val[a] > val[b] || (val[a] == val[b] && cand[a] < cand[b]); });
      order.resize(static_cast<size_t>(options.beam));
      std::sort(order.begin(), order.end());
      std::vector<int> c2, b2;
      std::vector<double> v2;
      for (size_t o : order) {
        c2.push_back(cand[o]);
        v2.push_back(val[o]);
        b2.push_back(bp[o]);
      }
      cand.swap(c2);
      val.swap(v2);
      bp.swap(b2);
    }
    support[t] = std::move(cand);
    back[t] = std::move(bp);
    score = std::move(val);
  }
  // Backtrack from the best final state (ties: smallest index).
  size_t arg = 0;
  for (size_t i = 1; i < score.size(); ++i) {
    if (score[i] > score[arg] || (score[i] == score[arg] && support[steps - 1][i] < support[steps - 1][arg])) arg = i;
  }
  ViterbiResult out;
  out.log_probability = score[arg];
  out.states.resize(steps);
  int state = support[steps - 1][arg];
  int pred = back[steps - 1][arg];
  out.states[steps - 1] = state;
  for (size_t t = steps - 1; t-- > 0;) {
    state = pred;
    out.states[t] = state;
    const std::vector<int>& s = support[t];
    const auto it = std::find(s.begin(), s.end(), state);
    pred = back[t][static_cast<size_t>(it - s.begin())];
  }
  return out;
}

}  // namespace indoorloc::analog
