// `rendulic fit` (interfaces.md): fits one envelope from a CSV file. Lands with issue 5.
#include "commands.hpp"
#include "rendulic/core/errors.hpp"

namespace rendulic::app {
Subcommand add_fit(CLI::App& parent) {
  auto* sub = parent.add_subcommand("fit", "Fit an ellipse or a line to one envelope (CSV)");
  sub->allow_extras();
  return {sub, [] () -> int {
            throw NotAvailable("fit: envelope fitting has not landed yet (issue 5)");
          }};
}
}  // namespace rendulic::app
