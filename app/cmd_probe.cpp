// `rendulic probe PACKING --out DIR [--methods ...] [--amplitudes ...] [--directions M]
// [--set key=value ...]` (docs/interop.md, docs/usage.md): the probes, linear response and fits
// of a packing made elsewhere (a LAMMPS data file or dump) or of a state of a results file,
// written as DIR/results.h5 in the usual schema (docs/results.md), the packing under
// /states/<label>.
//
// The settings are the scenario keys, so a packing is probed exactly as `rendulic run` probes
// its states. A results file's state keeps that run's scenario (its material and probe keys) and
// restarts from its checkpoint, so probing it again gives the envelopes the run stored; a LAMMPS
// packing takes the seed's defaults, with <r> and w from its own radii (k* = k / 2<r> then
// scales its stress). Like the run's states, the packing is probed from rest: if its net
// forces are not balanced (rest.hpp's criterion) or it moves, it is relaxed and minimised at
// its fixed box first, and what moved is reported.
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "cli_options.hpp"
#include "commands.hpp"
#include "packing_system.hpp"
#include "pipeline.hpp"
#include "progress.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/log.hpp"
#include "rendulic/core/option_table.hpp"
#include "rendulic/core/packing_file.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/core/results.hpp"
#include "rendulic/dem/probe_campaign.hpp"
#include "rendulic/dem/rest.hpp"
#include "rendulic/dem/scenario_keys.hpp"
#include "stages.hpp"

namespace rendulic::app {
namespace {

constexpr char kLinear[] = "linear_response";

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The scenario the packing is probed with: a results file's own (its material and probe keys,
// so that its stored envelopes come out again), else the defaults; then the overrides.
Scenario probe_scenario(const PackingSource& src, const ProbeRequest& o) {
  Scenario sc(scenario_schema());
  if (src.format == PackingFormat::kResultsState) {
    const ResultsReader in(src.file);
    if (in.has_attr("/", "scenario")) {
      try {
        sc = Scenario::from_string(in.attr_string("/", "scenario"),
                                   src.file.string() + ":/scenario", scenario_schema());
      } catch (const InputError& e) {
        log::warning("the scenario stored in ", src.file.string(),
                     " does not parse with this version (", e.what(),
                     "); the defaults and the file's /material are used");
        for (const auto& [attribute, key] : kMaterialAttributes)
          if (in.has_attr(paths::kMaterial, attribute))
            sc.set(key, in.attr_double(paths::kMaterial, attribute));
      }
    }
  }
  for (const auto& s : o.sets) sc.apply_override(s);
  if (!o.amplitudes.empty()) sc.set("probes.amplitudes", o.amplitudes);
  if (o.directions > 0) sc.set("probes.directions", std::int64_t{o.directions});
  if (!o.planes.empty()) sc.set("probes.planes", o.planes);
  return sc;
}

// A packing from another engine: its size distribution sets <r> (hence k*) and w (hence the
// smallest contact duration and the time step), unless the keys say otherwise.
void size_keys_from_packing(Scenario& sc, const Packing& p) {
  const auto [lo, hi] = std::minmax_element(p.radii.begin(), p.radii.end());
  try {
    if (!sc.is_set("material.r_mean")) sc.set("material.r_mean", p.mean_radius());
    if (!sc.is_set("material.w")) sc.set("material.w", *hi / *lo);
  } catch (const InputError& e) {
    throw InputError(p.origin + ": its radii do not fit the material keys: " + e.what());
  }
}

struct Moved {
  double max_over_r = 0, rms_over_r = 0;
  long count = 0;  // particles moved by more than kMovedOverR <r>
};
constexpr double kMovedOverR = 1e-3;

Moved what_moved(const Packing& before, const dem::DemSystem& after, double r_mean) {
  Moved m;
  const dem::Particles& p = after.particles();
  const Eigen::Vector3d L = after.cell().lengths();
  double sum = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    Eigen::Vector3d d =
        p.position(i) - before.positions.row(static_cast<Eigen::Index>(i)).transpose();
    for (int a = 0; a < 3; ++a) d[a] -= L[a] * std::round(d[a] / L[a]);
    const double u = d.norm() / r_mean;
    m.max_over_r = std::max(m.max_over_r, u);
    sum += u * u;
    m.count += u > kMovedOverR;
  }
  m.rms_over_r = std::sqrt(sum / static_cast<double>(std::max<std::size_t>(p.size(), 1)));
  return m;
}

// One line per envelope: the stress fit's semi-axes per unit strain (in k*) and inclination.
void print_summary(const ResultsReader& in, const std::string& group) {
  const std::string envs = paths::envelopes(group);
  // Wide enough for the longest name (e.g. linear_response_meridian_22.5_5e-05).
  int width = 26;
  if (in.is_group(envs))
    for (const std::string& name : in.children(envs))
      width = std::max(width, static_cast<int>(name.size()) + 2);
  std::cout << std::left << std::setw(width) << "envelope" << std::setw(9) << "shape" << std::right
            << std::setw(14) << "a/strain[k*]" << std::setw(14) << "b/strain[k*]" << std::setw(18)
            << "inclination[deg]"
            << "\n";
  if (!in.is_group(envs)) return;
  for (const std::string& name : in.children(envs)) {
    const std::string g = paths::envelope(group, name), f = g + paths::kFitStress;
    std::cout << std::left << std::setw(width) << name;
    if (!in.is_group(f) || !in.has_attr(f, "semi_axes")) {
      std::cout << (in.has_attr(g, "error") ? in.attr_string(g, "error") : "no fit") << "\n";
      continue;
    }
    const double amp = in.attr_double(g, "amplitude");
    const std::vector<double> ab = in.attr_doubles(f, "semi_axes");
    std::cout << std::setw(9) << in.attr_string(f, "shape") << std::right << std::setprecision(5)
              << std::setw(14) << ab.at(0) / amp << std::setw(14) << ab.at(1) / amp << std::setw(18)
              << (in.has_attr(f, "inclination_deg") ? in.attr_double(f, "inclination_deg")
                                                    : std::nan(""))
              << "\n";
  }
}

}  // namespace

