// The run's fits stage (app/stages.hpp; docs/fitting.md): an envelope it cannot fit keeps the
// reason in its fit groups' `error`, and that reason names the results file the run writes.
// It named the run's temporary file (DIR/.results.h5.tmp-PID), gone once the run ended.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "commands.hpp"
#include "pipeline.hpp"
#include "rendulic/core/envelope_io.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/core/results.hpp"
#include "stages.hpp"

namespace rendulic::app {
namespace {
namespace fs = std::filesystem;

TEST(StageFits, AnEnvelopeItCannotFitIsNamedInTheFileTheRunWrites) {
  const fs::path dir = fs::path(RENDULIC_TEST_TMP) / "app_stage_fits";
  fs::remove_all(dir);
  const fs::path file = dir / "results.h5";
  const std::string g = paths::envelope(paths::state("a"), "dynamic_0.0001");
  ResultsWriter out(file);
  EnvelopeRecord e;
  e.method = "dynamic";
  e.amplitude = 1e-4;
  e.k_star = 1e8;
  for (int i = 0; i < 8; ++i) {
    const double t = 0.785398 * i;
    e.theta_deg.push_back(45.0 * i);
    e.strain.emplace_back(1e-4 * std::cos(t), 1e-4 * std::sin(t));
    e.stress_star.emplace_back(2e-4 * std::cos(t), 1e-4 * std::sin(t));
    e.fabric.emplace_back(3e-4 * std::cos(t), 1e-4 * std::sin(t));
  }
  write_envelope(out, g, e);
  out.attr(g, "amplitude", 0.0);  // what no reader can use: every reader refuses it
  stage_fits(Scenario(scenario_schema()), out, RunContext{});
  out.commit();
  const ResultsReader in(file);
  for (const char* fit : {paths::kFitStress, paths::kFitFabric}) {
    EXPECT_EQ(in.attr_string(g + fit, "shape"), "none");
    const std::string why = in.attr_string(g + fit, "error");
    EXPECT_EQ(why.rfind(file.string() + ": envelope " + g + ": @amplitude is 0", 0), 0u) << why;
  }
}

}  // namespace
}  // namespace rendulic::app
