// Python bindings of the analog subsystem: catalogs, kNN transitions, the analog HMM and the
// generic sparse forward-backward / Viterbi.
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "indoorloc/analog/analog_hmm.h"
#include "indoorloc/analog/catalog.h"
#include "indoorloc/analog/forward_backward.h"
#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "numpy_args.h"

namespace indoorloc::bindings {

using analog::AnalogHMM;
using analog::AnalogHmmOptions;
using analog::Catalog;
using analog::CatalogOptions;
using analog::SparseTransitions;

namespace {

SparseTransitions TransitionsFromNumpy(const py::object& next_idx, const py::object& prob) {
  MatrixArg p = ToMatrix(prob, "prob");
  MatrixArg n = ToMatrix(next_idx, "next_idx", p.map.rows(), p.map.cols());
  // Checked here with the caller's names (SparseTransitions::Validate can only say 'transitions').
  const Eigen::Index m = p.map.rows();
  for (Eigen::Index i = 0; i < m; ++i) {
    double row = 0.0;
    for (Eigen::Index j = 0; j < p.map.cols(); ++j) {
      const double v = n.map(i, j);
      if (!(v >= 0.0 && v < static_cast<double>(m) && v == std::floor(v)))
        ThrowInvalidArgument("next_idx", DescribeEntry(i, j, false) + " = " + FormatValue(v) +
                                             " is not a state index in [0, " + std::to_string(m) + ")");
      if (!(p.map(i, j) >= 0.0))
        ThrowInvalidArgument("prob", DescribeEntry(i, j, false) + " is negative: " + FormatValue(p.map(i, j)));
      row += p.map(i, j);
    }
    if (!(std::abs(row - 1.0) <= 1e-9))
      ThrowInvalidArgument("prob", "row " + std::to_string(i) + " sums to " + FormatValue(row) + ", not 1 (within 1e-9)");
  }
  SparseTransitions tr;
  tr.num_states = static_cast<int>(p.map.rows());
  tr.k = static_cast<int>(p.map.cols());
  tr.next.resize(static_cast<size_t>(p.map.size()));
  tr.prob.assign(p.map.data(), p.map.data() + p.map.size());
  for (Eigen::Index i = 0; i < n.map.size(); ++i) tr.next[static_cast<size_t>(i)] = static_cast<int>(n.map.data()[i]);
  return tr;
}

// The arguments of the generic forward_backward / viterbi bindings, converted and checked.
struct GenericHmm {
  SparseTransitions transitions;
  analog::RowMatrixXd log_b;
  Eigen::VectorXd initial;
  analog::ForwardBackwardOptions options;

