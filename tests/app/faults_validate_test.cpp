// A probe campaign that cannot converge, run to its end (label validate: a million FIRE
// iterations, about 20 s of CPU): minimisation probes of a state that reaches no force
// equilibrium at the asked tolerance used to end with "internal error" (exit 1) and throw
// away every stage before them. Now: exit 2, one line that says why and what to change, and
// the four completed stages kept in results.h5.partial (docs/usage.md "Results are atomic").
// And the damaged-file walk (damage_walk.hpp) with every subcommand on every damage (2400 runs
// of the binary, minutes on 2 cores): the default suite walks each damage with one command.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "cli_runner.hpp"
#include "damage_walk.hpp"
#include "rendulic/core/results.hpp"
#include "tiny_run.hpp"

namespace {
namespace fs = std::filesystem;

TEST(FaultsValidate, MinimisationProbesWithoutEquilibriumExitTwoAndKeepTheStages) {
  const fs::path d = rendulic::testing::fresh_dir("app_faults_validate/minimisation");
  // The tiny run (tiny_run.hpp) up to the probes, which are minimisations asked for a force
  // balance below rounding (FIRE never gets there, and stops where round-off stalls it).
  const fs::path scenario = rendulic::testing::tiny_scenario(d);
  const fs::path out = d / "out";
  const auto r = rendulic::testing::run_rendulic(
      "run " + scenario.string() +
          " --quiet --set run.stages=prepare,isotropic,path,states,probes"
          " --set probes.methods=minimisation --set probes.force_tolerance=1e-16 --out " +
          out.string(),
      false);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(rendulic::testing::error_lines(r.err), 1) << r.err;  // warnings kept by --quiet
  EXPECT_NE(r.err.find("minimisation probes: probes.force_tolerance = 1e-16 is below the "
                       "round-off floor of this state's forces"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("completed stages (prepare, isotropic, path, states) kept in " +
                       (out / "results.h5.partial").string()),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(rendulic::ResultsReader(out / "results.h5.partial").has_attr("/timings", "states"));
  EXPECT_FALSE(fs::exists(out / "results.h5"));
}

TEST(FaultsValidate, EveryDamageWithEverySubcommand) {
  const fs::path dir = fs::path(RENDULIC_TEST_TMP) / "app_faults_validate";
  rendulic::testing::walk_damaged_copies(rendulic::testing::tiny_results(),
                                         "app_faults_validate/walk", dir / "walk-outcomes.txt",
                                         rendulic::testing::Coverage::every_command);
}

}  // namespace
