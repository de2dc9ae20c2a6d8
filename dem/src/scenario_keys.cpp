// Declaration of the DEM scenario keys and their conversion to protocol options (see
// scenario_keys.hpp). Defaults are the seed study's (docs/physics.md sections 1 and 4) except where
// the seed gives no number (rates, relaxation thresholds), where the choice is explained in
// the help text and docs/dem.md.
#include "rendulic/dem/scenario_keys.hpp"

#include <limits>
#include <set>
#include <sstream>

#include "rendulic/core/errors.hpp"
#include "rendulic/core/result_paths.hpp"

namespace rendulic::dem {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

KeySpec num(const std::string& path, double def, const std::string& unit, const std::string& help,
            double min, double max, bool min_open = false, bool max_open = false) {
  KeySpec k;
  k.path = path;
  k.type = KeyType::kDouble;
  k.default_value = def;
  k.unit = unit;
  k.help = help;
  k.min = min;
  k.max = max;
  k.min_open = min_open;
  k.max_open = max_open;
  return k;
}

KeySpec integer(const std::string& path, std::int64_t def, const std::string& unit,
                const std::string& help, double min, double max) {
  KeySpec k = num(path, 0, unit, help, min, max);
  k.type = KeyType::kInt;
  k.default_value = def;
  return k;
}

}  // namespace

