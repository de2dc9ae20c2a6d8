// Engine invariants with closed forms (docs/physics.md sections 1-3): stress, fabric
// and coordination of a lattice with known forces; affine deformation of a non-touching
// lattice creates no forces; volume conserved on a constant-volume path; momentum
// conservation; rattler removal; bit-identical restart (refused with another skin);
// thread-count independence; a step straining the cell too far refused.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include "comma_locale.hpp"
#include "dem_helpers.hpp"
#include "input_error.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/core/errors.hpp"

namespace rendulic::dem {
namespace {

using rendulic::testing::input_error;

// Unit tests run on one thread: the build machine is shared, and a spinning second thread
// only adds noise. Thread independence has its own test below.
const bool kOneThread = (omp_set_num_threads(1), true);

// Simple cubic lattice of n^3 equal spheres of radius r and spacing a, at rest.
DemSystem lattice(int n, double r, double a, const Material& mat) {
  Particles p;
  p.resize(static_cast<std::size_t>(n) * n * n);
  std::size_t i = 0;
  for (int kz = 0; kz < n; ++kz)
    for (int ky = 0; ky < n; ++ky)
      for (int kx = 0; kx < n; ++kx, ++i) {
        p.x[i] = (kx + 0.5) * a;
        p.y[i] = (ky + 0.5) * a;
        p.z[i] = (kz + 0.5) * a;
        p.radius[i] = r;
        p.inv_mass[i] = 1.0 / mat.sphere_mass(r);
      }
  SystemOptions o;
  o.material = mat;
  return DemSystem(p, PeriodicCell::orthorhombic(Eigen::Vector3d::Constant(n * a)), o);
}

TEST(Engine, StressFabricCoordinationOfLatticeWithKnownForces) {
  Material mat;
  const double r = 1e-3, delta = 2e-6, a = 2 * r - delta;
  const int n = 5;
  DemSystem s = lattice(n, r, a, mat);
  const Measures m = s.measure();
  // Every particle has 6 contacts of force k delta and branch length a: sigma_aa = k delta / a^2.
  const double expect = mat.k * delta / (a * a);
  constexpr double kRel = 1e-12;  // round-off of a few hundred summed terms
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(m.stress(d, d), expect, kRel * expect);
  EXPECT_NEAR((m.stress - m.stress.diagonal().asDiagonal().toDenseMatrix()).norm(), 0,
              kRel * expect);
  EXPECT_NEAR(m.pressure_star, expect / mat.k_star(), kRel * expect / mat.k_star());
  // Fabric: 2 contacts per axis per particle, weighted by V_p / V: F_aa = 2 nu.
  const double nu = s.volume_fraction();
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(m.fabric(d, d), 2 * nu, 1e-12);
  EXPECT_EQ(m.contacts, 3 * n * n * n);
  EXPECT_DOUBLE_EQ(m.coordination, 6.0);
  EXPECT_DOUBLE_EQ(m.coordination_nonrattler, 6.0);
  EXPECT_DOUBLE_EQ(m.rattler_fraction, 0.0);
  EXPECT_NEAR(m.elastic_energy, 3 * n * n * n * 0.5 * mat.k * delta * delta,
              1e-12 * m.elastic_energy);
  EXPECT_DOUBLE_EQ(m.kinetic_energy, 0.0);
  // The fast per-step stress (servo) agrees with eq. 1.
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(s.last_stress_diag()[d], expect, kRel * expect);
  // Forces balance on a perfect lattice.
  for (std::size_t i = 0; i < s.particles().size(); ++i)
    EXPECT_NEAR(std::abs(s.particles().fx[i]), 0, 1e-9 * mat.k * delta);
}

TEST(Engine, AffineDeformationOfNonTouchingLatticeCreatesNoForces) {
  Material mat;
  const double r = 1e-3, a = 2.6e-3;
  DemSystem s = lattice(5, r, a, mat);
  const Particles p0 = s.particles();
  // Compress x by 10 %, extend y and z: gaps stay open (a * 0.9 > 2r).
  const Eigen::Vector3d D(-2000.0, 1500.0, 500.0);
  const std::int64_t n = static_cast<std::int64_t>(std::log(0.9) / (-2000.0 * s.dt()));
  s.advance(n, D);
  const Eigen::Vector3d S = s.cell().lengths() / (5 * a);
  const auto& p = s.particles();
  for (std::size_t i = 0; i < p.size(); ++i) {
    EXPECT_EQ(p.fx[i], 0.0);
    EXPECT_EQ(p.fy[i], 0.0);
    EXPECT_EQ(p.fz[i], 0.0);
    EXPECT_EQ(p.vx[i], 0.0);
    // Positions follow the cell exactly (round-off of n products only).
    EXPECT_NEAR(p.x[i], S[0] * p0.x[i], 1e-12 * a);
    EXPECT_NEAR(p.y[i], S[1] * p0.y[i], 1e-12 * a);
    EXPECT_NEAR(p.z[i], S[2] * p0.z[i], 1e-12 * a);
  }
  EXPECT_EQ(s.measure().contacts, 0);
  // A product of n ~ 1e4 factors exp(D dt) against one exp: n round-offs of 1e-16.
  EXPECT_NEAR(S[0], std::exp(-2000.0 * n * s.dt()), 1e-11);
}

TEST(Engine, VolumeConservedOnConstantVolumePath) {
  SystemOptions o;
  GasOptions g;
  g.n_particles = 300;
  g.volume_fraction = 0.3;
  DemSystem s = make_gas(o, g, 7);
  const double V0 = s.volume();
  for (int k = 0; k < 5000; ++k) s.step(Eigen::Vector3d(2000.0, -1000.0, -1000.0));
  // exp(D dt) per axis: the trace-free rate leaves only round-off (~1e-16 per step).
  EXPECT_NEAR(s.volume() / V0 - 1.0, 0.0, 1e-9);
  EXPECT_NEAR(s.strain_E().sum(), 0.0, 1e-12);
  const Measures m = s.measure();
  EXPECT_NEAR(m.eps_v, 0.0, 1e-12);
  // -eps_dev = sqrt(3/2) E_xx on this path; E_xx = rate * t.
  EXPECT_NEAR(-m.eps_dev, std::sqrt(1.5) * 2000.0 * s.time(), 1e-12);
}

TEST(Engine, MomentumConservedWithContactDamping) {
  SystemOptions o;
  o.material.gamma_b = 0;  // background damping is an external force by design
  GasOptions g;
  g.n_particles = 400;
  g.volume_fraction = 0.35;
  g.velocity = 20;
  DemSystem s = make_gas(o, g, 11);
  auto momentum = [&] {
    Eigen::Vector3d P = Eigen::Vector3d::Zero();
    double scale = 0;
    const auto& p = s.particles();
    for (std::size_t i = 0; i < p.size(); ++i) {
      P += p.mass(i) * p.velocity(i);
      scale += p.mass(i) * p.velocity(i).norm();
    }
    return std::pair{P, scale};
  };
  const auto [P0, scale] = momentum();
  s.advance(3000, Eigen::Vector3d::Zero());
  EXPECT_GT(s.measure().contacts, -1);
  const auto [P1, scale1] = momentum();
  // Pair forces are applied as exact opposites; only the order of the per-particle sums
  // rounds: 1e-13 of the momentum scale.
  EXPECT_LT((P1 - P0).norm(), 1e-13 * scale);
  EXPECT_LT(scale1, scale);  // collisions dissipated energy, so something happened
}

TEST(Engine, RattlersRemovedIteratively) {
  // A chain: particle 0 has 4 contacts (1..4), which have 1 contact each: all rattlers once
  // they are gone, 0 loses its contacts too. A K5 clique (5..9) keeps 4 contacts each.
  std::vector<Contact> cs;
  auto add = [&](int i, int j) {
    Contact c;
    c.i = i;
    c.j = j;
    cs.push_back(c);
  };
  for (int j = 1; j <= 4; ++j) add(0, j);
  for (int i = 5; i <= 9; ++i)
    for (int j = i + 1; j <= 9; ++j) add(i, j);
  const std::vector<bool> keep = non_rattlers(10, cs);
  for (int i = 0; i <= 4; ++i) EXPECT_FALSE(keep[i]) << i;
  for (int i = 5; i <= 9; ++i) EXPECT_TRUE(keep[i]) << i;
}

std::vector<double> flat(const Particles& p) {
  std::vector<double> v;
  for (const auto* a : {&p.x, &p.y, &p.z, &p.vx, &p.vy, &p.vz, &p.fx, &p.fy, &p.fz})
    v.insert(v.end(), a->begin(), a->end());
  return v;
}

// 400 particles from nu = 0.35, compressed for 1500 steps (the list rebuilt on the way).
DemSystem compressed_gas(const SystemOptions& o) {
  GasOptions g;
  g.n_particles = 400;
  g.volume_fraction = 0.35;
  DemSystem a = make_gas(o, g, 3);
  a.advance(1500, Eigen::Vector3d::Constant(-3000.0));
  return a;
}

TEST(Engine, RestartIsBitIdentical) {
  SystemOptions o;
  DemSystem a = compressed_gas(o);
  const Eigen::Vector3d D = Eigen::Vector3d::Constant(-3000.0);
  const State saved = a.save();
  a.advance(1500, D);
  DemSystem b = DemSystem::restore(saved, o);
  b.advance(1500, D);
  EXPECT_GT(a.list_builds(), 1);                        // the list was rebuilt along the way
  EXPECT_EQ(flat(a.particles()), flat(b.particles()));  // exact, not near
  EXPECT_EQ(a.cell().lengths(), b.cell().lengths());
  EXPECT_EQ(a.time(), b.time());
}

// A saved list's half skins fit the skin it was made with only (the list, and with friction
// the springs kept per entry, could not be rebuilt with another): restore() says so as bad
// input naming dem.skin and both values, not as an internal error of the list.
TEST(Engine, RestoreWithAnotherSkinIsRefusedNamingIt) {
  SystemOptions o;
  const State saved = compressed_gas(o).save();
  ASSERT_FALSE(saved.ref_half_skin.empty());
  SystemOptions other = o;
  other.skin = 0.5 * o.skin;
  try {
    DemSystem::restore(saved, other);
    ADD_FAILURE() << "restored with another skin";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("dem.skin"), std::string::npos) << m;
    char made[64];
    std::snprintf(made, sizeof made, "= %.6g, not %.6g", o.skin, other.skin);
    EXPECT_NE(m.find(made), std::string::npos) << m;
  }
  EXPECT_NO_THROW(DemSystem::restore(saved, o));
}

// A step the integrator cannot follow is refused before it changes anything: a rate that
// strains the cell by more than DemSystem::kMaxStrainPerStep in one step, and a rate that is
// not finite (a servo gone wrong). Just below the limit the step is taken.
TEST(Engine, AStepStrainingTheCellTooFarOrByNaNIsRefusedUntouched) {
  SystemOptions o;
  DemSystem s = compressed_gas(o);
  const double limit = DemSystem::kMaxStrainPerStep / s.dt();
  const State before = s.save();
  for (const Eigen::Vector3d& D :
       {Eigen::Vector3d(0.0, 1.001 * limit, 0.0), Eigen::Vector3d(-1.001 * limit, 0.0, 0.0),
        Eigen::Vector3d(std::nan(""), 0.0, 0.0), Eigen::Vector3d(1.0, std::nan(""), 2.0),
        Eigen::Vector3d(-3.0, 1.0, std::nan("")),
        Eigen::Vector3d(0.0, 0.0, std::numeric_limits<double>::infinity())}) {
    try {
      s.step(D);
      ADD_FAILURE() << "stepped with D = " << D.transpose();
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("per time step"), std::string::npos) << e.what();
    }
    EXPECT_EQ(s.steps(), before.steps);
    EXPECT_EQ(s.cell().lengths(), before.lengths);
    EXPECT_EQ(flat(s.particles()), flat(before.particles));
  }
  EXPECT_NO_THROW(s.step(Eigen::Vector3d(0.0, 0.999 * limit, 0.0)));
  EXPECT_EQ(s.steps(), before.steps + 1);
}

