// Between packing files (core/packing_file.hpp) and the DEM engine (docs/interop.md): a system
// as a Packing (to export it), a Packing as a system (to probe it), and the exact restart of a
// results file's state from its checkpoint (docs/results.md /states/<label>/checkpoint), which
// continues bit for bit where the run stood. Here, in the app layer, so that the engine in dem/
// never reads or writes files.
#pragma once

#include <optional>
#include <string>

#include "rendulic/core/packing_file.hpp"
#include "rendulic/core/results.hpp"
#include "rendulic/dem/dem_system.hpp"

namespace rendulic::app {

// Positions, radii, peculiar velocities and cell of the system.
Packing packing_of_system(const dem::DemSystem& system);
// A system at the packing's positions with the packing's radii (masses from the material's
// density), velocities zero: a packing made elsewhere is probed from rest.
dem::DemSystem system_of_packing(const Packing& packing, const dem::SystemOptions& options);
// The state under `group` restored from its checkpoint (DemSystem::restore), or nothing when
// the state has none. InputError if the checkpoint is incomplete or of the wrong shape.
std::optional<dem::DemSystem> restore_checkpoint(const ResultsReader& in, const std::string& group,
                                                 const dem::SystemOptions& options);

}  // namespace rendulic::app
