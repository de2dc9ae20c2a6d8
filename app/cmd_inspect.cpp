// `rendulic inspect FILE.h5` (docs/results.md): human summary of a results file. A file that is
// missing, not HDF5, corrupt or not ours is an InputError (exit 2), never an HDF5 stack dump.
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "rendulic/core/results.hpp"

namespace rendulic::app {
Subcommand add_inspect(CLI::App& parent) {
  auto file = std::make_shared<std::string>();
  auto* sub = parent.add_subcommand("inspect", "Summary of a results file");
  sub->add_option("file", *file, "results file (HDF5, schema rendulic/2 or 1)")->required();
  return {sub, [file]() -> int {
            ResultsReader reader(*file);
            std::cout << reader.summary();
            return 0;
          }};
}
}  // namespace rendulic::app