// A saved state the engine cannot have made (finite numbers of a damaged file) is refused by
// restore(), naming what: a particle or a reference position beyond its cell by more than the
// cell's length, a particle that crosses its own radius in one step, a strain rate beyond one
// step's limit, half skins that fit no skin (-1e308 said "made with dem.skin = -inf"). From a
// results file they crashed the packing's pair search, or ended in an internal error of the list or
// a diverged integration. Within the bounds the state restores.
TEST(Engine, RestoreRefusesAStateTheEngineCannotHaveMade) {
  SystemOptions o;
  const State good = compressed_gas(o).save();
  const double dt = DemSystem::restore(good, o).dt();
  const double L = good.lengths[0], r = good.particles.radius[3];
  const struct {
    void (*damage)(State&, double, double, double);
    const char* words;
  } cases[] = {
      {[](State& s, double, double, double) { s.particles.x[3] = -1e308; },
       "DEM state: particle 3 at -1e+308 m on axis x lies beyond its cell [0, "},
      {[](State& s, double, double, double) { s.ref_y[5] = 2.0 * s.ref_lengths[1]; },
       "DEM state: the reference position of particle 5 at "},
      {[](State& s, double, double, double) { s.particles.vz[3] = -1e308; },
       "m per time step (|v| = 1e+308 m/s"},
      {[](State& s, double, double r, double dt) { s.particles.vx[3] = 1.01 * r / dt; },
       "more than its radius"},
      {[](State& s, double, double, double dt) {
         s.last_D[2] = 1.01 * DemSystem::kMaxStrainPerStep / dt;
       },
       "DEM state: its last strain rate strains the cell by 0.0101 per time step"},
      {[](State& s, double, double, double) { s.ref_half_skin[4] = -1e308; },
       "DEM state: its neighbour list's half skins fit no skin (the smallest is -1e+308 m)"},
      {[](State& s, double L, double, double) { s.ref_half_skin[4] = L; },
       "DEM state: its neighbour list's half skins fit no skin"},
  };
  for (const auto& c : cases) {
    State s = good;
    c.damage(s, L, r, dt);
    const std::string why = input_error([&] { DemSystem::restore(s, o); });
    EXPECT_NE(why.find(c.words), std::string::npos) << why;
  }
  State edge = good;
  edge.particles.x[3] = -0.99 * L;
  edge.particles.vx[3] = 0.99 * r / dt;
  edge.last_D[2] = 0.99 * DemSystem::kMaxStrainPerStep / dt;
  EXPECT_NO_THROW(DemSystem::restore(edge, o));
}

