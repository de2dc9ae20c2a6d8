// The affine map of an envelope (core/affine_map.hpp) against closed forms: a linear law plus a
// shift is recovered exactly by the fit and by the projection, and the ellipse of a rotated
// diagonal map has the diagonal as its semi-axes and the rotation as its inclination.
#include "rendulic/core/affine_map.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "rendulic/core/conventions.hpp"

namespace rendulic {
namespace {

constexpr double kExact = 1e-12;  // round-off of a 3-column least-squares solve

std::vector<double> directions() {
  std::vector<double> th;
  for (int k = 0; k < 9; ++k) th.push_back(11.0 + 40.0 * k);
  return th;
}

TEST(AffineMap, FitAndProjectionRecoverALinearLawPlusAShift) {
  Eigen::Matrix2d M;
  M << 2.0, -0.5, 0.7, 1.2;  // any map: not symmetric
  const Eigen::Vector2d c(0.3, -0.1);
  const std::vector<double> th = directions();
  const std::vector<Eigen::Vector2d> u = direction_vectors(th);
  std::vector<Eigen::Vector2d> r;
  for (const auto& x : u) r.push_back(c + M * x);
  const AffineMapFit fit = fit_affine_map(u, r);
  ASSERT_TRUE(fit.ok);
  EXPECT_EQ(fit.rank, 3);
  EXPECT_LT((fit.map - M).norm(), kExact);
  EXPECT_LT((fit.center - c).norm(), kExact);
  EXPECT_LT(fit.rms, kExact);
  const Eigen::Matrix<double, 3, Eigen::Dynamic> P = affine_projection(th);
  Eigen::Matrix<double, 3, 2> coef = Eigen::Matrix<double, 3, 2>::Zero();
  for (std::size_t i = 0; i < r.size(); ++i)
    coef += P.col(static_cast<Eigen::Index>(i)) * r[i].transpose();
  EXPECT_LT((coef.row(0).transpose() - c).norm(), kExact);
  EXPECT_LT((coef.bottomRows(2).transpose() - M).norm(), kExact);
}

TEST(AffineMap, CollinearOrTooFewPointsAreNotFitted) {
  const std::vector<Eigen::Vector2d> x = {{0, 0}, {1, 1}, {2, 2}, {3, 3}};
  const std::vector<Eigen::Vector2d> r = {{0, 1}, {1, 2}, {2, 0}, {3, 1}};
  const AffineMapFit collinear = fit_affine_map(x, r);
  EXPECT_FALSE(collinear.ok);
  EXPECT_LT(collinear.rank, 3);
  EXPECT_FALSE(fit_affine_map({{1, 0}, {0, 1}}, {{1, 0}, {0, 1}}).ok);
  EXPECT_FALSE(fit_affine_map(x, {{0, 1}}).ok);
}

TEST(AffineMap, EllipseOfARotatedDiagonalMap) {
  const double phi = deg_to_rad(123.0);
  Eigen::Matrix2d R;
  R << std::cos(phi), -std::sin(phi), std::sin(phi), std::cos(phi);
  // R diag(3, 1) Q with Q orthogonal: semi-axes 3 and 1, major axis along R's first column,
  // a direction (123 deg), whatever Q.
  Eigen::Matrix2d Q;
  Q << 0.0, 1.0, 1.0, 0.0;
  const MapEllipse e = ellipse_of_map(R * Eigen::Vector2d(3.0, 1.0).asDiagonal() * Q);
  EXPECT_NEAR(e.semi_major, 3.0, kExact);
  EXPECT_NEAR(e.semi_minor, 1.0, kExact);
  EXPECT_NEAR(e.inclination_deg, 123.0, 1e-9);
  // The opposite vector is the same axis: the inclination stays in [0, 180).
  const MapEllipse f = ellipse_of_map(-R * Eigen::Vector2d(3.0, 1.0).asDiagonal());
  EXPECT_NEAR(f.inclination_deg, 123.0, 1e-9);
}

}  // namespace
}  // namespace rendulic
