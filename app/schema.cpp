// The complete scenario schema: run.* keys plus every module's own keys. The one place that
// knows which modules contribute keys; each module declares its keys next to its options.
#include "commands.hpp"
#include "pipeline.hpp"
#include "rendulic/calibration/settings.hpp"
#include "rendulic/dem/probe_campaign.hpp"
#include "rendulic/dem/scenario_keys.hpp"
#include "stages.hpp"
#include "stages_calibration.hpp"

namespace rendulic::app {

const ScenarioSchema& scenario_schema() {
  static const ScenarioSchema schema = [] {
    ScenarioSchema s;
    register_run_keys(s);
    dem::register_dem_keys(s);
    dem::register_probe_keys(s);
    register_fit_keys(s);
    calibration::register_calibration_keys(s);
    return s;
  }();
  return schema;
}

}  // namespace rendulic::app
