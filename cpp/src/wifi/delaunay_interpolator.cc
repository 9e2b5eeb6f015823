// Implementation of DelaunayInterpolator. CGAL builds the Delaunay triangulation (and gives
// Sibson coordinates); queries then run on flat arrays extracted from it: per triangle its three
// vertex indices, its three neighbours, and the inverse of its edge matrix. Point location is a
// visibility walk on those arrays (move across the edge whose barycentric coordinate is most
// negative). The walk is lock-free (CGAL's own locate keeps a mutable random generator, so it is
// not safe to share between threads) and needs no exact predicates: interpolated values are
// continuous, so a query within rounding of an edge may be assigned to either triangle. A walk
// that exceeds its step budget (possible only in floating-point degenerate cases) falls back to
// CGAL's exact locate under a mutex.
#include "indoorloc/wifi/delaunay_interpolator.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <CGAL/function_objects.h>
#include <CGAL/natural_neighbor_coordinates_2.h>

#include "indoorloc/core/check.h"
#include "indoorloc/core/parallel.h"
#include "indoorloc/core/validate.h"

namespace indoorloc::wifi {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<int, Kernel>;  // point index
using FaceBase = CGAL::Triangulation_face_base_with_info_2<int, Kernel>;      // triangle index
using Tds = CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>;
using Delaunay = CGAL::Delaunay_triangulation_2<Kernel, Tds>;
using Point = Kernel::Point_2;

// Barycentric coordinates within this tolerance below zero count as inside (rounding).
constexpr double kInsideTolerance = 1e-12;

struct Triangle {
  int vertex[3];
  int neighbor[3];  // triangle across the edge opposite vertex j; -1 - hull_edge if outside
  double origin[2];     // position of vertex 0
  double inverse[2][2];  // (b1, b2) = inverse * (p - origin); b0 = 1 - b1 - b2
};

struct HullEdge {
  int from, to;     // point indices, in hull order
  int triangle;     // the finite triangle owning the edge
  int next, prev;   // neighbouring hull edges
};

}  // namespace

struct DelaunayInterpolator::Impl {
  Delaunay dt;
  RowMatrixXd positions;  // N x 2
  RowMatrixXd fields;     // N x F
  std::vector<Triangle> triangles;
  std::vector<HullEdge> hull;
  std::vector<Delaunay::Face_handle> face_handles;
  // Coarse grid of start triangles for random-order queries.
  double grid_x0 = 0, grid_y0 = 0, grid_inv_cell = 1;
  int grid_nx = 1, grid_ny = 1;
  std::vector<int> grid_start;
  mutable std::recursive_mutex fallback_mutex;  // Sibson holds it while calling Locate

  void Barycentric(int t, double x, double y, double b[3]) const {
    const Triangle& tri = triangles[static_cast<size_t>(t)];
    const double dx = x - tri.origin[0], dy = y - tri.origin[1];
    b[1] = tri.inverse[0][0] * dx + tri.inverse[0][1] * dy;
    b[2] = tri.inverse[1][0] * dx + tri.inverse[1][1] * dy;
    b[0] = 1.0 - b[1] - b[2];
  }

  // Returns the triangle containing (x, y), or -1 - hull_edge if (x, y) lies outside the hull
  // beyond that hull edge.
  int Walk(int start, double x, double y) const {
    int t = start;
    const int budget = 64 + 8 * static_cast<int>(std::sqrt(static_cast<double>(triangles.size())));
    for (int step = 0; step < budget; ++step) {
      double b[3];
      Barycentric(t, x, y, b);
      int worst = 0;
      if (b[1] < b[worst]) worst = 1;
      if (b[2] < b[worst]) worst = 2;
      if (b[worst] >= -kInsideTolerance) return t;
      t = triangles[static_cast<size_t>(t)].neighbor[worst];
      if (t < 0) return t;  // crossed a hull edge: outside the convex hull
    }
    return ExactLocate(x, y);
  }

