// `rendulic export RESULTS.h5 --state LABEL --lammps FILE` (docs/interop.md): a state of a
// results file as a LAMMPS data file (atom_style sphere, its peculiar velocities included), from
// which LAMMPS, with the pair settings that docs/interop.md gives and this command prints,
// computes the stored stress to round-off. The same writer serves `rendulic bench --lammps`.
#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "commands.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/log.hpp"
#include "rendulic/core/packing_file.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/core/results.hpp"
#include "rendulic/dem/contact.hpp"
#include "stages.hpp"

namespace rendulic::app {
namespace {
struct ExportOptions {
  std::string results;
  std::string state;
  std::string lammps;
};

}  // namespace

Subcommand add_export(CLI::App& parent) {
  auto o = std::make_shared<ExportOptions>();
  auto* sub = parent.add_subcommand(
      "export",
      "Write a state of a results file as a LAMMPS data file (atom_style sphere, velocities "
      "included); the LAMMPS settings that reproduce its stress are in docs/interop.md");
  sub->add_option("results", o->results, "results file (HDF5)")->required();
  sub->add_option("--state", o->state,
                  "the state: a label (a for /states/a) or a group (/pressure/nu0.7/states/a)")
      ->required();
  sub->add_option("--lammps", o->lammps, "the LAMMPS data file to write")->required();
  return {sub, [o]() -> int {
            std::string group = o->state;
            if (group.empty() || group.front() != '/') {
              if (const std::string why = invalid_object_name_reason(group); !why.empty())
                throw InputError("export --state '" + o->state + "' " + why);
              group = paths::state(group);
            }
            const Packing p = read_results_state(o->results, group);
            const ResultsReader in(o->results);
            // Written into the data file and the pair settings: NaN, a negative stiffness or
            // density went out as `pair_coeff * * hooke nan ...` with exit 0.
            const auto material = [&](const char* key, bool zero_allowed) {
              const double v = in.attr_double(paths::kMaterial, key);
              if (!std::isfinite(v) || v < 0.0 || (v == 0.0 && !zero_allowed)) {
                std::ostringstream why;
                why << o->results << ":" << paths::kMaterial << "@" << key << " is " << v
                    << ", not a "
                    << (zero_allowed ? "finite number >= 0" : "positive finite number");
                throw InputError(why.str());
              }
              return v;
            };
            const double k = material("k", false);
            const double gamma = material("gamma", true);
            const double density = material("density", false);
            const double dt = material("dt", false);
            std::ostringstream title;
            title << std::setprecision(17) << "rendulic state " << group << " of " << o->results
                  << " (N = " << p.size() << ", nu = " << p.volume_fraction() << ", k = " << k
                  << ", gamma = " << gamma << ", dt = " << dt << " s)";
            write_lammps_data(o->lammps, p, density, title.str());
            log::info("wrote ", o->lammps, ": ", p.size(),
                      " spheres; the LAMMPS pair settings of its material follow (units si, "
                      "atom_style sphere; docs/interop.md)");
            dem::Material m;
            m.k = k;
            m.gamma = gamma;
            // Friction is stored only when it is on (stages_dem.cpp, write_material).
            if (in.has_attr(paths::kMaterial, "friction")) {
              m.mu = in.attr_double(paths::kMaterial, "friction");
              m.k_t_ratio = in.attr_double(paths::kMaterial, "k_t_ratio");
              m.gamma_t_ratio = in.attr_double(paths::kMaterial, "gamma_t_ratio");
            }
            if (in.has_attr(paths::kMaterial, "rolling_friction")) {
              m.mu_r = in.attr_double(paths::kMaterial, "rolling_friction");
              m.k_r_ratio = in.attr_double(paths::kMaterial, "k_r_ratio");
              m.gamma_r_ratio = in.attr_double(paths::kMaterial, "gamma_r_ratio");
            }
            std::cout << dem::lammps_pair_lines(m);
            // `rendulic probe` of a data file takes <r> and w from its radii (the sample's mean
            // radius, not the distribution's) and the rest of the material from the defaults:
            // the keys that give it the run's material, hence the run's k* and time step.
            const Scenario defaults(scenario_schema());
            std::string sets;
            for (const auto& [attribute, key] : kMaterialAttributes) {
              if (!in.has_attr(paths::kMaterial, attribute)) continue;
              const double v = in.attr_double(paths::kMaterial, attribute);
              const std::string k = key;
              if (k == "material.r_mean" || k == "material.w" || v != defaults.get_double(k))
                sets += " --set " + k + "=" + decimal_text(v);
            }
            log::info("to probe ", o->lammps,
                      " with the run's material (a data file has neither <r> nor w, which set k* "
                      "and the time step): rendulic probe ",
                      o->lammps, sets);
            return 0;
          }};
}

}  // namespace rendulic::app
