// Test helper: the ellipse traced by response points r_i = c + M s_i of probe points s_i,
// from a least-squares fit of the affine map (c, M) and the SVD of M. It is an independent
// route to the envelope features (does not use probes/): for an incrementally linear law the
// response is exactly affine in the probe, and the ellipse's semi-axes are the singular values
// of M and its major axis is M's first left singular vector (docs/physics.md section 6).
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <vector>

namespace rendulic::models::testing {

struct AffineEllipse {
  Eigen::Vector2d center;
  Eigen::Matrix2d map;
  double a = 0, b = 0;         // semi-axes, a >= b
  double inclination_deg = 0;  // of the major axis, in [0, 180)
  double rms = 0;              // residual of the affine fit
};

inline AffineEllipse ellipse_of(const Eigen::Matrix<double, Eigen::Dynamic, 2>& strain,
                                const Eigen::Matrix<double, Eigen::Dynamic, 2>& response) {
  const int m = static_cast<int>(strain.rows());
  Eigen::MatrixXd x(m, 3);
  x.col(0).setOnes();
  x.rightCols(2) = strain;
  const Eigen::MatrixXd coef = x.colPivHouseholderQr().solve(response);  // 3 x 2
  AffineEllipse e;
  e.center = coef.row(0).transpose();
  e.map = coef.bottomRows(2).transpose();
  e.rms = std::sqrt((x * coef - response).squaredNorm() / m);
  Eigen::JacobiSVD<Eigen::Matrix2d> svd(e.map, Eigen::ComputeFullU);
  // The probe points lie on a circle of radius |d_eps|: semi-axes = singular values x radius.
  const double radius = strain.rowwise().norm().mean();
  e.a = svd.singularValues()(0) * radius;
  e.b = svd.singularValues()(1) * radius;
  const Eigen::Vector2d u = svd.matrixU().col(0);
  double deg = std::atan2(u.y(), u.x()) * 180.0 / M_PI;
  while (deg < 0) deg += 180.0;
  while (deg >= 180.0) deg -= 180.0;
  e.inclination_deg = deg;
  return e;
}

// The pairs of an envelope record (core/envelope_record.hpp) as the rows of a matrix.
inline Eigen::Matrix<double, Eigen::Dynamic, 2> rows_of(const std::vector<Eigen::Vector2d>& v) {
  Eigen::Matrix<double, Eigen::Dynamic, 2> m(static_cast<Eigen::Index>(v.size()), 2);
  for (std::size_t i = 0; i < v.size(); ++i) m.row(static_cast<Eigen::Index>(i)) = v[i];
  return m;
}

inline AffineEllipse ellipse_of(const std::vector<Eigen::Vector2d>& strain,
                                const std::vector<Eigen::Vector2d>& response) {
  return ellipse_of(rows_of(strain), rows_of(response));
}

}  // namespace rendulic::models::testing
