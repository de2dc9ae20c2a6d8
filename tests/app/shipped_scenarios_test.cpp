// The scenarios shipped in data/scenarios (docs/usage.md): each parses against the whole schema
// (docs/scenario-keys.md: a mistyped or removed key in a shipped file is an error) and passes
// the cross-key rules `rendulic run` checks before its first stage, so none fails for a user
// after minutes of simulation.
#include <gtest/gtest.h>

#include <filesystem>

#include "commands.hpp"
#include "pipeline.hpp"
#include "rendulic/core/scenario.hpp"

namespace rendulic::app {
namespace {
namespace fs = std::filesystem;

TEST(ShippedScenarios, EachParsesAndPassesTheRunsChecks) {
  const fs::path dir = fs::path(RENDULIC_SOURCE_DIR) / "data/scenarios";
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".toml") continue;
    ++files;
    SCOPED_TRACE(entry.path().filename().string());
    EXPECT_NO_THROW({
      const Scenario sc = Scenario::from_file(entry.path().string(), scenario_schema());
      check_stages_available(sc);
    });
  }
  EXPECT_GE(files, 4);  // quick, paper, pressure, frictional at least
}

}  // namespace
}  // namespace rendulic::app
