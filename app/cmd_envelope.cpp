// `rendulic envelope` (interfaces.md): envelope predicted by a constitutive model. Lands with
// issue 6.
#include "commands.hpp"
#include "rendulic/core/errors.hpp"

namespace rendulic::app {
Subcommand add_envelope(CLI::App& parent) {
  auto* sub = parent.add_subcommand("envelope", "Envelope predicted by a constitutive model");
  sub->allow_extras();
  return {sub, [] () -> int {
            throw NotAvailable("envelope: constitutive models have not landed yet (issue 6)");
          }};
}
}  // namespace rendulic::app