// The two refusals' numbers keep their point under a Python session's decimal-comma locale
// (printf wrote "more than 0,01" and "dem.skin = 0,3").
using EngineInACommaLocale = CommaLocale;
TEST_F(EngineInACommaLocale, RefusalsKeepTheirPoint) {
  SystemOptions o;
  o.skin = 0.25;
  DemSystem s = compressed_gas(o);
  const std::string step = input_error(
      [&] { s.step(Eigen::Vector3d(0.0, 0.0, 2.0 * DemSystem::kMaxStrainPerStep / s.dt())); });
  EXPECT_NE(step.find("strains the cell by 0.02 per time step"), std::string::npos) << step;
  EXPECT_NE(step.find("more than 0.01: lower the rate"), std::string::npos) << step;
  SystemOptions other = o;
  other.skin = 0.5;
  const std::string skin = input_error([&] { DemSystem::restore(s.save(), other); });
  EXPECT_NE(skin.find("dem.skin = 0.25, not 0.5:"), std::string::npos) << skin;
}

// Two spheres at one point have no contact normal: their force was NaN, and the first step
// ended in "DEM integration diverged", an internal error (exit 1). A particle listed twice in a
// packing file, or in a saved state, is refused naming both.
TEST(Engine, TwoParticlesAtOnePointAreRefusedNamingThem) {
  SystemOptions o;
  const State good = compressed_gas(o).save();
  State twice = good;
  twice.particles.x[5] = twice.particles.x[3];
  twice.particles.y[5] = twice.particles.y[3];
  twice.particles.z[5] = twice.particles.z[3];
  const std::string why = input_error([&] { DemSystem::restore(twice, o); });
  EXPECT_NE(why.find("DEM system: particles 3 and 5 (counted from 0 in the packing's order) are "
                     "both at ("),
            std::string::npos)
      << why;
  EXPECT_NE(why.find("two spheres at one point have no contact normal"), std::string::npos);

  const auto n = static_cast<Eigen::Index>(good.particles.size());
  Eigen::MatrixXd x(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    x.row(i) << good.particles.x[k], good.particles.y[k], good.particles.z[k];
  }
  EXPECT_NO_THROW(system_from_positions(x, good.particles.radius, good.lengths, o));
  Eigen::MatrixXd twice_x = x;
  twice_x.row(7) = x.row(2);
  const std::string read =
      input_error([&] { system_from_positions(twice_x, good.particles.radius, good.lengths, o); });
  EXPECT_NE(read.find("particles 2 and 7"), std::string::npos) << read;
  // One rounding apart is a pair with a normal: its force is finite.
  Eigen::MatrixXd near = x;
  near.row(7) = x.row(2);
  near(7, 0) = std::nextafter(near(7, 0), 1.0);
  const DemSystem s = system_from_positions(near, good.particles.radius, good.lengths, o);
  EXPECT_TRUE(std::isfinite(s.stress().norm()));
}

