// Stage table of `rendulic run` (see pipeline.hpp); the names and their order follow the
// protocol of docs/physics.md section 4.
#include "pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <functional>
#include <string>
#include <vector>

#include "packing_system.hpp"
#include "progress.hpp"
#include "rendulic/calibration/settings.hpp"
#include "rendulic/core/comma_list.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/log.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/dem/probe_campaign.hpp"
#include "rendulic/dem/probe_elastic_range.hpp"
#include "rendulic/dem/scenario_keys.hpp"
#include "report.hpp"
#include "stages.hpp"
#include "stages_calibration.hpp"

namespace rendulic::app {

namespace {

// The DEM stages hand the live system on through the session; the stages after them read
// what was written.
using StageFn =
    std::function<void(const Scenario&, ResultsWriter&, const RunContext&, DemRunSession&)>;
using PostFn =
    std::function<void(const Scenario&, const std::filesystem::path&, const RunContext&)>;
struct Stage {
  const char* name;
  StageFn run;  // empty for a stage that only reads the committed file
  PostFn post;  // runs on the committed file instead (the report reads what was written)
  bool reads_the_run = false;  // works on what the DEM stages before it wrote
  // The stages of which at least one must run before it in the same run: what it works on
  // lives only in the run's memory (the live packing, the path's snapshots, the relaxed states)
  // or, for the calibration, is the envelopes the run measures.
  std::vector<std::string> needs_one_of = {};
};

void report_stage(const Scenario& scenario, const std::filesystem::path& results,
                  const RunContext& ctx) {
  (void)ctx;
  log::info("[report] started");
  const auto path = write_report(results, scenario.get_bool("report.figures"));
  log::info("[report] wrote ", path.string());
}

const std::vector<Stage>& stages() {
  static const std::vector<Stage> table = {
      {.name = "prepare", .run = stage_prepare},
      {.name = "isotropic", .run = stage_isotropic, .needs_one_of = {"prepare"}},
      {.name = "path", .run = stage_path, .needs_one_of = {"prepare"}},
      {.name = "states", .run = stage_states, .needs_one_of = {"path"}},
      {.name = "elastic_range", .run = stage_elastic_range, .needs_one_of = {"states"}},
      {.name = "probes", .run = stage_probes, .needs_one_of = {"states"}},
      {.name = "linear_response", .run = stage_linear_response, .needs_one_of = {"states"}},
      {.name = "pressure", .run = stage_pressure, .needs_one_of = {"isotropic"}},
      {.name = "fits",
       .run = [](const Scenario& sc, ResultsWriter& out, const RunContext& ctx,
                 DemRunSession&) { stage_fits(sc, out, ctx); },
       .reads_the_run = true},
      {.name = "calibration",
       .run = [](const Scenario& sc, ResultsWriter& out, const RunContext& ctx,
                 DemRunSession&) { run_calibration_stage(sc, out, ctx); },
       .reads_the_run = true,
       .needs_one_of = {"probes", "linear_response"}},
      {.name = "report", .post = report_stage},
  };
  return table;
}

}  // namespace

bool stage_requested(const Scenario& scenario, const std::string& name) {
  for (const auto& s : scenario.get_strings("run.stages"))
    if (s == name) return true;
  return false;
}

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
              .help =
                  "Stages to run, executed in the fixed order prepare, isotropic, path, "
                  "states, elastic_range, probes, linear_response, pressure, fits, calibration, "
                  "report; each at most once, and each with the stages it builds on (docs/usage.md "
                  "\"Results are atomic\").",
              .choices = names,
              .distinct = true});
  schema.add({.path = "report.figures",
              .type = KeyType::kBool,
              .default_value = true,
              .unit = "-",
              .help =
                  "Draw the figures (PNG, PDF and SVG) next to report.md; needs python3-matplotlib "
                  "and python3-h5py."});
  schema.add({.path = "run.description",
              .type = KeyType::kString,
              .default_value = std::string{},
              .unit = "-",
              .help = "Free text stored with the results."});
}

