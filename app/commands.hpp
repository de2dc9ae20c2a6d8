// Subcommand registry of the `rendulic` CLI (docs/usage.md). Each cmd_*.cpp
// adds its options to the parent app and returns the action main() runs when it is chosen;
// options live in objects owned by the action, so registration has no globals.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "rendulic/core/scenario.hpp"
#include "rendulic/models/driver.hpp"
#include "rendulic/models/envelope.hpp"
#include "rendulic/models/law.hpp"

namespace rendulic::app {

using Action = std::function<int()>;
struct Subcommand {
  CLI::App* app;
  Action action;
};

Subcommand add_run(CLI::App& parent);
Subcommand add_fit(CLI::App& parent);
Subcommand add_envelope(CLI::App& parent);
Subcommand add_calibrate(CLI::App& parent);
Subcommand add_bench(CLI::App& parent);
Subcommand add_inspect(CLI::App& parent);
Subcommand add_plot(CLI::App& parent);
Subcommand add_keys(CLI::App& parent);
Subcommand add_sweep(CLI::App& parent);
Subcommand add_report(CLI::App& parent);
Subcommand add_probe(CLI::App& parent);
Subcommand add_export(CLI::App& parent);

// The work of `rendulic run` and `rendulic probe` behind their options, callable from a program
// (the Python module, docs/python.md) with the same results and the same errors. run_scenario
// is one process: the CLI's MPI workers are the CLI's own (cmd_run.cpp). Both return the results
// file they wrote.
struct RunRequest {
  std::string scenario;  // the scenario file (TOML)
  std::string out = "out";
  std::vector<std::string> sets;  // key=value overrides
  int threads = 0;
  bool quiet = false;
  bool resume = false;
  double progress_every = 30.0;
  int mpi_ranks = 1;  // said in the log only; the ranks are started by the caller
};
std::filesystem::path run_scenario(const RunRequest& request);

struct ProbeRequest {
  std::string packing;  // a LAMMPS data file or dump, or RESULTS.h5:/states/LABEL
  std::string out = "out";
  std::string label = "imported";
  std::vector<std::string> methods;
  std::vector<double> amplitudes;
  int directions = 0;
  std::vector<std::string> planes;  // probes.planes when not empty
  std::vector<std::string> sets;
  int threads = 0;
  bool quiet = false;
  double progress_every = 30.0;
  bool summary = true;  // the CLI's table of the fits on stdout
  // A frictionless packing that is a saddle of its energy is moved off it to a minimum first
  // (dem::leave_saddle; docs/probes.md "Replicated packings").
  bool leave_saddle = false;
};
std::filesystem::path probe_packing(const ProbeRequest& request);

// `rendulic envelope`'s computation (cmd_envelope.cpp), for the CLI and the Python module: the
// law (built-in by name, or `umat` with its library), its parameters and the state from TOML
// files, or from TOML text when *_is_text (messages then name "parameters" and "state").
// InputError on any problem, with the CLI's messages.
struct EnvelopeRequest {
  std::string model, umat, params, state;
  bool params_is_text = false, state_is_text = false;
  double amplitude = 0.0;
  int directions = 36;
  std::string method = "integrated";      // or "rate"
  std::string scheme = "modified-euler";  // or "explicit"
  double tolerance = models::StepOptions{}.tolerance;
  int substeps = 1;
  // Messages spell an option as the command line does ("--substeps 7"), else as Python's
  // keyword arguments ("substeps = 7").
  bool cli = false;
};
EnvelopeRecord envelope_for(const EnvelopeRequest& request, std::string* law_name = nullptr);
// Its pieces: the law with its parameters (params empty: the defaults), the state, the driver's
// step options. `cli` as in EnvelopeRequest.
std::unique_ptr<models::Law> law_for(const std::string& model, const std::string& umat,
                                     const std::string& params, bool params_is_text,
                                     bool cli = false);
models::MaterialState state_for(const models::Law& law, const std::string& state,
                                bool state_is_text);
models::StepOptions step_options_for(const std::string& scheme, double tolerance, int substeps,
                                     bool cli = false);

// Draws the figures of a results file into out_dir (cmd_plot.cpp); used by the report stage.
// The figure script is `script` if given, else the first of RENDULIC_PLOT_SCRIPT, plot.py
// beside the binary, <prefix>/share/rendulic/plot.py, and the copy compiled in.
int plot_results(const std::filesystem::path& file, const std::filesystem::path& out_dir,
                 const std::filesystem::path& script = {});

// The processes plot_results draws with: RENDULIC_PLOT_JOBS when set (InputError unless a whole
// number in [1, kMaxThreads]), else 0 (as many as the threads). Checked before a run too, so
// that a mistyped value does not fail it at its report, after the DEM.
int plot_jobs_from_environment();

// The figure script plot_results would run given `script` (empty: the compiled-in copy).
std::filesystem::path plot_script_file(const std::filesystem::path& script = {});

// Every scenario key of every module (app/schema.cpp).
const ScenarioSchema& scenario_schema();

}  // namespace rendulic::app
