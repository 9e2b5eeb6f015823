// Piecewise-linear interpolation of scalar fields over a Delaunay triangulation, with
// gradients (paper 004, §3.2-3.3, eq. 18-21 and the gradient formula after eq. 21).
//
// Inside a triangle (P1, P2, P3) every field f is the affine function through its three vertex
// values: f(P) = Σ_j b_j(P) f_j with barycentric coordinates b_j, and its gradient is the
// constant Σ_j ∇b_j f_j. This equals the paper's determinant form (eq. 21): the plane through
// (x_j, y_j, f_j). Per triangle the 2x2 inverse of [P2 - P1, P3 - P1] is precomputed, so a
// query costs one point location plus 3 multiply-adds per field (and 6 for the gradient).
//
// Point location uses CGAL's Delaunay_triangulation_2 (kept out of this header) with a hint:
// for sequences the previous face (a walk of a few steps), for random queries a coarse grid
// of faces built once. Outside the convex hull the value is that of the nearest point of the
// hull (the query is projected onto the nearest hull edge) and `inside` is false; the gradient
// there is the gradient of the triangle owning that hull edge.
//
// Sibson's natural-neighbour interpolation (paper 004, §3.1) is offered as a second interpolant
// (smooth except at the data points; no gradient here).
#pragma once

#include <memory>

#include <Eigen/Core>

namespace indoorloc::wifi {

using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Values and gradients of all fields at a batch of query points.
struct InterpolationBatch {
  RowMatrixXd values;            ///< Q x F field values
  RowMatrixXd gradients;         ///< Q x 2F: columns (d/dx f_1, d/dy f_1, d/dx f_2, ...)
  Eigen::Matrix<bool, Eigen::Dynamic, 1> inside;  ///< Q: query inside the convex hull
  RowMatrixXd evaluated_at_m;    ///< Q x 2: the query, or its projection onto the hull
};

/// Where a point falls in the triangulation: f(z) = Σ_j weights[j] f(vertices[j]) for every field.
struct BarycentricLocation {
  int vertices[3] = {0, 0, 0};     ///< point indices (rows of positions / fields)
  double weights[3] = {0, 0, 0};   ///< barycentric coordinates (of the hull projection when outside)
  bool inside = true;              ///< z inside the convex hull
};

/// A located face with what a caller needs to interpolate chosen fields and their gradients:
/// f(z) = Σ_j weights[j] f(vertices[j]); ∇f = (f(v1) - f(v0)) grad_b1 + (f(v2) - f(v0)) grad_b2.
struct FaceLocation {
  int triangle = 0;                ///< face index in [0, num_triangles())
  int vertices[3] = {0, 0, 0};     ///< point indices (rows of positions / fields)
  double weights[3] = {0, 0, 0};   ///< barycentric coordinates (of the hull projection when outside)
  double grad_b1[2] = {0, 0};      ///< gradient of weights[1] [1/m]
  double grad_b2[2] = {0, 0};      ///< gradient of weights[2] [1/m]
  bool inside = true;              ///< z inside the convex hull
};

class DelaunayInterpolator {
 public:
  /// Triangulates positions_m (N x 2) [m] carrying fields (N x F). Throws
  /// std::invalid_argument on NaN, N < 3, all points collinear, or duplicate positions.
  DelaunayInterpolator(const Eigen::Ref<const RowMatrixXd>& positions_m,
                       const Eigen::Ref<const RowMatrixXd>& fields);
  ~DelaunayInterpolator();
  DelaunayInterpolator(DelaunayInterpolator&&) noexcept;
  DelaunayInterpolator& operator=(DelaunayInterpolator&&) noexcept;

  int num_points() const;
  int num_fields() const;
  int num_triangles() const;

  /// Interpolates every field at z_m. `values` (F) and `gradients` (2 x F, rows d/dx, d/dy)
  /// must be sized by the caller. `hint` carries the last face between calls (start it at -1);
  /// returns true if z_m is inside the convex hull. Not thread-safe with a shared hint only.
  bool Interpolate(const Eigen::Vector2d& z_m, Eigen::Ref<Eigen::VectorXd> values,
                   Eigen::Ref<RowMatrixXd> gradients, int* hint) const;

  /// Locates z_m as Interpolate does (same hint rule, same face and weights) without
  /// evaluating any field: for callers that need a few fields of many (sparse likelihoods).
  FaceLocation LocateFace(const Eigen::Vector2d& z_m, int* hint) const;

  /// Batch version: queries_m (Q x 2). With `sequential` the previous query's face is the hint
  /// (paths); otherwise the coarse grid hint is used (random order). Multi-threaded over
  /// query blocks when num_threads != 1 (results do not depend on the thread count).
  InterpolationBatch InterpolateBatch(const Eigen::Ref<const RowMatrixXd>& queries_m,
                                      bool sequential = false, int num_threads = 1) const;

  /// As InterpolateBatch, writing into caller-owned buffers (e.g. numpy arrays) of shapes
  /// values (Q x F), gradients (Q x 2F), inside (Q), evaluated_at_m (Q x 2): no copies.
  void InterpolateBatchInto(const Eigen::Ref<const RowMatrixXd>& queries_m, bool sequential,
                            int num_threads, Eigen::Ref<RowMatrixXd> values,
                            Eigen::Ref<RowMatrixXd> gradients,
                            Eigen::Ref<Eigen::Matrix<bool, Eigen::Dynamic, 1>> inside,
                            Eigen::Ref<RowMatrixXd> evaluated_at_m) const;

  /// Locates z_m (projected onto the hull when outside) from the coarse grid of faces: the fast
  /// path for scattered queries (particle clouds) that need only some fields; combine with
  /// fields(). Thread-safe.
  BarycentricLocation Locate(const Eigen::Vector2d& z_m) const;
  /// The fields at the data points (N x F), as given at construction.
  const RowMatrixXd& fields() const;
  /// Nearest point of the triangulated region (the point itself when inside).
  Eigen::Vector2d ClampToHull(const Eigen::Vector2d& z_m) const;

  /// Sibson natural-neighbour interpolation of every field at each query (Q x 2 -> Q x F).
  /// Outside the hull the clamped point is used.
  RowMatrixXd SibsonInterpolate(const Eigen::Ref<const RowMatrixXd>& queries_m) const;

  /// Vertex indices (T x 3) of the triangles, for plots.
  Eigen::MatrixXi Triangles() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace indoorloc::wifi
