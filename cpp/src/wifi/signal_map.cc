#include "indoorloc/wifi/signal_map.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "rss_limits.h"

namespace indoorloc::wifi {
namespace {

constexpr const char* kFileMagic = "# indoorloc signal map v1";

bool IsNotHeard(double v, double sentinel) { return std::isnan(v) || v == sentinel; }

}  // namespace

bool SignalMapOptions::IsValid(std::string* error) const {
  return Validator(error)
      .InRange(not_heard_dbm, -internal::kMaxAbsRssDb, internal::kMaxAbsRssDb, "not_heard_dbm")
      .Scale(variance_floor_db2, "variance_floor_db2")
      .InRange(min_point_fraction, 0.0, 1.0, "min_point_fraction");
}

RowMatrixXd ReplaceNotHeard(const Eigen::Ref<const RowMatrixXd>& rss_dbm, double not_heard_sentinel,
                            double not_heard_dbm) {
  RowMatrixXd out = rss_dbm;
  for (Eigen::Index i = 0; i < out.rows(); ++i) {
    for (Eigen::Index j = 0; j < out.cols(); ++j) {
      double& v = out(i, j);
      if (IsNotHeard(v, not_heard_sentinel)) {
        v = not_heard_dbm;
      } else if (!std::isfinite(v)) {
        ThrowInvalidArgument("rss_dbm", DescribeEntry(i, j, false) + " is infinite");
      }
    }
  }
  return out;
}

SignalMap::SignalMap(const Eigen::Ref<const RowMatrixXd>& positions_m, const Eigen::VectorXi& floors,
                     const Eigen::Ref<const RowMatrixXd>& mean_dbm,
                     const Eigen::Ref<const RowMatrixXd>& variance_db2)
    : positions_m_(positions_m),
      floors_(floors),
      mean_dbm_(mean_dbm),
      variance_db2_(variance_db2),
      detection_rate_(RowMatrixXd::Ones(mean_dbm.rows(), mean_dbm.cols())),
      scan_counts_(Eigen::VectorXi::Zero(positions_m.rows())),
      access_point_indices_(Eigen::VectorXi::LinSpaced(mean_dbm.cols(), 0,
                                                       static_cast<int>(mean_dbm.cols()) - 1)) {
  Validate();
}

void SignalMap::Validate() const {
  const Eigen::Index n = positions_m_.rows();
  CheckArgument(n > 0, "positions_m", "the map is empty (no reference points)");
  CheckShape(positions_m_, -1, 2, "positions_m");
  CheckFinite(positions_m_, "positions_m");
  CheckArgument(floors_.size() == n, "floors",
                "expected length " + std::to_string(n) + ", got " + std::to_string(floors_.size()));
  CheckArgument(mean_dbm_.cols() > 0, "mean_dbm", "no access points (K = 0)");
  CheckShape(mean_dbm_, n, -1, "mean_dbm");
  CheckShape(variance_db2_, n, mean_dbm_.cols(), "variance_db2");
  CheckFinite(mean_dbm_, "mean_dbm");
  internal::CheckRss(mean_dbm_, "mean_dbm");
  CheckFinite(variance_db2_, "variance_db2");
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < variance_db2_.cols(); ++j) {
      if (!(variance_db2_(i, j) > 0.0)) {
        ThrowInvalidArgument("variance_db2", DescribeEntry(i, j, false) + " is not > 0");
      }
    }
  }
}

