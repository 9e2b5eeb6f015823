#include "indoorloc/mapmatch/road_network.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <set>
#include <sstream>
#include <unordered_set>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"

namespace indoorloc::mapmatch {
namespace {

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a[0] * b[1] - a[1] * b[0]; }

// Parameters t in (0, 1) where segment (p, p + r) must be split because segment (q, q + s)
// crosses it or ends on its interior.
void SplitParameters(const Eigen::Vector2d& p, const Eigen::Vector2d& r, const Eigen::Vector2d& q,
                     const Eigen::Vector2d& s, double tol, std::vector<double>* out) {
  const double len = r.norm();
  const double denom = Cross(r, s);
  if (std::abs(denom) > 1e-12 * len * s.norm()) {
    const double t = Cross(q - p, s) / denom;
    const double u = Cross(q - p, r) / denom;
    const double tol_t = tol / len, tol_u = tol / s.norm();
    if (t > tol_t && t < 1 - tol_t && u > -tol_u && u < 1 + tol_u) out->push_back(t);
    return;
  }
  // Parallel: an end of the other segment lying on this one's interior (collinear overlap).
  for (const Eigen::Vector2d& e : {q, Eigen::Vector2d(q + s)}) {
    const double t = (e - p).dot(r) / (len * len);
    if (t > tol / len && t < 1 - tol / len && std::abs(Cross(r, e - p)) / len < tol) out->push_back(t);
  }
}

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(int n) : parent(static_cast<size_t>(n)) { std::iota(parent.begin(), parent.end(), 0); }
  int Find(int x) {
    while (parent[static_cast<size_t>(x)] != x) x = parent[static_cast<size_t>(x)] = parent[static_cast<size_t>(parent[static_cast<size_t>(x)])];
    return x;
  }
  void Union(int a, int b) { parent[static_cast<size_t>(Find(a))] = Find(b); }
};

}  // namespace

namespace {
constexpr double kMaxCoordinateM = 1e12;  // squared distances stay finite
}  // namespace

bool RoadNetworkOptions::IsValid(std::string* error) const {
  return Validator(error).InRange(snap_tolerance_m, 0.0, 1e6, "snap_tolerance_m");
}

RoadNetwork::RoadNetwork(const Eigen::Ref<const RowMatrixXd>& segments_m, const Eigen::VectorXi& ids,
                         const RoadNetworkOptions& options) {
  ValidateOptions(options);
  CheckArgument(segments_m.rows() > 0, "segments_m", "the network is empty (no segments)");
  CheckShape(segments_m, -1, 4, "segments_m");
  CheckFinite(segments_m, "segments_m");
  RequireAllInRange(segments_m, -kMaxCoordinateM, kMaxCoordinateM, "segments_m");  // lengths must not overflow
  const Eigen::Index m = segments_m.rows();
  Eigen::VectorXi input_ids = ids;
  if (input_ids.size() == 0) input_ids = Eigen::VectorXi::LinSpaced(m, 1, static_cast<int>(m));
  CheckArgument(input_ids.size() == m, "ids", "expected one id per segment");
  {
    std::unordered_set<int> seen;
    for (Eigen::Index i = 0; i < m; ++i) {
      if (!seen.insert(input_ids[i]).second) {
        ThrowInvalidArgument("ids", "duplicate segment id " + std::to_string(input_ids[i]));
      }
    }
  }
  const double tol = std::max(options.snap_tolerance_m, 1e-12);
  for (Eigen::Index i = 0; i < m; ++i) {
    const double len = std::hypot(segments_m(i, 2) - segments_m(i, 0), segments_m(i, 3) - segments_m(i, 1));
    if (!(len > tol)) {
      ThrowInvalidArgument("segments_m", "segment id " + std::to_string(input_ids[i]) + " (row " +
                                             std::to_string(i) + ") has zero length" +
                                             (len > 0.0 ? " (not longer than snap_tolerance_m = " +
                                                              FormatValue(options.snap_tolerance_m) + ")"
                                                        : ""));
    }
  }

  // Optional splitting at crossings and T-junctions (O(M^2): fine for warehouse-sized maps).
  std::vector<Eigen::Vector4d> pieces;
  std::vector<int> piece_ids;
  for (Eigen::Index i = 0; i < m; ++i) {
    const Eigen::Vector2d p(segments_m(i, 0), segments_m(i, 1));
    const Eigen::Vector2d r = Eigen::Vector2d(segments_m(i, 2), segments_m(i, 3)) - p;
    std::vector<double> cuts;
    if (options.split_at_intersections) {
      for (Eigen::Index j = 0; j < m; ++j) {
        if (j == i) continue;
        const Eigen::Vector2d q(segments_m(j, 0), segments_m(j, 1));
        const Eigen::Vector2d s = Eigen::Vector2d(segments_m(j, 2), segments_m(j, 3)) - q;
        SplitParameters(p, r, q, s, tol, &cuts);
      }
    }
    cuts.push_back(0.0);
    cuts.push_back(1.0);
    std::sort(cuts.begin(), cuts.end());
    for (size_t c = 0; c + 1 < cuts.size(); ++c) {
      if ((cuts[c + 1] - cuts[c]) * r.norm() <= tol) continue;  // duplicate cut
      const Eigen::Vector2d a = p + cuts[c] * r, b = p + cuts[c + 1] * r;
      pieces.emplace_back(a[0], a[1], b[0], b[1]);
      piece_ids.push_back(input_ids[i]);
    }
  }
  const Eigen::Index n = static_cast<Eigen::Index>(pieces.size());
  ends_.resize(n, 4);
  ids_.resize(n);
  headings_.resize(n);
  lengths_.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    ends_.row(i) = pieces[static_cast<size_t>(i)].transpose();
    ids_[i] = piece_ids[static_cast<size_t>(i)];
    headings_[i] = std::atan2(ends_(i, 3) - ends_(i, 1), ends_(i, 2) - ends_(i, 0));
    lengths_[i] = std::hypot(ends_(i, 2) - ends_(i, 0), ends_(i, 3) - ends_(i, 1));
  }
  total_length_ = lengths_.sum();
  BuildConnectivity(tol);
  BuildIndex();
}

