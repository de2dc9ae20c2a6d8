// Contact law and integrator against closed forms (docs/physics.md section 1):
// binary collision of the smallest pair (t_c = 0.2279 us, e = 0.804), the stability limit
// refusing a too-large time step, the integrator failing exactly at omega dt = 2 and the
// engine's bound staying below that, and the seed's numbers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "dem_helpers.hpp"
#include "input_error.hpp"
#include "rendulic/core/errors.hpp"

namespace rendulic::dem {
namespace {

using rendulic::testing::input_error;

struct Collision {
  double contact_time;
  double restitution;
};

// Runs a head-on collision and measures the contact duration (overlap zero crossings,
// linearly interpolated between steps) and the ratio of separation to approach speed.
Collision collide(const Material& mat, double dt_factor) {
  const double r = mat.r_min(), v = 0.1;
  DemSystem s = testing::two_spheres(mat, r, v, dt_factor);
  auto overlap = [&] {
    const auto& p = s.particles();
    return 2 * r - std::abs(p.x[1] - p.x[0]);
  };
  double prev = overlap(), t_in = -1, t_out = -1;
  const Eigen::Vector3d still = Eigen::Vector3d::Zero();
  for (int k = 0; k < 100000 && t_out < 0; ++k) {
    const double t = s.time();
    s.step(still);
    const double now = overlap();
    if (prev <= 0 && now > 0) t_in = t + s.dt() * (-prev) / (now - prev);
    if (t_in >= 0 && prev > 0 && now <= 0) t_out = t + s.dt() * prev / (prev - now);
    prev = now;
  }
  s.advance(5, still);  // well separated, no force left
  const double v_out = s.particles().vx[1] - s.particles().vx[0];
  return {t_out - t_in, v_out / v};
}

TEST(Contact, SmallestPairClosedFormsMatchTheSeed) {
  Material mat;
  const double m_red = 0.5 * mat.sphere_mass(mat.r_min());
  // Closed forms for the seed material: t_c = 0.2279 us (docs/dem.md) and e = 0.804, checked to
  // the 4 and 3 significant digits they are quoted with.
  EXPECT_NEAR(contact_time(mat.contact(), m_red), 0.2279e-6, 0.00005e-6);
  EXPECT_NEAR(restitution(mat.contact(), m_red), 0.804, 0.0005);
  EXPECT_NEAR(mat.r_min(), 0.5e-3, 1e-15);
  EXPECT_NEAR(mat.r_max(), 1.5e-3, 1e-15);
}

TEST(Contact, TwoParticleCollisionOfSmallestPairMatchesClosedForm) {
  Material mat;
  mat.gamma_b = 0;  // a binary collision: the closed forms know no background damping
  const double m_red = 0.5 * mat.sphere_mass(mat.r_min());
  const Collision c = collide(mat, 1.0 / 50);
  // dt = t_c/50 and a second-order scheme: errors O((dt/t_c)^2) = 4e-4, measured 1.4e-4 on
  // t_c and 5e-4 on e; the bounds leave a factor ~3 and still pin the seed's 4 digits of t_c.
  EXPECT_NEAR(c.contact_time, contact_time(mat.contact(), m_red), 5e-4 * 0.2279e-6);
  EXPECT_NEAR(c.restitution, restitution(mat.contact(), m_red), 1.5e-3);
  // Convergence: a 4x smaller step is at least 2x closer on e (first order or better).
  const Collision fine = collide(mat, 1.0 / 200);
  const double e = restitution(mat.contact(), m_red);
  EXPECT_LT(std::abs(fine.restitution - e), 0.5 * std::abs(c.restitution - e) + 1e-6);
}

TEST(Contact, TimeStepBeyondStabilityIsRefused) {
  Material mat;
  EXPECT_THROW(testing::two_spheres(mat, mat.r_min(), 0.1, 0.5), InputError);
  EXPECT_THROW(check_time_step(mat, 0.2, "dem.dt_factor"), InputError);
  EXPECT_THROW(check_time_step(mat, -1.0, "dem.dt_factor"), InputError);
  EXPECT_NO_THROW(check_time_step(mat, 1.0 / 50, "dem.dt_factor"));
  const std::string what = input_error([&] { check_time_step(mat, 0.5, "dem.dt_factor"); });
  EXPECT_NE(what.find("dem.dt_factor"), std::string::npos) << what;
}

// The culprit of a pair with no contact time is the material, not dt_factor: the message said
// "gamma too large for k" for radii so small that the mass was 0 (from a packing file in
// metres taken for millimetres) and named neither the radius nor the bound on gamma.
TEST(Contact, APairWithNoContactTimeIsRefusedWithTheNumbersThatCauseIt) {
  Material mat;
  mat.gamma = 1e9;
  const double m_red = 0.5 * mat.sphere_mass(mat.r_min());
  const std::string damped = input_error([&] { check_time_step(mat, 0.02, "dem.dt_factor"); });
  EXPECT_NE(damped.find("material.gamma = 1e+09 kg/s is at least 2 sqrt(k m)"), std::string::npos)
      << damped;
  std::ostringstream bound;
  bound << 2.0 * std::sqrt(mat.k * m_red) << " kg/s";
  EXPECT_NE(damped.find(bound.str()), std::string::npos) << damped;
  Material tiny;
  tiny.r_mean = 1e-200;  // r^3 underflows to 0
  const std::string zero = input_error([&] { check_time_step(tiny, 0.02, "dem.dt_factor"); });
  EXPECT_NE(zero.find("has a mass of 0 kg, not a positive finite number"), std::string::npos)
      << zero;
  EXPECT_NE(zero.find("radius 5e-201 m"), std::string::npos) << zero;
}

// A ring of four equal spheres on the x axis, each pressed on its two neighbours (one of them
// through the periodic boundary), integrated by the engine from the ring's highest mode
// (neighbours moving against each other, omega = 2 sqrt(k/m)) at omega dt = h. Returns the
// largest kinetic energy over `steps` steps over the initial one, stopping once it passes 1e6.
// Undamped velocity Verlet conserves v^2 + omega^2 (1 - h^2/4) x^2 on this mode, so for h < 2
// the kinetic energy never exceeds its start (displacement starts at zero); for h > 2 the mode
// grows by |lambda| > 1 per step. The spheres are a quarter of the material's smallest radius
// (their true masses): the engine's bound, made for the material's r_min, then admits a dt on
// either side of 2 / omega.
double ring_energy_growth(double h, int steps) {
  Material mat;
  mat.gamma = 0;
  mat.gamma_b = 0;
  const double r = 0.25 * mat.r_min(), m = mat.sphere_mass(r);
  const double omega = 2.0 * std::sqrt(mat.k / m);
  const double overlap = 0.01 * r, spacing = 2 * r - overlap, L = 4 * spacing;
  // Displacement amplitude 1e-5 of the overlap: even the 1 / sqrt(1 - h^2/4) swing of h = 1.98
  // keeps every contact closed, so the ring stays the linear system the mode belongs to.
  const double v = 1e-5 * overlap * omega;
  Particles p;
  p.resize(4);
  for (int i = 0; i < 4; ++i) {
    p.radius[i] = r;
    p.inv_mass[i] = 1.0 / m;
    p.x[i] = (i + 0.5) * spacing;
    p.y[i] = p.z[i] = 0.5 * L;
    p.vx[i] = (i % 2 == 0) ? v : -v;
  }
  SystemOptions o;
  o.material = mat;
  o.skin = 0.05;  // in <r>: the cell of four small spheres must exceed twice the list's range
  o.dt_factor = h / omega / time_step(mat, 1.0);
  DemSystem s(p, PeriodicCell::orthorhombic(Eigen::Vector3d::Constant(L)), o);
  EXPECT_NEAR(s.dt() * omega, h, 1e-12 * h);
  const double k0 = s.kinetic_energy();
  const Eigen::Vector3d still = Eigen::Vector3d::Zero();
  double worst = 1.0;
  for (int n = 0; n < steps && worst < 1e6; ++n) {
    s.step(still);
    worst = std::max(worst, s.kinetic_energy() / k0);
  }
  return worst;
}

TEST(Contact, StabilityLimitIsReallyWhereVerletFails) {
  // The engine's integrator fails exactly where velocity Verlet does, at omega dt = 2: 1 %
  // below, 20,000 steps leave the energy of the highest mode bounded; 1 % above,
  // it grows past a million times its start within 200 steps (|lambda| = 1.22 per step). The
  // bounded side allows 1 % for rounding, which a near-resonant step amplifies.
  EXPECT_LT(ring_energy_growth(0.99 * 2.0, 20000), 1.01);
  EXPECT_GT(ring_energy_growth(1.01 * 2.0, 200), 1e6);
  // The engine's bound (Gershgorin, at most 12 contacts on a smallest sphere) keeps omega dt
  // below 2 for the stiffest real arrangements of the material's smallest spheres: the pair
  // (omega^2 = 2k/m) and the same ring of smallest spheres (omega^2 = 4k/m).
  Material mat;
  mat.gamma = 0;
  mat.gamma_b = 0;
  const double m_min = mat.sphere_mass(mat.r_min());
  EXPECT_LT(stability_limit(mat), 2.0 / std::sqrt(2.0 * mat.k / m_min));
  EXPECT_LT(stability_limit(mat), 2.0 / std::sqrt(4.0 * mat.k / m_min));
}

}  // namespace
}  // namespace rendulic::dem
