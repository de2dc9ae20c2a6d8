// The stages of `rendulic run` (docs/usage.md, docs/dem.md; docs/physics.md section 4): a table
// from stage name to the function that runs it against the open results file. The scenario key
// run.stages picks which run, in the table's order.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "rendulic/core/results.hpp"
#include "rendulic/core/scenario.hpp"

namespace rendulic::app {

struct RunContext {
  std::filesystem::path out_dir;
  int threads = 0;     // 0: OpenMP's default
  bool quiet = false;  // no progress display and no info lines (log level warning)
  // In a log (stderr not a terminal): seconds of work between two progress lines.
  double progress_every = 30.0;
};

// Whether run.stages lists the stage `name`.
bool stage_requested(const Scenario& scenario, const std::string& name);
// Registers the run.* keys (seed, stages, ...).
void register_run_keys(ScenarioSchema& schema);
// Checks, before the first stage runs, that the stage list computes something and that the
// cross-key rules of the requested stages hold (InputError otherwise).
void check_stages_available(const Scenario& scenario);
// Runs every requested stage, in order, writing into `out`; wall time per stage goes to the
// attributes of /timings. The stages in `completed` (a resumed run's, resume_plan()) are
// already in `out` and are skipped; the states they left are restored from their checkpoints.
void run_pipeline(const Scenario& scenario, ResultsWriter& out, const RunContext& ctx,
                  const std::vector<std::string>& completed = {});
// What the kept stages of an interrupted run (ResultsWriter::resume) let `run --resume` skip
// (docs/usage.md "Resuming a run"): `completed` its requested stages that are in `kept`, or
// empty, with the reason in `why_not`, when the run must start over: a stage still to run needs
// the live system of the DEM stages before it (prepare .. states, and pressure, which needs the
// loading's snapshots), which a results file does not keep. InputError if `kept` is another
// scenario's.
struct ResumePlan {
  std::vector<std::string> completed;
  std::string why_not;
};
ResumePlan resume_plan(const Scenario& scenario, const ResultsReader& kept);
// Whether `results` is a whole run of `scenario`: ours, the same scenario text, and every
// requested stage that computes in it. A file that is not readable is not one.
bool holds_every_stage(const Scenario& scenario, const std::filesystem::path& results);
// Stages that read the committed results file (the report), run after commit().
void run_post_commit(const Scenario& scenario, const std::filesystem::path& results,
                     const RunContext& ctx);

}  // namespace rendulic::app