SignalMap SignalMap::FromScans(const Eigen::Ref<const RowMatrixXd>& scan_positions_m,
                               const Eigen::VectorXi& scan_floors,
                               const Eigen::Ref<const RowMatrixXd>& rss_dbm,
                               const SignalMapOptions& options) {
  ValidateOptions(options);
  const Eigen::Index s = rss_dbm.rows();
  CheckArgument(s > 0, "rss_dbm", "no scans");
  CheckArgument(rss_dbm.cols() > 0, "rss_dbm", "no access point columns");
  CheckShape(scan_positions_m, s, 2, "scan_positions_m");
  CheckFinite(scan_positions_m, "scan_positions_m");
  CheckArgument(scan_floors.size() == s, "scan_floors",
                "expected length " + std::to_string(s) + ", got " + std::to_string(scan_floors.size()));

  // Group scans by exact (floor, x, y): each group is one reference point, in first-seen order.
  std::map<std::tuple<int, double, double>, int> point_of;
  std::vector<int> point_of_scan(static_cast<size_t>(s));
  std::vector<Eigen::Vector2d> positions;
  std::vector<int> floors;
  for (Eigen::Index r = 0; r < s; ++r) {
    const auto key = std::make_tuple(scan_floors[r], scan_positions_m(r, 0), scan_positions_m(r, 1));
    auto it = point_of.find(key);
    if (it == point_of.end()) {
      it = point_of.emplace(key, static_cast<int>(positions.size())).first;
      positions.emplace_back(scan_positions_m(r, 0), scan_positions_m(r, 1));
      floors.push_back(scan_floors[r]);
    }
    point_of_scan[static_cast<size_t>(r)] = it->second;
  }
  const int n = static_cast<int>(positions.size());
  const Eigen::Index k_all = rss_dbm.cols();

  // Per point and AP: count, heard count, sum and sum of squares of the floor-model readings.
  Eigen::VectorXi counts = Eigen::VectorXi::Zero(n);
  Eigen::MatrixXd heard = Eigen::MatrixXd::Zero(n, k_all);
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(n, k_all);
  Eigen::MatrixXd sum_sq = Eigen::MatrixXd::Zero(n, k_all);
  // Shift by the floor value: sums of (v - floor) keep the variance accurate in floating point.
  const double shift = options.not_heard_dbm;
  for (Eigen::Index r = 0; r < s; ++r) {
    const int p = point_of_scan[static_cast<size_t>(r)];
    ++counts[p];
    for (Eigen::Index j = 0; j < k_all; ++j) {
      const double raw = rss_dbm(r, j);
      double v = options.not_heard_dbm;
      if (!IsNotHeard(raw, options.not_heard_sentinel)) {
        if (!std::isfinite(raw)) {
          ThrowInvalidArgument("rss_dbm", DescribeEntry(r, j, false) + " is infinite");
        }
        if (std::abs(raw) > internal::kMaxAbsRssDb) {  // its square would overflow the variance
          ThrowInvalidArgument("rss_dbm", DescribeEntry(r, j, false) + " must be in [-1e4, 1e4] dB, got " +
                                              FormatValue(raw));
        }
        v = raw;
        heard(p, j) += 1.0;
      }
      sum(p, j) += v - shift;
      sum_sq(p, j) += (v - shift) * (v - shift);
    }
  }

  // AP selection: heard at >= min_point_fraction of the points (and at least at one point).
  std::vector<int> kept;
  for (Eigen::Index j = 0; j < k_all; ++j) {
    const int points_heard = static_cast<int>((heard.col(j).array() > 0.0).count());
    if (points_heard > 0 && points_heard >= options.min_point_fraction * n) {
      kept.push_back(static_cast<int>(j));
    }
  }
  CheckArgument(!kept.empty(), "rss_dbm",
                "no access point passes the selection (none heard, or min_point_fraction too high)");

  SignalMap map;
  const Eigen::Index k = static_cast<Eigen::Index>(kept.size());
  map.positions_m_.resize(n, 2);
  map.floors_.resize(n);
  map.mean_dbm_.resize(n, k);
  map.variance_db2_.resize(n, k);
  map.detection_rate_.resize(n, k);
  map.scan_counts_ = counts;
  map.access_point_indices_.resize(k);
  for (int i = 0; i < n; ++i) {
    map.positions_m_.row(i) = positions[static_cast<size_t>(i)].transpose();
    map.floors_[i] = floors[static_cast<size_t>(i)];
    const double c = counts[i];
    for (Eigen::Index a = 0; a < k; ++a) {
      const int j = kept[static_cast<size_t>(a)];
      const double mean_shifted = sum(i, j) / c;
      // Unbiased sample variance = 1/λ with the paper's λ = (N-1)/(N δ_biased) (§5.4).
      const double variance =
          c > 1 ? std::max(0.0, (sum_sq(i, j) - c * mean_shifted * mean_shifted) / (c - 1)) : 0.0;
      map.mean_dbm_(i, a) = mean_shifted + shift;
      map.variance_db2_(i, a) = std::max(variance, options.variance_floor_db2);
      map.detection_rate_(i, a) = heard(i, j) / c;
    }
  }
  for (Eigen::Index a = 0; a < k; ++a) map.access_point_indices_[a] = kept[static_cast<size_t>(a)];
  map.Validate();
  return map;
}

