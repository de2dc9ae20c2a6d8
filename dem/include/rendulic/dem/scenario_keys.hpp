// Scenario keys of the DEM stages (docs/physics.md sections 1-4; docs/scenario-keys.md):
// material.*, dem.*, preparation.*, relax.*, isotropic.*, path.*, states.*, pressure.*. Each key is
// declared once with type, unit, default (the seed study's values), range and help; the
// options of the protocols are built from a validated scenario, and cross-key rules (e.g.
// nu0 < nu_max, snapshot strains within the path) are checked here, before any simulation.
#pragma once

#include <string>
#include <vector>

#include "rendulic/core/scenario.hpp"
#include "rendulic/dem/protocols.hpp"
#include "rendulic/dem/rest.hpp"

namespace rendulic::dem {

void register_dem_keys(ScenarioSchema& schema);

struct DemRunOptions {
  SystemOptions system;
  GasOptions gas;
  double mix_time = 0;           // s at fixed cell before compressing the gas
  double prepare_gamma_b = 0.1;  // background damping during gas, compression, relax at nu0
  CompressOptions prepare;       // gas -> nu0 (constant rate)
  RelaxOptions relax;            // at nu0 and at nu_max
  CompressOptions loading;       // nu0 -> nu_max (isotropic branch)
  PathOptions path;
  // Volume fractions of the pressure branches (snapshots of the loading, loading.snapshot_nu).
  std::vector<double> branch_nu;
  std::vector<std::string> state_labels;  // one per path.snapshot_eps_dev
  RestOptions state_rest;                 // dynamic relaxation, then FIRE to equilibrium (rest.hpp)
};

// The material.* keys.
Material material_from_scenario(const Scenario& scenario);
// Throws InputError naming the key for values that are individually valid but inconsistent.
DemRunOptions dem_options_from_scenario(const Scenario& scenario);

}  // namespace rendulic::dem