  GenericHmm(const py::object& next_idx, const py::object& prob, const py::object& log_emission,
             const py::object& initial_obj, const py::object& beam)
      : transitions(TransitionsFromNumpy(next_idx, prob)) {
    log_b = ToMatrix(log_emission, "log_emission", -1, transitions.num_states, Finiteness::kAllowMinusInf).map;
    CheckArgument(log_b.rows() >= 1, "log_emission", "has no time step (0 rows)");
    initial = ToVector(initial_obj, "initial", transitions.num_states).map;
    options.beam = beam.is_none() ? 0 : ToInt(beam, "beam", 0, 1 << 30);
  }
  int steps() const { return static_cast<int>(log_b.rows()); }
  analog::LogEmission emission() const {
    return [this](int t, const int* s, int n, double* out) {
      for (int i = 0; i < n; ++i) out[i] = log_b(t, s[i]);
    };
  }
};

py::array_t<double> DensePosterior(const analog::SparsePosteriors& p, int m) {
  const py::ssize_t steps = static_cast<py::ssize_t>(p.states.size());
  py::array_t<double> out({steps, static_cast<py::ssize_t>(m)});
  double* data = out.mutable_data();
  std::fill(data, data + steps * m, 0.0);
  for (size_t t = 0; t < p.states.size(); ++t)
    for (size_t i = 0; i < p.states[t].size(); ++i) data[t * static_cast<size_t>(m) + static_cast<size_t>(p.states[t][i])] = p.probabilities[t][i];
  return out;
}

}  // namespace

/// The catalog of analogs (states and their successors).
static void BindCatalog(py::module_& m) {
  py::class_<Catalog, std::shared_ptr<Catalog>>(m, "Catalog", R"doc(
Catalog of (analog, successor) pairs from historical trajectories (paper 001, eq. 2 and 6).

Parameters
----------
trajectories : list of (T_i, d) float arrays
lag : int
    Time-lag embedding δ: a state is (x_t, x_{t-1}, ..., x_{t-δ+1}), dimension d·δ.
stride : int
    The successor of the state at t is the state at t + stride.)doc")
      .def(py::init([](const py::list& trajectories, int lag, int stride) {
             std::vector<analog::RowMatrixXd> trajs;
             for (size_t i = 0; i < trajectories.size(); ++i) {
               const std::string name = "trajectories[" + std::to_string(i) + "]";
               MatrixArg a = ToMatrix(trajectories[i], name.c_str());
               trajs.emplace_back(a.map);
             }
             CatalogOptions o;
             o.lag = lag;
             o.stride = stride;
             py::gil_scoped_release release;
             return std::make_shared<Catalog>(trajs, o);
           }),
           py::arg("trajectories"), py::arg("lag") = 1, py::arg("stride") = 1)
      .def_property_readonly("states", &Catalog::states, "(M, D) every embedded state.")
      .def_property_readonly("analogs", &Catalog::analogs, "Indices of the states that have a successor.")
      .def_property_readonly("successors", &Catalog::successors, "Successor state index of each analog.")
      .def_property_readonly("num_states", &Catalog::num_states)
      .def_property_readonly("num_analogs", &Catalog::num_analogs)
      .def_property_readonly("dim", &Catalog::dim)
      .def_property_readonly("base_dim", &Catalog::base_dim)
      .def("knn", [](const Catalog& c, const py::object& queries, int k) {
             MatrixArg q = ToMatrix(queries, "queries", -1, c.dim());
             Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> idx;
             analog::RowMatrixXd d2;
             {
               py::gil_scoped_release release;
               analog::KnnAnalogs(c, q.map, k, &idx, &d2);
             }
             return py::make_tuple(idx, d2);
           },
           py::arg("queries"), py::arg("k"),
           "Exact K nearest analogs of queries (Q, D): (indices into `analogs` (Q, K), squared distances (Q, K)).");
}

/// The analog HMM and its smoother.
static void BindAnalogHmm(py::module_& m) {
  py::class_<AnalogHMM, std::shared_ptr<AnalogHMM>>(m, "AnalogHMM", R"doc(
Analog HMM (paper 001 §2.2): kNN transitions (eq. 4, adaptive σ) and Gaussian observations of
selected state components with covariance R (eq. 5).

Parameters
----------
catalog : Catalog
k : int
    Successors per state (K of eq. 4; the paper uses 5-15).
observed : list of int
    State components that are observed.
R : (m, m) array
    Observation covariance, symmetric positive definite, in the state's units squared.
sigma_scale : float
    Multiplier of the adaptive kernel width σ_i = std of state i's K distances (1 = the paper;
    smaller values concentrate each transition on the nearest analog's successor).
successor_rule : {"catalog", "incremental"}
    Target of the transition through analog a_j: "catalog" = its successor (eq. 4, the paper);
    "incremental" = the catalog state nearest to s_i + (successor - a_j) (locally incremental
    analog operator; equal targets merged).)doc")
      .def(py::init([](const std::shared_ptr<Catalog>& catalog, int k, const std::vector<int>& observed, const py::object& R,
                       double sigma_scale, const std::string& successor_rule) {
             CheckArgument(catalog != nullptr, "catalog", "is None");  // a null holder would crash
             AnalogHmmOptions o;
             o.k = k;
             o.sigma_scale = sigma_scale;
             if (successor_rule == "catalog") {
               o.successor_rule = analog::SuccessorRule::kCatalog;
             } else if (successor_rule == "incremental") {
               o.successor_rule = analog::SuccessorRule::kIncremental;
             } else {
               ThrowInvalidArgument("successor_rule", "must be 'catalog' or 'incremental', got '" + successor_rule + "'");
             }
             o.observed = observed;
             const Eigen::Index mdim = static_cast<Eigen::Index>(observed.empty() ? 1 : observed.size());
             MatrixArg r = ToMatrix(R, "R", mdim, mdim);
             o.R = r.map;
             py::gil_scoped_release release;
             return std::make_shared<AnalogHMM>(catalog, o);
           }),
           py::arg("catalog"), py::arg("k") = AnalogHmmOptions().k, py::arg("observed") = std::vector<int>{0}, py::arg("R"),
           py::arg("sigma_scale") = AnalogHmmOptions().sigma_scale,
           py::arg("successor_rule") = AnalogHmmOptions().successor_rule == analog::SuccessorRule::kCatalog
                                           ? "catalog"
                                           : "incremental")
      .def_property_readonly("transitions_next", [](const AnalogHMM& h) {
        const auto& t = h.transitions();
        return Eigen::Map<const Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(t.next.data(), t.num_states, t.k);
      })
      .def_property_readonly("transitions_prob", [](const AnalogHMM& h) {
        const auto& t = h.transitions();
        return Eigen::Map<const analog::RowMatrixXd>(t.prob.data(), t.num_states, t.k);
      })
      .def("smooth", [](const AnalogHMM& h, const py::object& observations, const py::object& beam, int beam_unobserved,
                        double max_dropped_mass, int beam_max, const py::object& initial) {
             MatrixArg obs = ToMatrix(observations, "observations", -1, -1, Finiteness::kAny);
             const int n = beam.is_none() ? 0 : ToInt(beam, "beam", 0, 1 << 30);
             CheckArgument(n >= 0, "beam", "must be >= 0 or None");
             CheckArgument(beam_unobserved >= 0, "beam_unobserved", "must be >= 0");
             CheckArgument(max_dropped_mass >= 0.0 && max_dropped_mass <= 1.0, "max_dropped_mass", "must be in [0, 1]");
             CheckArgument(beam_max >= 0, "beam_max", "must be >= 0 (0: no cap)");
             analog::SmoothOptions so;
             so.beam = n;
             so.beam_unobserved = beam_unobserved;
             so.max_dropped_mass = max_dropped_mass;
             so.beam_max = beam_max;
             if (!initial.is_none()) {
               so.initial = ToVector(initial, "initial", h.catalog().num_states()).map;
             }
             analog::SmoothingOutput out;
             {
               py::gil_scoped_release release;
               out = h.Smooth(obs.map, so);
             }
             py::dict d;
             d["mean"] = out.mean;
             d["mpm"] = out.mpm;
             d["filtering_mean"] = out.filtering_mean;
             d["std"] = out.std;
             d["log_likelihood"] = out.log_likelihood;
             d["dropped_mass"] = out.dropped_mass;
             d["support_size"] = out.support_size;
             d["seconds"] = out.seconds;
             return d;
           },
           py::arg("observations"), py::arg("beam") = py::none(),
           py::arg("beam_unobserved") = analog::SmoothOptions().beam_unobserved,
           py::arg("max_dropped_mass") = analog::SmoothOptions().max_dropped_mass,
           py::arg("beam_max") = analog::SmoothOptions().beam_max, py::arg("initial") = py::none(), R"doc(
Forward-backward on observations (T, m) (NaN = missing). beam=None: exact; beam=N: truncated
(paper §2.3); beam_unobserved: a wider beam at steps with no observation (0: same as beam);
max_dropped_mass: mass-adaptive beam, keep more than N states (most likely first) until at most
this filtering mass is dropped per step (1: off), capped at beam_max states (0: no cap);
initial: prior P(X_1) as non-negative weights, one per catalog state (num_states,), None = uniform. Returns a dict: mean (T, D) posterior mean, std (T, D) posterior standard deviation, mpm (T, D), filtering_mean (T, D),
log_likelihood, dropped_mass (T,), support_size (T,), seconds.)doc")
      .def("viterbi", [](const AnalogHMM& h, const py::object& observations, const py::object& beam) {
             MatrixArg obs = ToMatrix(observations, "observations", -1, -1, Finiteness::kAny);
             const int n = beam.is_none() ? 0 : ToInt(beam, "beam", 0, 1 << 30);
             analog::ViterbiResult v;
             {
               py::gil_scoped_release release;
               v = h.MapSequence(obs.map, n);
             }
             analog::RowMatrixXd states(static_cast<Eigen::Index>(v.states.size()), h.catalog().dim());
             for (size_t t = 0; t < v.states.size(); ++t) states.row(static_cast<Eigen::Index>(t)) = h.catalog().states().row(v.states[t]);
             py::dict d;
             d["indices"] = v.states;
             d["states"] = states;
             d["log_probability"] = v.log_probability;
             return d;
           },
           py::arg("observations"), py::arg("beam") = py::none(), "MAP state sequence (Viterbi): dict indices (T,), states (T, D).");
}

/// forward_backward and viterbi on explicit sparse transitions.
static void BindSparseHmmAlgorithms(py::module_& m) {
  m.def("forward_backward", [](const py::object& next_idx, const py::object& prob, const py::object& log_emission,
                               const py::object& initial, const py::object& beam) {
          const GenericHmm h(next_idx, prob, log_emission, initial, beam);
          analog::ForwardBackwardResult r;
          {
            py::gil_scoped_release release;
            r = analog::ForwardBackward(h.transitions, h.initial, h.steps(), h.emission(), h.options);
          }
          const int num_states = h.transitions.num_states;
          py::dict d;
          d["posterior"] = DensePosterior(r.smoothing, num_states);
          d["filtering"] = DensePosterior(r.filtering, num_states);
          d["log_likelihood"] = r.log_likelihood;
          d["dropped_mass"] = r.dropped_mass;
          d["seconds"] = r.seconds;
          return d;
        },
        py::arg("next_idx"), py::arg("prob"), py::arg("log_emission"), py::arg("initial"), py::arg("beam") = py::none(), R"doc(
Forward-backward for any HMM with K successors per state: next_idx (M, K) int, prob (M, K)
(rows sum to 1), log_emission (T, M) = log b_j(y_t), initial (M,) >= 0. Returns a dict with
dense posterior (T, M), filtering (T, M), log_likelihood, dropped_mass (T,), seconds.)doc");

  m.def("viterbi", [](const py::object& next_idx, const py::object& prob, const py::object& log_emission,
                      const py::object& initial, const py::object& beam) {
          const GenericHmm h(next_idx, prob, log_emission, initial, beam);
          const analog::ViterbiResult v = analog::Viterbi(h.transitions, h.initial, h.steps(), h.emission(), h.options);
          return py::make_tuple(v.states, v.log_probability);
        },
        py::arg("next_idx"), py::arg("prob"), py::arg("log_emission"), py::arg("initial"), py::arg("beam") = py::none(),
        "MAP path (T,) and its log-probability for an HMM given as in forward_backward.");
}

void BindAnalog(py::module_& m) {
  BindCatalog(m);
  BindAnalogHmm(m);
  BindSparseHmmAlgorithms(m);
}

}  // namespace indoorloc::bindings
