// Entry point of the `rendulic` executable (interfaces.md "Command line"): parses with CLI11,
// dispatches to one subcommand, and maps failures to exit codes: 0 success, 2 bad input
// (one line on stderr naming the culprit), 1 an internal error.
#include <CLI/CLI.hpp>
#include <iostream>
#include <vector>

#include "commands.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/version.hpp"

int main(int argc, char** argv) {
  using namespace rendulic;
  CLI::App cli{"rendulic: calibrate constitutive models of granular soils from DEM envelopes"};
  cli.set_version_flag("--version", std::string("rendulic ") + kVersion + " (" + kGitSha + ")");
  cli.require_subcommand(1);
  std::vector<app::Subcommand> subs = {
      app::add_run(cli),   app::add_fit(cli),     app::add_envelope(cli), app::add_calibrate(cli),
      app::add_bench(cli), app::add_inspect(cli), app::add_plot(cli),     app::add_keys(cli),
      app::add_sweep(cli), app::add_report(cli)};
  try {
    cli.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return cli.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return cli.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return cli.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "rendulic: " << e.what() << " (see rendulic --help)\n";
    return kExitInput;
  }
  try {
    for (const auto& sub : subs)
      if (sub.app->parsed()) return sub.action();
  } catch (const InputError& e) {
    std::cerr << "rendulic: " << e.what() << "\n";
    return kExitInput;
  } catch (const NotAvailable& e) {
    std::cerr << "rendulic: " << e.what() << "\n";
    return kExitInput;
  } catch (const std::exception& e) {
    std::cerr << "rendulic: internal error: " << e.what() << "\n";
    return 1;
  }
  return 1;
}
