// The protocol of a run up to the isotropic state (docs/physics.md section 4, docs/dem.md):
// the options of every step and the sequence gas -> mixing -> compression to nu0 ->
// relaxation at nu0 (at the preparation's own background damping) -> isotropic loading to
// nu_max -> relaxation there. The `run` stages (app/stages_dem.cpp) and the sweep
// (app/sweep.cpp) both take their packings from here, so the sequence is written once; the
// engine's side only, with no scenario file and no results file (scenario_keys.hpp makes the
// options from a scenario).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "rendulic/dem/protocols.hpp"
#include "rendulic/dem/rest.hpp"

namespace rendulic::dem {

// The in-class values are the scenario keys' defaults (scenario_keys.hpp reads its table's
// defaults from DemRunOptions{}): the seed study's run. Where a step's own struct has other
// defaults (a relaxation or a compression used on its own), the run's are set here.
struct DemRunOptions {
  SystemOptions system;  // Material{} (the seed's material), dt_factor, skin
  GasOptions gas{.n_particles = 9261, .volume_fraction = 0.3, .velocity = 1.0};
  double mix_time = 0;           // s at fixed cell before compressing the gas
  double prepare_gamma_b = 0.1;  // background damping during gas, compression, relax at nu0
  // Friction of the preparation and the isotropic loading as a fraction of the material's mu
  // (loading_system_options); 1 prepares with the run's own friction.
  double loading_friction_factor = 1.0;
  // gas -> nu0 at one constant rate
  CompressOptions prepare{.target_nu = 0.64, .rate_max = 300, .rate_min = 300};
  RelaxOptions relax{.kinetic_to_elastic = 1e-5, .time_cap = 2e-3};  // at nu0 and at nu_max
  // nu0 -> nu_max (isotropic branch)
  CompressOptions loading{
      .target_nu = 0.82, .rate_max = 400, .rate_min = 50, .inertial_number = 5e-4, .samples = 60};
  PathOptions path{.rate = 400};
  // Volume fractions of the pressure branches (snapshots of the loading, loading.snapshot_nu).
  std::vector<double> branch_nu;
  std::vector<std::string> state_labels{"a", "b", "c", "d", "e"};  // one per snapshot_eps_dev
  // Dynamic relaxation, then FIRE to equilibrium (rest.hpp); minimise.k is the material's.
  RestOptions state_rest{.relax = {.kinetic_to_elastic = 1e-6, .time_cap = 2e-3}};
};

// The system options of the preparation and the isotropic loading: the run's, with the friction
// mu x loading_friction_factor and the rolling friction mu_r x the same (docs/dem.md "Dense
// frictional packings": a packing loaded with less friction jams denser).
SystemOptions loading_system_options(const DemRunOptions& options);
// `sys` (a packing of the loading, at rest) carried on with the run's own material, as every
// stage from the path on runs: friction raised to mu, the tangential springs as they are (all
// zero after a frictionless loading, within the loading's smaller Coulomb limit otherwise). A
// no-op when the loading already ran with it (loading_friction_factor = 1), which keeps such
// runs bitwise as they were.
void use_run_material(DemSystem& sys, const DemRunOptions& options);

// Called with the name of each step as it starts ("gas", "compress to nu0", "relax at nu0").
using TaskFn = std::function<void(const std::string&)>;

struct PreparedPacking {
  DemSystem system;  // at nu0, with the material's own background damping, the loading's mu
  Measures at_nu0;   // measured at the end of the relaxation at nu0
  CompressSummary compression;  // gas -> nu0
  RelaxSummary relax;           // at nu0
  std::int64_t steps = 0;
};
// The random gas of `seed`, its mixing, its compression to nu0 and the relaxation there, all at
// options.prepare_gamma_b (refused with an InputError naming preparation.gamma_b if that makes
// the time step unstable) and with the loading's friction (loading_system_options), which the
// returned system keeps.
PreparedPacking prepare_packing(const DemRunOptions& options, std::uint64_t seed,
                                const TaskFn& task = {}, const ProgressFn& progress = {});

struct IsotropicLoading {
  CompressSummary loading;  // nu0 -> nu_max, with the snapshots at loading.snapshot_nu
  RelaxSummary relax;       // at nu_max
};
// The isotropic loading of `sys` to loading.target_nu, then its relaxation ("loading to nu_max",
// "relax at nu_max"); with loading.target_pressure_star > 0 the loading to that pressure and a
// relaxation holding it (relax_at_pressure) with the paths' lateral servo, `servo_of`'s gains
// (path.servo_gain, path.servo_integral_gain: the same reasoning) and the loading's largest
// rate as its bound.
IsotropicLoading load_isotropic(DemSystem& sys, const CompressOptions& loading,
                                const RelaxOptions& relax, const SampleFn& sample = {},
                                const TaskFn& task = {}, const ProgressFn& progress = {},
                                const PathOptions& servo_of = {});

}  // namespace rendulic::dem
