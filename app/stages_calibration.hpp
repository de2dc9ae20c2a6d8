// The `calibration` stage of `rendulic run` (pipeline.hpp): calibrates a model
// against the states and envelopes already written by the earlier stages of the same run and
// stores /calibration/<model>. Its scenario keys are calibration.* (calibration/settings.hpp).
#pragma once

#include "pipeline.hpp"
#include "rendulic/core/results.hpp"
#include "rendulic/core/scenario.hpp"

namespace rendulic::app {

void run_calibration_stage(const Scenario& scenario, ResultsWriter& out, const RunContext& ctx);

}  // namespace rendulic::app
