// The `calibration` stage of `rendulic run` (pipeline.hpp): calibrates a model
// against the states and envelopes already written by the earlier stages of the same run and
// stores /calibration/<model>. Its scenario keys are calibration.*.
#pragma once

#include "pipeline.hpp"
#include "rendulic/core/results.hpp"
#include "rendulic/core/scenario.hpp"

namespace rendulic::app {

// calibration.model, calibration.states, calibration.holdout, calibration.backend,
// calibration.path, calibration.features.
void register_calibration_keys(ScenarioSchema& schema);
void run_calibration_stage(const Scenario& scenario, ResultsWriter& out, const RunContext& ctx);

}  // namespace rendulic::app
