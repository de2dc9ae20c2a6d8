// The hypoplastic sand's limit state in a triaxial stress state, found from the law's equation
// by a second method (bisection, not the driver): shared by the driver's and the paths' tests.
#pragma once

#include <Eigen/Dense>

#include "rendulic/models/law.hpp"

namespace rendulic::models {

// The sand's limit surface at sigma = diag(R, 1, 1) p, a second implementation from the
// equation (docs/models.md, Wu and Bauer 1994): d_sigma = L : d_eps + N |d_eps| can vanish, for
// some d_eps, only where |L^-1 : N| = 1. Tensors as 3 x 3 arrays, |.| Frobenius; bisection on R
// between `inside` (R = 1, the isotropic state, is inside) and `outside`: R > 1 is the limit
// in triaxial compression, R < 1 in extension.
inline double wu_limit_ratio(const Law& law, double p, double inside = 1.0, double outside = 20.0) {
  const double c1 = law.parameter("c1"), c2 = law.parameter("c2"), c3 = law.parameter("c3"),
               c4 = law.parameter("c4");
  auto excess = [&](double R) {
    const Eigen::Matrix3d s = p * Eigen::Vector3d(R, 1.0, 1.0).asDiagonal().toDenseMatrix();
    const double tr = s.trace();
    Eigen::Matrix<double, 9, 9> L;
    for (int k = 0; k < 9; ++k) {
      Eigen::Matrix3d x = Eigen::Matrix3d::Zero();
      x(k / 3, k % 3) = 1.0;
      const Eigen::Matrix3d y = -c1 * tr * x - c2 * (s.cwiseProduct(x).sum() / tr) * s;
      L.col(k) = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(y.data());
    }
    const Eigen::Matrix3d sd = s - tr / 3.0 * Eigen::Matrix3d::Identity();
    const Eigen::Matrix3d n = (c3 * s * s + c4 * sd * sd) / tr;
    return L.fullPivLu().solve(Eigen::Map<const Eigen::Matrix<double, 9, 1>>(n.data())).norm() -
           1.0;
  };
  double in = inside, out = outside;
  for (int it = 0; it < 200 && std::abs(out - in) > 1e-14 * std::abs(out); ++it)
    (excess(0.5 * (in + out)) < 0.0 ? in : out) = 0.5 * (in + out);
  return 0.5 * (in + out);
}

}  // namespace rendulic::models