namespace {
void check_friction(const Scenario& scenario) {
  // The energy minimisation models frictionless contacts only (packing_of, docs/dem.md
  // "Friction"; the linear response has a frictional path, docs/probes.md): a
  // frictional run that asks for one would otherwise fail after its preparation and path.
  const double mu = scenario.get_double("dem.friction");
  if (!(mu > 0)) return;
  std::vector<std::string> asked;
  const bool probes = stage_requested(scenario, "probes");
  const auto methods = scenario.get_strings("probes.methods");
  if (probes && std::find(methods.begin(), methods.end(), "minimisation") != methods.end())
    asked.push_back("probes.methods has minimisation (" + scenario.origin("probes.methods") + ")");
  if (stage_requested(scenario, "elastic_range") &&
      scenario.get_string("elastic_range.method") == "minimisation")
    asked.push_back("elastic_range.method is minimisation (" +
                    scenario.origin("elastic_range.method") + ")");
  if (asked.empty()) return;
  std::string list;
  for (const std::string& a : asked) list += (list.empty() ? "" : "; ") + a;
  throw InputError("dem.friction = " + decimal_g(mu) + " (" + scenario.origin("dem.friction") +
                   "): the energy minimisation models frictionless contacts only, but " + list +
                   "; use the dynamic method or dem.friction = 0");
}

void check_servo(const Scenario& scenario, const dem::DemRunOptions& o) {
  // The servo's gain per step is path.servo_gain x dem.dt_factor times the packing's K*
  // (O(0.1 .. 1)): beyond 2 the explicit servo overshoots more each step, and the rate bound
  // turns it into a swing between the bounds (docs/dem.md "Paths"). 1 keeps a margin for K*.
  const bool path = (stage_requested(scenario, "path") || stage_requested(scenario, "pressure")) &&
                    dem::path_type(o.path.type).mixed();
  const bool hold = stage_requested(scenario, "isotropic") && o.loading.target_pressure_star > 0;
  const double step_gain = o.path.servo_gain * o.system.dt_factor;
  if (!(path || hold) || step_gain <= 1) return;
  throw InputError("path.servo_gain = " + decimal_g(o.path.servo_gain) + " (" +
                   scenario.origin("path.servo_gain") +
                   ") with dem.dt_factor = " + decimal_g(o.system.dt_factor) + " gives the " +
                   (path ? "path's lateral servo" : "hold at isotropic.pressure_star") +
                   " a gain of " + decimal_g(step_gain) +
                   " per step, beyond the explicit limit of 1: lower either");
}
}  // namespace

void check_stages_available(const Scenario& scenario) {
  // A run that computes nothing would replace an existing results.h5 with an empty file; so
  // would one of fits or calibration alone (`--set run.stages=fits` wrote a file of nothing in
  // place of the run's): they read what the DEM stages before them wrote.
  bool computes = false, reads_the_run = false;
  for (const auto& s : stages()) {
    if (!stage_requested(scenario, s.name) || !s.run) continue;
    computes = computes || !s.reads_the_run;
    reads_the_run = reads_the_run || s.reads_the_run;
  }
  if (!computes && reads_the_run)
    throw InputError("run.stages (" + scenario.origin("run.stages") +
                     "): fits and calibration read what the DEM stages before them wrote; for an "
                     "existing file use `rendulic fit --results FILE.h5` or `rendulic calibrate "
                     "--results FILE.h5`");
  if (!computes)
    throw InputError("run.stages (" + scenario.origin("run.stages") +
                     "): no stage that computes anything; the report of an existing file is "
                     "`rendulic report FILE.h5`");
  // A stage whose input the run would not make failed only when its turn came, after the
  // stages before it (`run.stages = prepare, probes` prepared, then said "needs 'states'").
  for (const auto& s : stages()) {
    if (!stage_requested(scenario, s.name) || s.needs_one_of.empty()) continue;
    if (std::any_of(s.needs_one_of.begin(), s.needs_one_of.end(),
                    [&](const std::string& n) { return stage_requested(scenario, n); }))
      continue;
    std::string needed;
    for (std::size_t k = 0; k < s.needs_one_of.size(); ++k)
      needed += (k ? " or '" : "'") + s.needs_one_of[k] + "'";
    throw InputError(
        "run.stages (" + scenario.origin("run.stages") + "): stage '" + s.name +
        "' needs the stage " + needed + " in the same run" +
        (s.needs_one_of.front() == "states"
             ? "; to probe a state of an existing file: `rendulic probe FILE.h5:LABEL`"
         : std::string(s.name) == "calibration"
             ? "; to calibrate on an existing file: `rendulic calibrate --results FILE.h5`"
             : ""));
  }
  // Cross-key rules of the DEM and probe stages, before the first (possibly long) stage runs.
  const dem::DemRunOptions dem_options = dem::dem_options_from_scenario(scenario);
  check_friction(scenario);
  check_servo(scenario, dem_options);
  if (stage_requested(scenario, "probes") || stage_requested(scenario, "linear_response") ||
      stage_requested(scenario, "elastic_range"))
    dem::probe_options_from(scenario);
  if (stage_requested(scenario, "elastic_range")) dem::elastic_range_options_from(scenario);
  if (stage_requested(scenario, "pressure") &&
      scenario.get_doubles("pressure.volume_fractions").empty())
    throw InputError("run: stage 'pressure' needs pressure.volume_fractions (" +
                     scenario.origin("pressure.volume_fractions") + ")");
  // The calibration's settings too (a UMAT's library and parameters file are loaded here).
  if (stage_requested(scenario, "calibration")) {
    calibration::calibration_plan(calibration::calibration_settings_from(scenario));
    // The labels it names are this run's states (a mistyped one failed after every DEM stage).
    const auto& labels = dem_options.state_labels;
    for (const char* key : {"calibration.states", "calibration.holdout"})
      for (const std::string& label : scenario.get_strings(key)) {
        if (std::string(key) == "calibration.holdout" && (label == "auto" || label == "none"))
          continue;
        if (std::find(labels.begin(), labels.end(), label) != labels.end()) continue;
        throw InputError(std::string(key) + " (" + scenario.origin(key) + "): no state '" + label +
                         "' in this run (states.labels: " + comma_list(labels) + ")");
      }
  }
}

