// Closed forms of the linear spring-dashpot contact and the time-step rules (docs/physics.md
// section 1). See contact.hpp for the derivation of the stability bound.
#include "rendulic/dem/contact.hpp"

#include <algorithm>
#include <iomanip>
#include <limits>
#include <sstream>

#include "rendulic/core/errors.hpp"

namespace rendulic::dem {

bool Material::IsValid(std::string* why) const {
  auto fail = [why](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (!(k > 0 && std::isfinite(k))) return fail("k must be positive and finite");
  if (!(gamma >= 0 && std::isfinite(gamma))) return fail("gamma must be >= 0");
  if (!(gamma_b >= 0 && std::isfinite(gamma_b))) return fail("gamma_b must be >= 0");
  if (!(density > 0 && std::isfinite(density))) return fail("density must be positive");
  if (!(r_mean > 0 && std::isfinite(r_mean))) return fail("r_mean must be positive");
  if (!(w >= 1 && std::isfinite(w))) return fail("w must be >= 1");
  if (!(mu >= 0 && std::isfinite(mu))) return fail("dem.friction (mu) must be >= 0");
  if (!(k_t_ratio >= kMinSpringRatio && std::isfinite(k_t_ratio)))
    return fail("dem.k_t_ratio must be >= 1e-6");
  if (!(gamma_t_ratio >= 0 && std::isfinite(gamma_t_ratio)))
    return fail("dem.gamma_t_ratio must be >= 0");
  if (!(mu_r >= 0 && std::isfinite(mu_r))) return fail("dem.rolling_friction (mu_r) must be >= 0");
  if (!(k_r_ratio >= kMinSpringRatio && std::isfinite(k_r_ratio)))
    return fail("dem.k_r_ratio must be >= 1e-6");
  if (!(gamma_r_ratio >= 0 && std::isfinite(gamma_r_ratio)))
    return fail("dem.gamma_r_ratio must be >= 0");
  if (mu_r > 0 && !(mu > 0))
    return fail(
        "dem.rolling_friction > 0 needs dem.friction > 0 (rotations exist only with friction)");
  return true;
}

std::string lammps_pair_lines(const Material& m) {
  std::ostringstream s;
  s << std::setprecision(17) << "pair_style granular\npair_coeff * * hooke " << m.k << " "
    << m.gamma << " damping velocity tangential ";
  if (m.frictional())
    s << "linear_history " << m.k_t_ratio * m.k << " " << m.gamma_t_ratio << " " << m.mu;
  else
    s << "linear_nohistory 0 0";
  // LAMMPS's rolling damping is a coefficient of its own (force x time / length), unlike the
  // tangential one, which it takes as a multiple of the normal damping.
  if (m.rolling()) {
    const TangentialContact r = m.rolling_contact();
    s << " rolling sds " << r.k_t << " " << r.gamma_t << " " << r.mu;
  }
  s << "\n";
  return s.str();
}

double contact_time(const NormalContact& c, double m_reduced) {
  const double eta = c.gamma / (2.0 * m_reduced);
  const double omega2 = c.k / m_reduced - eta * eta;
  if (omega2 <= 0) return std::numeric_limits<double>::infinity();
  return std::numbers::pi / std::sqrt(omega2);
}

double restitution(const NormalContact& c, double m_reduced) {
  const double tc = contact_time(c, m_reduced);
  if (!std::isfinite(tc)) return 0.0;
  return std::exp(-c.gamma / (2.0 * m_reduced) * tc);
}

namespace {
double smallest_reduced_mass(const Material& m) { return 0.5 * m.sphere_mass(m.r_min()); }
}  // namespace

double contact_duration(const Material& m) {
  return contact_time(m.contact(), smallest_reduced_mass(m));
}

double time_step(const Material& m, double factor) { return factor * contact_duration(m); }

double stability_limit(const Material& m) {
  constexpr double kMaxContacts = 12.0;  // kissing number: most contacts a smallest sphere has
  const double m_min = m.sphere_mass(m.r_min());
  // A tangential spring moves the translation and the rotation (1/m + r^2/I = 3.5/m).
  constexpr double kTangentialLever = 3.5;
  double k = m.frictional() ? std::max(m.k, kTangentialLever * m.k_t_ratio * m.k) : m.k;
  double gamma =
      m.frictional() ? std::max(m.gamma, kTangentialLever * m.gamma_t_ratio * m.gamma) : m.gamma;
  // A rolling spring turns the rotation alone, through a' <= r (a'^2 / I <= 2.5 / m).
  constexpr double kRollingLever = 2.5;
  if (m.rolling()) {
    k = std::max(m.k, (kTangentialLever * m.k_t_ratio + kRollingLever * m.k_r_ratio) * m.k);
    gamma = std::max(
        m.gamma, (kTangentialLever * m.gamma_t_ratio + kRollingLever * m.gamma_r_ratio) * m.gamma);
  }
  const double omega_max = std::sqrt(2.0 * kMaxContacts * k / m_min);
  const double damping_rate = (2.0 * kMaxContacts * gamma + m.gamma_b) / m_min;
  double limit = 2.0 / omega_max;
  if (damping_rate > 0) limit = std::min(limit, 2.0 / damping_rate);
  return limit;
}

void check_time_step(const Material& m, double factor, const std::string& key) {
  const double m_red = smallest_reduced_mass(m);
  // Named with its numbers: the culprit is a radius, density, gamma or k, not dt_factor.
  if (!(m_red > 0) || !std::isfinite(m_red)) {
    std::ostringstream s;
    s << key << ": the smallest sphere (radius " << m.r_min() << " m, density " << m.density
      << " kg/m^3) has a mass of " << 2.0 * m_red
      << " kg, not a positive finite number; give radii and density in SI units";
    throw InputError(s.str());
  }
  const double tc = contact_time(m.contact(), m_red);
  if (!std::isfinite(tc)) {
    std::ostringstream s;
    s << key << ": the smallest pair (radius " << m.r_min() << " m, reduced mass " << m_red
      << " kg) is overdamped: material.gamma = " << m.gamma
      << " kg/s is at least 2 sqrt(k m) = " << 2.0 * std::sqrt(m.k * m_red)
      << " kg/s, so there is no contact time to derive a time step from";
    throw InputError(s.str());
  }
  const double dt = factor * tc;
  const double limit = stability_limit(m);
  if (!(factor > 0) || !(dt < limit)) {
    std::ostringstream s;
    s << key << " = " << factor << " gives dt = " << dt << " s, beyond the explicit stability "
      << "limit " << limit << " s (= " << limit / tc << " t_c); use a smaller factor";
    throw InputError(s.str());
  }
}

}  // namespace rendulic::dem