std::filesystem::path probe_packing(const ProbeRequest& r) {
  // What the CLI's option checks say before this runs, for callers without them (Python).
  for (const auto& m : r.methods)
    if (const std::string why = choice_refusal(m, kProbeMethods); !why.empty())
      throw InputError("--methods: " + why);
  // Twice, a method's campaign ran twice into the same groups (probes.methods refuses it too).
  if (const std::string* again = first_repeat(r.methods))
    throw InputError("--methods: method '" + *again + "' given twice");
  if (const std::string why = invalid_object_name_reason(r.label); !why.empty())
    throw InputError("--label: label '" + r.label + "' " + why);
  if (r.directions < 0) throw InputError("--directions must not be negative");
  check_thread_count(r.threads);
  if (r.quiet) log::set_level(log::Level::kWarning);
  // Everything is read and checked before the output folder is touched.
  refuse_empty_output_folder(r.out);
  const PackingSource src = packing_source(r.packing);
  {
    // The probes' results.h5 replaces the file at --out whole: probing a state of DIR/results.h5
    // into DIR replaced the run it came from by one state's envelopes, without a word.
    const std::filesystem::path target = std::filesystem::path(r.out) / "results.h5";
    std::error_code ec;
    if (std::filesystem::equivalent(src.file, target, ec))
      throw InputError("--out " + r.out +
                       ": its results.h5 is the file the packing is read from (" +
                       src.file.string() +
                       "), which the probes' results would replace; give "
                       "another --out");
  }
  const Packing packing = read_packing(src);
  Scenario sc = probe_scenario(src, r);
  const bool from_results = src.format == PackingFormat::kResultsState;
  if (!from_results) size_keys_from_packing(sc, packing);
  const dem::DemRunOptions dro = dem::dem_options_from_scenario(sc);
  dem::ProbeOptions po = dem::probe_options_from(sc);
  if (r.threads > 0) {
    po.threads = r.threads;
    omp_set_num_threads(r.threads);
  }
  std::vector<std::string> methods = r.methods;
  if (methods.empty()) {
    methods = dem::probe_methods_from(sc);
    methods.push_back(kLinear);
  }
  const double r_mean = dro.system.material.r_mean;
  log::info(packing.origin, ": N = ", packing.size(), ", nu = ", packing.volume_fraction(),
            ", <r> = ", r_mean, " m, box ", packing.lengths.transpose());
  if (!packing.densities.empty() &&
      std::any_of(packing.densities.begin(), packing.densities.end(), [&](double d) {
        return std::abs(d - dro.system.material.density) > 1e-12 * dro.system.material.density;
      }))
    log::warning(packing.origin, ": its densities differ from material.density (",
                 dro.system.material.density,
                 " kg/m^3), which is used (only the dynamic probes depend on it)");
  // Starred envelopes do not depend on the length unit (k* = k / (2 <r>)), but the rates, the
  // time step and the stress in Pa are those of metres.
  if (!packing.units.empty() && packing.units != "si")
    log::warning(packing.origin, ": its units are '", packing.units,
                 "'; its lengths are read as metres (rendulic works in SI)");

  std::optional<dem::DemSystem> sys;
  if (from_results) sys = restore_checkpoint(ResultsReader(src.file), src.object, dro.system);
  if (!sys) {
    try {
      sys = system_of_packing(packing, dro.system);
    } catch (const InputError& e) {
      throw InputError(packing.origin + ": " + e.what());
    }
  }
  if (!from_results && packing.velocities.rows() > 0 && !packing.velocities.isZero(0))
    log::info(packing.origin, ": its velocities are not used (a packing is probed from rest)");

  const std::filesystem::path out_dir = r.out;
  ResultsWriter out(out_dir / "results.h5");
  for (const auto& note : out.notes()) log::info(note);
  out.attr("/", "seed", sc.get_int("run.seed"));
  out.attr("/", "scenario", sc.to_toml());
  out.attr("/", "packing", r.packing);
  write_material(out, dro.system, static_cast<std::int64_t>(packing.size()));
  RunContext ctx{out_dir, r.threads, r.quiet, r.progress_every};

  // At rest, as the run's states are (rest.hpp): the criterion first, and only a
  // packing that fails it (or moves) is relaxed and minimised.
  auto t0 = Clock::now();
  log::info("[rest] started");
  dem::RestSummary rest;
  // A frictional packing has no minimum to go to (rest.hpp): its balance is that of its own
  // forces and torques, and it is relaxed again only if it moves.
  const bool frictional = dro.system.material.frictional();
  rest.after_relax = rest.at_rest =
      frictional ? dem::force_balance(*sys)
                 : dem::force_balance(dem::packing_of(*sys), dro.system.material.k);
  rest.stress_change.setZero();
  rest.relaxed.converged = true;
  const bool moving = sys->kinetic_energy() > 0;
  // Contacts without a backbone (spheres pressed together, no rigid structure) carry forces
  // that nothing balances, though the criterion, judged over non-rattlers, is 0: two spheres
  // overlapping by 1.9 radii were "at rest as read".
  const bool pressed =
      !frictional && rest.at_rest.non_rattlers == 0 && rest.at_rest.all_contacts > 0;
  if ((!frictional && rest.at_rest.ratio >= dem::kEquilibrium) || pressed || moving) {
    if (pressed)
      log::info(rest.at_rest.all_contacts,
                " contact(s) but no rigid backbone: every particle is a rattler, so nothing "
                "balances their forces; relaxing and minimising at the fixed box");
    else
      log::info("net force ", rest.at_rest.ratio, " of the mean contact force (at rest: below ",
                dem::kEquilibrium, "): relaxing and minimising at the fixed box");
    try {
      rest = dem::bring_to_rest(*sys, dro.state_rest);
    } catch (const std::runtime_error& e) {
      throw InputError(packing.origin + ": cannot be brought to rest: " + e.what());
    }
    if (!frictional && !(rest.at_rest.ratio < dem::kEquilibrium))
      throw InputError(packing.origin + ": not at rest after minimisation (net force " +
                       decimal_g(rest.at_rest.ratio) + " of the mean contact force)");
    const Moved m = what_moved(packing, *sys, r_mean);
    // Spheres pressed together without a backbone fly apart: no pressure is left to compare with.
    const double p = sys->measure().pressure;
    std::ostringstream change;
    if (p > 0.0)
      change << "the minimisation changed the stress by " << rest.stress_change.norm() / p
             << " of p";
    else
      change << "no contact is left (p = 0; the minimisation changed the stress by "
             << rest.stress_change.norm() << " Pa)";
    log::info("at rest: relaxed for ", rest.relaxed.time, " s (", rest.relaxed.steps,
              " steps), then ", rest.minimised.iterations, " FIRE iterations: net force ",
              rest.at_rest.ratio, " of the mean contact force; ", m.count, " of ", packing.size(),
              " particles moved more than ", kMovedOverR,
              " <r> from the file's positions (largest ", m.max_over_r, " <r>, rms ", m.rms_over_r,
              " <r>); ", change.str());
  } else {
    log::info("at rest as read: net force ", rest.at_rest.ratio,
              " of the mean contact force; nothing moved");
  }
  std::optional<dem::SaddleEscape> saddle;
  if (r.leave_saddle && frictional) {
    log::warning(
        "--leave-saddle: a frictional packing has no energy whose saddles to leave; "
        "ignored");
  } else if (r.leave_saddle) {
    const double p0 = sys->measure().pressure;
    const Eigen::Matrix3d s0 = sys->stress();
    saddle = dem::leave_saddle(*sys, dro.state_rest.minimise);
    if (saddle->rounds == 0) {
      log::info("not a saddle of its energy (", saddle->negative_modes,
                " negative modes at rest): nothing moved");
    } else {
      // The state's force_balance is that of where it ended.
      rest.at_rest = dem::force_balance(dem::packing_of(*sys), dro.system.material.k);
      const Moved m = what_moved(packing, *sys, r_mean);
      log::info("a saddle of its energy with ", saddle->negative_modes,
                " negative mode(s): moved off along them and minimised (", saddle->rounds,
                " round(s), ", saddle->iterations, " FIRE iterations); ", m.count, " of ",
                packing.size(), " particles moved more than ", kMovedOverR,
                " <r> from the file's positions (largest ", m.max_over_r, " <r>, rms ",
                m.rms_over_r, " <r>); the stress changed by ", (sys->stress() - s0).norm() / p0,
                " of p, p by ", sys->measure().pressure / p0 - 1);
      if (!saddle->left)
        log::warning("still not at a minimum after ", saddle->rounds,
                     " round(s): ", saddle->message);
    }
  }
  const std::string group = paths::state(r.label);
  write_state(out, group, *sys, rest, dro.state_rest.minimise.force_tolerance, true);
  out.attr(group, "source", packing.origin);
  if (saddle) {
    out.attr(group, "saddle_negative_modes", static_cast<std::int64_t>(saddle->negative_modes));
    out.attr(group, "saddle_rounds", static_cast<std::int64_t>(saddle->rounds));
  }
  out.attr(paths::kTimings, "rest", since(t0));
  log::info("[rest] done in ", human_seconds(since(t0)));

  t0 = Clock::now();
  log::info("[probes] started");
  {
    Progress progress(ctx, "probes");
    std::atomic<long> done{0};
    long total = 0;
    for (const auto& m : methods)
      total += m == kLinear
                   ? 0
                   : static_cast<long>(po.planes.size() * po.amplitudes.size()) * po.directions;
    po.probe_done = [&progress, &done, total] { progress.count(++done, total); };
    po.stop = stop_checker();
    for (const auto& m : methods) {
      progress.start_task(m);
      try {
        write_probe_campaign(*sys, group, {m}, po, out);
      } catch (const std::runtime_error& e) {
        if (m != kLinear || dynamic_cast<const InputError*>(&e)) throw;
        // As in the run: a network with no elastic response is a finding, recorded.
        for (const std::string& plane : po.planes)
          for (double a : po.amplitudes) {
            const std::string g = paths::envelope(group, paths::envelope_name(m, a, plane));
            out.attr(g, "method", m);
            out.attr(g, "amplitude", a);
            out.attr(g, "plane", plane);
            out.attr(g, "error", std::string(e.what()));
          }
        log::warning("no linear response: ", e.what());
      }
    }
  }
  out.attr(paths::kTimings, "probes", since(t0));
  log::info("[probes] done in ", human_seconds(since(t0)));
  t0 = Clock::now();
  fit_state_envelopes(sc, out, group);
  out.attr(paths::kTimings, "fits", since(t0));
  if (r.summary) print_summary(out.read_back(), group);
  out.commit();
  log::info("wrote ", out.final_path().string());
  return out.final_path();
}