ResumePlan resume_plan(const Scenario& scenario, const ResultsReader& kept) {
  ResumePlan plan;
  if (!kept.has_attr("/", "scenario")) return plan;  // nothing kept
  // Compared setting by setting, not as text: the same scenario file given by another path was
  // refused as "another scenario", and the refusal did not say which setting differed.
  const auto differ = scenario.differences_from(kept.attr_string("/", "scenario"));
  if (!differ.empty()) {
    std::string which;
    for (std::size_t i = 0; i < differ.size() && i < 3; ++i)
      which += (i ? "; " : "") + differ[i].key + " = " + differ[i].stored + " there, " +
               differ[i].now + " now";
    if (differ.size() > 3) which += "; and " + std::to_string(differ.size() - 3) + " more";
    throw InputError("run --resume: " + kept.path().string() +
                     " holds the stages of another scenario (" + which +
                     "); give the interrupted run's settings, or run without --resume");
  }
  for (const auto& s : stages()) {
    if (!stage_requested(scenario, s.name) || !s.run) continue;
    if (kept.has_attr(paths::kTimings, s.name)) {
      plan.completed.emplace_back(s.name);
      continue;
    }
    // Only the states at rest are stored with their checkpoints; the live system before them
    // and the loading's snapshots are not.
    for (const char* live : {"prepare", "isotropic", "path", "states", "pressure"})
      if (s.name == std::string(live)) {
        plan.why_not = std::string("stage '") + s.name +
                       "' needs the live DEM system of the stages before it, which the file does "
                       "not keep";
        plan.completed.clear();
        return plan;
      }
  }
  return plan;
}

bool holds_every_stage(const Scenario& scenario, const std::filesystem::path& results) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(results, ec)) return false;
  try {
    const ResultsReader file(results);
    if (!file.has_attr("/", "scenario") ||
        !scenario.differences_from(file.attr_string("/", "scenario")).empty())
      return false;
    for (const auto& s : stages())
      if (stage_requested(scenario, s.name) && s.run && !file.has_attr(paths::kTimings, s.name))
        return false;
    return true;
  } catch (const InputError&) {
    return false;  // damaged, or not ours: a plain run replaces it
  }
}

void run_pipeline(const Scenario& scenario, ResultsWriter& out, const RunContext& ctx,
                  const std::vector<std::string>& completed_before) {
  std::vector<std::string> completed = completed_before;
  DemRunSession session;
  auto was_completed = [&](const std::string& name) {
    return std::find(completed_before.begin(), completed_before.end(), name) !=
           completed_before.end();
  };
  if (was_completed("states")) {
    // The states as the states stage left them: restarted bit for bit from their checkpoints.
    session.options = dem::dem_options_from_scenario(scenario);
    const ResultsReader kept(out.temporary_path(), out.partial_path());
    for (const std::string& label : session.options->state_labels) {
      auto sys = restore_checkpoint(kept, paths::state(label), session.options->system);
      if (!sys)
        throw InputError("run --resume: state " + label + " has no checkpoint in " +
                         kept.path().string());
      session.relaxed.emplace_back(label, std::move(*sys));
    }
  }
  for (const auto& s : stages()) {
    if (!stage_requested(scenario, s.name) || !s.run) continue;
    if (was_completed(s.name)) continue;
    // Every stage says when it starts and ends, in a log as on a terminal: a short stage
    // shows no progress line of its own (progress.hpp).
    log::info("[", s.name, "] started");
    const auto t0 = std::chrono::steady_clock::now();
    s.run(scenario, out, ctx, session);
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    log::info("[", s.name, "] done in ", human_seconds(secs));
    out.attr(paths::kTimings, s.name, secs);  // wall seconds, reported in report.md
    // What a later failure keeps (results.h5.partial): hours of DEM are not thrown away.
    completed.emplace_back(s.name);
    out.save_partial("completed stages (" + comma_list(completed) + ")");
  }
}

void run_post_commit(const Scenario& scenario, const std::filesystem::path& results,
                     const RunContext& ctx) {
  for (const auto& s : stages())
    if (stage_requested(scenario, s.name) && s.post) s.post(scenario, results, ctx);
}

}  // namespace rendulic::app