void register_dem_keys(ScenarioSchema& s) {
  s.add(num("material.k", 1e8, "kg/s^2", "Normal contact stiffness k.", 0, kInf, true, true));
  s.add(num("material.gamma", 1.0, "kg/s", "Normal contact viscosity gamma (dashpot).", 0, kInf,
            false, true));
  s.add(num("material.gamma_b", 0.1, "kg/s",
            "Background damping on the velocity relative to the imposed flow.", 0, kInf, false,
            true));
  s.add(num("material.density", 2000, "kg/m^3", "Particle density rho.", 0, kInf, true, true));
  s.add(num("material.r_mean", 1e-3, "m", "Mean radius <r> of the uniform size distribution.", 0,
            kInf, true, true));
  s.add(num("material.w", 3.0, "-",
            "Polydispersity w = r_max / r_min (radii uniform in "
            "[r_min, r_max], number-weighted).",
            1, 100));
  s.add(integer("dem.n_particles", 9261, "-", "Number of particles N (the seed: 9261 = 21^3).", 50,
                5e6));
  s.add(num("dem.dt_factor", 0.02, "-",
            "Time step as a fraction of the contact duration t_c of the two smallest particles; "
            "values beyond the explicit stability limit are refused.",
            0, 1, true));
  s.add(num("dem.skin", 0.3, "-", "Verlet-list skin in units of <r> (speed only, not physics).", 0,
            2, true));
  s.add(num("preparation.nu_gas", 0.3, "-", "Volume fraction of the initial random gas.", 0, 0.4,
            true));
  s.add(num("preparation.gas_velocity", 1.0, "m/s",
            "Standard deviation of each component of the gas's random velocities.", 0, 1e3));
  s.add(num("preparation.mix_time", 0.0, "s",
            "Time the gas mixes at fixed cell before compression (random insertion already "
            "gives a random gas).",
            0, 1));
  s.add(num("preparation.rate", 300, "1/s",
            "Isotropic compression rate of the gas to nu0 (|D_aa|); fast compression heats the "
            "gas through affine collisions, which the relaxation at nu0 then removes.",
            0, 1e6, true));
  s.add(num("preparation.gamma_b", 0.1, "kg/s",
            "Background damping during the preparation only (gas, compression to nu0, relaxation "
            "at nu0); the seed's value by default. A larger value cools the compressed gas "
            "faster; the packing at nu0 is unjammed, and every later stage uses material.gamma_b.",
            0, kInf, false, true));
  s.add(num("preparation.nu0", 0.64, "-",
            "Volume fraction nu0 reached by the gas compression, "
            "just below isotropic jamming.",
            0, 1, true, true));
  s.add(num("relax.kinetic_to_elastic", 1e-5, "-",
            "Relaxation at nu0 and nu_max ends when E_kin / max(E_el, N k (1e-4 <r>)^2 / 2) "
            "falls below this.",
            0, 1, true));
  s.add(num("relax.time_cap", 2e-3, "s", "Longest relaxation at nu0 and nu_max (reported if hit).",
            0, 10, true));
  s.add(num("isotropic.nu_max", 0.82, "-", "Volume fraction nu_max of the isotropic loading.", 0, 1,
            true, true));
  s.add(integer("isotropic.samples", 60, "-",
                "Samples of the isotropic branch (equally spaced in ln nu, ends included).", 50,
                1e6));
  s.add(num("isotropic.inertial_number", 5e-4, "-",
            "Inertial number held by the loading rate (0: constant rate isotropic.rate_max).", 0,
            1e-2));
  s.add(num("isotropic.rate_max", 400, "1/s", "Largest isotropic loading rate |D_aa|.", 0, 1e6,
            true));
  s.add(num("isotropic.rate_min", 50, "1/s",
            "Smallest isotropic loading rate (used while the pressure is ~0, below jamming).", 0,
            1e6, true));
  {
    KeySpec k = num("pressure.volume_fractions", 0, "-",
                    "Volume fractions (between preparation.nu0 and isotropic.nu_max) at which the "
                    "isotropic loading is also snapshotted; the pressure stage repeats the path, "
                    "the states, their elastic range, probes and linear response from each "
                    "(docs/dem.md 'Pressure branches').",
                    0, 1, true, true);
    k.type = KeyType::kDoubleList;
    k.default_value = std::vector<double>{};
    s.add(k);
  }
  s.add(num("path.rate", 400, "1/s",
            "Axial extension rate D_xx of the undrained path D = rate diag(1, -1/2, -1/2).", 0, 1e6,
            true));
  s.add(num("path.eps_dev_max", 0.32, "-", "Final -eps_dev of the undrained path.", 0, 2, true));
  s.add(integer("path.samples", 200, "-", "Samples along the path (equally spaced in -eps_dev).", 2,
                1e7));
  {
    KeySpec k =
        num("states.eps_dev", 0, "-",
            "-eps_dev of the snapshots taken on the path and relaxed at fixed cell.", 0, 2, true);
    k.type = KeyType::kDoubleList;
    k.default_value = std::vector<double>{0.006, 0.021, 0.043, 0.068, 0.32};
    k.min_size = 1;
    s.add(k);
  }
  {
    KeySpec k = num("states.labels", 0, "-",
                    "Group names /states/<label> of the snapshots, one per states.eps_dev (the "
                    "seed's figure panels a-e).",
                    -kInf, kInf);
    std::vector<std::string> labels;
    for (char c = 'a'; c <= 'e'; ++c) labels.emplace_back(1, c);
    k.type = KeyType::kStringList;
    k.default_value = labels;
    k.min_size = 1;
    s.add(k);
  }
  s.add(num("states.kinetic_to_elastic", 1e-6, "-",
            "Relaxation of each snapshot ends when E_kin / E_el falls below this.", 0, 1, true));
  s.add(num("states.time_cap", 2e-3, "s", "Longest relaxation of a snapshot (reported if hit).", 0,
            10, true));
  s.add(num("states.force_tolerance", 1e-9, "-",
            "After the dynamic relaxation each snapshot is minimised (FIRE, fixed cell) until the "
            "largest net force on a particle is below this x the mean contact force: the state "
            "is then at rest, and so are its stress, fabric, linear response and envelopes.",
            0, 1e-4, true));
}

Material material_from_scenario(const Scenario& sc) {
  Material m;
  m.k = sc.get_double("material.k");
  m.gamma = sc.get_double("material.gamma");
  m.gamma_b = sc.get_double("material.gamma_b");
  m.density = sc.get_double("material.density");
  m.r_mean = sc.get_double("material.r_mean");
  m.w = sc.get_double("material.w");
  return m;
}

