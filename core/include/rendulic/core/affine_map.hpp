// The affine map of a response envelope in the Rendulic plane and its ellipse (docs/probes.md
// "Envelopes", docs/fitting.md): the one home of the least-squares fit R_i = c + M x_i that
// the DEM's probe checks (x = the strain pairs), the envelope fits (x = u(theta) =
// (cos theta, sin theta)) and the calibration's features (the same, as a linear projection
// that derivatives pass through) all use. For a linear law R = M x exactly and c = 0; the
// semi-axes of the ellipse are the singular values of M and its inclination is that of the
// first left singular vector.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "rendulic/core/conventions.hpp"

namespace rendulic {

struct AffineMapFit {
  Eigen::Vector2d center = Eigen::Vector2d::Zero();  // c
  Eigen::Matrix2d map = Eigen::Matrix2d::Zero();     // M
  double rms = 0.0;                                  // rms of the 2D residual vectors
  int rank = 0;  // of the rows (1, x_i): 3 when c and M are determined
  bool ok = false;
};

// Least squares over the points, by QR with column pivoting of the rows (1, x_i). ok = false
// with fewer than 3 points, sizes that differ, x_i that do not determine c and M (collinear
// points, fewer than three independent directions) or a non-finite result.
AffineMapFit fit_affine_map(const std::vector<Eigen::Vector2d>& x,
                            const std::vector<Eigen::Vector2d>& response);

// u(theta) = (cos theta, sin theta) of each direction in degrees: the strain pair of a probe
// of unit amplitude (core/conventions.hpp probe_strain).
std::vector<Eigen::Vector2d> direction_vectors(const std::vector<double>& theta_deg);

// The fit of fit_affine_map() for x = u(theta) as a linear operator: the 3 x m matrix P with
// [c^T; M^T] = P [R_1^T; ...; R_m^T] (normal equations). Any scalar type passes through it, so
// the calibration's features of a model envelope carry their derivatives. Inline: compiled out
// of line, GCC schedules the normal equations differently from where the calibration's
// objective once held them, and its features moved by ~5e-8 relative.
inline Eigen::Matrix<double, 3, Eigen::Dynamic> affine_projection(
    const std::vector<double>& theta_deg) {
  Eigen::MatrixXd U(theta_deg.size(), 3);
  for (std::size_t i = 0; i < theta_deg.size(); ++i) {
    const double t = deg_to_rad(theta_deg[i]);
    U.row(static_cast<Eigen::Index>(i)) << 1.0, std::cos(t), std::sin(t);
  }
  return (U.transpose() * U).ldlt().solve(U.transpose());
}

// The ellipse of x -> M x for |x| = 1: semi-axes a >= b >= 0 and the inclination of the major
// axis in [0, 180) deg from the sqrt(2)-lateral axis.
struct MapEllipse {
  double semi_major = 0.0;
  double semi_minor = 0.0;
  double inclination_deg = 0.0;
};
MapEllipse ellipse_of_map(const Eigen::Matrix2d& map);

}  // namespace rendulic
