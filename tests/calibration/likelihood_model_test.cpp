// The likelihood's block as Levenberg-Marquardt sees it (solver.hpp likelihood_block_model;
// docs/calibration.md "The likelihood's curvature"): against the closed form of the block's
// -2 ln L (rho = N (ln x + 1) above the noise floor, N x below it, x = |r|^2 / floor2), the
// presented residuals carry the cost rho / 2 and the gradient rho' J^T r exactly, and the
// model's curvature J'^T J' is rho' J^T J less rho' (1 - beta^2) along the block's own
// residual, beta^2 = 1 / (ln x + 1); below the floor it is the plain scaling by sqrt(rho').
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "rendulic/calibration/solver.hpp"

namespace rendulic::calibration {
namespace {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct Presented {
  Eigen::VectorXd r;
  RowMatrix J;
};

Presented present(double n, double floor2, const Eigen::VectorXd& r, const RowMatrix& J) {
  Presented out{r, J};
  likelihood_block_model(n, floor2, static_cast<int>(r.size()), static_cast<int>(J.cols()),
                         out.r.data(), out.J.data());
  return out;
}

// A block of 6 residuals and 3 parameters, not aligned with anything.
Eigen::VectorXd residuals(double scale) {
  Eigen::VectorXd r(6);
  r << 0.3, -1.2, 0.7, 0.05, -0.4, 0.9;
  return scale * r;
}
RowMatrix jacobian() {
  RowMatrix J(6, 3);
  J << 1.0, 0.2, -0.3, 0.4, -1.1, 0.5, 0.0, 0.7, 0.8, -0.6, 0.1, 1.3, 0.9, -0.2, 0.05, 0.3, 0.6,
      -0.7;
  return J;
}

TEST(LikelihoodModel, AboveTheFloorCostAndGradientExactCurvatureAlongTheResidualReduced) {
  const double n = 6.0, floor2 = 0.05;
  const Eigen::VectorXd r = residuals(1.0);
  const RowMatrix J = jacobian();
  const double s = r.squaredNorm(), x = s / floor2;
  ASSERT_GT(x, 1.0);
  const double rho = n * (std::log(x) + 1.0), rho1 = n / s;
  const Presented p = present(n, floor2, r, J);
  EXPECT_NEAR(p.r.squaredNorm(), rho, 1e-13 * rho);
  // Along r: the presented residuals keep its direction.
  EXPECT_NEAR(p.r.normalized().dot(r.normalized()), 1.0, 1e-15);
  const Eigen::VectorXd gradient = p.J.transpose() * p.r, want = rho1 * J.transpose() * r;
  EXPECT_LT((gradient - want).norm(), 1e-13 * want.norm());
  const Eigen::VectorXd u = r.normalized();
  const double beta2 = 1.0 / (std::log(x) + 1.0);
  const Eigen::MatrixXd H = p.J.transpose() * p.J;
  const Eigen::MatrixXd H_want =
      rho1 * (J.transpose() * J - (1.0 - beta2) * J.transpose() * u * u.transpose() * J);
  EXPECT_LT((H - H_want).norm(), 1e-13 * H_want.norm());
  // Less curved than Ceres's loss corrector leaves it (rho' J^T J) along J^T r, more than the
  // likelihood's own Hessian (rho' J^T J + 2 rho'' J^T r r^T J, rho'' = -N / s^2).
  const Eigen::VectorXd d = J.transpose() * u;
  const double corrector = rho1 * d.dot(J.transpose() * J * d);
  const double own = corrector - 2.0 * n / (s * s) * s * std::pow(d.dot(d), 2);
  const double presented = d.dot(H * d);
  EXPECT_LT(presented, corrector);
  EXPECT_GT(presented, own);
}

TEST(LikelihoodModel, BelowTheFloorAPlainScaling) {
  const double n = 6.0, floor2 = 100.0;
  const Eigen::VectorXd r = residuals(1.0);
  const RowMatrix J = jacobian();
  ASSERT_LT(r.squaredNorm(), floor2);
  const double root1 = std::sqrt(n / floor2);
  const Presented p = present(n, floor2, r, J);
  EXPECT_EQ(p.r, Eigen::VectorXd(root1 * r));
  EXPECT_EQ(p.J, RowMatrix(root1 * J));
  // The residuals alone (a value-only evaluation) are presented the same way.
  Eigen::VectorXd alone = r;
  likelihood_block_model(n, floor2, 6, 3, alone.data(), nullptr);
  EXPECT_EQ(alone, p.r);
}

TEST(LikelihoodModel, ContinuousAtTheFloor) {
  const double n = 6.0;
  const Eigen::VectorXd r = residuals(1.0);
  const RowMatrix J = jacobian();
  const double s = r.squaredNorm();
  const Presented below = present(n, s * (1.0 + 1e-12), r, J);
  const Presented above = present(n, s * (1.0 - 1e-12), r, J);
  EXPECT_LT((below.r - above.r).norm(), 1e-9 * below.r.norm());
  EXPECT_LT((below.J - above.J).norm(), 1e-9 * below.J.norm());
}

}  // namespace
}  // namespace rendulic::calibration
