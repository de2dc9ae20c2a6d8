// The stage functions of `rendulic run` (pipeline.cpp's table) and the live DEM state they
// share within one run: the DEM stages leave the relaxed states in memory for the probe
// stages; stages that need data already written (fits, calibration) read the writer's
// temporary file through a ResultsReader.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "pipeline.hpp"
#include "rendulic/dem/dem_system.hpp"
#include "rendulic/dem/protocols.hpp"
#include "rendulic/dem/scenario_keys.hpp"

namespace rendulic::app {

// Live DEM state shared by the stages of one run.
struct DemRunSession {
  std::optional<dem::DemSystem> system;                         // after prepare / isotropic / path
  std::vector<dem::DemSystem> snapshots;                        // on the path, states.labels order
  std::vector<std::pair<std::string, dem::DemSystem>> relaxed;  // after states
  std::optional<dem::DemRunOptions> options;
};
DemRunSession& dem_run_session();

// DEM (stages_dem.cpp, issue 3).
void stage_prepare(const Scenario&, ResultsWriter&, const RunContext&);
void stage_isotropic(const Scenario&, ResultsWriter&, const RunContext&);
void stage_path(const Scenario&, ResultsWriter&, const RunContext&);
void stage_states(const Scenario&, ResultsWriter&, const RunContext&);
// Probe campaigns and linear response (stages_probes.cpp, issue 4).
void stage_probes(const Scenario&, ResultsWriter&, const RunContext&);
void stage_linear_response(const Scenario&, ResultsWriter&, const RunContext&);
// Envelope fits (stages_probes.cpp, issue 5): fit_stress / fit_fabric of every envelope.
void register_fit_keys(ScenarioSchema& schema);
void stage_fits(const Scenario&, ResultsWriter&, const RunContext&);

}  // namespace rendulic::app