  int ExactLocate(double x, double y) const {
    std::lock_guard<std::recursive_mutex> lock(fallback_mutex);
    Delaunay::Locate_type type;
    int li;
    const Delaunay::Face_handle f = dt.locate(Point(x, y), type, li);
    if (!dt.is_infinite(f)) return f->info();
    // An infinite face: its finite edge is a hull edge; return its index (encoded).
    const int inf = f->index(dt.infinite_vertex());
    const int a = f->vertex(Delaunay::ccw(inf))->info();
    for (size_t e = 0; e < hull.size(); ++e) {
      if (hull[e].from == a || hull[e].to == a) return -1 - static_cast<int>(e);
    }
    return -1;
  }

  static double SegmentDistanceSq(const double* p, const double* a, const double* b, double* t_out) {
    const double ux = b[0] - a[0], uy = b[1] - a[1];
    const double len_sq = ux * ux + uy * uy;
    double t = len_sq > 0 ? ((p[0] - a[0]) * ux + (p[1] - a[1]) * uy) / len_sq : 0.0;
    t = std::clamp(t, 0.0, 1.0);
    const double dx = a[0] + t * ux - p[0], dy = a[1] + t * uy - p[1];
    *t_out = t;
    return dx * dx + dy * dy;
  }

  // Nearest point on the hull to an outside point, starting from a hull edge that faces it.
  // The distance from an outside point to the edges of a convex polygon is unimodal along the
  // hull, so walking both ways while it decreases finds the nearest edge.
  void ProjectOntoHull(int edge, double x, double y, double* px, double* py, int* triangle) const {
    const double p[2] = {x, y};
    auto dist = [&](int e, double* t) {
      const HullEdge& h = hull[static_cast<size_t>(e)];
      return SegmentDistanceSq(p, positions.row(h.from).data(), positions.row(h.to).data(), t);
    };
    double t;
    double best = dist(edge, &t);
    for (int dir = 0; dir < 2; ++dir) {
      for (size_t guard = 0; guard < hull.size(); ++guard) {
        const HullEdge& h = hull[static_cast<size_t>(edge)];
        const int candidate = dir == 0 ? h.next : h.prev;
        double tc;
        const double d = dist(candidate, &tc);
        if (d < best) {
          best = d;
          edge = candidate;
        } else {
          break;
        }
      }
    }
    dist(edge, &t);
    const HullEdge& h = hull[static_cast<size_t>(edge)];
    *px = positions(h.from, 0) + t * (positions(h.to, 0) - positions(h.from, 0));
    *py = positions(h.from, 1) + t * (positions(h.to, 1) - positions(h.from, 1));
    *triangle = h.triangle;
  }

  int GridStart(double x, double y) const {
    int ix = static_cast<int>((x - grid_x0) * grid_inv_cell);
    int iy = static_cast<int>((y - grid_y0) * grid_inv_cell);
    ix = std::clamp(ix, 0, grid_nx - 1);
    iy = std::clamp(iy, 0, grid_ny - 1);
    return grid_start[static_cast<size_t>(iy) * grid_nx + ix];
  }

  // Locates (x, y) from `start`, projects it onto the hull when outside; fills the triangle,
  // the evaluation point and barycentric coordinates. Returns true if inside.
  bool Locate(int start, double x, double y, int* triangle, double* ex, double* ey, double b[3]) const {
    const int t = Walk(start, x, y);
    if (t >= 0) {
      *triangle = t;
      *ex = x;
      *ey = y;
      Barycentric(t, x, y, b);
      return true;
    }
    ProjectOntoHull(-1 - t, x, y, ex, ey, triangle);
    Barycentric(*triangle, *ex, *ey, b);
    for (int j = 0; j < 3; ++j) b[j] = std::clamp(b[j], 0.0, 1.0);
    return false;
  }

