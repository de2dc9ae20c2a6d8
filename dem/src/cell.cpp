// Cell controls and the stress servo (docs/physics.md section 2; gains justified in cell.hpp).
#include "rendulic/dem/cell.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "rendulic/core/errors.hpp"

namespace rendulic::dem {

std::array<int, 3> cell_list_bins(const Eigen::Vector3d& widths, double min_width, std::size_t n) {
  const double most = std::max(65536.0, kMaxBinsPerParticle * static_cast<double>(n));
  std::array<double, 3> b{};
  for (int a = 0; a < 3; ++a) {
    const double fit = std::floor(widths[a] / min_width);
    b[a] = fit >= 1.0 ? std::min(fit, most) : 1.0;  // NaN (no width) takes one bin
  }
  // Coarser alike along the axes that keep more than one bin, until the total fits: an axis that
  // would fall below one bin keeps one, and the others share the bound (at most three passes,
  // each of which either fits or holds another axis at one bin).
  for (double total = b[0] * b[1] * b[2]; total > most; total = b[0] * b[1] * b[2]) {
    const double free = (b[0] > 1.0) + (b[1] > 1.0) + (b[2] > 1.0);
    const double s = std::pow(most / total, 1.0 / free);
    for (double& v : b)
      if (v > 1.0) v = std::max(1.0, std::floor(v * s));
  }
  return {static_cast<int>(b[0]), static_cast<int>(b[1]), static_cast<int>(b[2])};
}

void require_minimum_image(const Eigen::Vector3d& widths, double range) {
  for (int a = 0; a < 3; ++a)
    if (!(widths[a] > 2.0 * range)) {
      std::ostringstream s;
      s << "periodic cell too small: width " << widths[a] << " m on axis " << a
        << " must exceed twice the interaction range " << range
        << " m, or the minimum image is ambiguous (use more particles or a smaller skin)";
      throw InputError(s.str());
    }
}

bool ServoOptions::IsValid(std::string* why) const {
  if (!(gain > 0 && std::isfinite(gain))) {
    if (why) *why = "servo gain must be positive";
    return false;
  }
  if (!(integral_gain >= 0 && std::isfinite(integral_gain))) {
    if (why) *why = "servo integral gain must be >= 0";
    return false;
  }
  if (!(max_rate > 0 && std::isfinite(max_rate))) {
    if (why) *why = "servo max_rate must be positive";
    return false;
  }
  return true;
}

CellControl CellControl::strain_rate(const Eigen::Vector3d& D) {
  CellControl c;
  for (int a = 0; a < 3; ++a) c.axis[a].rate = D[a];
  return c;
}
CellControl CellControl::isotropic_compression(double rate) {
  return strain_rate(Eigen::Vector3d::Constant(-rate));
}
CellControl CellControl::undrained_axisymmetric(double rate) {
  return strain_rate(Eigen::Vector3d(rate, -0.5 * rate, -0.5 * rate));
}
CellControl CellControl::drained_triaxial(double axial_rate, double lateral_stress) {
  CellControl c;
  c.axis[0].rate = axial_rate;
  for (int a = 1; a < 3; ++a) {
    c.axis[a].mode = AxisControl::Mode::kStress;
    c.axis[a].target_stress = lateral_stress;
  }
  return c;
}

bool CellControl::needs_stress() const {
  return std::any_of(axis.begin(), axis.end(),
                     [](const AxisControl& a) { return a.mode == AxisControl::Mode::kStress; });
}

Eigen::Vector3d CellControl::velocity_gradient(const Eigen::Vector3d& stress_diag,
                                               double k_star) const {
  Eigen::Vector3d D;
  for (int a = 0; a < 3; ++a) {
    if (axis[a].mode == AxisControl::Mode::kStrainRate) {
      D[a] = axis[a].rate;
    } else {
      const double d = servo.gain * (stress_diag[a] - axis[a].target_stress) / k_star;
      D[a] = std::clamp(d, -servo.max_rate, servo.max_rate);
    }
  }
  return D;
}

Eigen::Vector3d CellControl::velocity_gradient(const Eigen::Vector3d& stress_diag, double k_star,
                                               double dt, Eigen::Vector3d& integral) const {
  Eigen::Vector3d D;
  for (int a = 0; a < 3; ++a) {
    if (axis[a].mode == AxisControl::Mode::kStrainRate) {
      D[a] = axis[a].rate;
      continue;
    }
    const double e = (stress_diag[a] - axis[a].target_stress) / k_star;
    // The integral is held inside the rate bound (anti-windup): a term beyond it could not act
    // and would only delay the recovery once the error changes sign.
    integral[a] =
        std::clamp(integral[a] + servo.integral_gain * e * dt, -servo.max_rate, servo.max_rate);
    D[a] = std::clamp(integral[a] + servo.gain * e, -servo.max_rate, servo.max_rate);
  }
  return D;
}

}  // namespace rendulic::dem
