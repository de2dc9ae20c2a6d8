// `rendulic keys`: the scenario key reference (every key, unit, default, range), generated
// from the schema so that docs/scenario-keys.md can be checked against the code.
#include <iostream>

#include "commands.hpp"

namespace rendulic::app {
Subcommand add_keys(CLI::App& parent) {
  auto* sub = parent.add_subcommand("keys", "Print the scenario key reference (Markdown)");
  return {sub, []() -> int {
            std::cout << scenario_schema().markdown();
            return 0;
          }};
}
}  // namespace rendulic::app