  // Values and gradients of every field at barycentric coordinates b in triangle t. The
  // gradient of field k goes to grad_x[k * stride] and grad_y[k * stride] (stride 2: the
  // interleaved batch layout; stride 1 with two separate rows: the 2 x F layout).
  void Evaluate(int t, const double b[3], double* values, double* grad_x, double* grad_y,
                Eigen::Index stride) const {
    const Triangle& tri = triangles[static_cast<size_t>(t)];
    const Eigen::Index f = fields.cols();
    const double* f0 = fields.row(tri.vertex[0]).data();
    const double* f1 = fields.row(tri.vertex[1]).data();
    const double* f2 = fields.row(tri.vertex[2]).data();
    for (Eigen::Index k = 0; k < f; ++k) values[k] = b[0] * f0[k] + b[1] * f1[k] + b[2] * f2[k];
    if (grad_x == nullptr) return;
    // grad b1 = row 0 of the inverse, grad b2 = row 1, grad b0 = -(grad b1 + grad b2):
    // grad f = (f1 - f0) grad b1 + (f2 - f0) grad b2.
    const double g1x = tri.inverse[0][0], g1y = tri.inverse[0][1];
    const double g2x = tri.inverse[1][0], g2y = tri.inverse[1][1];
    for (Eigen::Index k = 0; k < f; ++k) {
      const double d1 = f1[k] - f0[k], d2 = f2[k] - f0[k];
      grad_x[k * stride] = d1 * g1x + d2 * g2x;
      grad_y[k * stride] = d1 * g1y + d2 * g2y;
    }
  }
};

