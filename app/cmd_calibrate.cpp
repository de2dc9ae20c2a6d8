// `rendulic calibrate` (interfaces.md): fits a model to a results file. Lands with issue 7.
#include "commands.hpp"
#include "rendulic/core/errors.hpp"

namespace rendulic::app {
Subcommand add_calibrate(CLI::App& parent) {
  auto* sub = parent.add_subcommand("calibrate", "Fit a model to the envelopes of a results file");
  sub->allow_extras();
  return {sub, [] () -> int {
            throw NotAvailable("calibrate: calibration has not landed yet (issue 7)");
          }};
}
}  // namespace rendulic::app
