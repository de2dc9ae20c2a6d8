// The calibration settings, their keys and their one translation (settings.hpp).
#include "rendulic/calibration/settings.hpp"

#include <algorithm>

#include "rendulic/core/errors.hpp"
#include "rendulic/models/law.hpp"
#include "rendulic/models/umat.hpp"

namespace rendulic::calibration {

const OptionTable<CalibrationSettings>& calibration_option_table() {
  using Row = OptionRow<CalibrationSettings>;
  static const OptionTable<CalibrationSettings> table = [] {
    std::vector<std::string> models = models::law_names();
    models.insert(models.begin(), "all");
    models.push_back("umat");
    return OptionTable<CalibrationSettings>({
        Row{{.path = "calibration.model",
             .unit = "-",
             .help = "Constitutive law to calibrate against the envelopes and the path; all: "
                     "every family in turn, each under /calibration/<model>; umat: the Abaqus "
                     "UMAT of calibration.umat (docs/umat.md).",
             .choices = models},
            [](CalibrationSettings& s) -> std::string& { return s.model; }},
        Row{{.path = "calibration.states",
             .unit = "-",
             .help = "State labels to fit (empty: every state with envelopes).",
             .distinct = true},
            [](CalibrationSettings& s) -> std::vector<std::string>& { return s.states; }},
        Row{{.path = "calibration.holdout",
             .unit = "-",
             .help = "State labels predicted but not fitted (held-out error); [\"auto\"]: with "
                     "three states or more every second one inside the path (a..e: b and d); "
                     "[] or [\"none\"]: none.",
             .distinct = true},
            [](CalibrationSettings& s) -> std::vector<std::string>& { return s.holdout; }},
        Row{{.path = "calibration.backend",
             .unit = "-",
             .help = "ceres (local least squares), multistart, global (NLopt global + "
                     "BOBYQA + Ceres polish) or bobyqa.",
             .choices = {"ceres", "multistart", "global", "bobyqa"}},
            [](CalibrationSettings& s) -> std::string& { return s.backend; }},
        Row{{.path = "calibration.path",
             .unit = "-",
             .help = "Fit the main undrained path together with the envelopes."},
            [](CalibrationSettings& s) -> bool& { return s.path; }},
        Row{{.path = "calibration.max_iterations",
             .unit = "-",
             .help = "Most iterations of the Ceres stage per model; a fit that reaches it is "
                     "reported as not converged.",
             .min = 1.0,
             .max = 10000.0},
            [](CalibrationSettings& s) -> int& { return s.max_iterations; }},
        Row{{.path = "calibration.function_tolerance",
             .unit = "-",
             .help = "Ceres stops when an iteration lowers the cost by less than this "
                     "fraction: a backstop; with exact derivatives the fits stop by their "
                     "gradient or parameter tolerance (docs/calibration.md).",
             .min = 1e-16,
             .max = 0.1},
            [](CalibrationSettings& s) -> double& { return s.function_tolerance; }},
        Row{{.path = "calibration.features",
             .unit = "-",
             .help = "Add the envelope-feature objective (centre and affine matrix)."},
            [](CalibrationSettings& s) -> bool& { return s.features; }},
        Row{{.path = "calibration.driver_tolerance",
             .unit = "-",
             .help = "Local relative error per substep of the integrated predictions (probes "
                     "above 1e-4 and the path). 1e-4 fits the elasto-plastic law about 3x faster "
                     "but may stop in another basin (docs/calibration.md 'Predictions and "
                     "derivatives').",
             .min = 1e-10,
             .max = 1e-2},
            [](CalibrationSettings& s) -> double& { return s.driver_tolerance; }},
        Row{{.path = "calibration.driver_scheme",
             .unit = "-",
             .help = "Scheme of the integrated predictions: auto (the third-order "
                     "bogacki-shampine for a law without a yield surface, modified-euler for one "
                     "with it), modified-euler or bogacki-shampine for every law "
                     "(docs/calibration.md 'Predictions and derivatives').",
             .choices = {"auto", "modified-euler", "bogacki-shampine"}},
            [](CalibrationSettings& s) -> std::string& { return s.driver_scheme; }},
        Row{{.path = "calibration.max_substeps",
             .unit = "-",
             .help = "Most driver substeps of one integrated prediction during a fit; a trial "
                     "point that needs more counts as not evaluable. The calibration warns when "
                     "its optimum needs half of it or more (docs/calibration.md 'When to stop').",
             .min = 10,
             .max = 10000000},
            [](CalibrationSettings& s) -> int& { return s.max_substeps; }},
        Row{{.path = "calibration.umat",
             .unit = "-",
             .help = "Shared library of an Abaqus UMAT (entry umat_ or umat) for model umat "
                     "(docs/umat.md)."},
            [](CalibrationSettings& s) -> std::string& { return s.umat; }},
        Row{{.path = "calibration.umat_params",
             .unit = "-",
             .help = "Parameters file of the UMAT: props, prop_names, nstatv, statev and the "
                     "[bounds] of the free props (docs/umat.md)."},
            [](CalibrationSettings& s) -> std::string& { return s.umat_params; }},
    });
  }();
  return table;
}

bool CalibrationSettings::IsValid(std::string* why) const {
  return calibration_option_table().check(*this, why);
}

void register_calibration_keys(ScenarioSchema& schema) {
  calibration_option_table().register_keys(schema);
}

CalibrationSettings calibration_settings_from(const Scenario& scenario) {
  CalibrationSettings s;
  calibration_option_table().read(scenario, s);
  return s;
}

CalibrationPlan calibration_plan(const CalibrationSettings& s) {
  std::string why;
  if (!s.IsValid(&why)) throw InputError(why);
  if (s.model == "umat") {
    if (s.umat.empty() || s.umat_params.empty())
      throw InputError(
          "model umat needs calibration.umat and calibration.umat_params (--umat "
          "PATH.so and --params FILE.toml): the UMAT's library and parameters file");
    std::shared_ptr<const models::UmatLaw> u = models::make_umat_law(s.umat, s.umat_params);
    models::set_session_umat(std::move(u));
  } else if (!s.umat.empty()) {
    throw InputError("calibration.umat (--umat) goes with model umat, not " + s.model);
  }
  CalibrationPlan p;
  p.models = s.model == "all" ? models::law_names() : std::vector<std::string>{s.model};
  CalibrationOptions& opt = p.options;
  opt.model = p.models.front();
  opt.holdout = s.holdout;
  if (opt.holdout.size() == 1 && opt.holdout[0] == "none") opt.holdout.clear();
  opt.solver.backend = backend_from_string(s.backend);
  opt.solver.max_iterations = s.max_iterations;
  opt.solver.function_tolerance = s.function_tolerance;
  opt.solver.gradient_tolerance = kDemGradientTolerance;
  opt.objective.path = s.path;
  opt.objective.envelope_features = s.features;
  opt.objective.step.tolerance = s.driver_tolerance;
  // The key's choices are names of kSchemeNames (IsValid above).
  models::scheme_from_name(s.driver_scheme, &opt.objective.step.scheme);
  opt.objective.step.max_substeps = s.max_substeps;
  p.load.states = s.states;
  // Held-out states are predicted, so their data must be loaded too.
  if (!p.load.states.empty())
    for (const auto& h : opt.holdout)
      if (h != "auto" &&
          std::find(p.load.states.begin(), p.load.states.end(), h) == p.load.states.end())
        p.load.states.push_back(h);
  p.load.load_path = s.path;
  return p;
}

}  // namespace rendulic::calibration