DelaunayInterpolator::DelaunayInterpolator(const Eigen::Ref<const RowMatrixXd>& positions_m,
                                           const Eigen::Ref<const RowMatrixXd>& fields)
    : impl_(std::make_unique<Impl>()) {
  CheckShape(positions_m, -1, 2, "positions_m");
  CheckFinite(positions_m, "positions_m");
  const Eigen::Index n = positions_m.rows();
  CheckArgument(n >= 3, "positions_m", "needs at least 3 points, got " + std::to_string(n));
  CheckShape(fields, n, -1, "fields");
  CheckFinite(fields, "fields");
  Impl& s = *impl_;
  s.positions = positions_m;
  s.fields = fields;

  std::vector<std::pair<Point, int>> points;
  points.reserve(static_cast<size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    points.emplace_back(Point(positions_m(i, 0), positions_m(i, 1)), static_cast<int>(i));
  }
  s.dt.insert(points.begin(), points.end());  // spatially sorted insertion
  if (static_cast<Eigen::Index>(s.dt.number_of_vertices()) != n) {
    // CGAL merged equal points: name one duplicated pair.
    std::map<std::pair<double, double>, Eigen::Index> seen;
    for (Eigen::Index i = 0; i < n; ++i) {
      auto [it, inserted] = seen.emplace(std::make_pair(positions_m(i, 0), positions_m(i, 1)), i);
      if (!inserted) {
        ThrowInvalidArgument("positions_m", "duplicate positions: rows " + std::to_string(it->second) +
                                                " and " + std::to_string(i) + " are equal");
      }
    }
  }
  CheckArgument(s.dt.dimension() == 2, "positions_m",
                "all points are collinear: a triangulation needs 3 non-collinear points");

  // Flatten the finite faces.
  int t = 0;
  for (auto f = s.dt.finite_faces_begin(); f != s.dt.finite_faces_end(); ++f) f->info() = t++;
  s.triangles.resize(static_cast<size_t>(t));
  s.face_handles.resize(static_cast<size_t>(t));
  for (auto f = s.dt.finite_faces_begin(); f != s.dt.finite_faces_end(); ++f) {
    Triangle& tri = s.triangles[static_cast<size_t>(f->info())];
    s.face_handles[static_cast<size_t>(f->info())] = f;
    for (int j = 0; j < 3; ++j) tri.vertex[j] = f->vertex(j)->info();
    const double x0 = positions_m(tri.vertex[0], 0), y0 = positions_m(tri.vertex[0], 1);
    const double ax = positions_m(tri.vertex[1], 0) - x0, ay = positions_m(tri.vertex[1], 1) - y0;
    const double bx = positions_m(tri.vertex[2], 0) - x0, by = positions_m(tri.vertex[2], 1) - y0;
    const double det = ax * by - ay * bx;  // > 0: CGAL faces are counter-clockwise
    tri.origin[0] = x0;
    tri.origin[1] = y0;
    tri.inverse[0][0] = by / det;
    tri.inverse[0][1] = -bx / det;
    tri.inverse[1][0] = -ay / det;
    tri.inverse[1][1] = ax / det;
    // CGAL's exact predicates accept triangles whose area underflows in double (points 1e-300
    // apart): the barycentric inverse is then inf and every value NaN. Refuse such positions.
    if (!(det > 0.0) || !std::isfinite(tri.inverse[0][0]) || !std::isfinite(tri.inverse[0][1]) ||
        !std::isfinite(tri.inverse[1][0]) || !std::isfinite(tri.inverse[1][1])) {
      ThrowInvalidArgument("positions_m", "the triangle of rows " + std::to_string(tri.vertex[0]) + ", " +
                                              std::to_string(tri.vertex[1]) + ", " + std::to_string(tri.vertex[2]) +
                                              " is too small for double precision (twice its area is " +
                                              FormatValue(det) + ")");
    }
  }
  // Hull edges: one per infinite face; neighbours across hull edges are encoded -1 - edge.
  std::map<int, int> edge_from, edge_to;
  for (auto f = s.dt.all_faces_begin(); f != s.dt.all_faces_end(); ++f) {
    if (!s.dt.is_infinite(f)) continue;
    const int inf = f->index(s.dt.infinite_vertex());
    const Delaunay::Face_handle inner = f->neighbor(inf);
    HullEdge h;
    h.from = f->vertex(Delaunay::ccw(inf))->info();
    h.to = f->vertex(Delaunay::cw(inf))->info();
    h.triangle = inner->info();
    const int e = static_cast<int>(s.hull.size());
    s.hull.push_back(h);
    edge_from[h.from] = e;
    edge_to[h.to] = e;
    const int j = inner->index(f);
    s.triangles[static_cast<size_t>(inner->info())].neighbor[j] = -1 - e;
  }
  for (HullEdge& h : s.hull) {
    h.next = edge_from.at(h.to);
    h.prev = edge_to.at(h.from);
  }
  for (auto f = s.dt.finite_faces_begin(); f != s.dt.finite_faces_end(); ++f) {
    Triangle& tri = s.triangles[static_cast<size_t>(f->info())];
    for (int j = 0; j < 3; ++j) {
      if (!s.dt.is_infinite(f->neighbor(j))) tri.neighbor[j] = f->neighbor(j)->info();
    }
  }

  // Grid of start triangles, about one cell per two triangles, filled by walking cell to cell.
  const double x_min = positions_m.col(0).minCoeff(), x_max = positions_m.col(0).maxCoeff();
  const double y_min = positions_m.col(1).minCoeff(), y_max = positions_m.col(1).maxCoeff();
  const double width = std::max(x_max - x_min, 1e-9), height = std::max(y_max - y_min, 1e-9);
  const double cells = std::max(1.0, t / 2.0);
  const double cell = std::sqrt(width * height / cells);
  s.grid_nx = std::clamp(static_cast<int>(std::ceil(width / cell)), 1, 4096);
  s.grid_ny = std::clamp(static_cast<int>(std::ceil(height / cell)), 1, 4096);
  s.grid_x0 = x_min;
  s.grid_y0 = y_min;
  s.grid_inv_cell = 1.0 / std::max(width / s.grid_nx, height / s.grid_ny);
  s.grid_start.assign(static_cast<size_t>(s.grid_nx) * s.grid_ny, 0);
  int current = 0;
  for (int iy = 0; iy < s.grid_ny; ++iy) {
    for (int k = 0; k < s.grid_nx; ++k) {
      const int ix = iy % 2 == 0 ? k : s.grid_nx - 1 - k;  // snake order: short walks
      const double cx = s.grid_x0 + (ix + 0.5) / s.grid_inv_cell;
      const double cy = s.grid_y0 + (iy + 0.5) / s.grid_inv_cell;
      const int found = s.Walk(current, cx, cy);
      const int tri_index = found >= 0 ? found : s.hull[static_cast<size_t>(-1 - found)].triangle;
      s.grid_start[static_cast<size_t>(iy) * s.grid_nx + ix] = tri_index;
      current = tri_index;
    }
  }
}

DelaunayInterpolator::~DelaunayInterpolator() = default;
DelaunayInterpolator::DelaunayInterpolator(DelaunayInterpolator&&) noexcept = default;
DelaunayInterpolator& DelaunayInterpolator::operator=(DelaunayInterpolator&&) noexcept = default;

int DelaunayInterpolator::num_points() const { return static_cast<int>(impl_->positions.rows()); }
int DelaunayInterpolator::num_fields() const { return static_cast<int>(impl_->fields.cols()); }
int DelaunayInterpolator::num_triangles() const { return static_cast<int>(impl_->triangles.size()); }

