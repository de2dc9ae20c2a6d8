// Scenario keys of the DEM run (dem/scenario_keys.hpp): the defaults are the seed study's run,
// written here as the study states them (docs/physics.md sections 1 and 4) rather than read back
// from DemRunOptions{}, so that a changed default fails; every key reaches its member, including
// the members one key sets for several steps.
#include <gtest/gtest.h>

#include "input_error.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/dem/scenario_keys.hpp"

namespace rendulic::dem {
namespace {

using rendulic::testing::input_error;

ScenarioSchema schema() {
  ScenarioSchema s;
  register_dem_keys(s);
  return s;
}

TEST(RunScenario, DefaultsAreTheSeedStudysRun) {
  const ScenarioSchema s = schema();
  const DemRunOptions o = dem_options_from_scenario(Scenario(s));
  EXPECT_EQ(o.system.material.k, 1e8);
  EXPECT_EQ(o.system.material.gamma, 1.0);
  EXPECT_EQ(o.system.material.gamma_b, 0.1);
  EXPECT_EQ(o.system.material.density, 2000.0);
  EXPECT_EQ(o.system.material.r_mean, 1e-3);
  EXPECT_EQ(o.system.material.w, 3.0);
  EXPECT_EQ(o.gas.n_particles, 9261u);
  EXPECT_EQ(o.system.dt_factor, 0.02);
  EXPECT_EQ(o.prepare.target_nu, 0.64);
  EXPECT_EQ(o.loading.target_nu, 0.82);
  EXPECT_EQ(o.path.eps_dev_max, 0.32);
  EXPECT_EQ(o.path.snapshot_eps_dev, (std::vector<double>{0.006, 0.021, 0.043, 0.068, 0.32}));
  EXPECT_EQ(o.state_labels, (std::vector<std::string>{"a", "b", "c", "d", "e"}));
  // The choices of this project where the seed gives no number (docs/dem.md).
  EXPECT_EQ(o.prepare.rate_max, 300.0);
  EXPECT_EQ(o.prepare.rate_min, 300.0);
  EXPECT_EQ(o.relax.kinetic_to_elastic, 1e-5);
  EXPECT_EQ(o.state_rest.relax.kinetic_to_elastic, 1e-6);
  EXPECT_EQ(o.state_rest.minimise.force_tolerance, 1e-9);
  EXPECT_EQ(o.state_rest.minimise.k, o.system.material.k);
  EXPECT_TRUE(o.branch_nu.empty());
  EXPECT_TRUE(o.loading.snapshot_nu.empty());
}

TEST(RunScenario, EveryKeyReachesItsMember) {
  const ScenarioSchema s = schema();
  const Scenario sc = Scenario::from_string(
      "[material]\nk = 2e8\ngamma = 0.5\ngamma_b = 0.2\ndensity = 1000.0\nr_mean = 2e-3\nw = 2.0\n"
      "[dem]\nn_particles = 1000\ndt_factor = 0.01\nskin = 0.4\nfriction = 0.3\nk_t_ratio = 0.5\n"
      "gamma_t_ratio = 0.25\nrolling_friction = 0.05\nk_r_ratio = 0.125\ngamma_r_ratio = "
      "0.375\n"
      "[preparation]\nnu_gas = 0.25\ngas_velocity = 2.0\nmix_time = 1e-3\nrate = 200.0\n"
      "gamma_b = 0.3\nnu0 = 0.6\n"
      "[relax]\nkinetic_to_elastic = 1e-4\ntime_cap = 1e-3\n"
      "[isotropic]\nnu_max = 0.8\nsamples = 70\ninertial_number = 1e-4\nrate_max = 500.0\n"
      "rate_min = 60.0\npressure_star = 0.02\nfriction_factor = 0.25\n"
      "[pressure]\nvolume_fractions = [0.7]\n"
      "[path]\nrate = 300.0\neps_dev_max = 0.1\nsamples = 50\ntype = \"proportional\"\n"
      "direction = [1.0, 0.0, -1.0]\nservo_gain = 1.5\nservo_integral_gain = 0.25\n"
      "servo_tolerance = 0.05\ninertial_number = 2e-4\nrate_min = 7.0\n"
      "[states]\neps_dev = [0.01, 0.05]\nlabels = [\"p\", \"q\"]\nkinetic_to_elastic = 1e-7\n"
      "time_cap = 1e-3\nforce_tolerance = 1e-8\n",
      "run.toml", s);
  const DemRunOptions o = dem_options_from_scenario(sc);
  const Material& m = o.system.material;
  EXPECT_EQ(m.k, 2e8);
  EXPECT_EQ(m.gamma, 0.5);
  EXPECT_EQ(m.gamma_b, 0.2);
  EXPECT_EQ(m.density, 1000.0);
  EXPECT_EQ(m.r_mean, 2e-3);
  EXPECT_EQ(m.w, 2.0);
  EXPECT_EQ(m.mu, 0.3);
  EXPECT_EQ(m.k_t_ratio, 0.5);
  EXPECT_EQ(m.gamma_t_ratio, 0.25);
  EXPECT_EQ(m.mu_r, 0.05);
  EXPECT_EQ(m.k_r_ratio, 0.125);
  EXPECT_EQ(m.gamma_r_ratio, 0.375);
  EXPECT_EQ(material_from_scenario(sc).k, 2e8);
  EXPECT_EQ(o.gas.n_particles, 1000u);
  EXPECT_EQ(o.system.dt_factor, 0.01);
  EXPECT_EQ(o.system.skin, 0.4);
  EXPECT_EQ(o.gas.volume_fraction, 0.25);
  EXPECT_EQ(o.gas.velocity, 2.0);
  EXPECT_EQ(o.mix_time, 1e-3);
  EXPECT_EQ(o.prepare.rate_max, 200.0);
  EXPECT_EQ(o.prepare.rate_min, 200.0);
  EXPECT_EQ(o.prepare_gamma_b, 0.3);
  EXPECT_EQ(o.prepare.target_nu, 0.6);
  EXPECT_EQ(o.relax.kinetic_to_elastic, 1e-4);
  EXPECT_EQ(o.relax.time_cap, 1e-3);
  EXPECT_EQ(o.loading.target_nu, 0.8);
  EXPECT_EQ(o.loading.samples, 70);
  EXPECT_EQ(o.loading.inertial_number, 1e-4);
  EXPECT_EQ(o.loading.rate_max, 500.0);
  EXPECT_EQ(o.loading.rate_min, 60.0);
  EXPECT_EQ(o.branch_nu, (std::vector<double>{0.7}));
  EXPECT_EQ(o.loading.snapshot_nu, (std::vector<double>{0.7}));
  EXPECT_EQ(o.path.rate, 300.0);
  EXPECT_EQ(o.path.eps_dev_max, 0.1);
  EXPECT_EQ(o.path.samples, 50);
  EXPECT_EQ(o.path.snapshot_eps_dev, (std::vector<double>{0.01, 0.05}));
  EXPECT_EQ(o.path.type, "proportional");
  EXPECT_EQ(o.path.direction, (std::vector<double>{1.0, 0.0, -1.0}));
  EXPECT_EQ(o.path.servo_gain, 1.5);
  EXPECT_EQ(o.path.servo_integral_gain, 0.25);
  EXPECT_EQ(o.path.servo_tolerance, 0.05);
  EXPECT_EQ(o.loading.target_pressure_star, 0.02);
  EXPECT_EQ(o.loading_friction_factor, 0.25);
  EXPECT_EQ(loading_system_options(o).material.mu, 0.25 * 0.3);
  EXPECT_EQ(loading_system_options(o).material.mu_r, 0.25 * 0.05);
  EXPECT_EQ(o.path.inertial_number, 2e-4);
  EXPECT_EQ(o.path.rate_min, 7.0);
  EXPECT_EQ(o.state_labels, (std::vector<std::string>{"p", "q"}));
  EXPECT_EQ(o.state_rest.relax.kinetic_to_elastic, 1e-7);
  EXPECT_EQ(o.state_rest.relax.time_cap, 1e-3);
  EXPECT_EQ(o.state_rest.minimise.force_tolerance, 1e-8);
  EXPECT_EQ(o.state_rest.minimise.k, 2e8);
  // Every row of the table was set above: one key per row, none forgotten.
  EXPECT_EQ(dem_run_option_table().rows().size(), 46u);
}

TEST(RunScenario, ACodeBuiltRunIsHeldToTheKeysRanges) {
  DemRunOptions o;
  std::string why;
  EXPECT_TRUE(dem_run_option_table().check(o, &why)) << why;
  o.system.dt_factor = 1.5;
  EXPECT_FALSE(dem_run_option_table().check(o, &why));
  EXPECT_NE(why.find("dem.dt_factor"), std::string::npos) << why;
}

TEST(RunScenario, APathFloorAboveItsRateIsRefusedNamingIt) {
  const ScenarioSchema s = schema();
  const Scenario sc = Scenario::from_string(
      "[path]\nrate = 50.0\ninertial_number = 1e-3\nrate_min = 60.0\n", "run.toml", s);
  const std::string what = input_error([&] { dem_options_from_scenario(sc); });
  EXPECT_NE(what.find("path.rate_min"), std::string::npos) << what;
  // Without a held inertial number the floor is not used, and not checked.
  EXPECT_NO_THROW(dem_options_from_scenario(
      Scenario::from_string("[path]\nrate = 50.0\nrate_min = 60.0\n", "run.toml", s)));
}

}  // namespace
}  // namespace rendulic::dem