Eigen::Vector2d RoadNetwork::end_point(int segment, int end) const {
  return Eigen::Vector2d(ends_(segment, 2 * end), ends_(segment, 2 * end + 1));
}

Eigen::Vector2d RoadNetwork::point_at(int segment, double along_m) const {
  const double t = along_m / lengths_[segment];
  return Eigen::Vector2d(ends_(segment, 0) + t * (ends_(segment, 2) - ends_(segment, 0)),
                         ends_(segment, 1) + t * (ends_(segment, 3) - ends_(segment, 1)));
}

void RoadNetwork::BuildConnectivity(double tol) {
  const int n = num_segments();
  // Sort the 2n ends by x, then sweep: ends within tol in x and in distance are one junction.
  std::vector<int> order(static_cast<size_t>(2 * n));
  std::iota(order.begin(), order.end(), 0);
  auto x_of = [&](int e) { return ends_(e / 2, 2 * (e % 2)); };
  std::sort(order.begin(), order.end(), [&](int a, int b) { return x_of(a) < x_of(b); });
  std::vector<std::vector<int>> touching(static_cast<size_t>(2 * n));
  for (size_t i = 0; i < order.size(); ++i) {
    const int a = order[i];
    const Eigen::Vector2d pa = end_point(a / 2, a % 2);
    for (size_t j = i + 1; j < order.size() && x_of(order[j]) - pa[0] <= tol; ++j) {
      const int b = order[j];
      if ((end_point(b / 2, b % 2) - pa).norm() <= tol) {
        touching[static_cast<size_t>(a)].push_back(b);
        touching[static_cast<size_t>(b)].push_back(a);
      }
    }
  }
  continuations_.assign(static_cast<size_t>(2 * n), {});
  UnionFind uf(n);
  for (int e = 0; e < 2 * n; ++e) {
    const int s = e / 2;
    for (int other : touching[static_cast<size_t>(e)]) {
      if (other / 2 == s) continue;  // a segment cannot continue onto itself except at a dead end
      continuations_[static_cast<size_t>(e)].push_back({other / 2, other % 2});
      uf.Union(s, other / 2);
    }
    std::sort(continuations_[static_cast<size_t>(e)].begin(), continuations_[static_cast<size_t>(e)].end(),
              [](const Continuation& x, const Continuation& y) {
                return x.segment != y.segment ? x.segment < y.segment : x.enter_end < y.enter_end;
              });
    if (continuations_[static_cast<size_t>(e)].empty()) {
      continuations_[static_cast<size_t>(e)].push_back({s, e % 2});  // dead end: U-turn
    }
  }
  components_.resize(n);
  std::vector<int> label(static_cast<size_t>(n), -1);
  num_components_ = 0;
  for (int s = 0; s < n; ++s) {
    const int root = uf.Find(s);
    if (label[static_cast<size_t>(root)] < 0) label[static_cast<size_t>(root)] = num_components_++;
    components_[s] = label[static_cast<size_t>(root)];
  }
}

std::vector<std::pair<int, int>> RoadNetwork::dangling_ends() const {
  std::vector<std::pair<int, int>> out;
  for (int s = 0; s < num_segments(); ++s) {
    for (int end = 0; end < 2; ++end) {
      const auto& c = continuations(s, end);
      if (c.size() == 1 && c[0].segment == s) out.emplace_back(s, end);
    }
  }
  return out;
}