bool DelaunayInterpolator::Interpolate(const Eigen::Vector2d& z_m, Eigen::Ref<Eigen::VectorXd> values,
                                       Eigen::Ref<RowMatrixXd> gradients, int* hint) const {
  CheckArgument(std::isfinite(z_m[0]) && std::isfinite(z_m[1]), "z_m", "is not finite");
  CheckArgument(values.size() == impl_->fields.cols(), "values", "must have one entry per field");
  CheckShape(gradients, 2, impl_->fields.cols(), "gradients");
  const Impl& s = *impl_;
  const int start = (hint != nullptr && *hint >= 0 && *hint < num_triangles())
                        ? *hint
                        : s.GridStart(z_m[0], z_m[1]);
  int t;
  double ex, ey, b[3];
  const bool inside = s.Locate(start, z_m[0], z_m[1], &t, &ex, &ey, b);
  if (hint != nullptr) *hint = t;
  s.Evaluate(t, b, values.data(), gradients.row(0).data(), gradients.row(1).data(), 1);
  return inside;
}

FaceLocation DelaunayInterpolator::LocateFace(const Eigen::Vector2d& z_m, int* hint) const {
  CheckArgument(std::isfinite(z_m[0]) && std::isfinite(z_m[1]), "z_m", "is not finite");
  const Impl& s = *impl_;
  const int start = (hint != nullptr && *hint >= 0 && *hint < num_triangles())
                        ? *hint
                        : s.GridStart(z_m[0], z_m[1]);
  FaceLocation out;
  double ex, ey;
  out.inside = s.Locate(start, z_m[0], z_m[1], &out.triangle, &ex, &ey, out.weights);
  if (hint != nullptr) *hint = out.triangle;
  const Triangle& tri = s.triangles[static_cast<size_t>(out.triangle)];
  for (int j = 0; j < 3; ++j) out.vertices[j] = tri.vertex[j];
  out.grad_b1[0] = tri.inverse[0][0];
  out.grad_b1[1] = tri.inverse[0][1];
  out.grad_b2[0] = tri.inverse[1][0];
  out.grad_b2[1] = tri.inverse[1][1];
  return out;
}

BarycentricLocation DelaunayInterpolator::Locate(const Eigen::Vector2d& z_m) const {
  const Impl& s = *impl_;
  int t;
  double ex, ey;
  BarycentricLocation out;
  out.inside = s.Locate(s.GridStart(z_m[0], z_m[1]), z_m[0], z_m[1], &t, &ex, &ey, out.weights);
  const auto& tri = s.triangles[static_cast<size_t>(t)];
  for (int j = 0; j < 3; ++j) out.vertices[j] = tri.vertex[j];
  return out;
}

const RowMatrixXd& DelaunayInterpolator::fields() const { return impl_->fields; }

InterpolationBatch DelaunayInterpolator::InterpolateBatch(const Eigen::Ref<const RowMatrixXd>& queries_m,
                                                          bool sequential, int num_threads) const {
  CheckShape(queries_m, -1, 2, "queries_m");
  const Eigen::Index q = queries_m.rows();
  const Eigen::Index f = impl_->fields.cols();
  InterpolationBatch out;
  out.values.resize(q, f);
  out.gradients.resize(q, 2 * f);
  out.inside.resize(q);
  out.evaluated_at_m.resize(q, 2);
  InterpolateBatchInto(queries_m, sequential, num_threads, out.values, out.gradients, out.inside,
                       out.evaluated_at_m);
  return out;
}

