#include "indoorloc/wifi/delaunay_interpolator.h"

#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

#include "indoorloc/core/random.h"

namespace indoorloc::wifi {
namespace {

// Scattered points and two fields: an affine one (reproduced exactly everywhere) and a smooth
// nonlinear one.
struct Scattered {
  RowMatrixXd positions, fields;
};

Scattered MakeScattered(int n, std::uint64_t seed) {
  RandomStream rng(seed);
  Scattered s;
  s.positions.resize(n, 2);
  s.fields.resize(n, 2);
  for (int i = 0; i < n; ++i) {
    const double x = rng.Uniform(0, 10), y = rng.Uniform(0, 5);
    s.positions.row(i) << x, y;
    s.fields.row(i) << 3.0 * x - 2.0 * y + 1.0, std::sin(x) * std::cos(y);
  }
  return s;
}

TEST(DelaunayInterpolator, ExactAtVerticesAndAffineFieldsEverywhere) {
  const Scattered s = MakeScattered(200, 1);
  DelaunayInterpolator interp(s.positions, s.fields);
  EXPECT_EQ(interp.num_points(), 200);
  EXPECT_EQ(interp.num_fields(), 2);
  const InterpolationBatch at_vertices = interp.InterpolateBatch(s.positions);
  EXPECT_LT((at_vertices.values - s.fields).cwiseAbs().maxCoeff(), 1e-9);
  RandomStream rng(2);
  RowMatrixXd queries(1000, 2);
  for (int i = 0; i < 1000; ++i) queries.row(i) << rng.Uniform(0, 10), rng.Uniform(0, 5);
  const InterpolationBatch b = interp.InterpolateBatch(queries);
  for (int i = 0; i < 1000; ++i) {
    if (!b.inside[i]) continue;
    EXPECT_NEAR(b.values(i, 0), 3.0 * queries(i, 0) - 2.0 * queries(i, 1) + 1.0, 1e-9);
    EXPECT_NEAR(b.gradients(i, 0), 3.0, 1e-9);
    EXPECT_NEAR(b.gradients(i, 1), -2.0, 1e-9);
  }
}

TEST(DelaunayInterpolator, LinearInsideATriangleAndGradientsMatchFiniteDifferences) {
  const Scattered s = MakeScattered(100, 3);
  DelaunayInterpolator interp(s.positions, s.fields);
  const Eigen::MatrixXi tris = interp.Triangles();
  RandomStream rng(4);
  Eigen::VectorXd v(2), vp(2), vm(2);
  RowMatrixXd g(2, 2), unused(2, 2);
  for (int t = 0; t < tris.rows(); t += 7) {
    // A point strictly inside triangle t (barycentric weights bounded away from 0).
    double w[3] = {rng.Uniform(0.2, 1), rng.Uniform(0.2, 1), rng.Uniform(0.2, 1)};
    const double sum = w[0] + w[1] + w[2];
    Eigen::Vector2d z = Eigen::Vector2d::Zero();
    Eigen::VectorXd expected = Eigen::VectorXd::Zero(2);
    for (int j = 0; j < 3; ++j) {
      z += w[j] / sum * s.positions.row(tris(t, j)).transpose();
      expected += w[j] / sum * s.fields.row(tris(t, j)).transpose();
    }
    int hint = -1;
    ASSERT_TRUE(interp.Interpolate(z, v, g, &hint));
    EXPECT_EQ(hint, t);
    EXPECT_LT((v - expected).cwiseAbs().maxCoeff(), 1e-10);  // linear in barycentric coords
    const double h = 1e-6;
    for (int axis = 0; axis < 2; ++axis) {
      Eigen::Vector2d dz = Eigen::Vector2d::Zero();
      dz[axis] = h;
      int h1 = t, h2 = t;
      interp.Interpolate(z + dz, vp, unused, &h1);
      interp.Interpolate(z - dz, vm, unused, &h2);
      for (int f = 0; f < 2; ++f) EXPECT_NEAR(g(axis, f), (vp[f] - vm[f]) / (2 * h), 1e-5);
    }
  }
}

TEST(DelaunayInterpolator, OutsideTheHullUsesTheNearestHullPoint) {
  RowMatrixXd pos(4, 2), fields(4, 1);
  pos << 0, 0, 2, 0, 2, 2, 0, 2;
  fields << 0, 2, 4, 2;  // f = x + y
  DelaunayInterpolator interp(pos, fields);
  RowMatrixXd q(3, 2);
  q << 5, 1, -1, -1, 1, 1;
  const InterpolationBatch b = interp.InterpolateBatch(q);
  EXPECT_FALSE(b.inside[0]);
  EXPECT_NEAR(b.evaluated_at_m(0, 0), 2.0, 1e-12);
  EXPECT_NEAR(b.evaluated_at_m(0, 1), 1.0, 1e-12);
  EXPECT_NEAR(b.values(0, 0), 3.0, 1e-12);
  EXPECT_FALSE(b.inside[1]);
  EXPECT_NEAR(b.values(1, 0), 0.0, 1e-12);  // nearest hull point is the corner (0, 0)
  EXPECT_TRUE(b.inside[2]);
  EXPECT_NEAR(b.values(2, 0), 2.0, 1e-12);
  EXPECT_TRUE(interp.ClampToHull(Eigen::Vector2d(3, 3)).isApprox(Eigen::Vector2d(2, 2)));
}

TEST(DelaunayInterpolator, SequentialRandomAndThreadedBatchesAgree) {
  const Scattered s = MakeScattered(2000, 5);
  DelaunayInterpolator interp(s.positions, s.fields);
  RandomStream rng(6);
  RowMatrixXd path(20000, 2);
  for (int i = 0; i < 20000; ++i) {  // a wandering path, partly outside the hull
    path.row(i) << 5 + 6 * std::cos(i * 1e-3), 2.5 + 3 * std::sin(i * 1.3e-3);
  }
  const InterpolationBatch a = interp.InterpolateBatch(path, /*sequential=*/true, 1);
  const InterpolationBatch b = interp.InterpolateBatch(path, /*sequential=*/false, 3);
  EXPECT_LT((a.values - b.values).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_EQ(a.inside, b.inside);
}

TEST(DelaunayInterpolator, SibsonIsExactAtVerticesAndForAffineFields) {
  const Scattered s = MakeScattered(150, 7);
  DelaunayInterpolator interp(s.positions, s.fields);
  RowMatrixXd q(50, 2);
  RandomStream rng(8);
  for (int i = 0; i < 50; ++i) q.row(i) << rng.Uniform(2, 8), rng.Uniform(1, 4);
  const RowMatrixXd sib = interp.SibsonInterpolate(q);
  for (int i = 0; i < 50; ++i) {
    EXPECT_NEAR(sib(i, 0), 3.0 * q(i, 0) - 2.0 * q(i, 1) + 1.0, 1e-8);  // linear precision
  }
  const RowMatrixXd at_vertices = interp.SibsonInterpolate(s.positions.topRows(10));
  EXPECT_LT((at_vertices - s.fields.topRows(10)).cwiseAbs().maxCoeff(), 1e-8);
}

TEST(DelaunayInterpolator, BadInputGivesClearErrors) {
  RowMatrixXd two(2, 2), f2(2, 1);
  two << 0, 0, 1, 1;
  f2 << 1, 2;
  EXPECT_THROW(DelaunayInterpolator(two, f2), std::invalid_argument);
  RowMatrixXd collinear(4, 2), f4(4, 1);
  collinear << 0, 0, 1, 1, 2, 2, 3, 3;
  f4 << 1, 2, 3, 4;
  EXPECT_THROW(DelaunayInterpolator(collinear, f4), std::invalid_argument);
  RowMatrixXd dup(4, 2);
  dup << 0, 0, 1, 0, 0, 1, 1, 0;
  try {
    DelaunayInterpolator d(dup, f4);
    FAIL() << "duplicates accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("duplicate positions: rows 1 and 3"), std::string::npos);
  }
  RowMatrixXd nan_pos(3, 2), f3(3, 1);
  nan_pos << 0, 0, 1, std::nan(""), 0, 1;
  f3 << 1, 2, 3;
  EXPECT_THROW(DelaunayInterpolator(nan_pos, f3), std::invalid_argument);
}

}  // namespace
}  // namespace indoorloc::wifi
