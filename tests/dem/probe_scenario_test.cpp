// Scenario keys of the probe campaigns: defaults equal the documented
// ProbeOptions, values reach the options, and out-of-range values are refused naming the key.
#include <gtest/gtest.h>

#include "input_error.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/dem/probe_campaign.hpp"

namespace rendulic::dem {
namespace {

using rendulic::testing::input_error;

ScenarioSchema schema() {
  ScenarioSchema s;
  register_probe_keys(s);
  return s;
}

TEST(ProbeScenario, DefaultsAreTheOptionsDefaults) {
  const ScenarioSchema s = schema();
  const ProbeOptions o = probe_options_from(Scenario(s));
  const ProbeOptions d;
  EXPECT_EQ(o.directions, 36);
  EXPECT_EQ(o.amplitudes, (std::vector<double>{5e-5, 2e-3}));
  EXPECT_EQ(o.inertial_number, d.inertial_number);
  EXPECT_EQ(o.rate, d.rate);
  EXPECT_EQ(o.relax.kinetic_to_elastic, d.relax.kinetic_to_elastic);
  EXPECT_EQ(o.relax.time_cap, d.relax.time_cap);
  EXPECT_EQ(o.minimise.force_tolerance, d.minimise.force_tolerance);
  EXPECT_EQ(probe_methods_from(Scenario(s)), (std::vector<std::string>{"dynamic"}));
}

TEST(ProbeScenario, ValuesReachTheOptions) {
  const ScenarioSchema s = schema();
  const Scenario sc = Scenario::from_string(
      "[probes]\ndirections = 12\namplitudes = [1e-5]\nmethods = [\"dynamic\", "
      "\"minimisation\"]\nrate = 50.0\nrelax_kinetic_to_elastic = 1e-8\n",
      "test.toml", s);
  const ProbeOptions o = probe_options_from(sc);
  EXPECT_EQ(o.directions, 12);
  EXPECT_EQ(o.amplitudes, (std::vector<double>{1e-5}));
  EXPECT_EQ(o.rate, 50.0);
  EXPECT_EQ(o.relax.kinetic_to_elastic, 1e-8);
  EXPECT_EQ(probe_methods_from(sc).size(), 2u);
}

TEST(ProbeScenario, RefusesBadValuesNamingTheKey) {
  const ScenarioSchema s = schema();
  for (const char* bad : {"[probes]\ndirections = 2\n", "[probes]\namplitudes = [0.0]\n",
                          "[probes]\nmethods = [\"linear\"]\n", "[probes]\nrate = -1.0\n"}) {
    const std::string what = input_error([&] { (void)Scenario::from_string(bad, "bad.toml", s); });
    EXPECT_NE(what.find("probes."), std::string::npos) << bad << ": " << what;
  }
}

}  // namespace
}  // namespace rendulic::dem