std::string RoadNetwork::Report() const {
  std::ostringstream out;
  out << num_segments() << " segments, total length " << total_length_ << " m, " << num_components_
      << " connected component(s)";
  const auto dangling = dangling_ends();
  out << ", " << dangling.size() << " dangling end(s)";
  if (!dangling.empty()) {
    out << " (segment id:end";
    for (size_t i = 0; i < std::min<size_t>(dangling.size(), 10); ++i) {
      out << (i ? ", " : " ") << ids_[dangling[i].first] << (dangling[i].second == 0 ? ":A" : ":B");
    }
    out << (dangling.size() > 10 ? ", ...)" : ")");
  }
  if (num_components_ > 1) out << "; WARNING: the network is disconnected";
  return out.str();
}

void RoadNetwork::BuildIndex() {
  const double x0 = std::min(ends_.col(0).minCoeff(), ends_.col(2).minCoeff());
  const double x1 = std::max(ends_.col(0).maxCoeff(), ends_.col(2).maxCoeff());
  const double y0 = std::min(ends_.col(1).minCoeff(), ends_.col(3).minCoeff());
  const double y1 = std::max(ends_.col(1).maxCoeff(), ends_.col(3).maxCoeff());
  const double extent = std::max({x1 - x0, y1 - y0, 1e-6});
  // About one cell per segment along the larger side.
  grid_cell_ = std::max(extent / std::max(1.0, std::sqrt(static_cast<double>(num_segments())) * 2.0), 1e-6);
  grid_x0_ = x0;
  grid_y0_ = y0;
  grid_nx_ = std::min(4096, static_cast<int>((x1 - x0) / grid_cell_) + 1);
  grid_ny_ = std::min(4096, static_cast<int>((y1 - y0) / grid_cell_) + 1);
  grid_.assign(static_cast<size_t>(grid_nx_) * grid_ny_, {});
  for (int s = 0; s < num_segments(); ++s) {
    // Cells along the segment (sampled at a quarter cell): exact enough to list every cell the
    // segment passes, and a segment is never missed by the ring search below.
    const int samples = static_cast<int>(std::ceil(lengths_[s] / (0.25 * grid_cell_))) + 1;
    int last = -1;
    for (int k = 0; k <= samples; ++k) {
      const Eigen::Vector2d p = point_at(s, lengths_[s] * k / samples);
      const int ix = std::clamp(static_cast<int>((p[0] - grid_x0_) / grid_cell_), 0, grid_nx_ - 1);
      const int iy = std::clamp(static_cast<int>((p[1] - grid_y0_) / grid_cell_), 0, grid_ny_ - 1);
      const int cell = iy * grid_nx_ + ix;
      if (cell != last) {
        auto& list = grid_[static_cast<size_t>(cell)];
        if (list.empty() || list.back() != s) list.push_back(s);
        last = cell;
      }
    }
  }
  for (auto& list : grid_) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
}

Projection RoadNetwork::ProjectOnto(int segment, const Eigen::Vector2d& p_m) const {
  Projection out;
  out.segment = segment;
  const Eigen::Vector2d a = end_point(segment, 0), b = end_point(segment, 1);
  const Eigen::Vector2d r = b - a;
  const double t = std::clamp((p_m - a).dot(r) / r.squaredNorm(), 0.0, 1.0);
  out.along_m = t * lengths_[segment];
  out.point_m = a + t * r;
  out.distance_m = (p_m - out.point_m).norm();
  return out;
}

Projection RoadNetwork::Nearest(const Eigen::Vector2d& p_m) const {
  CheckArgument(p_m.allFinite(), "p_m", "is not finite");
  const int cx = std::clamp(static_cast<int>(std::floor((p_m[0] - grid_x0_) / grid_cell_)), 0, grid_nx_ - 1);
  const int cy = std::clamp(static_cast<int>(std::floor((p_m[1] - grid_y0_) / grid_cell_)), 0, grid_ny_ - 1);
  Projection best;
  best.distance_m = std::numeric_limits<double>::infinity();
  const int max_ring = std::max(grid_nx_, grid_ny_);
  for (int ring = 0; ring <= max_ring; ++ring) {
    // Cells of ring r lie at least (r - 1) cells from p's (clamped) cell: a lower bound on the
    // distance of every segment not yet seen. Stop when it exceeds the best distance.
    if (best.segment >= 0 && (ring - 1) * grid_cell_ > best.distance_m) break;
    for (int iy = cy - ring; iy <= cy + ring; ++iy) {
      if (iy < 0 || iy >= grid_ny_) continue;
      for (int ix = cx - ring; ix <= cx + ring; ++ix) {
        if (ix < 0 || ix >= grid_nx_) continue;
        if (std::max(std::abs(ix - cx), std::abs(iy - cy)) != ring) continue;  // ring cells only
        for (int s : grid_[static_cast<size_t>(iy * grid_nx_ + ix)]) {
          const Projection p = ProjectOnto(s, p_m);
          if (p.distance_m < best.distance_m || (p.distance_m == best.distance_m && s < best.segment)) best = p;
        }
      }
    }
  }
  return best;
}

}  // namespace indoorloc::mapmatch
