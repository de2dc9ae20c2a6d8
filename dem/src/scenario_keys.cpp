// The DEM run's option table and its conversion from a scenario (see scenario_keys.hpp).
// Defaults are DemRunOptions{}'s, which are the seed study's (docs/physics.md sections 1 and
// 4) except where the seed gives no number (rates, relaxation thresholds), where the choice
// is explained in the help text and docs/dem.md.
#include "rendulic/dem/scenario_keys.hpp"

#include <limits>
#include <sstream>

#include "rendulic/core/errors.hpp"
#include "rendulic/core/result_paths.hpp"

namespace rendulic::dem {

const OptionTable<DemRunOptions>& dem_run_option_table() {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  using Row = OptionRow<DemRunOptions>;
  using O = DemRunOptions;
  static const OptionTable<DemRunOptions> table({
      Row{{.path = "material.k",
           .unit = "kg/s^2",
           .help = "Normal contact stiffness k.",
           .min = 0,
           .max = kInf,
           .min_open = true,
           .max_open = true},
          [](O& o) -> double& { return o.system.material.k; }},
      Row{{.path = "material.gamma",
           .unit = "kg/s",
           .help = "Normal contact viscosity gamma (dashpot).",
           .min = 0,
           .max = kInf,
           .max_open = true},
          [](O& o) -> double& { return o.system.material.gamma; }},
      Row{{.path = "material.gamma_b",
           .unit = "kg/s",
           .help = "Background damping on the velocity relative to the imposed flow.",
           .min = 0,
           .max = kInf,
           .max_open = true},
          [](O& o) -> double& { return o.system.material.gamma_b; }},
      Row{{.path = "material.density",
           .unit = "kg/m^3",
           .help = "Particle density rho.",
           .min = 0,
           .max = kInf,
           .min_open = true,
           .max_open = true},
          [](O& o) -> double& { return o.system.material.density; }},
      Row{{.path = "material.r_mean",
           .unit = "m",
           .help = "Mean radius <r> of the uniform size distribution.",
           .min = 0,
           .max = kInf,
           .min_open = true,
           .max_open = true},
          [](O& o) -> double& { return o.system.material.r_mean; }},
      Row{{.path = "material.w",
           .unit = "-",
           .help = "Polydispersity w = r_max / r_min (radii uniform in [r_min, r_max], "
                   "number-weighted).",
           .min = 1,
           .max = 100},
          [](O& o) -> double& { return o.system.material.w; }},
      Row{{.path = "dem.n_particles",
           .unit = "-",
           .help = "Number of particles N (the seed: 9261 = 21^3).",
           .min = 50,
           .max = 5e6},
          [](O& o) -> std::size_t& { return o.gas.n_particles; }},
      Row{{.path = "dem.dt_factor",
           .unit = "-",
           .help = "Time step as a fraction of the contact duration t_c of the two smallest "
                   "particles; values beyond the explicit stability limit are refused.",
           .min = 0,
           .max = 1,
           .min_open = true},
          [](O& o) -> double& { return o.system.dt_factor; }},
      Row{{.path = "dem.skin",
           .unit = "-",
           .help = "Verlet-list skin in units of <r> (speed only, not physics).",
           .min = 0,
           .max = 2,
           .min_open = true},
          [](O& o) -> double& { return o.system.skin; }},
      Row{{.path = "dem.friction",
           .unit = "-",
           .help = "Coulomb friction coefficient mu of the tangential contact (|f_t| <= mu "
                   "|f_n|, with rotations and a tangential spring per contact, docs/physics.md "
                   "section 1b); 0 = frictionless (the seed study). The energy minimisation "
                   "and the minimisation probes refuse mu > 0; the linear response takes the "
                   "sticking contacts.",
           .min = 0,
           .max = 10},
          [](O& o) -> double& { return o.system.material.mu; }},
      Row{{.path = "dem.k_t_ratio",
           .unit = "-",
           .help = "Tangential stiffness k_t / k (used when dem.friction > 0); 2/7 gives a "
                   "sticking pair of equal spheres the normal contact's frequency.",
           .min = kMinSpringRatio,
           .max = 1},
          [](O& o) -> double& { return o.system.material.k_t_ratio; }},
      Row{{.path = "dem.gamma_t_ratio",
           .unit = "-",
           .help = "Tangential contact viscosity gamma_t / gamma (used when dem.friction > 0); "
                   "2/7 gives a sticking pair of equal spheres the normal contact's damping "
                   "rate.",
           .min = 0,
           .max = 1},
          [](O& o) -> double& { return o.system.material.gamma_t_ratio; }},
      Row{{.path = "dem.rolling_friction",
           .unit = "-",
           .help = "Rolling friction coefficient mu_r: the rolling resistance's Coulomb-like "
                   "limit |f_r| <= mu_r |f_n| on the rolling spring-dashpot's pseudo-force, "
                   "whose torque a' n x f_r (a' the reduced lever) resists the pair's relative "
                   "rolling (docs/physics.md section 1b); 0 = none. Needs dem.friction > 0. "
                   "At most 1: its limit torque a' mu_r |f_n| "
                   "(a' <= a) is then at most the sliding torque a |f_n| of mu = 1.",
           .min = 0,
           .max = 1},
          [](O& o) -> double& { return o.system.material.mu_r; }},
      Row{{.path = "dem.k_r_ratio",
           .unit = "-",
           .help = "Rolling stiffness k_r / k (used when dem.rolling_friction > 0); 2/7, as "
                   "k_t / k, makes the rolling spring's resistance to a turn (a'^2 k_r) a "
                   "quarter of the tangential spring's for equal spheres, so that rolling does "
                   "not set the time step.",
           .min = kMinSpringRatio,
           .max = 1},
          [](O& o) -> double& { return o.system.material.k_r_ratio; }},
      Row{{.path = "dem.gamma_r_ratio",
           .unit = "-",
           .help = "Rolling contact viscosity gamma_r / gamma (used when dem.rolling_friction "
                   "> 0); 2/7, as gamma_t / gamma, for the same reason as dem.k_r_ratio.",
           .min = 0,
           .max = 1},
          [](O& o) -> double& { return o.system.material.gamma_r_ratio; }},
      Row{{.path = "preparation.nu_gas",
           .unit = "-",
           .help = "Volume fraction of the initial random gas (a sparser gas than 1e-6 only "
                   "lengthens the compression to nu0).",
           .min = kGasVolumeFractionMin,
           .max = kGasVolumeFractionMax},
          [](O& o) -> double& { return o.gas.volume_fraction; }},
      Row{{.path = "preparation.gas_velocity",
           .unit = "m/s",
           .help = "Standard deviation of each component of the gas's random velocities.",
           .min = 0,
           .max = 1e3},
          [](O& o) -> double& { return o.gas.velocity; }},
      Row{{.path = "preparation.mix_time",
           .unit = "s",
           .help = "Time the gas mixes at fixed cell before compression (random insertion "
                   "already gives a random gas).",
           .min = 0,
           .max = 1},
          [](O& o) -> double& { return o.mix_time; }},
      Row{{.path = "preparation.rate",
           .unit = "1/s",
           .help = "Isotropic compression rate of the gas to nu0 (|D_aa|); fast compression "
                   "heats the gas through affine collisions, which the relaxation at nu0 then "
                   "removes.",
           .min = 0,
           .max = 1e6,
           .min_open = true},
          [](O& o) -> double& { return o.prepare.rate_max; }},
      Row{{.path = "preparation.gamma_b",
           .unit = "kg/s",
           .help = "Background damping during the preparation only (gas, compression to nu0, "
                   "relaxation at nu0); the seed's value by default. A larger value cools the "
                   "compressed gas faster; the packing at nu0 is unjammed, and every later "
                   "stage uses material.gamma_b.",
           .min = 0,
           .max = kInf,
           .max_open = true},
          [](O& o) -> double& { return o.prepare_gamma_b; }},
      Row{{.path = "preparation.nu0",
           .unit = "-",
           .help = "Volume fraction nu0 reached by the gas compression, just below isotropic "
                   "jamming.",
           .min = 0,
           .max = 1,
           .min_open = true,
           .max_open = true},
          [](O& o) -> double& { return o.prepare.target_nu; }},
      Row{{.path = "relax.kinetic_to_elastic",
           .unit = "-",
           .help = "Relaxation at nu0 and nu_max ends when E_kin / max(E_el, N k (1e-4 <r>)^2 "
                   "/ 2) falls below this.",
           .min = 0,
           .max = 1,
           .min_open = true},
          [](O& o) -> double& { return o.relax.kinetic_to_elastic; }},
      Row{{.path = "relax.time_cap",
           .unit = "s",
           .help = "Longest relaxation at nu0 and nu_max (reported if hit).",
           .min = 0,
           .max = 10,
           .min_open = true},
          [](O& o) -> double& { return o.relax.time_cap; }},
      Row{{.path = "isotropic.nu_max",
           .unit = "-",
           .help = "Volume fraction nu_max of the isotropic loading (its bound with "
                   "isotropic.pressure_star).",
           .min = 0,
           .max = 1,
           .min_open = true,
           .max_open = true},
          [](O& o) -> double& { return o.loading.target_nu; }},
      Row{{.path = "isotropic.pressure_star",
           .unit = "-",
           .help = "0: load to isotropic.nu_max. > 0: load to this P* = P / k* instead and relax "
                   "holding it with a stress servo (isotropic.nu_max is then the bound the "
                   "loading may not pass); frictional packings are prepared to a pressure.",
           .min = 0,
           .max = 1},
          [](O& o) -> double& { return o.loading.target_pressure_star; }},
      Row{{.path = "isotropic.friction_factor",
           .unit = "-",
           .help = "Friction of the preparation and the isotropic loading as a fraction of "
                   "dem.friction and dem.rolling_friction (1: the same; 0: frictionless, which "
                   "jams the densest random packing); from the path on every stage runs with "
                   "the material's own (docs/dem.md 'Dense frictional packings').",
           .min = 0,
           .max = 1},
          [](O& o) -> double& { return o.loading_friction_factor; }},
      Row{{.path = "isotropic.samples",
           .unit = "-",
           .help = "Samples of the isotropic branch (equally spaced in ln nu, ends included).",
           .min = 50,
           .max = 1e6},
          [](O& o) -> int& { return o.loading.samples; }},
      Row{{.path = "isotropic.inertial_number",
           .unit = "-",
           .help = "Inertial number held by the loading rate (0: constant rate "
                   "isotropic.rate_max).",
           .min = 0,
           .max = 1e-2},
          [](O& o) -> double& { return o.loading.inertial_number; }},
      Row{{.path = "isotropic.rate_max",
           .unit = "1/s",
           .help = "Largest isotropic loading rate |D_aa|.",
           .min = 0,
           .max = 1e6,
           .min_open = true},
          [](O& o) -> double& { return o.loading.rate_max; }},
      Row{{.path = "isotropic.rate_min",
           .unit = "1/s",
           .help = "Smallest isotropic loading rate (used while the pressure is ~0, below "
                   "jamming).",
           .min = 0,
           .max = 1e6,
           .min_open = true},
          [](O& o) -> double& { return o.loading.rate_min; }},
      Row{{.path = "pressure.volume_fractions",
           .unit = "-",
           .help = "Volume fractions (between preparation.nu0 and isotropic.nu_max) at which "
                   "the isotropic loading is also snapshotted; the pressure stage repeats the "
                   "path, the states, their elastic range, probes and linear response from each "
                   "(docs/dem.md 'Pressure branches').",
           .min = 0,
           .max = 1,
           .min_open = true,
           .max_open = true,
           .distinct = true},
          [](O& o) -> std::vector<double>& { return o.branch_nu; }},
      Row{{.path = "path.type",
           .unit = "-",
           .help = "The loading path from the isotropic state (docs/dem.md 'Paths'): undrained "
                   "(constant volume) axisymmetric, drained triaxial (lateral stress held at the "
                   "start's p), constant mean stress, isotropic, or proportional (path.direction); "
                   "the seed study's is undrained_extension.",
           .choices = path_type_choices()},
          [](O& o) -> std::string& { return o.path.type; }},
      Row{{.path = "path.rate",
           .unit = "1/s",
           .help = "Strain rate of the path: the largest |D_aa| of its strain-controlled axes "
                   "(the axial one on the drained and constant-p paths).",
           .min = 0,
           .max = 1e6,
           .min_open = true},
          [](O& o) -> double& { return o.path.rate; }},
      Row{{.path = "path.inertial_number",
           .unit = "-",
           .help = "0: the path runs at path.rate throughout. > 0: its rate follows the "
                   "pressure so that it holds this inertial number, at most path.rate and at "
                   "least path.rate_min (a loose frictional packing whose p falls on the path "
                   "stays quasi-static; docs/dem.md 'Paths').",
           .min = 0,
           .max = 1e-2},
          [](O& o) -> double& { return o.path.inertial_number; }},
      Row{{.path = "path.rate_min",
           .unit = "1/s",
           .help = "Smallest rate of a path that holds path.inertial_number (where p is near "
                   "zero, e.g. a liquefied packing); at most path.rate.",
           .min = 0,
           .max = 1e6,
           .min_open = true},
          [](O& o) -> double& { return o.path.rate_min; }},
      Row{{.path = "path.direction",
           .unit = "-",
           .help = "Principal strain-rate direction (D_xx, D_yy, D_zz up to a positive factor, "
                   "extension positive) of a proportional path; other paths ignore it.",
           .min = -1e6,
           .max = 1e6,
           .min_size = 3,
           .max_size = 3},
          [](O& o) -> std::vector<double>& { return o.path.direction; }},
      Row{{.path = "path.eps_dev_max",
           .unit = "-",
           .help = "End of the path in its strain s: -eps_dev on the seed's undrained "
                   "extension, |E| on every strain-controlled path, the axial strain on the "
                   "drained and constant-p paths.",
           .min = 0,
           .max = 2,
           .min_open = true},
          [](O& o) -> double& { return o.path.eps_dev_max; }},
      Row{{.path = "path.servo_gain",
           .unit = "1/t_c",
           .help = "Proportional gain of the lateral stress servo of the drained and constant-p "
                   "paths and of the hold at isotropic.pressure_star, D = I + (gain / t_c) "
                   "(sigma - target) / k*, in units of the smallest pair's contact time t_c "
                   "(docs/dem.md 'Paths'); gain x dem.dt_factor above 1 is refused (the "
                   "servo's explicit limit).",
           .min = 0,
           .max = 100,
           .min_open = true},
          [](O& o) -> double& { return o.path.servo_gain; }},
      Row{{.path = "path.servo_integral_gain",
           .unit = "1/t_c^2",
           .help = "Integral gain of the same servo, dI/dt = (gain_i / t_c^2) (sigma - target) "
                   "/ k* (0: proportional only, which lags behind the path).",
           .min = 0,
           .max = 100},
          [](O& o) -> double& { return o.path.servo_integral_gain; }},
      Row{{.path = "path.servo_tolerance",
           .unit = "-",
           .help = "Largest relative error of the stress a drained (lateral stresses) or "
                   "constant-p (mean stress) path holds at p0, at a sample after the first tenth "
                   "of the path; beyond it the run warns and /path says so.",
           .min = 0,
           .max = 1,
           .min_open = true},
          [](O& o) -> double& { return o.path.servo_tolerance; }},
      Row{{.path = "path.samples",
           .unit = "-",
           .help = "Samples along the path (equally spaced in its strain s, path.eps_dev_max).",
           .min = 2,
           .max = 1e7},
          [](O& o) -> int& { return o.path.samples; }},
      Row{{.path = "states.eps_dev",
           .unit = "-",
           .help =
               "Path strain s (-eps_dev on the seed's path) of the snapshots taken on the path and "
               "relaxed at fixed cell.",
           .min = 0,
           .max = 2,
           .min_open = true,
           .min_size = 1},
          [](O& o) -> std::vector<double>& { return o.path.snapshot_eps_dev; }},
      Row{{.path = "states.labels",
           .unit = "-",
           .help = "Group names /states/<label> of the snapshots, one per states.eps_dev (the "
                   "seed's figure panels a-e).",
           .min_size = 1,
           .distinct = true},
          [](O& o) -> std::vector<std::string>& { return o.state_labels; }},
      Row{{.path = "states.kinetic_to_elastic",
           .unit = "-",
           .help = "Relaxation of each snapshot ends when E_kin / E_el falls below this.",
           .min = 0,
           .max = 1,
           .min_open = true},
          [](O& o) -> double& { return o.state_rest.relax.kinetic_to_elastic; }},
      Row{{.path = "states.time_cap",
           .unit = "s",
           .help = "Longest relaxation of a snapshot (reported if hit).",
           .min = 0,
           .max = 10,
           .min_open = true},
          [](O& o) -> double& { return o.state_rest.relax.time_cap; }},
      Row{{.path = "states.force_tolerance",
           .unit = "-",
           .help = "After the dynamic relaxation each snapshot is minimised (FIRE, fixed cell) "
                   "until the largest net force on a particle is below this x the mean contact "
                   "force: the state is then at rest, and so are its stress, fabric, linear "
                   "response and envelopes.",
           .min = 0,
           .max = 1e-4,
           .min_open = true},
          [](O& o) -> double& { return o.state_rest.minimise.force_tolerance; }},
  });
  return table;
}

void register_dem_keys(ScenarioSchema& s) { dem_run_option_table().register_keys(s); }

Material material_from_scenario(const Scenario& sc) {
  DemRunOptions o;
  dem_run_option_table().read(sc, o);
  return o.system.material;
}

void complete_dem_run_options(DemRunOptions& o) {
  o.prepare.rate_min = o.prepare.rate_max;  // the gas is compressed at one rate
  o.prepare.rate_key = "preparation.rate";
  o.loading.rate_key = "isotropic.rate_max";
  o.loading.snapshot_nu = o.branch_nu;
  o.state_rest.minimise.k = o.system.material.k;
}

DemRunOptions dem_options_from_scenario(const Scenario& sc) {
  DemRunOptions o;
  dem_run_option_table().read(sc, o);
  complete_dem_run_options(o);
  const Material& m = o.system.material;
  check_time_step(m, o.system.dt_factor, "dem.dt_factor (" + sc.origin("dem.dt_factor") + ")");

  auto where = [&](const char* key) { return std::string(key) + " (" + sc.origin(key) + ")"; };
  if (!(o.gas.volume_fraction < o.prepare.target_nu))
    throw InputError(where("preparation.nu0") + ": must exceed preparation.nu_gas");
  if (!(o.prepare.target_nu < o.loading.target_nu))
    throw InputError(where("isotropic.nu_max") + ": must exceed preparation.nu0");
  if (o.loading.rate_min > o.loading.rate_max)
    throw InputError(where("isotropic.rate_min") + ": must not exceed isotropic.rate_max");
  if (o.path.inertial_number > 0 && o.path.rate_min > o.path.rate)
    throw InputError(where("path.rate_min") + ": must not exceed path.rate");
  if (o.state_labels.size() != o.path.snapshot_eps_dev.size())
    throw InputError(where("states.labels") + ": needs one label per states.eps_dev entry (" +
                     std::to_string(o.path.snapshot_eps_dev.size()) + ")");
  for (const auto& l : o.state_labels) {
    // Each label names the group /states/<label> of the results file (KeySpec::distinct).
    if (const std::string why = invalid_object_name_reason(l); !why.empty())
      throw InputError(where("states.labels") + ": label '" + printable(l) + "' " + why);
  }
  for (double nu : o.branch_nu)
    if (!(nu > o.prepare.target_nu && nu < o.loading.target_nu))
      throw InputError(where("pressure.volume_fractions") +
                       ": every entry must lie strictly between preparation.nu0 and "
                       "isotropic.nu_max");
  {  // The preparation runs with its own background damping: its time step must be stable too.
    Material prep = m;
    prep.gamma_b = o.prepare_gamma_b;
    const double dt = time_step(prep, o.system.dt_factor), limit = stability_limit(prep);
    if (!(dt < limit)) {
      std::ostringstream s;
      s << where("preparation.gamma_b") << ": " << prep.gamma_b
        << " kg/s makes the preparation's time step " << dt
        << " s (dem.dt_factor = " << o.system.dt_factor << ") exceed its explicit stability limit "
        << limit << " s; use a smaller preparation.gamma_b or dem.dt_factor";
      throw InputError(s.str());
    }
  }
  for (double e : o.path.snapshot_eps_dev)
    if (e > o.path.eps_dev_max)
      throw InputError(where("states.eps_dev") + ": every entry must be <= path.eps_dev_max");
  std::string why;
  if (!o.path.IsValid(&why)) throw InputError(where("path.type") + ": " + why);
  if (!o.system.IsValid(&why)) throw InputError("material/dem keys: " + why);
  if (!o.gas.IsValid(&why)) throw InputError("preparation keys: " + why);
  return o;
}

}  // namespace rendulic::dem
