// The settings of a calibration of DEM data, as both front ends take them: the `calibration`
// stage of `rendulic run` (keys calibration.*) and `rendulic calibrate` (its options, made from
// the same keys by app/cli_options.hpp). CalibrationSettings owns their defaults, its table
// their ranges and help (core/option_table.hpp); calibration_plan() is the one translation into
// the options of calibrate() and load_calibration_data() (docs/calibration.md "Two levels").
#pragma once

#include <string>
#include <vector>

#include "rendulic/calibration/calibrate.hpp"
#include "rendulic/calibration/data.hpp"
#include "rendulic/calibration/solver.hpp"
#include "rendulic/core/option_table.hpp"
#include "rendulic/core/scenario.hpp"

namespace rendulic::calibration {

struct CalibrationSettings {
  std::string model = "all";                    // a law of models::law_names(), or all of them
  std::vector<std::string> states;              // empty: every state with envelopes
  std::vector<std::string> holdout = {"auto"};  // {"none"} or {}: none
  std::string backend = "ceres";
  bool path = true;  // fit the main path with the envelopes
  int max_iterations = SolverOptions{}.max_iterations;
  double function_tolerance = kDemFunctionTolerance;
  bool features = false;  // the envelope-feature objective
  // Local relative error of the driver's substeps in the integrated predictions.
  double driver_tolerance = ObjectiveOptions{}.step.tolerance;
  // The driver's scheme there (a name of models::kSchemeNames, adaptive ones only).
  std::string driver_scheme =
      models::kSchemeNames[static_cast<int>(ObjectiveOptions{}.step.scheme)];
  // Most substeps of one integrated prediction during a fit (ObjectiveOptions::step).
  int max_substeps = ObjectiveOptions{}.step.max_substeps;
  std::string umat, umat_params;  // model umat: the UMAT's library and parameters file
  bool IsValid(std::string* why) const;
};

// The keys calibration.* of CalibrationSettings (defaults CalibrationSettings{}'s).
const OptionTable<CalibrationSettings>& calibration_option_table();
void register_calibration_keys(ScenarioSchema& schema);
// InputError naming the key for settings out of range.
CalibrationSettings calibration_settings_from(const Scenario& scenario);

struct CalibrationPlan {
  std::vector<std::string> models;  // model, or every law for "all"
  CalibrationOptions options;       // options.model is models.front()
  LoadOptions load;
};
// The one translation of the settings: holdout "none" is none, a held-out state joins an explicit
// list of states once, the DEM tolerances of solver.hpp; model umat loads the UMAT and makes it
// the session's (models/umat.hpp). InputError for settings out of range.
CalibrationPlan calibration_plan(const CalibrationSettings& settings);

}  // namespace rendulic::calibration
