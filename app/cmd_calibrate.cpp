// `rendulic calibrate` (docs/calibration.md): fits a constitutive law to the
// envelopes (and main path) of a results file, per state and across states
// (calibration/calibrate.hpp), prints or writes the JSON (model, params, stderr, correlation,
// per_state.<label> with B, G, A and the plastic features) and, unless --no-write, stores
// /calibration/<model> in the results file through ResultsWriter::update (atomic: the file is
// replaced only once the new content is complete; an unwritable --out is refused first). Any
// rendulic/1 file qualifies, including envelopes from another DEM code converted to the schema.
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>

#include "cli_options.hpp"
#include "commands.hpp"
#include "rendulic/calibration/calibrate.hpp"
#include "rendulic/calibration/report.hpp"
#include "rendulic/calibration/settings.hpp"
#include "rendulic/core/comma_list.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/log.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/core/results.hpp"
#include "rendulic/core/text_file.hpp"
#include "rendulic/models/law.hpp"
#include "rendulic/models/umat.hpp"

namespace rendulic::app {
namespace {

// The settings the calibration stage also takes (calibration/settings.hpp), and what only the
// command has.
struct CalibrateArgs {
  calibration::CalibrationSettings settings;
  std::string results, out;
  std::vector<std::string> states, holdout, free, values;
  bool no_path = false, no_write = false, progress = false;
  int threads = 0;
};

// The names of a list option, split at its commas by CLI11, which drops empty items but keeps
// a lone empty value: `--states "$S"` with S unset. That meant the option's default (every
// state, the model's free parameters, no held-out state chosen) without a word.
const std::vector<std::string>& names_of(const std::vector<std::string>& names,
                                         const char* option) {
  for (const auto& n : names)
    if (n.empty())
      throw InputError(std::string(option) +
                       ": the list is empty (leave the option out for its default)");
  return names;
}

int run_calibrate(const CalibrateArgs& a) {
  using namespace rendulic::calibration;
  // Cheap checks first, so that bad input costs nothing and touches nothing.
  calibration::CalibrationSettings settings = a.settings;
  if (settings.model != "umat" && !models::make_law(settings.model)) {
    throw InputError("calibrate: unknown model '" + settings.model +
                     "' (known: " + comma_list(models::law_names()) + ")");
  }
  settings.states = names_of(a.states, "--states");
  if (const auto& h = names_of(a.holdout, "--holdout"); !h.empty()) settings.holdout = h;
  settings.path = !a.no_path;
  CalibrationPlan plan = calibration_plan(settings);
  CalibrationOptions& opt = plan.options;
  opt.solver.progress = a.progress;
  opt.solver.threads = a.threads;
  opt.free = names_of(a.free, "--free");
  // A UMAT's props are also named by their 1-based PROPS index (docs/umat.md).
  if (settings.model == "umat")
    for (auto& f : opt.free)
      if (!f.empty() &&
          std::all_of(f.begin(), f.end(), [](unsigned char c) { return std::isdigit(c); })) {
        const auto& info = models::session_umat()->parameter_info();
        // Only the digits' count bounds it: stoul of 99999999999999999999999 threw (exit 1).
        const std::size_t i = f.size() > 9 ? 0 : std::stoul(f);
        if (i < 1 || i > info.size())
          throw InputError("--free " + f + ": the UMAT has PROPS(1.." +
                           std::to_string(info.size()) + ")");
        f = info[i - 1].name;
      }
  // The names of --free and --value, looked up before the results file is read, and an
  // unknown name before a repeated one, which would send the user to mend the wrong thing.
  const std::unique_ptr<models::Law> law = models::make_law(settings.model);
  for (const auto& f : opt.free)
    if (law && law->parameter_index(f) < 0)
      throw InputError("--free: " + law->unknown_parameter(f));
  for (const auto& kv : names_of(a.values, "--value")) {
    const auto eq = kv.find('=');
    // "=3" was looked up as a parameter named '' ("unknown parameter '' of ...").
    if (eq == std::string::npos || eq == 0)
      throw InputError("--value '" + printable(kv) + "': expected name=number");
    const std::string name = kv.substr(0, eq), number = kv.substr(eq + 1);
    if (law && law->parameter_index(name) < 0)
      throw InputError("--value: " + law->unknown_parameter(name));
    // K=1,K=2 kept the last without a word.
    if (opt.values.count(name)) throw InputError("--value: parameter '" + name + "' given twice");
    const std::optional<double> v = decimal_number(number);
    if (!v) throw InputError("--value '" + printable(kv) + "': " + not_a_decimal_number(number));
    opt.values[name] = *v;
  }
  // Made now, so that an --out that cannot be written is refused before the calibration runs
  // and before results.h5 is touched.
  std::optional<AtomicTextFile> json_out;
  if (!a.out.empty()) json_out.emplace(a.out, "the JSON output");
  const CalibrationData data = load_calibration_data(a.results, plan.load);
  const CalibrationSummary summary = calibrate(data, opt);
  const std::string json = to_json(summary);
  // "When the file is ours": a rendulic/1 file (the reader refused anything else)
  // that we may replace. A read-only file or folder is still calibrated, just not written to.
  const std::filesystem::path rp(a.results);
  const std::filesystem::path folder = rp.has_parent_path() ? rp.parent_path() : ".";
  const bool writable =
      ::access(a.results.c_str(), W_OK) == 0 && ::access(folder.c_str(), W_OK) == 0;
  if (!a.no_write && !writable)
    log::warning(a.results, " is read-only: /calibration/", settings.model, " not written");
  // The JSON is complete on disk before the results file is replaced: a failure to write
  // it must not leave the results file changed and the command failed.
  if (json_out) {
    json_out->stream() << json;
    json_out->flush();
  }
  if (!a.no_write && writable) {
    ResultsWriter w = ResultsWriter::update(a.results);
    for (const auto& note : w.notes()) log::info(note);
    // The selection over every law now in the file (the others as stored), read while the
    // update holds the file: a calibration of another law that ended meanwhile is in it.
    std::vector<ModelScore> scores{summary.score};
    {
      const ResultsReader r(a.results);
      if (r.exists(paths::kCalibration))
        for (const auto& m : r.children(paths::kCalibration)) {
          ModelScore ms;
          if (m != settings.model && read_model_score(r, m, &ms)) scores.push_back(ms);
        }
    }
    write_calibration(w, summary);
    write_selection(w, select_model(scores));
    w.commit();
  }
  if (json_out) {
    json_out->commit();
    std::cout << summary.BriefReport();
  } else {
    std::cout << json;
  }
  return 0;
}

}  // namespace

Subcommand add_calibrate(CLI::App& parent) {
  auto* sub = parent.add_subcommand(
      "calibrate", "Fit a constitutive model to the envelopes and path of a results file");
  auto args = std::make_shared<CalibrateArgs>();
  sub->add_option("--results", args->results, "Results file (HDF5, schema rendulic/2 or 1)")
      ->required();
  const auto& keys = calibration::calibration_option_table();
  sub->add_option("--model", args->settings.model,
                  "Model: isotropic_elastic, anisotropic_elastic, hypoplastic_wu, "
                  "elastoplastic_fabric, umat (with --umat and --params)")
      ->required();
  add_key_option(sub, "--umat", args->settings.umat, keys.key("calibration.umat"));
  add_key_option(sub, "--params", args->settings.umat_params, keys.key("calibration.umat_params"));
  sub->add_option("--states", args->states,
                  "States to use, comma separated (default: all with envelopes)")
      ->delimiter(',');
  sub->add_option("--out", args->out, "Write the JSON here (default: print it)");
  sub->add_option("--holdout", args->holdout,
                  "States to predict but not fit (held-out check), comma separated; default "
                  "auto (every second state inside the path), none for no held-out state")
      ->delimiter(',');
  add_key_option(sub, "--backend", args->settings.backend, keys.key("calibration.backend"));
  sub->add_option("--free", args->free,
                  "Free parameters, comma separated (default: per model; a UMAT's props by name "
                  "or PROPS index)")
      ->delimiter(',');
  sub->add_option("--value", args->values,
                  "name=value: start value of a free parameter or value of a fixed one")
      ->delimiter(',');
  sub->add_flag("--no-path", args->no_path, "Ignore the main path (envelopes only)");
  sub->add_flag("--features", args->settings.features, keys.key("calibration.features").help);
  add_key_option(sub, "--max-iterations", args->settings.max_iterations,
                 keys.key("calibration.max_iterations"));
  add_key_option(sub, "--function-tolerance", args->settings.function_tolerance,
                 keys.key("calibration.function_tolerance"));
  add_key_option(sub, "--driver-tolerance", args->settings.driver_tolerance,
                 keys.key("calibration.driver_tolerance"));
  add_key_option(sub, "--driver-scheme", args->settings.driver_scheme,
                 keys.key("calibration.driver_scheme"));
  add_key_option(sub, "--max-substeps", args->settings.max_substeps,
                 keys.key("calibration.max_substeps"));
  sub->add_flag("--progress", args->progress, "Print Ceres's iterations (cost, step) to stdout");
  sub->add_option("--threads", args->threads,
                  "Threads (0, the default: all cores): the likelihood's two starts side by side "
                  "and the exact Jacobians on a free core; results do not depend on it")
      ->check(thread_count());
  sub->add_flag("--no-write", args->no_write,
                "Do not store /calibration/<model> in the results file");
  return {sub, [args]() -> int { return run_calibrate(*args); }};
}

}  // namespace rendulic::app
