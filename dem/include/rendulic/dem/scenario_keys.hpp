// Scenario keys of the DEM stages (docs/physics.md sections 1-4; docs/scenario-keys.md):
// material.*, dem.*, preparation.*, relax.*, isotropic.*, path.*, states.*, pressure.*. They are
// the option table of DemRunOptions (core/option_table.hpp): each key is one row with unit,
// range and help, and its default is DemRunOptions{}'s member (the seed study's values), so
// the schema, `rendulic keys` and a DemRunOptions built in code share one set of numbers. The
// options of the protocols are read from a validated scenario, and cross-key rules (e.g.
// nu0 < nu_max, snapshot strains within the path) are checked here, before any simulation.
// Plain configuration: no file format is read here (the scenario was parsed by core).
#pragma once

#include <string>
#include <vector>

#include "rendulic/core/option_table.hpp"
#include "rendulic/core/scenario.hpp"
#include "rendulic/dem/run_protocol.hpp"

namespace rendulic::dem {

const OptionTable<DemRunOptions>& dem_run_option_table();
void register_dem_keys(ScenarioSchema& schema);
// The members one key sets for several steps: the gas's single compression rate (rate_min =
// rate_max), the loading's snapshots at the pressure branches, the minimiser's stiffness.
void complete_dem_run_options(DemRunOptions& options);

// The material.* keys.
Material material_from_scenario(const Scenario& scenario);
// Throws InputError naming the key for values that are individually valid but inconsistent.
DemRunOptions dem_options_from_scenario(const Scenario& scenario);

}  // namespace rendulic::dem
