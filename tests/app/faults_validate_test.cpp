// A probe campaign that cannot converge, run to its end (label validate: a million FIRE
// iterations, about 20 s of CPU): minimisation probes of a state that reaches no force
// equilibrium at the asked tolerance used to end with "internal error" (exit 1) and throw
// away every stage before them. Now: exit 2, one line that says why and what to change, and
// the four completed stages kept in results.h5.partial (docs/usage.md "Results are atomic").
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "cli_runner.hpp"
#include "rendulic/core/results.hpp"

namespace {
namespace fs = std::filesystem;

TEST(FaultsValidate, MinimisationProbesWithoutEquilibriumExitTwoAndKeepTheStages) {
  const fs::path d = rendulic::testing::fresh_dir("app_faults_validate/minimisation");
  std::ofstream(d / "s.toml") << R"(
[run]
stages = ["prepare", "isotropic", "path", "states", "probes"]
[dem]
n_particles = 250
[preparation]
rate = 20000.0
gamma_b = 5.0
[relax]
kinetic_to_elastic = 1e-4
time_cap = 2e-4
[isotropic]
nu_max = 0.75
samples = 50
inertial_number = 5e-3
rate_max = 5000.0
rate_min = 500.0
[path]
rate = 5000.0
eps_dev_max = 0.05
samples = 10
[states]
eps_dev = [0.01, 0.05]
labels = ["a", "b"]
kinetic_to_elastic = 1e-4
time_cap = 1e-4
[probes]
directions = 8
methods = ["minimisation"]
force_tolerance = 1e-16   # below rounding: FIRE never gets there
)";
  const fs::path out = d / "out";
  const auto r = rendulic::testing::run_rendulic(
      "run " + (d / "s.toml").string() + " --quiet --out " + out.string(), false);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("minimisation probes: the state reaches no force equilibrium"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("completed stages (prepare, isotropic, path, states) kept in " +
                       (out / "results.h5.partial").string()),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(rendulic::ResultsReader(out / "results.h5.partial").has_attr("/timings", "states"));
  EXPECT_FALSE(fs::exists(out / "results.h5"));
}

}  // namespace
