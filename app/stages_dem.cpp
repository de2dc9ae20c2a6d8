// The DEM stages of `rendulic run` (docs/physics.md section 4; docs/results.md):
//   prepare   -> /material, /preparation : random gas, compression to nu0, relaxation
//   isotropic -> /isotropic : loading nu0 -> nu_max (>= 50 samples), relaxation at nu_max
//   path      -> /path      : constant-volume axisymmetric extension, snapshots in memory
//   states    -> /states/<label> : each snapshot relaxed at fixed cell and minimised to
//                mechanical equilibrium (rest.hpp), stored with a checkpoint that restarts
//                bit-identically (same build)
// The stages of one run share the live system through the DemRunSession the pipeline hands
// them; later stages (probe campaigns) take the relaxed states from it. Progress lines
// (progress.hpp) go to the terminal or the log.
#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <optional>
#include <string>

#include "pipeline.hpp"
#include "progress.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/log.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/dem/protocols.hpp"
#include "rendulic/dem/rest.hpp"
#include "rendulic/dem/run_protocol.hpp"
#include "rendulic/dem/scenario_keys.hpp"
#include "rendulic/dem/team.hpp"
#include "stages.hpp"

namespace rendulic::app {

namespace {

void write_relax(ResultsWriter& out, const std::string& group, const std::string& prefix,
                 const dem::RelaxSummary& r) {
  out.attr(group, prefix + "relax_time", r.time);
  out.attr(group, prefix + "relax_ratio", r.ratio);
  out.attr(group, prefix + "relax_converged", std::int64_t{r.converged});
}

void warn_cap(const std::string& what, const dem::RelaxSummary& r) {
  if (!r.converged)
    log::warning("relaxation ", what, " hit its time cap (", r.time, " s) at kinetic/elastic ",
                 r.ratio);
}

Eigen::MatrixXd as_matrix(const std::vector<double>& x, const std::vector<double>& y,
                          const std::vector<double>& z) {
  Eigen::MatrixXd m(static_cast<Eigen::Index>(x.size()), 3);
  for (std::size_t i = 0; i < x.size(); ++i)
    m.row(static_cast<Eigen::Index>(i)) << x[i], y[i], z[i];
  return m;
}

// A spring history (3 doubles per list entry, State) as its checkpoint's [entries, 3] dataset.
Eigen::MatrixXd springs_matrix(const std::vector<double>& history) {
  using Rows = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  return Eigen::Map<const Rows>(history.data(), static_cast<Eigen::Index>(history.size() / 3), 3);
}

// The series that only a frictional packing has (frictionless files keep their layout).
void append_friction(ResultsWriter& out, const std::string& g, const dem::Measures& m,
                     const dem::Material& material) {
  if (!material.frictional()) return;
  out.append(g + datasets::kRotationalEnergy, m.rotational_energy);
  out.append(g + datasets::kSlidingDissipation, m.sliding_dissipation);
  out.append(g + datasets::kSlidingFraction, m.sliding_fraction);
}

dem::DemSystem& live_system(DemRunSession& s, const char* stage) {
  if (!s.system)
    throw InputError(std::string("run: stage '") + stage +
                     "' needs the stages before it "
                     "(prepare, isotropic, path) in run.stages");
  return *s.system;
}

}  // namespace

void write_material(ResultsWriter& out, const dem::SystemOptions& system,
                    std::int64_t n_particles) {
  const dem::Material& m = system.material;
  out.attr(paths::kMaterial, "k", m.k);
  out.attr(paths::kMaterial, "gamma", m.gamma);
  out.attr(paths::kMaterial, "gamma_b", m.gamma_b);
  out.attr(paths::kMaterial, "density", m.density);
  out.attr(paths::kMaterial, "r_mean", m.r_mean);
  out.attr(paths::kMaterial, "w", m.w);
  out.attr(paths::kMaterial, "k_star", m.k_star());
  out.attr(paths::kMaterial, "dt", dem::time_step(m, system.dt_factor));
  out.attr(paths::kMaterial, "dt_factor", system.dt_factor);
  out.attr(paths::kMaterial, "n_particles", n_particles);
  if (m.frictional()) {  // frictionless files keep their layout
    out.attr(paths::kMaterial, "friction", m.mu);
    out.attr(paths::kMaterial, "k_t_ratio", m.k_t_ratio);
    out.attr(paths::kMaterial, "gamma_t_ratio", m.gamma_t_ratio);
  }
  if (m.rolling()) {  // files without rolling keep their layout
    out.attr(paths::kMaterial, "rolling_friction", m.mu_r);
    out.attr(paths::kMaterial, "k_r_ratio", m.k_r_ratio);
    out.attr(paths::kMaterial, "gamma_r_ratio", m.gamma_r_ratio);
  }
}

void stage_prepare(const Scenario& sc, ResultsWriter& out, const RunContext& ctx,
                   DemRunSession& session) {
  session = DemRunSession{};
  session.options = dem::dem_options_from_scenario(sc);
  const dem::DemRunOptions& o = *session.options;
  Progress progress(ctx, "prepare");

  write_material(out, o.system, static_cast<std::int64_t>(o.gas.n_particles));

  dem::PreparedPacking p = dem::prepare_packing(
      o, static_cast<std::uint64_t>(sc.get_int("run.seed")),
      [&](const std::string& t) { progress.start_task(t); }, progress.fn());
  warn_cap("at nu0", p.relax);
  const dem::Measures& me = p.at_nu0;
  out.attr(paths::kPreparation, "nu0", me.volume_fraction);
  out.attr(paths::kPreparation, "pressure_star", me.pressure_star);
  out.attr(paths::kPreparation, "coordination", me.coordination);
  out.attr(paths::kPreparation, "compression_time", p.compression.time);
  write_relax(out, paths::kPreparation, "", p.relax);
  out.attr(paths::kPreparation, "steps", p.steps);
  out.attr(paths::kPreparation, "gamma_b", o.prepare_gamma_b);
  if (o.system.material.frictional())  // the friction it ran with (isotropic.friction_factor)
    out.attr(paths::kPreparation, "friction", p.system.material().mu);
  out.attr(paths::kPreparation, "wall_time_s", progress.elapsed());
  session.system = std::move(p.system);
}

void stage_isotropic(const Scenario&, ResultsWriter& out, const RunContext& ctx,
                     DemRunSession& session) {
  dem::DemSystem& sys = live_system(session, "isotropic");
  const dem::DemRunOptions& o = *session.options;
  Progress progress(ctx, "isotropic");
  const std::int64_t steps0 = sys.steps();
  const std::string g = paths::kIsotropic;
  auto row = [&](const dem::Measures& m) {
    out.append(g + datasets::kTime, m.time);
    out.append(g + datasets::kVolumeFraction, m.volume_fraction);
    out.append(g + datasets::kPressure, m.pressure);
    out.append(g + datasets::kPressureStar, m.pressure_star);
    out.append(g + datasets::kCoordination, m.coordination);
    out.append(g + datasets::kCoordinationNonrattler, m.coordination_nonrattler);
    out.append(g + datasets::kRattlerFraction, m.rattler_fraction);
    out.append(g + datasets::kStress, m.stress);
    out.append(g + datasets::kFabric, m.fabric);
    out.append(g + datasets::kKineticEnergy, m.kinetic_energy);
    out.append(g + datasets::kElasticEnergy, m.elastic_energy);
    out.append(g + datasets::kInertialNumber, m.inertial_number);
    append_friction(out, g, m, o.system.material);
  };
  dem::IsotropicLoading iso = dem::load_isotropic(
      sys, o.loading, o.relax, row, [&](const std::string& t) { progress.start_task(t); },
      progress.fn(), o.path);
  dem::CompressSummary& c = iso.loading;
  const dem::RelaxSummary& r = iso.relax;
  auto& branches = session.branches;
  branches.clear();
  for (std::size_t k = 0; k < c.snapshots.size(); ++k)
    branches.emplace_back(o.loading.snapshot_nu[k], std::move(c.snapshots[k]));
  warn_cap("at nu_max", r);
  if (o.system.material.frictional()) out.attr(paths::kIsotropic, "friction", sys.material().mu);
  dem::use_run_material(sys, o);
  const dem::Measures me = sys.measure();
  session.path_start_pressure = me.pressure;
  out.attr(paths::kIsotropic, "max_inertial_number", c.max_inertial_number);
  out.attr(paths::kIsotropic, "relaxed_pressure_star", me.pressure_star);
  out.attr(paths::kIsotropic, "relaxed_coordination", me.coordination);
  out.attr(paths::kIsotropic, "relaxed_coordination_nonrattler", me.coordination_nonrattler);
  write_relax(out, paths::kIsotropic, "", r);
  out.attr(paths::kIsotropic, "steps", sys.steps() - steps0);
  out.attr(paths::kIsotropic, "wall_time_s", progress.elapsed());
}

dem::SampleFn path_recorder(ResultsWriter& out, const std::string& g,
                            const dem::Material& material) {
  return [&out, g, material](const dem::Measures& m) {
    out.append(g + datasets::kTime, m.time);
    out.append(g + datasets::kStrain, m.strain);
    out.append(g + datasets::kEpsV, m.eps_v);
    out.append(g + datasets::kEpsDev, m.eps_dev);
    out.append(g + datasets::kStress, m.stress);
    out.append(g + datasets::kStressStar, m.stress_star);
    out.append(g + datasets::kFabric, m.fabric);
    out.append(g + datasets::kVolumeFraction, m.volume_fraction);
    out.append(g + datasets::kCoordination, m.coordination);
    out.append(g + datasets::kCoordinationNonrattler, m.coordination_nonrattler);
    out.append(g + datasets::kKineticEnergy, m.kinetic_energy);
    out.append(g + datasets::kElasticEnergy, m.elastic_energy);
    out.append(g + datasets::kInertialNumber, m.inertial_number);
    append_friction(out, g, m, material);
  };
}

void stage_path(const Scenario&, ResultsWriter& out, const RunContext& ctx,
                DemRunSession& session) {
  dem::DemSystem& sys = live_system(session, "path");
  const dem::DemRunOptions& o = *session.options;
  Progress progress(ctx, "path");
  progress.start_task(o.path.type);
  const std::int64_t steps0 = sys.steps();
  dem::PathSummary p = dem::run_path(
      sys, o.path, path_recorder(out, paths::kPath, o.system.material), progress.fn());
  out.attr(paths::kPath, "rate", o.path.rate);
  if (o.path.inertial_number > 0) {  // the rate followed p: the samples' time and I record it
    out.attr(paths::kPath, "inertial_number", o.path.inertial_number);
    out.attr(paths::kPath, "rate_min", o.path.rate_min);
  }
  out.attr(paths::kPath, "type", o.path.type);
  if (dem::path_type(o.path.type).mixed()) {
    out.attr(paths::kPath, "servo_error", p.servo_error);
    out.attr(paths::kPath, "servo_tolerance", o.path.servo_tolerance);
    if (!p.servo_held)
      log::warning("path: the lateral servo left an error of ", p.servo_error,
                   " p0, above path.servo_tolerance = ", o.path.servo_tolerance,
                   " (raise path.servo_integral_gain or lower path.rate)");
  }
  out.attr(paths::kPath, "max_inertial_number", p.max_inertial_number);
  out.attr(paths::kPath, "steps", sys.steps() - steps0);
  out.attr(paths::kPath, "wall_time_s", progress.elapsed());
  session.snapshots = std::move(p.snapshots);
}

std::vector<std::pair<dem::DemSystem, dem::RestSummary>> rest_states(
    const std::vector<dem::DemSystem>& snapshots, const dem::RestOptions& options,
    const std::vector<std::string>& labels, const RunContext& ctx) {
  // The states are independent: one OpenMP team over them, the engine's inner loops serial
  // inside each (as the probe campaigns do), so each state is the same whatever the thread
  // count. No exception may leave the parallel region.
  Progress progress(ctx, "states");
  const int n = static_cast<int>(snapshots.size());
  std::vector<std::optional<dem::DemSystem>> rested(snapshots.size());
  std::vector<dem::RestSummary> summaries(snapshots.size());
  // Bad input found while resting a state (a tolerance below the round-off floor) stays bad
  // input once it has left the parallel region (exit 2, not an internal error).
  std::vector<CaughtError> errors(snapshots.size());
  progress.start_task("relax and minimise " + std::to_string(n) + " states");
  long done = 0;
  const int team = dem::task_team(ctx.threads, snapshots.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(team)
  for (int k = 0; k < n; ++k) {
    omp_set_num_threads(1);
    const auto u = static_cast<std::size_t>(k);
    try {
      dem::DemSystem sys = snapshots[u];
      summaries[u] = dem::bring_to_rest(sys, options);
      rested[u] = std::move(sys);
    } catch (...) {
      errors[u] = CaughtError::current();
    }
    long finished = 0;
#pragma omp atomic capture
    finished = ++done;
    progress.count(finished, n);
  }
  std::vector<std::pair<dem::DemSystem, dem::RestSummary>> out;
  for (std::size_t k = 0; k < snapshots.size(); ++k) {
    if (!errors[k].message.empty()) errors[k].rethrow("state " + labels[k] + ": ");
    warn_cap("of state " + labels[k], summaries[k].relaxed);
    const bool frictional = snapshots[k].material().frictional();
    // A frictional state is relaxed dynamically only (rest.hpp): its balance is what that
    // relaxation reached within states.time_cap, stored as it is and reported if above.
    if (frictional && !(summaries[k].at_rest.ratio < dem::kEquilibrium &&
                        summaries[k].at_rest.torque_ratio < dem::kEquilibrium))
      log::warning("state ", labels[k], ": net force ", summaries[k].at_rest.ratio,
                   " and net torque ", summaries[k].at_rest.torque_ratio,
                   " of the mean contact force (x <r>) after states.time_cap; at rest is below ",
                   dem::kEquilibrium);
    if (!frictional && !(summaries[k].at_rest.ratio < dem::kEquilibrium))
      throw std::runtime_error(
          "state " + labels[k] + ": not at rest after minimisation (net force " +
          decimal_g(summaries[k].at_rest.ratio) + " of the mean contact force)");
    out.emplace_back(std::move(*rested[k]), summaries[k]);
  }
  return out;
}

void write_state(ResultsWriter& out, const std::string& g, const dem::DemSystem& sys,
                 const dem::RestSummary& r, double force_tolerance, bool with_configuration) {
  const dem::Measures m = sys.measure();
  out.attr(g, "eps_dev", m.eps_dev);
  out.attr(g, "volume_fraction", m.volume_fraction);
  out.attr(g, "pressure_star", m.pressure_star);
  out.attr(g, "coordination", m.coordination);
  out.attr(g, "coordination_nonrattler", m.coordination_nonrattler);
  out.attr(g, "rattler_fraction", m.rattler_fraction);
  out.attr(g, "kinetic_to_elastic", m.kinetic_to_elastic);
  write_relax(out, g, "", r.relaxed);
  // Equilibrium (rest.hpp): the criterion after the dynamic relaxation and at rest, what the
  // minimisation moved and changed.
  out.attr(g, "force_balance_relaxed", r.after_relax.ratio);
  out.attr(g, "force_balance", r.at_rest.ratio);
  if (sys.material().frictional()) {
    // No minimisation (rest.hpp): the torques' balance, the sliding contacts, and what the
    // continued relaxation changed.
    out.attr(g, "torque_balance", r.at_rest.torque_ratio);
    out.attr(g, "torque_balance_relaxed", r.after_relax.torque_ratio);
    out.attr(g, "sliding_fraction", m.sliding_fraction);
    out.attr(g, "rest_stress_change_over_p", r.stress_change.norm() / std::max(m.pressure, 1e-300));
  } else {
    out.attr(g, "minimise_iterations", r.minimised.iterations);
    out.attr(g, "minimise_force_tolerance", force_tolerance);
    out.attr(g, "minimise_max_displacement", r.max_displacement);
    out.attr(g, "minimise_stress_change_over_p",
             r.stress_change.norm() / std::max(m.pressure, 1e-300));
  }
  out.write(g + datasets::kStress, m.stress);
  out.write(g + datasets::kFabric, m.fabric);
  if (!with_configuration) return;
  const dem::Particles& p = sys.particles();
  out.write(g + datasets::kPositions, as_matrix(p.x, p.y, p.z));
  out.write(g + datasets::kRadii, p.radius);
  const Eigen::Vector3d lengths = sys.cell().lengths();
  out.write(g + datasets::kCellLengths, std::vector<double>(lengths.data(), lengths.data() + 3));
  // Checkpoint: everything DemSystem::restore() needs for a bit-identical continuation.
  const dem::State st = sys.save();
  const std::string cp = g + paths::kCheckpoint;
  out.write(cp + datasets::kVelocities, as_matrix(p.vx, p.vy, p.vz));
  out.write(cp + datasets::kForces, as_matrix(p.fx, p.fy, p.fz));
  out.write(cp + datasets::kReferencePositions, as_matrix(st.ref_x, st.ref_y, st.ref_z));
  out.write(cp + datasets::kReferenceCellLengths,
            std::vector<double>(st.ref_lengths.data(), st.ref_lengths.data() + 3));
  out.write(cp + datasets::kReferenceHalfSkins, st.ref_half_skin);
  out.write(cp + datasets::kStrainE,
            std::vector<double>(st.strain_E.data(), st.strain_E.data() + 3));
  out.write(cp + datasets::kLastD, std::vector<double>(st.last_D.data(), st.last_D.data() + 3));
  if (st.last_stress_known)
    out.write(cp + datasets::kLastStressDiag,
              std::vector<double>(st.last_stress_diag.data(), st.last_stress_diag.data() + 3));
  out.attr(cp, "time", st.time);
  out.attr(cp, "steps", st.steps);
  if (!sys.material().frictional()) return;  // frictionless checkpoints keep their layout
  out.write(cp + datasets::kAngularVelocities, as_matrix(p.wx, p.wy, p.wz));
  out.write(cp + datasets::kTorques, as_matrix(p.tx, p.ty, p.tz));
  out.write(cp + datasets::kTangentialSprings, springs_matrix(st.tangential_history));
  out.attr(cp, "sliding_dissipation", st.sliding_dissipation);
  if (!sys.material().rolling()) return;  // frictional checkpoints keep theirs
  out.write(cp + datasets::kRollingSprings, springs_matrix(st.rolling_history));
}

void stage_states(const Scenario&, ResultsWriter& out, const RunContext& ctx,
                  DemRunSession& session) {
  if (session.snapshots.empty())
    throw InputError("run: stage 'states' needs the stage 'path' in run.stages");
  const dem::DemRunOptions& o = *session.options;
  const auto t0 = std::chrono::steady_clock::now();
  auto rested = rest_states(session.snapshots, o.state_rest, o.state_labels, ctx);
  session.relaxed.clear();
  for (std::size_t k = 0; k < rested.size(); ++k) {
    const std::string& label = o.state_labels[k];
    write_state(out, paths::state(label), rested[k].first, rested[k].second,
                o.state_rest.minimise.force_tolerance, true);
    session.relaxed.emplace_back(label, std::move(rested[k].first));
  }
  out.attr(paths::kStates, "wall_time_s",
           std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
}

}  // namespace rendulic::app
