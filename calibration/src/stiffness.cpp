// Per-state Rendulic stiffness and plastic envelope features (stiffness.hpp; docs/calibration.md
// "Two levels", docs/physics.md sections 5-6).
#include "rendulic/calibration/stiffness.hpp"

#include <cmath>

#include "rendulic/core/affine_map.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/probes/envelope_fit.hpp"

namespace rendulic::calibration {

Eigen::Matrix2d RendulicStiffness::iso_dev_matrix() const {
  Eigen::Matrix2d d;
  d << 3.0 * B, kSqrt3 * A, kSqrt3 * A, 2.0 * G;
  return d;
}

Eigen::Matrix2d RendulicStiffness::rendulic_matrix() const {
  const Eigen::Matrix2d R = rendulic_to_iso_dev();
  return R.transpose() * iso_dev_matrix() * R;
}

bool StiffnessOptions::IsValid(std::string*) const { return true; }

namespace {

void set_ellipse(const Eigen::Matrix2d& M, double* a, double* b, double* inclination_deg) {
  const MapEllipse e = ellipse_of_map(M);
  *a = e.semi_major;
  *b = e.semi_minor;
  *inclination_deg = e.inclination_deg;
}

}  // namespace

RendulicStiffness fit_rendulic_stiffness(const EnvelopeRecord& env,
                                         const StiffnessOptions& options) {
  RendulicStiffness out;
  std::string why;
  if (!is_valid_envelope(env, &why)) {
    out.note = why;
    return out;
  }
  const int m = env.size();
  const int k = options.fit_center ? 5 : 3;
  const Eigen::Matrix2d R = rendulic_to_iso_dev();
  // Unknowns (B, G, A[, c_iso, c_dev]); rows: the iso and dev components of every probe:
  //   s_iso = 3B q_iso + sqrt3 A q_dev + c_iso,  s_dev = sqrt3 A q_iso + 2G q_dev + c_dev.
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(2 * m, k);
  Eigen::VectorXd y(2 * m);
  for (int i = 0; i < m; ++i) {
    const Eigen::Vector2d q = R * env.strain[i];
    const Eigen::Vector2d s = R * env.stress[i];
    X(2 * i, 0) = 3.0 * q(0);
    X(2 * i, 2) = kSqrt3 * q(1);
    X(2 * i + 1, 1) = 2.0 * q(1);
    X(2 * i + 1, 2) = kSqrt3 * q(0);
    if (k == 5) {
      X(2 * i, 3) = 1.0;
      X(2 * i + 1, 4) = 1.0;
    }
    y.segment<2>(2 * i) = s;
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(X);
  if (qr.rank() < k) {
    out.note = std::string("probe directions do not determine B, G, A (rank ") +
               std::to_string(qr.rank()) + " < " + std::to_string(k) + ")";
    return out;
  }
  const Eigen::VectorXd x = qr.solve(y);
  const Eigen::VectorXd res = y - X * x;
  out.B = x(0);
  out.G = x(1);
  out.A = x(2);
  if (k == 5) out.center = R.transpose() * Eigen::Vector2d(x(3), x(4));
  out.n_points = m;
  out.rms = std::sqrt(res.squaredNorm() / (2.0 * m));
  const int dof = 2 * m - k;
  if (dof > 0) {
    const double s2 = res.squaredNorm() / dof;
    const Eigen::MatrixXd cov = s2 * (X.transpose() * X).inverse();
    out.covariance = cov.topLeftCorner<3, 3>();
    out.B_stderr = std::sqrt(cov(0, 0));
    out.G_stderr = std::sqrt(cov(1, 1));
    out.A_stderr = std::sqrt(cov(2, 2));
  }
  set_ellipse(out.rendulic_matrix() * env.amplitude, &out.a, &out.b, &out.inclination_deg);
  out.ok = true;
  // An elastic envelope should be centred: a centre beyond 5% of the minor axis says the
  // probes were not in the linear range (or the state was not relaxed).
  if (out.center.norm() > 0.05 * std::max(out.b, 1e-300))
    out.note = std::string("centre ") + decimal_g(out.center.norm()) +
               " Pa is more than 5% of the minor semi-axis: envelope not purely elastic?";
  return out;
}

PlasticFeatures plastic_features(const EnvelopeRecord& env) {
  PlasticFeatures out;
  out.amplitude = env.amplitude;
  std::string why;
  if (!is_valid_envelope(env, &why)) {
    out.note = why;
    return out;
  }
  const AffineMapFit fs = fit_affine_map(direction_vectors(env.theta_deg), env.stress);
  if (!fs.ok) {
    out.note = "affine fit of the stress envelope failed";
    return out;
  }
  out.shift = fs.center;
  set_ellipse(fs.map, &out.a, &out.b, &out.inclination_deg);
  out.thinning = out.a > 0.0 ? out.b / out.a : 0.0;
  out.shift_ratio = out.a > 0.0 ? out.shift.norm() / out.a : 0.0;
  out.rms = fs.rms;
  if (env.has_fabric()) {
    const AffineMapFit ff = fit_affine_map(direction_vectors(env.theta_deg), env.fabric);
    if (ff.ok) {
      out.fabric_shift = ff.center;
      set_ellipse(ff.map, &out.fabric_a, &out.fabric_b, &out.fabric_inclination_deg);
    }
  }
  out.ok = true;
  return out;
}

}  // namespace rendulic::calibration