Subcommand add_probe(CLI::App& parent) {
  auto o = std::make_shared<ProbeRequest>();
  auto* sub = parent.add_subcommand(
      "probe",
      "Probe a packing made elsewhere (LAMMPS data file or dump) or a results file's state "
      "(FILE.h5:/states/a): rest, probes, linear response and fits into DIR/results.h5");
  sub->add_option("packing", o->packing,
                  "LAMMPS data file (atom_style sphere), LAMMPS text dump (id, radius or diameter, "
                  "x y z), or RESULTS.h5:/states/LABEL")
      ->required();
  sub->add_option("--out", o->out, "output folder")->capture_default_str();
  sub->add_option("--label", o->label, "the packing's state label in the results file")
      ->capture_default_str()
      ->check(CLI::Validator(
          [](std::string& s) {
            const std::string why = invalid_object_name_reason(s);
            return why.empty() ? why : "label '" + s + "' " + why;
          },
          "LABEL"));
  sub->add_option("--methods", o->methods,
                  "probe methods (default: probes.methods and linear_response)")
      ->check(one_of({kProbeMethods.begin(), kProbeMethods.end()}))
      ->delimiter(',');
  sub->add_option("--amplitudes", o->amplitudes, "probe strain amplitudes (probes.amplitudes)")
      ->delimiter(',');
  sub->add_option("--directions", o->directions, "probe directions M (probes.directions)")
      ->check(positive_number());
  sub->add_option("--planes", o->planes,
                  "probe planes: rendulic, deviatoric, meridian_<Lode deg> (probes.planes)")
      ->delimiter(',');
  sub->add_option("--set", o->sets, "override a scenario key by its dotted path: a.b=value")
      ->take_all();
  sub->add_option("--threads", o->threads, "OpenMP threads over the probes (0: all cores)")
      ->check(thread_count());
  sub->add_flag("--leave-saddle", o->leave_saddle,
                "a frictionless packing at rest whose energy has negative modes (a saddle, as "
                "copies of a smaller packing side by side often are) is moved off along them and "
                "minimised before it is probed; how far it moved is reported");
  sub->add_flag("--quiet", o->quiet, "no progress; warnings and errors still print");
  add_progress_every(sub, o->progress_every);
  return {sub, [o]() -> int {
            probe_packing(*o);
            return 0;
          }};
}

}  // namespace rendulic::app
