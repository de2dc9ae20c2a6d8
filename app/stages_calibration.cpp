// The `calibration` run stage (stages_calibration.hpp, docs/calibration.md "Two levels").
// It reads the states and envelopes through a ResultsReader on the writer's temporary file
// (same process: HDF5 shares the open file, so everything written so far is visible) and
// writes /calibration/<model> through the same writer.
#include "stages_calibration.hpp"

#include <chrono>
#include <iostream>

#include "rendulic/calibration/calibrate.hpp"
#include "rendulic/calibration/report.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/models/law.hpp"

namespace rendulic::app {

void register_calibration_keys(ScenarioSchema& schema) {
  std::vector<std::string> choices = models::law_names();
  choices.insert(choices.begin(), "all");
  schema.add({.path = "calibration.model",
              .type = KeyType::kString,
              .default_value = std::string{"all"},
              .unit = "-",
              .help = "Constitutive law to calibrate against the envelopes and the path; all: "
                      "every family in turn, each under /calibration/<model>.",
              .choices = choices});
  schema.add({.path = "calibration.states",
              .type = KeyType::kStringList,
              .default_value = std::vector<std::string>{},
              .unit = "-",
              .help = "State labels to fit (empty: every state with envelopes)."});
  schema.add({.path = "calibration.holdout",
              .type = KeyType::kStringList,
              .default_value = std::vector<std::string>{"auto"},
              .unit = "-",
              .help = "State labels predicted but not fitted (held-out error); [\"auto\"]: with "
                      "three states or more every second one inside the path (a..e: b and d); "
                      "[] or [\"none\"]: none."});
  schema.add({.path = "calibration.backend",
              .type = KeyType::kString,
              .default_value = std::string{"ceres"},
              .unit = "-",
              .help = "ceres (local least squares), multistart, global (NLopt global + "
                      "BOBYQA + Ceres polish) or bobyqa.",
              .choices = {"ceres", "multistart", "global", "bobyqa"}});
  schema.add({.path = "calibration.path",
              .type = KeyType::kBool,
              .default_value = true,
              .unit = "-",
              .help = "Fit the main undrained path together with the envelopes."});
  schema.add({.path = "calibration.max_iterations",
              .type = KeyType::kInt,
              .default_value = std::int64_t{calibration::SolverOptions{}.max_iterations},
              .unit = "-",
              .help = "Most iterations of the Ceres stage per model; a fit that reaches it is "
                      "reported as not converged.",
              .min = 1.0,
              .max = 10000.0});
  schema.add({.path = "calibration.function_tolerance",
              .type = KeyType::kDouble,
              .default_value = calibration::kDemFunctionTolerance,
              .unit = "-",
              .help = "Ceres stops when an iteration lowers the cost by less than this "
                      "fraction: a backstop; with exact derivatives the fits stop by their "
                      "gradient or parameter tolerance (docs/calibration.md).",
              .min = 1e-16,
              .max = 0.1});
  schema.add({.path = "calibration.features",
              .type = KeyType::kBool,
              .default_value = false,
              .unit = "-",
              .help = "Add the envelope-feature objective (centre and affine matrix)."});
}

void run_calibration_stage(const Scenario& scenario, ResultsWriter& out, const RunContext& ctx) {
  using namespace rendulic::calibration;
  CalibrationOptions opt;
  const std::string model = scenario.get_string("calibration.model");
  opt.holdout = scenario.get_strings("calibration.holdout");
  if (opt.holdout.size() == 1 && opt.holdout[0] == "none") opt.holdout.clear();
  opt.solver.backend = backend_from_string(scenario.get_string("calibration.backend"));
  opt.solver.max_iterations = static_cast<int>(scenario.get_int("calibration.max_iterations"));
  opt.solver.function_tolerance = scenario.get_double("calibration.function_tolerance");
  opt.solver.gradient_tolerance = calibration::kDemGradientTolerance;
  opt.objective.path = scenario.get_bool("calibration.path");
  opt.objective.envelope_features = scenario.get_bool("calibration.features");
  LoadOptions lo;
  lo.states = scenario.get_strings("calibration.states");
  if (!lo.states.empty())
    for (const auto& h : opt.holdout)
      if (h != "auto") lo.states.push_back(h);
  lo.load_path = opt.objective.path;
  const CalibrationData data = load_calibration_data(out.temporary_path(), lo);
  const std::vector<std::string> models =
      model == "all" ? models::law_names() : std::vector<std::string>{model};
  std::vector<ModelScore> scores;
  for (const std::string& m : models) {
    opt.model = m;
    // Said before and after: an integrated law's fit takes seconds to minutes (quick.toml's
    // elastoplastic_fabric ~20 s), and a silent run looks hung.
    if (!ctx.quiet) std::cerr << "rendulic: calibrating " << m << std::endl;
    const auto t0 = std::chrono::steady_clock::now();
    try {
      const CalibrationSummary summary = calibrate(data, opt);
      write_calibration(out, summary);
      scores.push_back(summary.score);
      if (!ctx.quiet) {
        std::cout << summary.BriefReport() << std::flush;
        std::cerr << "rendulic: calibrated " << m << " in "
                  << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()
                  << " s" << std::endl;
      }
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      // One family that cannot be fitted to these data (e.g. its driver fails on every
      // start) is a finding, not a reason to lose the others: recorded, said, skipped.
      const std::string g = paths::calibration(m);
      out.attr(g, "converged", std::int64_t{0});
      out.attr(g, "error", std::string(e.what()));
      std::cerr << "rendulic: warning: calibration of " << m << " failed: " << e.what() << "\n";
    }
  }
  // Which law this scene needs (docs/calibration.md "Model selection").
  if (!scores.empty()) {
    const Selection sel = select_model(scores);
    write_selection(out, sel);
    if (!ctx.quiet) std::cout << "model selection: " << sel.sentence << "\n" << std::flush;
  }
}

}  // namespace rendulic::app
