// `rendulic run SCENARIO.toml [--out DIR] [--set key=value ...] [--threads N]` (docs/usage.md).
// Validation happens in full before anything touches the disk: a bad scenario or override
// exits 2 and writes nothing. The results file is written under a temporary name and renamed
// to DIR/results.h5 only when every stage succeeded; a run that fails (or is stopped by a
// signal) after a stage completed keeps those stages in DIR/results.h5.partial and says so in
// its error line (docs/usage.md "Results are atomic"); `--resume` continues from them
// (docs/usage.md "Resuming a run").
// Under `mpirun -np K` (a build with RENDULIC_MPI) rank 0 runs all of this and alone prints and
// writes; ranks 1..K-1 only compute their share of the probe campaigns (probe_mpi.hpp) and are
// released when rank 0 returns or throws.
#include <omp.h>

#include <memory>
#include <optional>

#include "cli_options.hpp"
#include "commands.hpp"
#include "pipeline.hpp"
#include "rendulic/core/comma_list.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/log.hpp"
#include "rendulic/core/results.hpp"
#include "rendulic/dem/probe_campaign.hpp"
#include "rendulic/dem/probe_mpi.hpp"
#include "report.hpp"

namespace rendulic::app {
std::filesystem::path run_scenario(const RunRequest& r) {
  check_thread_count(r.threads);
  refuse_empty_output_folder(r.out);
  if (r.quiet) log::set_level(log::Level::kWarning);
  Scenario scenario = Scenario::from_file(r.scenario, scenario_schema());
  for (const auto& s : r.sets) scenario.apply_override(s);
  check_stages_available(scenario);
  if (r.threads > 0) omp_set_num_threads(r.threads);
  const std::filesystem::path out_dir = r.out;
  const std::filesystem::path final_path = out_dir / "results.h5";
  if (stage_requested(scenario, "report"))
    check_report_destination(out_dir, scenario.get_bool("report.figures"));
  const RunContext ctx{out_dir, r.threads, r.quiet, r.progress_every};
  std::optional<ResultsWriter> writer;
  std::vector<std::string> completed;
  if (r.resume) {
    writer.emplace(ResultsWriter::resume(final_path));
    for (const auto& note : writer->notes()) log::info(note);
    // A batch job resubmitted after its run had finished (a requeue, a retry loop) ran every
    // stage again. Only the report, which comes after the commit, may still be missing.
    std::error_code ec;
    if (!std::filesystem::exists(writer->partial_path(), ec) &&
        holds_every_stage(scenario, final_path)) {
      writer.reset();
      log::info("resume: ", final_path.string(),
                " already holds every stage of this scenario; nothing to run",
                stage_requested(scenario, "report") ? " (the report is written again)" : "");
      run_post_commit(scenario, final_path, ctx);
      return final_path;
    }
    // The working copy of DIR/results.h5.partial, named as that file in any message.
    const ResumePlan plan =
        resume_plan(scenario, ResultsReader(writer->temporary_path(), writer->partial_path()));
    completed = plan.completed;
    if (completed.empty()) {
      log::info("resume: ", plan.why_not.empty() ? "no completed stage kept" : plan.why_not,
                "; running every stage");
      writer.reset();  // its temporary file goes before the new writer makes its own
    } else {
      log::info("resume: the stages ", comma_list(completed), " are taken from ",
                writer->partial_path().string());
    }
  }
  if (!writer) writer.emplace(final_path);
  ResultsWriter& out = *writer;
  if (!r.resume)
    for (const auto& note : out.notes()) log::info(note);
  out.attr("/", "seed", scenario.get_int("run.seed"));
  out.attr("/", "scenario", scenario.to_toml());
  out.attr("/", "scenario_file", r.scenario);
  {
    // Say first what will run, on what, and where it goes.
    log::info(r.scenario, ": N = ", scenario.get_int("dem.n_particles"), ", stages ",
              comma_list(scenario.get_strings("run.stages")), "; writing ",
              (out_dir / "results.h5").string(),
              " (on 2 idle cores quick.toml takes under a minute, paper.toml about 10 min)");
  }
  if (r.mpi_ranks > 1) log::info(r.mpi_ranks, " MPI ranks share the probe campaigns");
  try {
    run_pipeline(scenario, out, ctx, completed);
    out.commit();
  } catch (...) {
    if (const std::string kept = out.keep_partial(); !kept.empty()) rethrow_with_note(kept);
    throw;
  }
  if (r.resume) {
    std::error_code ec;  // the kept stages are in the final file now, or were redone
    std::filesystem::remove(out.partial_path(), ec);
  }
  log::info("wrote ", out.final_path().string());
  run_post_commit(scenario, out.final_path(), ctx);
  return out.final_path();
}

Subcommand add_run(CLI::App& parent) {
  auto o = std::make_shared<RunRequest>();
  auto* sub = parent.add_subcommand(
      "run",
      "Run the stages of a scenario; writes DIR/results.h5. In a build with MPI, `mpirun -np K "
      "rendulic run ...` shares the probe campaigns among K ranks (same results as one process; "
      "give --threads cores/K)");
  sub->add_option("scenario", o->scenario, "scenario file (TOML)")->required();
  sub->add_option("--out", o->out, "output folder")->capture_default_str();
  sub->add_option("--set", o->sets, "override a scenario key by its dotted path: a.b=value")
      ->take_all();
  sub->add_option("--threads", o->threads,
                  "OpenMP threads (0, the default: all cores). DEM steps use a team only where it "
                  "pays: never below N = 1000, and only while it measures faster than one thread "
                  "(a busy core makes it slower); results do not depend on it")
      ->check(thread_count());
  sub->add_flag("--resume", o->resume,
                "continue an interrupted run from the stages it kept in DIR/results.h5.partial "
                "(same scenario and --set values): the result is that of an uninterrupted run");
  sub->add_flag("--quiet", o->quiet,
                "no progress display and no progress lines; warnings and errors still print");
  add_progress_every(sub, o->progress_every);
  return {sub, [o]() -> int {
            // Before anything else, so that the workers never parse, print or write.
            dem::MpiSession mpi;
            if (mpi.rank() != 0) {
              if (o->threads > 0) omp_set_num_threads(o->threads);
              mpi.serve(dem::compute_worker_share);
              return 0;
            }
            RunRequest request = *o;
            request.mpi_ranks = mpi.size();
            run_scenario(request);
            return 0;
          }};
}
}  // namespace rendulic::app
