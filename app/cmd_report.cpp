// `rendulic report FILE.h5 [--no-figures]`: writes report.md (and the figures)
// beside an existing results file, as the run's report stage does: for a file from an earlier
// version, another machine or an interrupted session, without re-running anything. The file
// is only read; report.md is replaced atomically.
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "rendulic/core/log.hpp"
#include "report.hpp"

namespace rendulic::app {
namespace {
struct ReportOptions {
  std::string file;
  bool no_figures = false;
};
}  // namespace

Subcommand add_report(CLI::App& parent) {
  auto o = std::make_shared<ReportOptions>();
  auto* sub = parent.add_subcommand(
      "report", "Write report.md (claims C1-C8, calibration, timings) and figures beside FILE.h5");
  sub->add_option("file", o->file, "results file (HDF5, schema rendulic/2 or 1)")->required();
  sub->add_flag("--no-figures", o->no_figures, "report.md only");
  return {sub, [o]() -> int {
            const auto path = write_report(o->file, !o->no_figures);
            log::info("wrote ", path.string());
            return 0;
          }};
}
}  // namespace rendulic::app
