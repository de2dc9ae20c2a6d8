// Contact law, time scales and the time step of the DEM engine (docs/physics.md section 1, seed
// paper section 2.1). NormalContact is the one statement of the contact law: a pure kernel of
// the overlap and its rate; the callers own minimum image, the relative velocity and the sums.
// The closed forms here (contact duration, restitution) are what the two-particle tests compare
// the integrator against.
#pragma once

#include <cmath>
#include <numbers>
#include <string>

namespace rendulic::dem {

// Linear spring-dashpot normal contact: f = k delta + gamma d(delta)/dt, positive = repulsive,
// along the branch vector l = x_i - x_j, with delta = r_i + r_j - |l| > 0 the overlap. The force
// is not clipped at zero: the closed forms of t_c and e below assume exactly this law (the
// dashpot may pull slightly just before separation).
//
// Evaluated per pair, in the manner of HOOMD-blue's pair evaluators: a small value made once
// outside a loop whose inline methods every user of the law calls per pair (the engine's force
// loop and measures, dem_system.cpp; the energy minimiser, probe_minimise.cpp; the static
// stress of the probe tools, probe_geometry.cpp; the Hessian of the linear response,
// linear_response.cpp; the force balance at rest, rest.cpp). It inlines into the engine's
// vectorised force loop, where it costs nothing (docs/performance.md). The static tools work
// at rest: they use the spring alone (elastic_force, energy, stiffness).
//
// Friction, when it comes, is added here: its parameters as members and one method giving the
// tangential force from the contact's tangential displacement and relative velocity, which the
// callers add to the normal force they take from this type now.
struct NormalContact {
  double k = 1e8;     // kg/s^2
  double gamma = 1.;  // kg/s
  double force(double delta, double delta_dot) const { return k * delta + gamma * delta_dot; }
  // The force loop's form: the force on i as a multiple s of l (F = s l), from delta, 1 / |l|
  // and l . v_rel, v_rel = v_i - v_j the true relative velocity (peculiar plus affine part), so
  // that d(delta)/dt = -l . v_rel / |l|. One scale factor instead of the normal's three
  // components.
  double force_over_distance(double delta, double inv_distance, double l_dot_v) const {
    return (k * delta - gamma * l_dot_v * inv_distance) * inv_distance;
  }
  // At rest (no relative velocity): the spring's force, its energy k delta^2 / 2, and its
  // stiffness df / d(delta), the normal part of the contact's block of the Hessian.
  double elastic_force(double delta) const { return k * delta; }
  double energy(double delta) const { return 0.5 * k * delta * delta; }
  double stiffness() const { return k; }
};

// Material of the seed study (docs/physics.md section 1), SI units.
struct Material {
  double k = 1e8;         // normal stiffness, kg/s^2
  double gamma = 1.0;     // contact viscosity, kg/s
  double gamma_b = 0.1;   // background damping on the peculiar velocity, kg/s
  double density = 2000;  // kg/m^3
  double r_mean = 1e-3;   // m
  double w = 3.0;         // r_max / r_min
  double r_min() const { return 2.0 * r_mean / (1.0 + w); }
  double r_max() const { return w * r_min(); }
  // k* = k / (2 <r>): the stress scale of sigma* (seed paper section 2.2).
  double k_star() const { return k / (2.0 * r_mean); }
  double sphere_mass(double r) const { return density * 4.0 / 3.0 * std::numbers::pi * r * r * r; }
  NormalContact contact() const { return {k, gamma}; }
  bool IsValid(std::string* why) const;
};

// Duration of a binary collision, t_c = pi / sqrt(k/m_red - (gamma / (2 m_red))^2).
// Returns +inf for an overdamped pair (no rebound).
double contact_time(const NormalContact& c, double m_reduced);
// Coefficient of normal restitution, e = exp(-gamma t_c / (2 m_red)).
double restitution(const NormalContact& c, double m_reduced);

// Time step: dt = factor * t_c of the two smallest particles (docs/physics.md section 1).
double time_step(const Material& m, double factor);
// A sufficient bound for the stability of the explicit scheme on any packing of this
// material. Springs: Gershgorin on the mass-weighted stiffness matrix bounds the highest
// frequency by omega_max^2 <= 2 z k / m_min with z = 12 contacts at most on the smallest
// particle; Verlet is stable for omega_max dt < 2. Dashpots, treated explicitly: the same
// bound with the damping rate (2 z gamma + gamma_b) / m_min in place of omega_max.
double stability_limit(const Material& m);
// Throws InputError (naming `key`) if factor gives a dt at or beyond stability_limit().
void check_time_step(const Material& m, double factor, const std::string& key);

}  // namespace rendulic::dem
