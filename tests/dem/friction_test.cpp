// Tangential contact with Coulomb friction (contact.hpp TangentialContact, docs/physics.md
// section 1b) against closed forms: loading at a fixed normal force follows f = k_t u up to
// mu f_n and stays there (the stick-slip transition at the step the closed form names); the
// work done on a contact equals the spring's energy plus the dashpot's and the slip's
// dissipation; the spring turned with a rotating contact stays in the tangent plane with its
// length; and, in the engine, a frictional collision of two spinning spheres conserves linear
// and angular momentum to round-off and energy (with the slip's dissipation) to O(dt^2), and a
// pair turning rigidly keeps its spring in the tangent plane without a spurious force.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "dem_helpers.hpp"
#include "rendulic/core/errors.hpp"

namespace rendulic::dem {
namespace {

using Vec = Eigen::Vector3d;

TEST(Friction, TangentialLoadingSticksUpToMuFnThenSlides) {
  const TangentialContact c{2e7, 0.0, 0.5};
  const double f_n = 10.0, v = 1e-3, dt = 1e-6;
  // Stick while k_t v t <= mu f_n: the closed form's last sticking step.
  const double slip_distance = c.mu * f_n / c.k_t;                                // 2.5e-7 m
  const int last_stick = static_cast<int>(std::floor(slip_distance / (v * dt)));  // 250
  Vec xi = Vec::Zero();
  const Vec vel(v, 0, 0);
  double dissipated = 0;
  for (int n = 1; n <= 2 * last_stick; ++n) {
    Vec f;
    c.force(xi, vel, vel, dt, f_n, &dissipated, f);
    if (n <= last_stick) {
      ASSERT_NEAR(f[0], -c.k_t * v * dt * n, 1e-12 * c.mu * f_n) << "step " << n;
      ASSERT_EQ(dissipated, 0.0) << "step " << n;
    } else {
      ASSERT_NEAR(f[0], -c.mu * f_n, 1e-12 * c.mu * f_n) << "step " << n;
      ASSERT_NEAR(xi[0], slip_distance, 1e-12 * slip_distance);
    }
    EXPECT_EQ(f[1], 0.0);
    EXPECT_EQ(f[2], 0.0);
  }
  // Sliding at the limit force dissipates mu f_n times the slip: the whole displacement
  // less the spring's share at the limit.
  const double slip = 2 * last_stick * v * dt - slip_distance;
  EXPECT_NEAR(dissipated, c.mu * f_n * slip, 1e-9 * dissipated);
  // The limit follows |f_n|, and mu = 0 gives no tangential force at all.
  Vec x0 = Vec::Zero(), f0;
  c.force(x0, Vec(1, 0, 0), Vec(1, 0, 0), 1.0, -f_n, &dissipated, f0);
  EXPECT_NEAR(f0.norm(), c.mu * f_n, 1e-12);
  const TangentialContact frictionless{2e7, 0.1, 0.0};
  Vec x1 = Vec::Zero(), f1;
  frictionless.force(x1, vel, vel, dt, f_n, &dissipated, f1);
  EXPECT_EQ(f1.norm(), 0.0);
}

TEST(Friction, WorkOnASlidingContactIsStoredOrDissipated) {
  // A contact driven along a turning path (the velocity turns by 3 rad), with a dashpot, under a
  // normal force that varies: it sticks, slides, sticks again when the load grows. The work
  // done on it (trapezoid rule on the force, exact for a linear spring) equals the spring's
  // energy, the dashpot's dissipation gamma_t |v|^2 dt and the slip's dissipation, to the
  // O(dt^2) of the steps where stick and slip alternate.
  const TangentialContact c{2e7, 0.05, 0.4};
  const double dt = 1e-7, v = 2e-3;
  const int steps = 20000;
  Vec xi = Vec::Zero(), f_prev = Vec::Zero();
  double work = 0, dashpot = 0, slip = 0;
  for (int n = 0; n < steps; ++n) {
    const double t = (n + 0.5) * dt, s = static_cast<double>(n) / steps;
    const Vec vel = v * Vec(std::cos(3.0 * s), std::sin(3.0 * s), 0.0);
    const double f_n = 2.0 + 1.5 * std::sin(2 * std::numbers::pi * 2 * s);
    Vec f;
    c.force(xi, vel, vel, dt, f_n, &slip, f);
    work += -0.5 * (f_prev + f).dot(vel) * dt;
    dashpot += c.gamma_t * vel.squaredNorm() * dt;
    f_prev = f;
    (void)t;
  }
  const double stored = c.energy(xi.squaredNorm());
  EXPECT_GT(slip, 0.5 * work);  // it mostly slid
  EXPECT_GT(stored, 0.0);
  // The trapezoid starts from f = 0 before the first step: half a step of dashpot work
  // (gamma_t v^2 dt / 2) is missing from `work`, which the tolerance covers with the
  // transitions' O(dt^2) terms; measured 2e-6 relative.
  EXPECT_NEAR(work, stored + dashpot + slip, 2e-5 * work);
}

TEST(Friction, TurningKeepsTheSpringInThePlaneWithItsLength) {
  // The normal turns about z by 1 rad in 1000 steps: xi, turned each step, ends rotated with
  // it to O(step^2) per step (the projection is first order in the angle, the rescaling makes
  // it a rotation to second order), its length exact.
  Vec n(1, 0, 0), xi(0, 3e-7, 1e-7);
  const double len = xi.norm();
  const int steps = 1000;
  const double dphi = 1.0 / steps;
  for (int k = 1; k <= steps; ++k) {
    n = Vec(std::cos(k * dphi), std::sin(k * dphi), 0);
    TangentialContact::turn(xi, n);
    ASSERT_NEAR(xi.dot(n), 0.0, 1e-15 * len);
    ASSERT_NEAR(xi.norm(), len, 1e-13 * len);  // round-off, growing with the steps
  }
  const Vec rotated = Eigen::AngleAxisd(1.0, Vec::UnitZ()) * Vec(0, 3e-7, 1e-7);
  EXPECT_LT((xi - rotated).norm(), 1e-3 * len);
}

// Two spheres of the seed material (radii r_min and r_max) in a big cell, without background
// damping.
DemSystem pair_of(const Material& mat, const Vec& x0, const Vec& x1, const Vec& v0, const Vec& v1,
                  const Vec& w0, const Vec& w1) {
  Particles p;
  p.resize(2);
  const double L = 40 * mat.r_mean;
  p.radius = {mat.r_min(), mat.r_max()};
  for (int i = 0; i < 2; ++i) {
    const Vec& x = i == 0 ? x0 : x1;
    const Vec& v = i == 0 ? v0 : v1;
    const Vec& w = i == 0 ? w0 : w1;
    const auto u = static_cast<std::size_t>(i);
    p.inv_mass[u] = 1.0 / mat.sphere_mass(p.radius[u]);
    p.x[u] = 0.5 * L + x[0], p.y[u] = 0.5 * L + x[1], p.z[u] = 0.5 * L + x[2];
    p.vx[u] = v[0], p.vy[u] = v[1], p.vz[u] = v[2];
    p.wx[u] = w[0], p.wy[u] = w[1], p.wz[u] = w[2];
  }
  SystemOptions o;
  o.material = mat;
  return DemSystem(p, PeriodicCell::orthorhombic(Vec::Constant(L)), o);
}

Vec momentum(const DemSystem& s) {
  const Particles& p = s.particles();
  Vec m = Vec::Zero();
  for (std::size_t i = 0; i < 2; ++i) m += p.mass(i) * p.velocity(i);
  return m;
}

// About the cell's origin: sum m x x v + I w (I = 2/5 m r^2).
Vec angular_momentum(const DemSystem& s) {
  const Particles& p = s.particles();
  Vec m = Vec::Zero();
  for (std::size_t i = 0; i < 2; ++i)
    m += p.mass(i) * p.position(i).cross(p.velocity(i)) +
         0.4 * p.mass(i) * p.radius[i] * p.radius[i] * Vec(p.wx[i], p.wy[i], p.wz[i]);
  return m;
}

double total_energy(const DemSystem& s) {
  const Measures m = s.measure();
  return m.kinetic_energy + m.rotational_energy + m.elastic_energy + m.sliding_dissipation;
}

TEST(Friction, ObliqueCollisionOfSpinningSpheresConservesMomentaAndEnergy) {
  Material mat;
  mat.gamma = mat.gamma_b = 0.0;  // no dashpots: only the slip dissipates
  mat.gamma_t_ratio = 0.0;
  mat.mu = 0.2;
  // Unequal spheres meeting off-centre, spinning about axes across the contact: the contact
  // sticks, then slides, and turns.
  const double gap = 1e-6, R = mat.r_min() + mat.r_max();
  const double dx = std::sqrt((R + gap) * (R + gap) - 0.2e-3 * 0.2e-3 - 0.05e-3 * 0.05e-3);
  DemSystem s =
      pair_of(mat, Vec(-0.5 * dx, 0.2e-3, 0), Vec(0.5 * dx, 0, 0.05e-3), Vec(0.3, 0.05, 0),
              Vec(-0.3, 0, 0.02), Vec(0, 0, 3000), Vec(1000, 0, -2000));
  const Vec p0 = momentum(s), l0 = angular_momentum(s);
  const double e0 = total_energy(s);
  bool touched = false, slid = false;
  double max_rotational = 0;
  for (int k = 0; k < 4000; ++k) {
    s.step(Vec::Zero());
    const Measures m = s.measure();
    touched = touched || m.contacts > 0;
    slid = slid || m.sliding_dissipation > 0;
    max_rotational = std::max(max_rotational, m.rotational_energy);
  }
  ASSERT_TRUE(touched);
  ASSERT_TRUE(slid);
  EXPECT_EQ(s.measure().contacts, 0);  // they parted again
  // Momenta: the half list adds each pair force to both ends, and the torques use levers a_i +
  // a_j = |l|, so l x f + tau_i + tau_j = 0 each step: round-off.
  EXPECT_LT((momentum(s) - p0).norm(), 1e-12 * p0.norm() + 1e-18);
  EXPECT_LT((angular_momentum(s) - l0).norm(), 1e-10 * l0.norm());
  // Energy, with the slip's dissipation: second order in dt (dt = t_c / 50), measured
  // 4e-5 of the initial energy.
  const double e1 = total_energy(s);

  EXPECT_NEAR(e1, e0, 2e-4 * e0);
  EXPECT_GT(s.sliding_dissipation(), 1e-3 * e0);
  EXPECT_GT(max_rotational, 0.0);
}

TEST(Friction, RigidlyTurningPairKeepsItsSpringInTheTangentPlane) {
  // Two spheres in contact with a preloaded spring, turning about z at Omega as one body: the
  // contact-point velocity vanishes to first order, so xi only turns with the contact. Masses
  // are made huge so that the contact forces do not change the imposed motion.
  Material mat;
  mat.gamma = mat.gamma_b = 0.0;
  mat.mu = 0.5;
  const double R = mat.r_min() + mat.r_max(), delta = 1e-2 * mat.r_min();
  const double omega = 2e3, d = R - delta;  // rad/s, m
  DemSystem s0 = pair_of(mat, Vec(-0.5 * d, 0, 0), Vec(0.5 * d, 0, 0), Vec(0, -0.5 * d * omega, 0),
                         Vec(0, 0.5 * d * omega, 0), Vec(0, 0, omega), Vec(0, 0, omega));
  State st = s0.save();
  for (double& im : st.particles.inv_mass) im *= 1e-30;
  ASSERT_EQ(st.tangential_history.size(), 3u);  // one list entry, no history yet
  const Vec xi0(0, 2e-7, 1e-7);                 // tangential (the branch is along x)
  st.tangential_history = {xi0[0], xi0[1], xi0[2]};
  DemSystem s = DemSystem::restore(st, s0.options());
  const Vec start = s.contacts().at(0).spring, l_start = s.contacts().at(0).branch;
  ASSERT_NEAR(start.norm(), xi0.norm(), 1e-15);
  // theta = 0.005 rad. The imposed velocities move the spheres on straight lines, which leaves
  // a contact-point velocity Omega^2 l0 t, normal to first order: its tangential part moves
  // the spring by about d theta^3 / 3 = 8e-11 m (4e-4 |xi|) over the test.
  const double theta = 0.005;
  const int steps = static_cast<int>(theta / omega / s.dt());
  double worst_normal = 0, worst_length = 0;
  for (int k = 0; k < steps; ++k) {
    s.step(Vec::Zero());
    const std::vector<Contact> cs = s.contacts();
    ASSERT_EQ(cs.size(), 1u);
    const Vec n = cs[0].branch.normalized();
    worst_normal = std::max(worst_normal, std::abs(cs[0].spring.dot(n)));
    worst_length = std::max(worst_length, std::abs(cs[0].spring.norm() - xi0.norm()));
  }
  // Without the turning, xi . n would grow to theta |xi| = 5e-3 |xi|.
  EXPECT_LT(worst_normal, 1e-12 * xi0.norm());
  EXPECT_LT(worst_length, 1e-3 * xi0.norm());
  // The spring turned with the branch (about z, by the branch's angle).
  const Vec l_end = s.contacts().at(0).branch;
  const double turned = std::atan2(l_start.cross(l_end)[2], l_start.dot(l_end));
  EXPECT_GT(turned, 0.9 * theta);
  const Vec expected = Eigen::AngleAxisd(turned, Vec::UnitZ()) * start;
  EXPECT_LT((s.contacts().at(0).spring - expected).norm(), 1e-3 * xi0.norm());
}

TEST(Friction, KeysRefuseBadValuesAndTheStaticToolsRefuseFriction) {
  Material mat;
  mat.mu = -0.1;
  std::string why;
  EXPECT_FALSE(mat.IsValid(&why));
  EXPECT_NE(why.find("dem.friction"), std::string::npos) << why;
  mat.mu = 0.5;
  mat.k_t_ratio = 0.0;
  EXPECT_FALSE(mat.IsValid(&why));
  EXPECT_NE(why.find("dem.k_t_ratio"), std::string::npos) << why;
  // Below kMinSpringRatio a slip's reset spring mu |f_n| / k_t could overflow when squared.
  mat.k_t_ratio = 0.5 * kMinSpringRatio;
  EXPECT_FALSE(mat.IsValid(&why));
  EXPECT_NE(why.find("dem.k_t_ratio must be >= 1e-6"), std::string::npos) << why;
  mat.k_t_ratio = kMinSpringRatio;
  mat.mu_r = 0.1;
  mat.k_r_ratio = 0.5 * kMinSpringRatio;
  EXPECT_FALSE(mat.IsValid(&why));
  EXPECT_NE(why.find("dem.k_r_ratio must be >= 1e-6"), std::string::npos) << why;
  mat.k_r_ratio = kMinSpringRatio;
  EXPECT_TRUE(mat.IsValid(&why)) << why;
  // The stability bound takes the tangential springs' faster rotation into account.
  Material stiff;
  stiff.mu = 0.5;
  stiff.k_t_ratio = 1.0;
  Material frictionless;
  EXPECT_LT(stability_limit(stiff), stability_limit(frictionless));
  stiff.mu = 0.0;
  EXPECT_EQ(stability_limit(stiff), stability_limit(frictionless));
}

}  // namespace
}  // namespace rendulic::dem
