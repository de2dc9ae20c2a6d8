// The affine map of an envelope and its ellipse (affine_map.hpp; docs/fitting.md).
#include "rendulic/core/affine_map.hpp"

#include <cmath>

#include "rendulic/core/conventions.hpp"

namespace rendulic {

AffineMapFit fit_affine_map(const std::vector<Eigen::Vector2d>& x,
                            const std::vector<Eigen::Vector2d>& response) {
  AffineMapFit out;
  const auto n = static_cast<Eigen::Index>(x.size());
  if (n < 3 || response.size() != x.size()) return out;
  Eigen::MatrixXd X(n, 3), Y(n, 2);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector2d& xi = x[static_cast<std::size_t>(i)];
    X.row(i) << 1.0, xi.x(), xi.y();
    Y.row(i) = response[static_cast<std::size_t>(i)].transpose();
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(X);
  out.rank = static_cast<int>(qr.rank());
  if (out.rank < 3) return out;
  const Eigen::MatrixXd B = qr.solve(Y);  // rows: c^T, then M^T
  out.center = B.row(0).transpose();
  out.map = B.bottomRows(2).transpose();
  out.rms = std::sqrt((X * B - Y).squaredNorm() / static_cast<double>(n));
  out.ok = out.center.allFinite() && out.map.allFinite();
  return out;
}

std::vector<Eigen::Vector2d> direction_vectors(const std::vector<double>& theta_deg) {
  std::vector<Eigen::Vector2d> u;
  u.reserve(theta_deg.size());
  for (double deg : theta_deg) {
    const double t = deg_to_rad(deg);
    u.emplace_back(std::cos(t), std::sin(t));
  }
  return u;
}

MapEllipse ellipse_of_map(const Eigen::Matrix2d& map) {
  const Eigen::JacobiSVD<Eigen::Matrix2d> svd(map, Eigen::ComputeFullU);
  MapEllipse e;
  e.semi_major = svd.singularValues()(0);
  e.semi_minor = svd.singularValues()(1);
  // A direction, not an orientation: folded into [0, 180).
  double deg = rad_to_deg(std::atan2(svd.matrixU()(1, 0), svd.matrixU()(0, 0)));
  deg = std::fmod(deg + 360.0, 180.0);
  e.inclination_deg = deg >= 180.0 ? deg - 180.0 : deg;
  return e;
}

}  // namespace rendulic
