// Python bindings of the shared-AP fingerprint matcher (indoorloc/wifi/shared_ap_matcher.h):
// indoorloc._core.wifi.SharedApMatcherOptions and SharedApMatcher (numpy in and out, GIL
// released around the matching, queries split over threads).
#include <cstdint>
#include <cstring>
#include <string>

#include "indoorloc/core/check.h"
#include "indoorloc/wifi/shared_ap_matcher.h"
#include "numpy_args.h"
#include "options_binding.h"

namespace indoorloc::bindings {
namespace {

using wifi::SharedApMatcher;
using wifi::SharedApMatcherOptions;
using wifi::SharedApNeighbours;
using wifi::SharedApParts;
using wifi::SharedApRowMatrixXd;

py::array_t<double> ToNumpyMatrix(const SharedApRowMatrixXd& x) {
  py::array_t<double> out({static_cast<py::ssize_t>(x.rows()), static_cast<py::ssize_t>(x.cols())});
  if (x.size() > 0) std::memcpy(out.mutable_data(), x.data(), sizeof(double) * static_cast<size_t>(x.size()));
  return out;
}

SharedApMatcher* MakeMatcher(const py::object& reference_rss_dbm, const py::object& ap_weights,
                             const py::object& options) {
  SharedApMatcherOptions o;
  if (!options.is_none()) {
    if (!py::isinstance<SharedApMatcherOptions>(options)) {
      ThrowInvalidArgument("options", "expected None or a SharedApMatcherOptions, got " +
                                          std::string(Py_TYPE(options.ptr())->tp_name));
    }
    o = options.cast<SharedApMatcherOptions>();
  }
  // NaN (not heard) is allowed; the C++ constructor checks the rest and names the argument.
  const MatrixArg rss = ToMatrix(reference_rss_dbm, "reference_rss_dbm", -1, -1, Finiteness::kAny);
  const VectorArg g = ap_weights.is_none() ? VectorArg()
                                           : ToVector(ap_weights, "ap_weights", rss.map.cols());
  py::gil_scoped_release release;
  return new SharedApMatcher(rss.map, g.map, o);
}

int Threads(const py::object& num_threads) { return ToInt(num_threads, "num_threads", -1024, 1024); }

}  // namespace

void BindWifiMatcher(py::module_& m) {
  py::class_<SharedApMatcherOptions> options(m, "SharedApMatcherOptions", R"doc(
Options of SharedApMatcher. Defaults (read them with ``SharedApMatcherOptions().to_dict()``) are
the fusion tracker's WiFi fix settings chosen by leave-one-floor-out cross-validation
(docs/fusion_real.md, "WiFi as fixes").)doc");
  options
      .def_readwrite("penalty_db", &SharedApMatcherOptions::penalty_db,
                     "c of d = rms + c u: cost of a fully unshared AP set [dB], in [0, 1e4].")
      .def_readwrite("strength_scale_db", &SharedApMatcherOptions::strength_scale_db,
                     "beta of the strength weights exp((rss + 40 dBm) / beta) [dB]; 0 = off, else >= 1.")
      .def_readwrite("k", &SharedApMatcherOptions::k, "Neighbours returned by nearest (>= 1, clamped to N).")
      .def_readwrite("temperature_db", &SharedApMatcherOptions::temperature_db,
                     "T of the neighbour weights exp(-(d - d_min) / T) [dB], > 0.");
  BindOptionsProtocol(options, "SharedApMatcherOptions");

  py::class_<SharedApMatcher>(m, "SharedApMatcher", R"doc(
Shared-access-point fingerprint matcher (docs/wifi.md, "Shared-AP kNN"; docs/fusion_real.md,
"WiFi as fixes"). With A, B the APs heard by a query a and a reference b, AP weights g_i and
strength weights f(x) = exp((x + 40 dBm) / beta) (1 when beta = 0), in dB:

    w_i = g_i f(a_i)
    rms(a, b) = sqrt( sum_{A^B} w_i (a_i - b_i)^2 / sum_{A^B} w_i )
    u(a, b)   = 1 - sum_{A^B} w_i / ( sum_A g_i f(a_i) + sum_{B\A} g_i f(b_i) )
    d(a, b)   = rms + c u            (+inf where nothing is shared)

Parameters
----------
reference_rss_dbm : (N, K) float array
    Reference fingerprints [dBm], NaN = not heard; other entries finite within +-1000 dBm.
ap_weights : (K,) float array or None
    g_i >= 0 (None: all 1).
options : SharedApMatcherOptions or None

Raises
------
ValueError
    Naming the argument: bad shapes, inf or |RSS| > 1000 dBm, negative weights, invalid options.)doc")
      .def(py::init(&MakeMatcher), py::arg("reference_rss_dbm"), py::arg("ap_weights") = py::none(),
           py::arg("options") = py::none())
      .def("parts",
           [](const SharedApMatcher& matcher, const py::object& queries_dbm, const py::object& num_threads) {
             const MatrixArg q = ToMatrix(queries_dbm, "queries_dbm", -1, -1, Finiteness::kAny);
             const int threads = Threads(num_threads);
             SharedApParts parts;
             {
               py::gil_scoped_release release;
               parts = matcher.Parts(q.map, threads);
             }
             return py::make_tuple(ToNumpyMatrix(parts.rms_db), ToNumpyMatrix(parts.unshared));
           },
           py::arg("queries_dbm"), py::arg("num_threads") = 1, R"doc(
(rms_db (Q, N), unshared (Q, N)) of queries_dbm (Q, K) [dBm, NaN = not heard] against every
reference: d = rms_db + c unshared for any c. num_threads <= 0: all cores (results do not depend on it).)doc")
      .def("dissimilarity",
           [](const SharedApMatcher& matcher, const py::object& queries_dbm, const py::object& num_threads) {
             const MatrixArg q = ToMatrix(queries_dbm, "queries_dbm", -1, -1, Finiteness::kAny);
             const int threads = Threads(num_threads);
             SharedApRowMatrixXd d;
             {
               py::gil_scoped_release release;
               d = matcher.Dissimilarity(q.map, threads);
             }
             return ToNumpyMatrix(d);
           },
           py::arg("queries_dbm"), py::arg("num_threads") = 1,
           "d (Q, N) [dB] of queries_dbm (Q, K) against every reference, with options.penalty_db.")
      .def("nearest",
           [](const SharedApMatcher& matcher, const py::object& queries_dbm, const py::object& num_threads) {
             const MatrixArg q = ToMatrix(queries_dbm, "queries_dbm", -1, -1, Finiteness::kAny);
             const int threads = Threads(num_threads);
             SharedApNeighbours nn;
             {
               py::gil_scoped_release release;
               nn = matcher.Nearest(q.map, threads);
             }
             py::array_t<std::int64_t> index({static_cast<py::ssize_t>(nn.index.rows()),
                                              static_cast<py::ssize_t>(nn.index.cols())});
             std::int64_t* out = index.mutable_data();
             for (Eigen::Index i = 0; i < nn.index.size(); ++i) out[i] = static_cast<std::int64_t>(nn.index.data()[i]);
             return py::make_tuple(index, ToNumpyMatrix(nn.distance_db), ToNumpyMatrix(nn.weight));
           },
           py::arg("queries_dbm"), py::arg("num_threads") = 1, R"doc(
The min(k, N) nearest references of each query, best first (ties: lower reference index).

Returns
-------
index : (Q, k) int64
    Reference rows; where fewer than k references share an AP, the rest are the lowest-numbered
    other references (d = inf, weight 0), so every index is a valid row.
distance_db : (Q, k) float64
    d [dB], +inf where nothing is shared.
weight : (Q, k) float64
    exp(-(d - d_min) / T), 0 where d = inf.)doc")
      .def_property_readonly("options", &SharedApMatcher::options)
      .def_property_readonly("num_references", &SharedApMatcher::num_references, "N.")
      .def_property_readonly("num_access_points", &SharedApMatcher::num_access_points, "K.")
      .def_property_readonly("num_heard", &SharedApMatcher::num_heard, "Heard entries of the references.")
      .def("__repr__", [](const SharedApMatcher& s) {
        return "SharedApMatcher(num_references=" + std::to_string(s.num_references()) +
               ", num_access_points=" + std::to_string(s.num_access_points()) +
               ", num_heard=" + std::to_string(s.num_heard()) + ")";
      });
}

}  // namespace indoorloc::bindings
