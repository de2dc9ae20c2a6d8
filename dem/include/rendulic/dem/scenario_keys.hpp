// Scenario keys of the DEM stages (docs/physics.md sections 1-4; docs/scenario-keys.md):
// material.*, dem.*, preparation.*, relax.*, isotropic.*, path.*, states.*, pressure.*. Each key is
// declared once with type, unit, default (the seed study's values), range and help; the
// options of the protocols are built from a validated scenario, and cross-key rules (e.g.
// nu0 < nu_max, snapshot strains within the path) are checked here, before any simulation.
#pragma once

#include <string>
#include <vector>

#include "rendulic/core/scenario.hpp"
#include "rendulic/dem/run_protocol.hpp"

namespace rendulic::dem {

void register_dem_keys(ScenarioSchema& schema);

// The material.* keys.
Material material_from_scenario(const Scenario& scenario);
// Throws InputError naming the key for values that are individually valid but inconsistent.
DemRunOptions dem_options_from_scenario(const Scenario& scenario);

}  // namespace rendulic::dem
