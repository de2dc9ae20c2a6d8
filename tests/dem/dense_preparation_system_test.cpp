// A frictional run prepared with less friction (isotropic.friction_factor; run_protocol.hpp,
// docs/dem.md "Dense frictional packings"): the preparation and the isotropic loading run with
// mu x factor, and the packing they leave at a pressure is denser the smaller the factor
// (frictionless jamming is the densest random packing); from the path on the run's own mu
// acts, every tangential spring starting from zero after a frictionless loading, and the
// packing is otherwise the loading's (positions, cell, stress).
#include <gtest/gtest.h>

#include <algorithm>

#include "rendulic/dem/run_protocol.hpp"

namespace rendulic::dem {
namespace {

DemRunOptions small_run(double factor) {
  DemRunOptions o;
  o.system.material.mu = 0.5;
  o.loading_friction_factor = factor;
  o.gas.n_particles = 250;
  o.gas.velocity = 0.0;
  o.prepare_gamma_b = 5.0;
  o.prepare.target_nu = 0.5;
  o.prepare.rate_max = o.prepare.rate_min = 3000.0;
  o.relax = {.kinetic_to_elastic = 1e-4, .time_cap = 2e-4};
  o.loading = {.target_nu = 0.75,
               .rate_max = 600.0,
               .rate_min = 600.0,
               .inertial_number = 0.0,
               .samples = 50,
               .target_pressure_star = 1e-3};
  return o;
}

DemSystem loaded(const DemRunOptions& o) {
  PreparedPacking p = prepare_packing(o, 3);
  EXPECT_EQ(p.system.material().mu, o.system.material.mu * o.loading_friction_factor);
  load_isotropic(p.system, o.loading, o.relax);
  return std::move(p.system);
}

TEST(DensePreparation, LessFrictionInTheLoadingJamsDenserAndThePathRunsWithTheRunsMu) {
  const DemRunOptions with = small_run(1.0), without = small_run(0.0);
  DemSystem rough = loaded(with);
  DemSystem smooth = loaded(without);
  // The same pressure, reached with and without friction: the frictionless loading packs
  // closer (random close packing against the looser frictional jamming).
  const double p_rough = rough.measure().pressure_star, p_smooth = smooth.measure().pressure_star;
  EXPECT_NEAR(p_rough, 1e-3, 2e-5);
  EXPECT_NEAR(p_smooth, 1e-3, 2e-5);
  EXPECT_GT(smooth.volume_fraction(), rough.volume_fraction() + 0.01)
      << smooth.volume_fraction() << " vs " << rough.volume_fraction();
  EXPECT_EQ(smooth.rotational_energy(), 0.0);

  // A factor of 1: the loading already ran with the run's material; nothing changes.
  const State before = rough.save();
  use_run_material(rough, with);
  EXPECT_EQ(rough.save().particles.x, before.particles.x);
  EXPECT_EQ(rough.save().tangential_history, before.tangential_history);

  // A factor of 0: the same packing, now frictional, every spring at zero.
  const Particles p0 = smooth.particles();
  const double pressure0 = smooth.measure().pressure;
  const Eigen::Vector3d lengths0 = smooth.cell().lengths();
  use_run_material(smooth, without);
  EXPECT_EQ(smooth.material().mu, 0.5);
  EXPECT_EQ(smooth.particles().x, p0.x);
  EXPECT_EQ(smooth.cell().lengths(), lengths0);
  const std::vector<double> springs = smooth.save().tangential_history;
  EXPECT_TRUE(std::all_of(springs.begin(), springs.end(), [](double x) { return x == 0.0; }));
  // Only the tangential dashpots of a packing not quite at rest differ from the frictionless
  // stress.
  EXPECT_NEAR(smooth.measure().pressure, pressure0, 1e-6 * pressure0);
  // Sheared, its contacts now carry tangential springs and rotate the particles.
  smooth.advance(2000, Eigen::Vector3d(-300.0, 150.0, 150.0));
  EXPECT_GT(smooth.measure().tangential_energy, 0.0);
  EXPECT_GT(smooth.rotational_energy(), 0.0);
}

}  // namespace
}  // namespace rendulic::dem
