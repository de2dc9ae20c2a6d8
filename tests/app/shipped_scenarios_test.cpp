// The scenarios shipped in data/scenarios (docs/usage.md): each parses against the whole schema
// (docs/scenario-keys.md: a mistyped or removed key in a shipped file is an error) and passes
// the cross-key rules `rendulic run` checks before its first stage, so none fails for a user
// after minutes of simulation.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "commands.hpp"
#include "pipeline.hpp"
#include "rendulic/core/errors.hpp"
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

// The cell's servo (docs/dem.md "Paths"): a gain per step, path.servo_gain x dem.dt_factor,
// above 1 is refused before the first stage, naming both keys and the servo that would use it;
// a scenario whose stages use no servo is not refused.
TEST(ServoCheck, AGainBeyondTheExplicitLimitIsRefusedNamingBothKeys) {
  const auto refusal = [](const std::string& text) -> std::string {
    try {
      check_stages_available(Scenario::from_string(text, "s.toml", scenario_schema()));
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  const std::string drained = "[path]\ntype = \"drained_compression\"\n";
  EXPECT_EQ(refusal(drained + "servo_gain = 50.0\n"), "");  // 50 x 0.02 = 1: at the limit
  const std::string path = refusal(drained + "servo_gain = 60.0\n");
  EXPECT_NE(path.find("path.servo_gain = 60 (s.toml:3)"), std::string::npos) << path;
  EXPECT_NE(path.find("dem.dt_factor = 0.02"), std::string::npos) << path;
  EXPECT_NE(path.find("lateral servo a gain of 1.2 per step"), std::string::npos) << path;
  const std::string hold = refusal(
      "[isotropic]\npressure_star = 1e-3\n[dem]\ndt_factor = 0.1\n[path]\nservo_gain = 15.0\n");
  EXPECT_NE(hold.find("hold at isotropic.pressure_star a gain of 1.5 per step"), std::string::npos)
      << hold;
  // Neither a mixed path nor a pressure target: no servo runs.
  EXPECT_EQ(refusal("[path]\nservo_gain = 60.0\n"), "");
}

}  // namespace
}  // namespace rendulic::app
