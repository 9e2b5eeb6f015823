#include "indoorloc/fusion/wifi_likelihood.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "indoorloc/core/check.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/core/options.h"

namespace indoorloc::fusion {

bool WifiLikelihoodOptions::IsValid(std::string* error) const {
  // max_term and max_age_s accept +inf (no cap, keep every reading); NaN fails every rule.
  return Validator(error)
      .Check(tempering > 0.0 && tempering <= 1.0, "tempering", "must be in (0, 1], got " + FormatValue(tempering))
      .Check(max_term > 0.0, "max_term", "must be > 0 (+inf disables the cap), got " + FormatValue(max_term))
      .Check(max_age_s >= 0.0, "max_age_s", "must be >= 0 (+inf keeps every reading), got " + FormatValue(max_age_s))
      .Check(not_heard_dbm > -300.0 && not_heard_dbm < 50.0, "not_heard_dbm",
             "must be a finite RSS in (-300, 50) dBm, got " + FormatValue(not_heard_dbm));
}

void RequireWifiReadingsMemory(double scans, double access_points) {
  // Per reading: the re-timed copy (24 B), the observation's AP and RSS entries (12 B) and their
  // copies when groups are merged and handed to Python (2 x 12 B); per scan an observation.
  const double readings = scans * access_points;
  RequireSizeLimit(readings, 64.0 + 200.0 / std::max(1.0, access_points), "rss_dbm",
                   "readings (scans x access points)");
}

std::vector<WifiObservation> MakeWifiObservations(const Eigen::Ref<const Eigen::VectorXd>& scan_times_s,
                                                  const Eigen::Ref<const RowMatrixXd>& rss_dbm,
                                                  const Eigen::Ref<const RowMatrixXd>& ages_s,
                                                  const WifiLikelihoodOptions& options, bool at_own_time,
                                                  WifiReadingCounts* counts) {
  ValidateOptions(options, "options");
  const Eigen::Index num_scans = scan_times_s.size();
  CheckShape(rss_dbm, num_scans, -1, "rss_dbm");
  const bool have_ages = ages_s.size() > 0;
  if (have_ages) CheckShape(ages_s, num_scans, rss_dbm.cols(), "ages_s");
  RequireWifiReadingsMemory(static_cast<double>(num_scans), static_cast<double>(rss_dbm.cols()));
  CheckFinite(scan_times_s, "scan_times_s");
  for (Eigen::Index s = 1; s < num_scans; ++s) {
    CheckArgument(scan_times_s[s] >= scan_times_s[s - 1], "scan_times_s",
                  "must be non-decreasing (entry " + std::to_string(s) + " goes back in time)");
  }
  WifiReadingCounts local;
  std::vector<WifiObservation> out;
  struct Reading {
    double time;
    int ap;
    double rss;
  };
  std::vector<Reading> timed;  // heard readings at their own time
  for (Eigen::Index s = 0; s < num_scans; ++s) {
    WifiObservation scan;
    scan.time_s = scan_times_s[s];
    for (Eigen::Index k = 0; k < rss_dbm.cols(); ++k) {
      const double v = rss_dbm(s, k);
      if (std::isnan(v)) {
        if (options.use_not_heard) {
          scan.access_points.push_back(static_cast<int>(k));
          scan.rss_dbm.push_back(options.not_heard_dbm);
          ++local.not_heard;
        }
        continue;
      }
      if (!std::isfinite(v) || v < -300.0 || v > 50.0) {
        ThrowInvalidArgument("rss_dbm", DescribeEntry(s, k, false) + " = " + std::to_string(v) +
                                            " is not an RSS in dBm (use NaN for not heard)");
      }
      double age = 0.0;
      if (have_ages) {
        age = ages_s(s, k);
        if (std::isnan(age)) age = 0.0;
        if (!std::isfinite(age) || age < 0.0) {
          ThrowInvalidArgument("ages_s", DescribeEntry(s, k, false) + " = " + std::to_string(age) +
                                             ": ages must be finite and >= 0 (scan time minus last-seen time)");
        }
      }
      if (at_own_time) {
        timed.push_back({scan.time_s - age, static_cast<int>(k), v});
        ++local.heard;
        continue;
      }
      if (age > options.max_age_s) {
        ++local.dropped_stale;
        continue;
      }
      scan.access_points.push_back(static_cast<int>(k));
      scan.rss_dbm.push_back(v);
      ++scan.num_heard;
      ++local.heard;
    }
    if (!at_own_time && scan.num_heard == 0) ++local.scans_without_readings;
    if (!scan.empty()) out.push_back(std::move(scan));
  }
  if (at_own_time) {
    // Group the heard readings by their own time; a not-heard group stays with its scan. An AP
    // read twice at one instant (the same reading reported by two scans) is kept once.
    std::stable_sort(timed.begin(), timed.end(), [](const Reading& a, const Reading& b) { return a.time < b.time; });
    std::vector<WifiObservation> heard;
    for (size_t i = 0; i < timed.size();) {
      WifiObservation group;
      group.time_s = timed[i].time;
      size_t j = i;
      for (; j < timed.size() && timed[j].time == timed[i].time; ++j) {
        if (std::find(group.access_points.begin(), group.access_points.end(), timed[j].ap) != group.access_points.end()) {
          --local.heard;
          continue;
        }
        group.access_points.push_back(timed[j].ap);
        group.rss_dbm.push_back(timed[j].rss);
        ++group.num_heard;
      }
      heard.push_back(std::move(group));
      i = j;
    }
    std::vector<WifiObservation> merged;
    merged.reserve(out.size() + heard.size());
    std::merge(heard.begin(), heard.end(), out.begin(), out.end(), std::back_inserter(merged),
               [](const WifiObservation& a, const WifiObservation& b) { return a.time_s < b.time_s; });
    out = std::move(merged);
  }
  if (counts) *counts = local;
  return out;
}

WifiLikelihood::WifiLikelihood(const wifi::RssModel& model, const WifiLikelihoodOptions& options)
    : model_(model), options_(options) {
  ValidateOptions(options, "options.wifi");
}

void WifiLikelihood::CheckObservation(const WifiObservation& observation, const char* argument) const {
  const std::string name(argument);
  CheckArgument(std::isfinite(observation.time_s), name + ".time_s", "must be finite");
  CheckArgument(observation.access_points.size() == observation.rss_dbm.size(), name,
                "access_points and rss_dbm differ in length");
  const int k = model_.num_access_points();
  for (size_t i = 0; i < observation.access_points.size(); ++i) {
    const int ap = observation.access_points[i];
    if (ap < 0 || ap >= k) {
      ThrowInvalidArgument(name + ".access_points", "entry " + std::to_string(i) + " = " + std::to_string(ap) +
                                                         " is not an AP column of the signal map (0.." +
                                                         std::to_string(k - 1) + ")");
    }
    const double v = observation.rss_dbm[i];
    if (!std::isfinite(v) || v < -300.0 || v > 50.0) {
      ThrowInvalidArgument(name + ".rss_dbm", "entry " + std::to_string(i) + " = " + std::to_string(v) +
                                                   " is not a finite RSS in dBm");
    }
  }
}

double WifiLikelihood::LogLikelihood(double x_m, double y_m, int model_floor_index,
                                     const WifiObservation& observation) const {
  if (observation.access_points.empty()) return 0.0;
  // Locate once (from the interpolator's coarse grid: particle clouds are scattered), then
  // interpolate only the fields of the observation's APs: mean_i and variance_i are columns i
  // and K + i of the model's fields (wifi/rss_model.h), the variance floored as in RssModel.
  const wifi::DelaunayInterpolator& interp = model_.interpolator(model_floor_index);
  const wifi::BarycentricLocation at = interp.Locate(Eigen::Vector2d(x_m, y_m));
  const wifi::RowMatrixXd& fields = interp.fields();
  const double* f0 = fields.row(at.vertices[0]).data();
  const double* f1 = fields.row(at.vertices[1]).data();
  const double* f2 = fields.row(at.vertices[2]).data();
  const double b0 = at.weights[0], b1 = at.weights[1], b2 = at.weights[2];
  const int k = model_.num_access_points();
  const double floor_db2 = model_.options().variance_floor_db2;
  constexpr double kHalfLog2Pi = 0.91893853320467274178;
  double total = 0.0;
  const size_t n = observation.access_points.size();
  for (size_t i = 0; i < n; ++i) {
    const int ap = observation.access_points[i];
    const double mean = b0 * f0[ap] + b1 * f1[ap] + b2 * f2[ap];
    const double var = std::max(b0 * f0[k + ap] + b1 * f1[k + ap] + b2 * f2[k + ap], floor_db2);
    const double r = observation.rss_dbm[i] - mean;
    const double term = std::min(0.5 * r * r / var, options_.max_term);
    total -= kHalfLog2Pi + 0.5 * std::log(var) + term;
  }
  return options_.tempering * total;
}

}  // namespace indoorloc::fusion