TEST(Engine, CellTooSmallForOneImageIsRefused) {
  Material mat;
  EXPECT_THROW(lattice(2, 1e-3, 2.1e-3, mat), InputError);
}

TEST(Engine, StressServoHoldsLateralStress) {
  // Drained triaxial control on a compressed lattice: lateral axes servo to a target below
  // the current stress and must get there (cell extends laterally).
  Material mat;
  const double r = 1e-3, delta = 4e-6, a = 2 * r - delta;
  DemSystem s = lattice(4, r, a, mat);
  const double s0 = mat.k * delta / (a * a);
  CellControl c = CellControl::drained_triaxial(0.0, 0.5 * s0);
  c.servo.gain = 1e5;
  for (int k = 0; k < 10000; ++k) s.step(c);
  const Eigen::Matrix3d sig = s.stress();
  // The lattice's lateral stiffness is K = k/a ~ k*, so the error decays at the rate
  // gain K / k* = 1e5 1/s: 10000 steps (4.6e-5 s) are 4.6 time constants, leaving 1 %.
  EXPECT_NEAR(sig(1, 1), 0.5 * s0, 0.02 * s0);
  EXPECT_NEAR(sig(2, 2), 0.5 * s0, 0.02 * s0);
  EXPECT_NEAR(s.cell().lengths()[0], 4 * a, 1e-15);  // axial axis held (rate 0)
}

}  // namespace
}  // namespace rendulic::dem