void DelaunayInterpolator::InterpolateBatchInto(
    const Eigen::Ref<const RowMatrixXd>& queries_m, bool sequential, int num_threads,
    Eigen::Ref<RowMatrixXd> values, Eigen::Ref<RowMatrixXd> gradients,
    Eigen::Ref<Eigen::Matrix<bool, Eigen::Dynamic, 1>> inside, Eigen::Ref<RowMatrixXd> evaluated_at_m) const {
  CheckShape(queries_m, -1, 2, "queries_m");
  CheckFinite(queries_m, "queries_m");
  const Impl& s = *impl_;
  const Eigen::Index q = queries_m.rows();
  const Eigen::Index f = s.fields.cols();
  CheckShape(values, q, f, "values");
  CheckShape(gradients, q, 2 * f, "gradients");
  CheckArgument(inside.size() == q, "inside", "must have one entry per query");
  CheckShape(evaluated_at_m, q, 2, "evaluated_at_m");
  // Contiguous blocks, one per thread; within a block the previous face is the hint when
  // `sequential`. Each query's result does not depend on the blocking (interpolation is
  // continuous and the triangle found contains the point), so thread count does not matter.
  const int threads = static_cast<int>(std::min<Eigen::Index>(ResolveThreadCount(num_threads),
                                                              std::max<Eigen::Index>(1, q / 4096)));
  auto work = [&](Eigen::Index begin, Eigen::Index end) {
    int previous = -1;
    for (Eigen::Index i = begin; i < end; ++i) {
      const double x = queries_m(i, 0), y = queries_m(i, 1);
      const int start = (sequential && previous >= 0) ? previous : s.GridStart(x, y);
      int t;
      double ex, ey, b[3];
      inside[i] = s.Locate(start, x, y, &t, &ex, &ey, b);
      previous = t;
      evaluated_at_m(i, 0) = ex;
      evaluated_at_m(i, 1) = ey;
      double* g = gradients.row(i).data();
      s.Evaluate(t, b, values.row(i).data(), g, g + 1, 2);
    }
  };
  if (threads <= 1) {
    work(0, q);
  } else {
    std::vector<std::thread> pool;
    const Eigen::Index chunk = (q + threads - 1) / threads;
    for (int k = 0; k < threads; ++k) {
      const Eigen::Index begin = k * chunk, end = std::min(q, begin + chunk);
      if (begin < end) pool.emplace_back(work, begin, end);
    }
    for (std::thread& th : pool) th.join();
  }
}

Eigen::Vector2d DelaunayInterpolator::ClampToHull(const Eigen::Vector2d& z_m) const {
  CheckArgument(std::isfinite(z_m[0]) && std::isfinite(z_m[1]), "z_m", "is not finite");
  const Impl& s = *impl_;
  int t;
  double ex, ey, b[3];
  s.Locate(s.GridStart(z_m[0], z_m[1]), z_m[0], z_m[1], &t, &ex, &ey, b);
  return Eigen::Vector2d(ex, ey);
}

RowMatrixXd DelaunayInterpolator::SibsonInterpolate(const Eigen::Ref<const RowMatrixXd>& queries_m) const {
  CheckShape(queries_m, -1, 2, "queries_m");
  CheckFinite(queries_m, "queries_m");
  const Impl& s = *impl_;
  RowMatrixXd out = RowMatrixXd::Zero(queries_m.rows(), s.fields.cols());
  using Coordinate = std::pair<Delaunay::Vertex_handle, Kernel::FT>;
  std::vector<Coordinate> coords;
  std::lock_guard<std::recursive_mutex> lock(s.fallback_mutex);  // CGAL's locate is not thread-safe
  for (Eigen::Index i = 0; i < queries_m.rows(); ++i) {
    const Eigen::Vector2d z = ClampToHull(queries_m.row(i).transpose());
    coords.clear();
    const auto result = CGAL::natural_neighbor_coordinates_2(
        s.dt, Point(z[0], z[1]), std::back_inserter(coords), CGAL::Identity<Coordinate>());
    if (!result.third || result.second <= 0) {
      // On the hull boundary Sibson coordinates are undefined: use the linear interpolant,
      // which Sibson's reduces to on hull edges.
      int t;
      double ex, ey, b[3];
      s.Locate(s.GridStart(z[0], z[1]), z[0], z[1], &t, &ex, &ey, b);
      s.Evaluate(t, b, out.row(i).data(), nullptr, nullptr, 0);
      continue;
    }
    for (const Coordinate& c : coords) {
      out.row(i) += (c.second / result.second) * s.fields.row(c.first->info());
    }
  }
  return out;
}

Eigen::MatrixXi DelaunayInterpolator::Triangles() const {
  Eigen::MatrixXi out(num_triangles(), 3);
  for (int t = 0; t < num_triangles(); ++t) {
    for (int j = 0; j < 3; ++j) out(t, j) = impl_->triangles[static_cast<size_t>(t)].vertex[j];
  }
  return out;
}

}  // namespace indoorloc::wifi
