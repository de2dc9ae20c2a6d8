// Subcommand registry of the `rendulic` CLI (docs/usage.md). Each cmd_*.cpp
// adds its options to the parent app and returns the action main() runs when it is chosen;
// options live in objects owned by the action, so registration has no globals.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>

#include "rendulic/core/scenario.hpp"

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

// Draws the figures of a results file into out_dir (cmd_plot.cpp); used by the report stage.
// The figure script is `script` if given, else the first of RENDULIC_PLOT_SCRIPT, plot.py
// beside the binary, <prefix>/share/rendulic/plot.py, and the copy compiled in.
int plot_results(const std::filesystem::path& file, const std::filesystem::path& out_dir,
                 const std::filesystem::path& script = {});

// The figure script plot_results would run given `script` (empty: the compiled-in copy).
std::filesystem::path plot_script_file(const std::filesystem::path& script = {});

// Every scenario key of every module (app/schema.cpp).
const ScenarioSchema& scenario_schema();

}  // namespace rendulic::app
