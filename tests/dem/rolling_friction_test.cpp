// Rolling resistance (contact.hpp Material::rolling_contact, docs/physics.md section 1b) in the
// engine against closed forms on two spheres: a pair rolling on each other at a fixed relative
// angular velocity (no sliding) builds the torque k_r a'^2 theta against it until mu_r f_n a',
// then slips, dissipating mu_r f_n times the rolling slip, and the work of the torques equals
// the rolling spring's energy plus that dissipation; a pair turning rigidly keeps its rolling
// spring in the tangent plane with its length; a frictional packing with rolling restarts from
// a saved state bit-identically; and the keys refuse rolling without friction.
#include <gtest/gtest.h>

#include <cmath>

#include "dem_helpers.hpp"
#include "input_error.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/dem/linear_response.hpp"
#include "rendulic/dem/scenario_keys.hpp"

namespace rendulic::dem {
namespace {

using rendulic::testing::input_error;

using Vec = Eigen::Vector3d;

// Spheres of radii r_min (i = 0) and r_max (i = 1) overlapping by delta along x, at rest, with
// angular velocities w0 and w1, their masses (and so inertias) made so large that the contact
// changes neither the positions nor the angular velocities: the imposed motion is exact.
DemSystem fixed_pair(const Material& mat, double delta, const Vec& w0, const Vec& w1) {
  Particles p;
  p.resize(2);
  const double L = 40 * mat.r_mean;
  p.radius = {mat.r_min(), mat.r_max()};
  const double d = p.radius[0] + p.radius[1] - delta;
  p.x = {0.5 * L - 0.5 * d, 0.5 * L + 0.5 * d};
  p.y = {0.5 * L, 0.5 * L};
  p.z = {0.5 * L, 0.5 * L};
  for (std::size_t i = 0; i < 2; ++i) p.inv_mass[i] = 1e-30 / mat.sphere_mass(p.radius[i]);
  p.wx = {w0[0], w1[0]}, p.wy = {w0[1], w1[1]}, p.wz = {w0[2], w1[2]};
  SystemOptions o;
  o.material = mat;
  return DemSystem(p, PeriodicCell::orthorhombic(Vec::Constant(L)), o);
}

Material rolling_material() {
  Material mat;
  mat.gamma = mat.gamma_b = 0.0;  // no dashpots: f_n = k delta, and only slip dissipates
  mat.gamma_t_ratio = mat.gamma_r_ratio = 0.0;
  mat.mu = 0.5;
  mat.mu_r = 0.1;
  return mat;
}

Vec torque(const DemSystem& s, std::size_t i) {
  const Particles& p = s.particles();
  return {p.tx[i], p.ty[i], p.tz[i]};
}

TEST(RollingFriction, TorqueGrowsAsKrA2ThetaThenSaturatesAtMuRFnA) {
  const Material mat = rolling_material();
  const double delta = 1e-2 * mat.r_min();
  const double a0 = mat.r_min() - 0.5 * delta, a1 = mat.r_max() - 0.5 * delta;
  const double ar = a0 * a1 / (a0 + a1);  // a'
  const double f_n = mat.k * delta,
               k_r = mat.rolling_contact().k_t;  // the law's spring constant: k_r
  // Rolling without sliding: a_0 w_0 + a_1 w_1 = 0 (the contact points move together), so the
  // tangential spring stays at rest and the relative rotation w_0 - w_1 is all rolling. About
  // z, in the tangent plane of the branch (x). Slip after ~200 steps.
  const double theta_slip = mat.mu_r * f_n / (k_r * ar);
  DemSystem probe = fixed_pair(mat, delta, Vec::Zero(), Vec::Zero());
  const double dt = probe.dt();
  const double w_rel = theta_slip / (200.5 * dt);
  const double w0 = w_rel / (1.0 + a0 / a1);
  const Vec W0(0, 0, w0), W1(0, 0, -a0 / a1 * w0);
  DemSystem s = fixed_pair(mat, delta, W0, W1);
  const Vec dw = W0 - W1;
  const double e_normal = 0.5 * mat.k * delta * delta;
  double work = 0;
  Vec q_prev0 = torque(s, 0), q_prev1 = torque(s, 1);
  const int steps = 600;
  for (int n = 1; n <= steps; ++n) {
    s.step(Vec::Zero());
    const Vec q0 = torque(s, 0), q1 = torque(s, 1);
    // The torques' work on the spheres, taken from them by the contact (trapezoid rule).
    work -= 0.5 * ((q_prev0 + q0).dot(W0) + (q_prev1 + q1).dot(W1)) * dt;
    q_prev0 = q0, q_prev1 = q1;
    const double theta = w_rel * n * dt;
    ASSERT_NEAR((q0 + q1).norm(), 0.0, 1e-12 * q0.norm()) << "step " << n;  // no net torque
    if (theta < theta_slip) {
      // Stick: q_0 = -k_r a'^2 theta along w_0 - w_1.
      const Vec expected = -k_r * ar * ar * n * dt * dw;
      ASSERT_LT((q0 - expected).norm(), 1e-9 * expected.norm()) << "step " << n;
      ASSERT_EQ(s.sliding_dissipation(), 0.0) << "step " << n;
    } else {
      // Slip: |q| held at mu_r f_n a', against the relative rotation.
      const Vec expected = -mat.mu_r * f_n * ar * dw.normalized();
      ASSERT_LT((q0 - expected).norm(), 1e-9 * expected.norm()) << "step " << n;
    }
  }
  // Rolling slip: the rolling displacement a' theta less the spring's share at the limit,
  // times the limit force. The step where stick turns to slip counts the mean of the spring's
  // force at its two ends, below the limit's (contact.hpp): 1.6e-6 of the whole here.
  const double xi_limit = mat.mu_r * f_n / k_r;
  const double slip = ar * w_rel * steps * dt - xi_limit;
  EXPECT_NEAR(s.sliding_dissipation(), mat.mu_r * f_n * slip, 1e-5 * mat.mu_r * f_n * slip);
  // The rolling spring's energy is in elastic_energy() (the tangential one stays at round-off).
  const double e_rolling = 0.5 * k_r * xi_limit * xi_limit;
  EXPECT_NEAR(s.elastic_energy() - e_normal, e_rolling, 1e-6 * e_rolling);
  // Work done on the contact = stored + dissipated, to round-off (3e-13 measured): the slip's
  // work takes the spring's force averaged over each step, as the trapezoid of the torques does.
  // (With the end's force alone it missed the step where stick turns to slip: 1.2e-6 of it.)
  EXPECT_NEAR(work, e_rolling + s.sliding_dissipation(), 1e-10 * work);
}

TEST(RollingFriction, RigidlyTurningPairKeepsItsRollingSpringInTheTangentPlane) {
  // Both spheres turn about z at Omega and move as one body: w_0 = w_1 gives no rolling
  // velocity, so the preloaded rolling spring only turns with the contact (as the tangential
  // one, friction_test.cpp): it stays normal to the branch and keeps its length.
  Material mat = rolling_material();
  mat.mu_r = 0.5;  // a limit far above the preload: no slip
  const double R = mat.r_min() + mat.r_max(), delta = 1e-2 * mat.r_min();
  const double omega = 2e3, d = R - delta;
  DemSystem s0 = fixed_pair(mat, delta, Vec(0, 0, omega), Vec(0, 0, omega));
  State st = s0.save();
  st.particles.vy = {-0.5 * d * omega, 0.5 * d * omega};
  ASSERT_EQ(st.rolling_history.size(), 3u);  // one list entry
  const Vec xr0(0, 2e-7, 1e-7);              // tangential (the branch is along x)
  st.rolling_history = {xr0[0], xr0[1], xr0[2]};
  DemSystem s = DemSystem::restore(st, s0.options());
  auto spring = [&] {
    const State now = s.save();
    return Vec(now.rolling_history[0], now.rolling_history[1], now.rolling_history[2]);
  };
  auto branch = [&] {  // x_0 - x_1 (no periodic image: both in the cell's middle)
    const Particles& p = s.particles();
    return Vec(p.position(0) - p.position(1));
  };
  const Vec l_start = branch();
  const double theta = 0.005;
  const int steps = static_cast<int>(theta / omega / s.dt());
  double worst_normal = 0, worst_length = 0;
  for (int k = 0; k < steps; ++k) {
    s.step(Vec::Zero());
    ASSERT_EQ(s.measure().contacts, 1);
    worst_normal = std::max(worst_normal, std::abs(spring().dot(branch().normalized())));
    worst_length = std::max(worst_length, std::abs(spring().norm() - xr0.norm()));
  }
  // Without the turning, xr . n would grow to theta |xr| = 5e-3 |xr|; w_0 = w_1 exactly, so
  // the length changes only by the turning's round-off.
  EXPECT_LT(worst_normal, 1e-12 * xr0.norm());
  EXPECT_LT(worst_length, 1e-12 * xr0.norm());
  const Vec l_end = branch();
  const double turned = std::atan2(l_start.cross(l_end)[2], l_start.dot(l_end));
  EXPECT_GT(turned, 0.9 * theta);
  const Vec expected = Eigen::AngleAxisd(turned, Vec::UnitZ()) * xr0;
  EXPECT_LT((spring() - expected).norm(), 1e-3 * xr0.norm());
}

std::vector<double> flat(const Particles& p) {
  std::vector<double> v;
  for (const auto* a : {&p.x, &p.y, &p.z, &p.vx, &p.vy, &p.vz, &p.fx, &p.fy, &p.fz, &p.wx, &p.wy,
                        &p.wz, &p.tx, &p.ty, &p.tz})
    v.insert(v.end(), a->begin(), a->end());
  return v;
}

// A dense, hot frictional gas of 1000 particles with rolling, to be compressed: contacts
// form, stick, slide and roll, and the list is rebuilt along the way.
DemSystem rolling_gas() {
  SystemOptions o;
  o.material.mu = 0.5;
  o.material.mu_r = 0.1;
  GasOptions g;
  g.n_particles = 1000;
  g.volume_fraction = 0.4;
  g.velocity = 50.0;  // fast: many collisions, and rebuilds
  return make_gas(o, g, 7);
}

TEST(RollingFriction, RestoredRunContinuesBitIdentically) {
  // The list is rebuilt after the save, so the rolling springs go through save, restore and
  // the carrying of history across rebuilds.
  const Vec D = Vec::Constant(-3000.0);
  DemSystem a = rolling_gas();
  a.advance(300, D);
  const State half = a.save();
  double rolling2 = 0;
  for (const double x : half.rolling_history) rolling2 += x * x;
  ASSERT_GT(rolling2, 0.0);  // rolling springs are loaded at the save
  const std::int64_t builds = a.list_builds();
  a.advance(300, D);
  ASSERT_GT(a.list_builds(), builds);
  DemSystem b = DemSystem::restore(half, a.options());
  b.advance(300, D);
  EXPECT_EQ(flat(a.particles()), flat(b.particles()));
  EXPECT_EQ(a.save().rolling_history, b.save().rolling_history);
  EXPECT_EQ(a.sliding_dissipation(), b.sliding_dissipation());
  EXPECT_GT(a.sliding_dissipation(), 0.0);
}

// The contact list (contacts(), which the force balance of a state at rest reads) states the
// rolling torque as the engine's four-lane loop does: at zero velocities the torques it sums
// per particle, levers and rolling couples, are the engine's torque accumulators.
TEST(RollingFriction, ContactsCarryTheEnginesRollingTorques) {
  DemSystem s = rolling_gas();
  s.advance(600, Vec::Constant(-3000.0));
  s.zero_velocities();  // forces and torques again, at rest: no dashpot, springs as they are
  const Particles& p = s.particles();
  std::vector<Vec> t(p.size(), Vec::Zero());
  double rolling = 0;
  for (const Contact& c : s.contacts()) {
    const Vec m = -(c.branch / c.branch.norm()).cross(c.tangential);
    t[c.i] += (p.radius[c.i] - 0.5 * c.overlap) * m + c.rolling_torque;
    t[c.j] += (p.radius[c.j] - 0.5 * c.overlap) * m - c.rolling_torque;
    rolling = std::max(rolling, c.rolling_torque.norm());
  }
  ASSERT_GT(rolling, 0.0);
  double largest = 0, worst = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    largest = std::max(largest, t[i].norm());
    worst = std::max(worst, (t[i] - Vec(p.tx[i], p.ty[i], p.tz[i])).norm());
  }
  EXPECT_LT(worst, 1e-9 * largest) << worst << " of " << largest;
  // Without the rolling couples the sums would miss them by about their size.
  EXPECT_GT(rolling, 1e-3 * largest);
}

TEST(RollingFriction, KeysRefuseRollingWithoutFrictionAndBadValues) {
  Material mat;
  mat.mu_r = 0.1;  // mu = 0
  std::string why;
  EXPECT_FALSE(mat.IsValid(&why));
  EXPECT_NE(why.find("dem.rolling_friction"), std::string::npos) << why;
  EXPECT_NE(why.find("dem.friction"), std::string::npos) << why;
  mat.mu = 0.5;
  EXPECT_TRUE(mat.IsValid(&why)) << why;
  mat.k_r_ratio = 0.0;
  EXPECT_FALSE(mat.IsValid(&why));
  EXPECT_NE(why.find("dem.k_r_ratio"), std::string::npos) << why;
  mat.k_r_ratio = 0.2;
  mat.gamma_r_ratio = -1.0;
  EXPECT_FALSE(mat.IsValid(&why));
  EXPECT_NE(why.find("dem.gamma_r_ratio"), std::string::npos) << why;
  // Through the scenario: one line naming both keys.
  ScenarioSchema schema;
  register_dem_keys(schema);
  const Scenario sc = Scenario::from_string("[dem]\nrolling_friction = 0.1\n", "roll.toml", schema);
  // Rolling without friction.
  const std::string what = input_error([&] { (void)dem_options_from_scenario(sc); });
  EXPECT_NE(what.find("dem.rolling_friction"), std::string::npos) << what;
  EXPECT_NE(what.find("dem.friction"), std::string::npos) << what;
  EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  // The defaults leave rolling off, and the stability bound is the frictional one.
  const Scenario plain = Scenario::from_string("[dem]\nfriction = 0.5\n", "f.toml", schema);
  const Material m = dem_options_from_scenario(plain).system.material;
  EXPECT_FALSE(m.rolling());
  Material frictional;
  frictional.mu = 0.5;
  Material rolling = frictional;
  rolling.k_r_ratio = 1.0;
  EXPECT_EQ(stability_limit(rolling), stability_limit(frictional));
  rolling.mu_r = 0.1;
  EXPECT_LT(stability_limit(rolling), stability_limit(frictional));
  // The linear response takes rolling springs with their stiffness, and refuses mu_r > 0
  // without one.
  LinearFriction lf;
  lf.k_t = 1e7;
  lf.mu = 0.5;
  EXPECT_TRUE(lf.IsValid(&why)) << why;
  lf.mu_r = 0.1;
  EXPECT_FALSE(lf.IsValid(&why));
  EXPECT_NE(why.find("k_r"), std::string::npos) << why;
  lf.k_r = 1e6;
  EXPECT_TRUE(lf.IsValid(&why)) << why;
}

}  // namespace
}  // namespace rendulic::dem
