// The `calibration` run stage (stages_calibration.hpp, docs/calibration.md "Two levels").
// It reads the states and envelopes through a ResultsReader on the writer's temporary file
// (same process: HDF5 shares the open file, so everything written so far is visible) and
// writes /calibration/<model> through the same writer.
#include "stages_calibration.hpp"

#include <chrono>
#include <iostream>

#include "progress.hpp"
#include "rendulic/calibration/calibrate.hpp"
#include "rendulic/calibration/report.hpp"
#include "rendulic/calibration/settings.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/log.hpp"
#include "rendulic/core/result_paths.hpp"

namespace rendulic::app {

void run_calibration_stage(const Scenario& scenario, ResultsWriter& out, const RunContext& ctx) {
  using namespace rendulic::calibration;
  CalibrationPlan plan = calibration_plan(calibration_settings_from(scenario));
  CalibrationOptions& opt = plan.options;
  opt.solver.threads = ctx.threads;  // --threads: the fits' threads too (docs/calibration.md)
  const CalibrationData data = load_calibration_data(out.read_back(), plan.load);
  const std::vector<std::string>& models = plan.models;
  std::vector<ModelScore> scores;
  // One report per law: a stop asked for (Ctrl-C in Python) ends the stage between two laws,
  // since a law's fit itself is not interruptible.
  Progress progress(ctx, "calibration");
  for (const std::string& m : models) {
    progress.start_task(m);
    progress.count(&m - models.data(), static_cast<long>(models.size()));
    opt.model = m;
    // Said before and after: an integrated law's fit takes seconds to minutes (quick.toml's
    // elastoplastic_fabric ~20 s), and a silent run looks hung.
    log::info("[calibration] ", m, " (", &m - models.data() + 1, " of ", models.size(), ")");
    const auto t0 = std::chrono::steady_clock::now();
    try {
      const CalibrationSummary summary = calibrate(data, opt);
      write_calibration(out, summary);
      scores.push_back(summary.score);
      if (!ctx.quiet) {
        std::cout << summary.BriefReport() << std::flush;
        log::info(
            "[calibration] ", m, " calibrated in ",
            human_seconds(
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()));
      }
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      // One family that cannot be fitted to these data (e.g. its driver fails on every
      // start) is a finding, not a reason to lose the others: recorded, said, skipped.
      const std::string g = paths::calibration(m);
      out.attr(g, "converged", std::int64_t{0});
      out.attr(g, "error", std::string(e.what()));
      log::warning("calibration of ", m, " failed: ", e.what());
    }
  }
  // Which law this scene needs (docs/calibration.md "Likelihood and model selection").
  if (!scores.empty()) {
    const Selection sel = select_model(scores);
    write_selection(out, sel);
    if (!ctx.quiet) std::cout << "model selection: " << sel.sentence << "\n" << std::flush;
  }
}

}  // namespace rendulic::app
