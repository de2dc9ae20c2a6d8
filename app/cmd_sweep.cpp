// `rendulic sweep [SCENARIO] [--out DIR] [--set key=value ...] [--threads T] [--quick] [--factors
// F,...] [--target E] [--path-rates R,...] [--path-seeds S] [--base-n N]` (docs/accuracy.md): the
// speed-versus-accuracy sweep of the probe methods and of the path's rate (sweep.hpp) around the
// scenario's settings; writes DIR/sweep.h5 (atomically), DIR/sweep.csv (DIR/sweep_path.csv for the
// path's rate) and the Pareto chart DIR/pareto.png / .svg (the embedded plot script). All input is
// validated before any simulation: bad input exits 2 and writes nothing.
#include <omp.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "cli_options.hpp"
#include "commands.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/log.hpp"
#include "rendulic/core/results.hpp"
#include "rendulic/core/text_file.hpp"
#include "sweep.hpp"

namespace rendulic::app {
namespace {
struct SweepCli {
  std::string scenario;
  std::string out = "out/sweep";
  std::vector<std::string> sets;
  std::vector<std::string> factors;
  int threads = 0;
  bool quick = false;
  bool quiet = false;
  double target = 0.02;
  int path_seeds = 0;              // 0: the preset's
  int base_n = 0;                  // 0: the preset's
  std::vector<double> path_rates;  // empty: the preset's
};
}  // namespace

Subcommand add_sweep(CLI::App& parent) {
  auto o = std::make_shared<SweepCli>();
  auto* sub = parent.add_subcommand(
      "sweep", "Speed versus accuracy of the probe methods: sweep.h5, sweep.csv, pareto.png");
  sub->add_option("scenario", o->scenario,
                  "scenario file (TOML); without it the built-in defaults (the seed's)")
      ->check(file_name());
  sub->add_option("--out", o->out, "output folder")->capture_default_str();
  sub->add_option("--set", o->sets, "override a scenario key by its dotted path: a.b=value")
      ->take_all();
  sub->add_option("--threads", o->threads, "OpenMP threads (0: all cores)")->check(thread_count());
  sub->add_flag("--quick", o->quick, "small sweep (N 250, 8 directions; about a minute)");
  sub->add_option("--factors", o->factors,
                  "factors to sweep (dt_factor, n_particles, inertial_number, relax, "
                  "dt_factor_tight, method, path_rate)")
      ->delimiter(',')
      ->check(one_of(kSweepFactors));
  // Checked here, in the option's words; SweepOptions::IsValid said "sweep: target must be in
  // (0, 1)" without naming the option.
  sub->add_option("--target", o->target,
                  "accuracy target: largest envelope error / reference major axis")
      ->capture_default_str()
      ->check(real_in_range(0.0, 1.0, /*open=*/true));
  sub->add_option("--path-seeds", o->path_seeds,
                  "path_rate: independent packings per rate (seeds run.seed, run.seed + 1, ...)")
      ->check(integer_in_range(1, 64));
  sub->add_option("--path-rates", o->path_rates, "path_rate: the rates to run (1/s, D_xx)")
      ->delimiter(',')
      ->check(positive_number());
  sub->add_option("--base-n", o->base_n,
                  "N of the base point and of the path_rate runs (default: 1000, --quick 250)")
      ->check(integer_in_range(50, 5000000));
  sub->add_flag("--quiet", o->quiet, "no progress lines");
  return {sub, [o]() -> int {
            Scenario scenario = o->scenario.empty()
                                    ? Scenario(scenario_schema())
                                    : Scenario::from_file(o->scenario, scenario_schema());
            for (const auto& s : o->sets) scenario.apply_override(s);
            SweepOptions so = SweepOptions::preset(o->quick);
            if (!o->factors.empty()) so.factors = o->factors;
            so.threads = o->threads;
            so.target = o->target;
            if (o->path_seeds > 0) so.path_seeds = o->path_seeds;
            if (o->base_n > 0) so.base_n = o->base_n;
            if (!o->path_rates.empty()) so.path_rates = o->path_rates;
            check_sweep_inputs(scenario, so);
            if (o->threads > 0) omp_set_num_threads(o->threads);
            // Refused before the sweep, not after it: an empty --out wrote into the current
            // folder, and a folder named sweep.csv failed once every point had run.
            refuse_empty_output_folder(o->out);
            const std::filesystem::path dir = o->out;
            for (const char* name : {"sweep.csv", "sweep_path.csv"})
              AtomicTextFile::refuse_folder(dir / name, "the sweep's table");
            // Only now, every input checked, does anything touch the disk.
            ResultsWriter out(dir / "sweep.h5");
            if (o->quiet) log::set_level(log::Level::kWarning);
            const SweepSummary summary =
                run_sweep(scenario, so, [](const std::string& l) { log::info("[sweep] ", l); });
            write_sweep_h5(summary, out);
            // The CSVs are on disk before sweep.h5 is committed, and renamed after it.
            AtomicTextFile csv(dir / "sweep.csv", "the sweep's table");
            csv.stream() << sweep_csv(summary);
            csv.flush();
            std::optional<AtomicTextFile> path_csv;
            if (!summary.path_points.empty()) {
              path_csv.emplace(dir / "sweep_path.csv", "the sweep's path table");
              path_csv->stream() << sweep_path_csv(summary);
              path_csv->flush();
            }
            out.commit();
            csv.commit();
            if (path_csv) path_csv->commit();
            for (const auto& l : summary.breaks) log::info("[sweep] break: ", l);
            for (const auto& l : summary.recommendations) log::info("[sweep] cheapest: ", l);
            try {
              plot_results(out.final_path(), dir);
            } catch (const std::exception& e) {
              // The numbers are written and valid; a missing matplotlib only costs the chart.
              log::warning("no Pareto chart: ", e.what());
            }
            log::info("wrote ", out.final_path().string(), " (", summary.points.size(), " points, ",
                      summary.wall_s, " s)");
            return 0;
          }};
}

}  // namespace rendulic::app
