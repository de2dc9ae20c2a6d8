// Cell controls and the stress servo (docs/physics.md section 2; gains justified in cell.hpp).
#include "rendulic/dem/cell.hpp"

#include <algorithm>
#include <cmath>

namespace rendulic::dem {

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
