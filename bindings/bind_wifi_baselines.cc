// Python bindings of the WiFi fingerprinting baselines (indoorloc/wifi/fingerprint_baselines.h):
// class indoorloc._core.wifi.FingerprintLocator (RADAR NNSS, NNSS-AVG, weighted kNN, Horus).
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <sstream>
#include <string>

#include "indoorloc/core/check.h"
#include "indoorloc/wifi/fingerprint_baselines.h"
#include "numpy_args.h"

namespace indoorloc::bindings {
namespace {

using wifi::FingerprintEstimates;
using wifi::FingerprintLocator;
using wifi::FingerprintOptions;

std::unique_ptr<FingerprintLocator> MakeLocator(
    const py::object& reference_rss_dbm, const py::object& reference_positions_m,
    const py::object& reference_floors, const py::object& reference_variance_db2,
    const std::string& method, int k, double distance_epsilon_db, double variance_floor_db2) {
  // Scalars are checked here so that the message names the Python keyword, not 'options'.
  CheckArgument(k >= 1, "k", "must be >= 1, got " + std::to_string(k));
  CheckPositive(distance_epsilon_db, "distance_epsilon_db");
  CheckPositive(variance_floor_db2, "variance_floor_db2");
  FingerprintOptions options;
  options.method = wifi::ParseFingerprintMethod(method, "method");
  options.k = k;
  options.distance_epsilon_db = distance_epsilon_db;
  options.variance_floor_db2 = variance_floor_db2;

  const MatrixArg rss = ToMatrix(reference_rss_dbm, "reference_rss_dbm");
  const Eigen::Index num_rows = rss.map.rows();
  const Eigen::Index num_aps = rss.map.cols();
  const MatrixArg positions = ToMatrix(reference_positions_m, "reference_positions_m", num_rows, 2);
  const Eigen::VectorXi floors = ToIntVector(reference_floors, "reference_floors", num_rows);
  // None: an empty (0 x 0) map. (No assignment to a MatrixArg: Map::operator= copies values.)
  const MatrixArg variance =
      reference_variance_db2.is_none()
          ? MatrixArg()
          : ToMatrix(reference_variance_db2, "reference_variance_db2", num_rows, num_aps);

  std::unique_ptr<FingerprintLocator> locator;
  {
    py::gil_scoped_release release;  // copies R x K matrices, precomputes horus terms
    locator = std::make_unique<FingerprintLocator>(rss.map, positions.map, floors, variance.map,
                                                   options);
  }
  return locator;
}

py::tuple Locate(const FingerprintLocator& locator, const py::object& scans_dbm,
                 int num_threads) {
  // The column count is checked in C++, with a message naming the expected K.
  const MatrixArg scans = ToMatrix(scans_dbm, "scans_dbm");
  FingerprintEstimates estimates;
  {
    py::gil_scoped_release release;
    estimates = locator.Locate(scans.map, num_threads);
  }
  const py::ssize_t num_scans = static_cast<py::ssize_t>(estimates.score.size());
  py::array_t<double> positions({num_scans, py::ssize_t{2}});
  std::copy(estimates.positions_m.data(), estimates.positions_m.data() + 2 * num_scans,
            positions.mutable_data());
  py::array_t<std::int64_t> floors(num_scans);
  std::int64_t* floor_data = floors.mutable_data();
  for (py::ssize_t q = 0; q < num_scans; ++q) floor_data[q] = estimates.floors[q];
  return py::make_tuple(positions, floors, ToNumpy(estimates.score));
}

}  // namespace

void BindWifiBaselines(py::module_& m) {
  const wifi::FingerprintOptions defaults;  // the keyword defaults below are read from C++
  py::class_<FingerprintLocator>(m, "FingerprintLocator", R"doc(
Fingerprinting baselines: locate WiFi scans by matching them against reference fingerprints.

Methods (the comparison of paper 004, §1.2), with d_i the Euclidean signal distance [dB] between
the scan and reference row i:

- ``"nnss"``: nearest neighbour in signal space (RADAR, Bahl & Padmanabhan 2000): the position
  of the reference row with the smallest d_i (``k`` is ignored).
- ``"nnss_avg"``: unweighted mean position of the k nearest rows.
- ``"wknn"``: mean of the k nearest rows weighted by 1 / (d_i + distance_epsilon_db); usually
  run on raw training scans (one reference row per scan).
- ``"horus"`` (Youssef & Agrawala 2005): Gaussian log-likelihood of the scan under each
  reference point (independent APs, variances floored at variance_floor_db2); the estimate is
  the posterior-weighted mean of the k most likely points.

Floors: nnss and horus take the floor of the best match; nnss_avg and wknn take a (weighted)
vote among the k neighbours. The position is averaged over the neighbours on that floor only.
All RSS inputs must be prepared (not-heard readings replaced by a floor value, e.g. with
``SignalMap.prepare_scans``), so every entry is finite.

Parameters
----------
reference_rss_dbm : (R, K) float array
    Reference RSS [dBm]: a signal map's means (nnss, nnss_avg, horus) or raw training scans.
reference_positions_m : (R, 2) float array
    Reference positions [m].
reference_floors : (R,) int array
    Floor number of each reference row.
reference_variance_db2 : (R, K) float array or None
    RSS variances [dB^2] (a signal map's variances); required by ``"horus"``, ignored otherwise.
method : {"nnss", "nnss_avg", "wknn", "horus"}
k : int
    Neighbours averaged (>= 1; clamped to R; ignored by nnss).
distance_epsilon_db : float
    wknn: epsilon [dB] in the weight 1 / (d + epsilon), > 0.
variance_floor_db2 : float
    horus: lower bound [dB^2] on every variance, > 0.

Raises
------
ValueError
    On an unknown method, invalid options, R = 0, K = 0, a shape mismatch, a non-finite entry,
    a negative variance, or horus without variances.)doc")
      .def(py::init(&MakeLocator), py::arg("reference_rss_dbm"),
           py::arg("reference_positions_m"), py::arg("reference_floors"),
           py::arg("reference_variance_db2") = py::none(),
           py::arg("method") = std::string(wifi::ToString(defaults.method)), py::arg("k") = defaults.k,
           py::arg("distance_epsilon_db") = defaults.distance_epsilon_db,
           py::arg("variance_floor_db2") = defaults.variance_floor_db2)
      .def("locate", &Locate, py::arg("scans_dbm"), py::arg("num_threads") = 1, R"doc(
Locate a batch of scans.

Parameters
----------
scans_dbm : (Q, K) float array
    Prepared scans [dBm], same AP columns as the reference.
num_threads : int
    Threads to use (<= 0: all cores). The result does not depend on it.

Returns
-------
positions_m : (Q, 2) float64 array
    Estimated positions [m].
floors : (Q,) int64 array
    Estimated floor numbers.
score : (Q,) float64 array
    Signal distance [dB] to the best match (nnss, nnss_avg, wknn), or the negative
    log-likelihood [nats] of the most likely point (horus). Lower is better.)doc")
      .def_property_readonly("method", [](const FingerprintLocator& l) {
             return std::string(wifi::ToString(l.method()));
           }, "Matching method: \"nnss\", \"nnss_avg\", \"wknn\" or \"horus\".")
      .def_property_readonly("k", &FingerprintLocator::k, "k as given (before clamping to R).")
      .def_property_readonly("effective_k", &FingerprintLocator::effective_k,
                             "Neighbours actually used: 1 for nnss, else min(k, R).")
      .def_property_readonly("num_references", &FingerprintLocator::num_references,
                             "Number R of reference rows.")
      .def_property_readonly("num_access_points", &FingerprintLocator::num_access_points,
                             "Number K of access points (columns).")
      .def_property_readonly("has_variances", &FingerprintLocator::has_variances,
                             "True if reference variances were given.")
      .def("__repr__", [](const FingerprintLocator& l) {
        return "FingerprintLocator(method='" + std::string(wifi::ToString(l.method())) +
               "', k=" + std::to_string(l.k()) +
               ", num_references=" + std::to_string(l.num_references()) +
               ", num_access_points=" + std::to_string(l.num_access_points()) + ")";
      });
}

}  // namespace indoorloc::bindings