DemRunOptions dem_options_from_scenario(const Scenario& sc) {
  DemRunOptions o;
  o.system.material = material_from_scenario(sc);
  const Material& m = o.system.material;
  o.system.dt_factor = sc.get_double("dem.dt_factor");
  o.system.skin = sc.get_double("dem.skin");
  check_time_step(m, o.system.dt_factor, "dem.dt_factor (" + sc.origin("dem.dt_factor") + ")");

  o.gas.n_particles = static_cast<std::size_t>(sc.get_int("dem.n_particles"));
  o.gas.volume_fraction = sc.get_double("preparation.nu_gas");
  o.gas.velocity = sc.get_double("preparation.gas_velocity");
  o.mix_time = sc.get_double("preparation.mix_time");
  o.prepare_gamma_b = sc.get_double("preparation.gamma_b");
  o.prepare.target_nu = sc.get_double("preparation.nu0");
  o.prepare.rate_max = o.prepare.rate_min = sc.get_double("preparation.rate");
  o.relax.kinetic_to_elastic = sc.get_double("relax.kinetic_to_elastic");
  o.relax.time_cap = sc.get_double("relax.time_cap");
  o.loading.target_nu = sc.get_double("isotropic.nu_max");
  o.loading.samples = static_cast<int>(sc.get_int("isotropic.samples"));
  o.loading.inertial_number = sc.get_double("isotropic.inertial_number");
  o.loading.rate_max = sc.get_double("isotropic.rate_max");
  o.loading.rate_min = sc.get_double("isotropic.rate_min");
  o.branch_nu = sc.get_doubles("pressure.volume_fractions");
  o.loading.snapshot_nu = o.branch_nu;
  o.path.rate = sc.get_double("path.rate");
  o.path.eps_dev_max = sc.get_double("path.eps_dev_max");
  o.path.samples = static_cast<int>(sc.get_int("path.samples"));
  o.path.snapshot_eps_dev = sc.get_doubles("states.eps_dev");
  o.state_labels = sc.get_strings("states.labels");
  o.state_rest.relax.kinetic_to_elastic = sc.get_double("states.kinetic_to_elastic");
  o.state_rest.relax.time_cap = sc.get_double("states.time_cap");
  o.state_rest.minimise.force_tolerance = sc.get_double("states.force_tolerance");
  o.state_rest.minimise.k = m.k;

  auto where = [&](const char* key) { return std::string(key) + " (" + sc.origin(key) + ")"; };
  if (!(o.gas.volume_fraction < o.prepare.target_nu))
    throw InputError(where("preparation.nu0") + ": must exceed preparation.nu_gas");
  if (!(o.prepare.target_nu < o.loading.target_nu))
    throw InputError(where("isotropic.nu_max") + ": must exceed preparation.nu0");
  if (o.loading.rate_min > o.loading.rate_max)
    throw InputError(where("isotropic.rate_min") + ": must not exceed isotropic.rate_max");
  if (o.state_labels.size() != o.path.snapshot_eps_dev.size())
    throw InputError(where("states.labels") + ": needs one label per states.eps_dev entry (" +
                     std::to_string(o.path.snapshot_eps_dev.size()) + ")");
  std::set<std::string> seen;
  for (const auto& l : o.state_labels) {
    // Each label names the group /states/<label> of the results file.
    if (const std::string why = invalid_object_name_reason(l); !why.empty())
      throw InputError(where("states.labels") + ": label '" + printable(l) + "' " + why);
    if (!seen.insert(l).second)
      throw InputError(where("states.labels") + ": duplicate label '" + l + "'");
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
  if (!o.system.IsValid(&why)) throw InputError("material/dem keys: " + why);
  if (!o.gas.IsValid(&why)) throw InputError("preparation keys: " + why);
  return o;
}

}  // namespace rendulic::dem
