// `rendulic plot` (interfaces.md): figures of a results file. Lands with issue 8.
#include "commands.hpp"
#include "rendulic/core/errors.hpp"

namespace rendulic::app {
Subcommand add_plot(CLI::App& parent) {
  auto* sub = parent.add_subcommand("plot", "Figures of a results file (PNG and SVG)");
  sub->allow_extras();
  return {sub, [] () -> int {
            throw NotAvailable("plot: figures have not landed yet (issue 8)");
          }};
}
}  // namespace rendulic::app
