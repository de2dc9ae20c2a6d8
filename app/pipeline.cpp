// Stage table of `rendulic run` (see pipeline.hpp). Stages are added here as their modules
// land; the names and their order are fixed by physics.md section 4 and issue 8.
#include "pipeline.hpp"

#include <functional>
#include <string>
#include <vector>

#include "rendulic/core/errors.hpp"

namespace rendulic::app {

// DEM stages (app/stages_dem.cpp, issue 3).
void stage_prepare(const Scenario&, ResultsWriter&, const RunContext&);
void stage_isotropic(const Scenario&, ResultsWriter&, const RunContext&);
void stage_path(const Scenario&, ResultsWriter&, const RunContext&);
void stage_states(const Scenario&, ResultsWriter&, const RunContext&);

namespace {

using StageFn = std::function<void(const Scenario&, ResultsWriter&, const RunContext&)>;
struct Stage {
  const char* name;
  const char* issue;  // where it lands, for the NotAvailable message
  StageFn run;        // empty: not landed yet
};

const std::vector<Stage>& stages() {
  static const std::vector<Stage> table = {
      {"prepare", "3", stage_prepare},
      {"isotropic", "3", stage_isotropic},
      {"path", "3", stage_path},
      {"states", "3", stage_states},
      {"probes", "4", {}},
      {"linear_response", "4", {}},
      {"fits", "5", {}},
      {"calibration", "7", {}},
      {"report", "8", {}},
  };
  return table;
}

bool requested(const Scenario& scenario, const std::string& name) {
  for (const auto& s : scenario.get_strings("run.stages"))
    if (s == name) return true;
  return false;
}

}  // namespace

void register_run_keys(ScenarioSchema& schema) {
  std::vector<std::string> names;
  for (const auto& s : stages()) names.emplace_back(s.name);
  schema.add({.path = "run.seed",
              .type = KeyType::kInt,
              .default_value = std::int64_t{1},
              .unit = "-",
              .help = "Seed of every random draw of the run (same seed, same build: same result).",
              .min = 0,
              .max = 4.0e18});
  schema.add({.path = "run.stages",
              .type = KeyType::kStringList,
              .default_value = std::vector<std::string>{"prepare", "isotropic", "path", "states"},
              .unit = "-",
              .help = "Stages to run, executed in the fixed order prepare, isotropic, path, "
                      "states, probes, linear_response, fits, calibration, report.",
              .choices = names});
  schema.add({.path = "run.description",
              .type = KeyType::kString,
              .default_value = std::string{},
              .unit = "-",
              .help = "Free text stored with the results."});
}

void check_stages_available(const Scenario& scenario) {
  for (const auto& s : stages())
    if (requested(scenario, s.name) && !s.run)
      throw NotAvailable(std::string("run: stage '") + s.name + "' has not landed yet (issue " +
                         s.issue + "); remove it from run.stages");
}

void run_pipeline(const Scenario& scenario, ResultsWriter& out, const RunContext& ctx) {
  for (const auto& s : stages())
    if (requested(scenario, s.name)) s.run(scenario, out, ctx);
}

}  // namespace rendulic::app
