// `rendulic bench` (interfaces.md): DEM throughput on the standard states. Lands with issue 3.
#include "commands.hpp"
#include "rendulic/core/errors.hpp"

namespace rendulic::app {
Subcommand add_bench(CLI::App& parent) {
  auto* sub = parent.add_subcommand("bench", "DEM throughput (ns per particle-step)");
  sub->allow_extras();
  return {sub, [] () -> int {
            throw NotAvailable("bench: the DEM engine has not landed yet (issue 3)");
          }};
}
}  // namespace rendulic::app
