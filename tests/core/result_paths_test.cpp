// The names of the results file (core/result_paths.hpp) against the layout that
// docs/results.md states as the contract.
#include "rendulic/core/result_paths.hpp"

#include <gtest/gtest.h>

namespace rendulic {
namespace {

TEST(ResultPaths, GroupsAreThoseOfTheContract) {
  EXPECT_EQ(paths::state("a"), "/states/a");
  EXPECT_EQ(paths::envelope(paths::state("a"), "dynamic_5e-05"),
            "/states/a/envelopes/dynamic_5e-05");
  EXPECT_EQ(paths::elastic_range(paths::state("b")), "/states/b/elastic_range");
  EXPECT_EQ(paths::calibration("elastic_iso"), "/calibration/elastic_iso");
  EXPECT_EQ(paths::state("c", paths::calibration("m")), "/calibration/m/states/c");
  EXPECT_EQ(paths::envelope(paths::state("c"), "x") + datasets::kStressStar,
            "/states/c/envelopes/x/stress_star");
  EXPECT_EQ(paths::envelope(paths::state("c"), "x") + paths::kFitFabric,
            "/states/c/envelopes/x/fit_fabric");
}

TEST(ResultPaths, NumbersArePrintedWithPercentG) {
  EXPECT_EQ(paths::envelope_name("dynamic", 5e-5), "dynamic_5e-05");
  EXPECT_EQ(paths::envelope_name("minimisation", 2e-2), "minimisation_0.02");
  EXPECT_EQ(paths::pressure_branch(0.7), "/pressure/nu0.7");
  EXPECT_EQ(paths::pressure_branch(0.75), "/pressure/nu0.75");
  EXPECT_EQ(paths::state("a", paths::pressure_branch(0.7)), "/pressure/nu0.7/states/a");
}

}  // namespace
}  // namespace rendulic