std::vector<int> SignalMap::distinct_floors() const {
  std::set<int> s(floors_.data(), floors_.data() + floors_.size());
  return std::vector<int>(s.begin(), s.end());
}

RowMatrixXd SignalMap::PrepareScans(const Eigen::Ref<const RowMatrixXd>& rss_dbm,
                                    double not_heard_sentinel, double not_heard_dbm) const {
  const int k_needed = access_point_indices_.size() == 0 ? 0 : access_point_indices_.maxCoeff() + 1;
  CheckArgument(rss_dbm.cols() >= k_needed, "rss_dbm",
                "has " + std::to_string(rss_dbm.cols()) + " AP columns but the map uses column " +
                    std::to_string(k_needed - 1) + " (K mismatch between map and scans)");
  RowMatrixXd selected(rss_dbm.rows(), access_point_indices_.size());
  for (Eigen::Index a = 0; a < access_point_indices_.size(); ++a) {
    selected.col(a) = rss_dbm.col(access_point_indices_[a]);
  }
  return ReplaceNotHeard(selected, not_heard_sentinel, not_heard_dbm);
}

void SignalMap::Save(const std::string& path) const {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("indoorloc: cannot open '" + path + "' for writing");
  const Eigen::Index k = mean_dbm_.cols();
  out << kFileMagic << "\n";
  out << "points " << num_points() << " access_points " << k << "\n";
  out << "ap_columns";
  for (Eigen::Index a = 0; a < k; ++a) out << ' ' << access_point_indices_[a];
  out << "\n" << std::setprecision(17);
  for (int i = 0; i < num_points(); ++i) {
    out << positions_m_(i, 0) << ' ' << positions_m_(i, 1) << ' ' << floors_[i] << ' '
        << scan_counts_[i];
    for (Eigen::Index a = 0; a < k; ++a) out << ' ' << mean_dbm_(i, a);
    for (Eigen::Index a = 0; a < k; ++a) out << ' ' << variance_db2_(i, a);
    for (Eigen::Index a = 0; a < k; ++a) out << ' ' << detection_rate_(i, a);
    out << "\n";
  }
  if (!out) throw std::runtime_error("indoorloc: writing '" + path + "' failed");
}

SignalMap SignalMap::Load(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("indoorloc: cannot open signal map '" + path + "'");
  auto fail = [&](const std::string& why) -> void {
    throw std::runtime_error("indoorloc: malformed signal map '" + path + "': " + why);
  };
  std::string line;
  if (!std::getline(in, line) || line != kFileMagic) fail("missing header '" + std::string(kFileMagic) + "'");
  std::string word;
  long n = 0, k = 0;
  if (!(in >> word) || word != "points" || !(in >> n) || !(in >> word) || word != "access_points" ||
      !(in >> k) || n <= 0 || k <= 0) {
    fail("second line must be 'points N access_points K' with N, K > 0");
  }
  SignalMap map;
  map.access_point_indices_.resize(k);
  if (!(in >> word) || word != "ap_columns") fail("third line must start with 'ap_columns'");
  for (long a = 0; a < k; ++a) {
    if (!(in >> map.access_point_indices_[a])) fail("ap_columns has fewer than K entries");
  }
  map.positions_m_.resize(n, 2);
  map.floors_.resize(n);
  map.scan_counts_.resize(n);
  map.mean_dbm_.resize(n, k);
  map.variance_db2_.resize(n, k);
  map.detection_rate_.resize(n, k);
  for (long i = 0; i < n; ++i) {
    bool ok = static_cast<bool>(in >> map.positions_m_(i, 0) >> map.positions_m_(i, 1) >>
                                map.floors_[i] >> map.scan_counts_[i]);
    for (long a = 0; ok && a < k; ++a) ok = static_cast<bool>(in >> map.mean_dbm_(i, a));
    for (long a = 0; ok && a < k; ++a) ok = static_cast<bool>(in >> map.variance_db2_(i, a));
    for (long a = 0; ok && a < k; ++a) ok = static_cast<bool>(in >> map.detection_rate_(i, a));
    if (!ok) fail("point line " + std::to_string(i) + " is incomplete");
  }
  try {
    map.Validate();
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
  return map;
}

}  // namespace indoorloc::wifi
