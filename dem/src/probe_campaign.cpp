// Probe campaigns by the dynamic, minimisation and linear-response methods, and their
// scenario keys (docs/physics.md section 5). See probe_campaign.hpp.
#include "rendulic/dem/probe_campaign.hpp"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iterator>
#include <limits>
#include <optional>
#include <sstream>

#include "rendulic/core/conventions.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/option_table.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/dem/probe_elastic_range.hpp"
#include "rendulic/dem/probe_mpi.hpp"
#include "rendulic/dem/rest.hpp"
#include "rendulic/dem/scenario_keys.hpp"
#include "rendulic/dem/team.hpp"

namespace rendulic {
// A probe's error travels with its record between MPI ranks (probe_mpi.hpp; found by
// argument-dependent lookup, so it sits in CaughtError's namespace).
template <class A>
void io(A& a, CaughtError& e) {
  a(e.message), a(e.input);
}
}  // namespace rendulic

namespace rendulic::dem {

bool ProbeOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!probe_option_table().check(*this, why)) return false;
  for (const auto& plane : planes)  // given twice: the table's check (KeySpec::distinct)
    if (!probe_plane_named(plane))
      return fail("probes.planes: unknown plane '" + plane + "' (" + kProbePlaneNames + ")");
  if (threads < 0) return fail("probes: threads must be >= 0");
  if (!relax.IsValid(why)) return false;
  if (!minimise.IsValid(why)) return false;
  return linear.IsValid(why);
}

std::vector<double> probe_directions(int m, const ProbePlane& plane) {
  const Eigen::VectorXd d = plane_directions_deg(plane, m);
  return {d.data(), d.data() + d.size()};
}

namespace {

// The key that sets the probes' rate, with its value: the words of a refusal of that rate.
std::string rate_key(const ProbeOptions& options) {
  return options.rate > 0.0 ? "probes.rate = " + decimal_g(options.rate)
                            : "probes.inertial_number = " + decimal_g(options.inertial_number);
}

}  // namespace

double probe_rate(const DemSystem& state, const ProbeOptions& options) {
  const Material& mat = state.material();
  double rate = options.rate;
  if (!(rate > 0.0)) {
    const double p = pressure(state.stress());
    if (!(p > 0.0)) {
      throw InputError(
          "probes: the state has no pressure, so the inertial number cannot set the rate; give "
          "probes.rate");
    }
    rate = options.inertial_number * std::sqrt(p / mat.density) / (2.0 * mat.r_mean);
  }
  // Refused here, naming the key, rather than by the engine's step inside a probe task: only a
  // probe longer than one step's limit reached that check, as "the imposed strain rate".
  if (const std::string excess = DemSystem::strain_per_step_excess(rate, state.dt());
      !excess.empty())
    throw InputError(rate_key(options) + " " + excess + " in the probes: lower it");
  return rate;
}

namespace {

// Contacts as sorted (i, j) keys, i < j.
std::vector<std::uint64_t> contact_keys(const std::vector<Contact>& contacts) {
  std::vector<std::uint64_t> keys;
  keys.reserve(contacts.size());
  for (const Contact& c : contacts) {
    const auto a = static_cast<std::uint64_t>(std::min(c.i, c.j));
    const auto b = static_cast<std::uint64_t>(std::max(c.i, c.j));
    keys.push_back(a << 32 | b);
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}
std::vector<std::uint64_t> contact_keys(const std::vector<PairGeometry>& pairs,
                                        double min_overlap) {
  std::vector<std::uint64_t> keys;
  for (const PairGeometry& c : pairs) {
    if (c.overlap > min_overlap) keys.push_back(static_cast<std::uint64_t>(c.i) << 32 | c.j);
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}
// (opened, closed) between two sorted key sets.
std::pair<double, double> contact_changes(const std::vector<std::uint64_t>& before,
                                          const std::vector<std::uint64_t>& after) {
  std::vector<std::uint64_t> d;
  std::set_difference(before.begin(), before.end(), after.begin(), after.end(),
                      std::back_inserter(d));
  const double opened = static_cast<double>(d.size());
  d.clear();
  std::set_difference(after.begin(), after.end(), before.begin(), before.end(),
                      std::back_inserter(d));
  return {opened, static_cast<double>(d.size())};
}

// The keys whose two particles are both in `keep` (the backbone of the starting state).
std::vector<std::uint64_t> among(const std::vector<std::uint64_t>& keys,
                                 const std::vector<bool>& keep) {
  std::vector<std::uint64_t> out;
  for (std::uint64_t key : keys) {
    if (keep[key >> 32] && keep[key & 0xffffffffu]) out.push_back(key);
  }
  return out;
}

void check(const ProbeOptions& options, double amplitude, const std::vector<double>& theta) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  if (!(amplitude > 0.0) || !(amplitude <= 0.05))
    throw InputError("probes: amplitude must be in (0, 0.05]");
  if (theta.empty()) throw InputError("probes: no directions");
}

// Symmetric matrix exponential: the deformation gradient exp(-d_eps) of a log strain.
Eigen::Matrix3d exp_sym(const Eigen::Matrix3d& a) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(a);
  return eig.eigenvectors() * eig.eigenvalues().array().exp().matrix().asDiagonal() *
         eig.eigenvectors().transpose();
}

// Per-probe results that every probe method reports the same way.
struct ProbeOutcome {
  Eigen::Matrix3d d_stress, d_fabric;
  std::pair<double, double> changes, backbone_changes;  // contacts (opened, closed)
  FabricSplit split;                                    // of d_fabric
};

// No exception may leave a parallel region: probes record their errors, the first is thrown
// after the loop, of its kind (a probe rate the engine refuses stays bad input, exit 2).
void rethrow_first(const std::vector<CaughtError>& errors, const std::string& method) {
  for (const CaughtError& e : errors)
    if (!e.message.empty()) e.rethrow(method + " probe: ");
}

ProbeOutcome outcome_of(const Eigen::Matrix3d& d_stress, const Eigen::Matrix3d& d_fabric,
                        const std::vector<std::uint64_t>& keys_before,
                        const std::vector<std::uint64_t>& keys_after,
                        const std::vector<bool>& backbone, const FabricSplit& split) {
  return {d_stress, d_fabric, contact_changes(keys_before, keys_after),
          contact_changes(among(keys_before, backbone), among(keys_after, backbone)), split};
}

// The (i, j) pairs of sorted contact keys.
std::vector<std::pair<int, int>> pairs_of(const std::vector<std::uint64_t>& keys) {
  std::vector<std::pair<int, int>> out;
  out.reserve(keys.size());
  for (std::uint64_t key : keys)
    out.emplace_back(static_cast<int>(key >> 32), static_cast<int>(key & 0xffffffffu));
  return out;
}

// The envelope of a campaign with the contact-change diagnostics common to the methods, from
// the per-probe records (each with its ProbeOutcome `outcome`); the caller adds its own
// diagnostics and attributes.
template <class Record>
Envelope assemble_envelope(const std::string& method, const ProbePlane& plane, double amplitude,
                           double k_star, const std::vector<double>& theta_deg,
                           const std::vector<Record>& records) {
  Envelope env;
  env.method = method;
  env.plane = plane;
  env.amplitude = amplitude;
  env.k_star = k_star;
  auto& diag = env.diagnostics;
  for (std::size_t p = 0; p < records.size(); ++p) {
    const ProbeOutcome& o = records[p].outcome;
    env.add(theta_deg[p], plane_strain(plane, theta_deg[p], amplitude), o.d_stress, o.d_fabric,
            o.split.volume, o.split.rotation, o.split.contacts);
    diag["contacts_opened"].push_back(o.changes.first);
    diag["contacts_closed"].push_back(o.changes.second);
    diag["backbone_contacts_opened"].push_back(o.backbone_changes.first);
    diag["backbone_contacts_closed"].push_back(o.backbone_changes.second);
  }
  return env;
}

}  // namespace

// Archive functions of what a probe reports, for the records that travel from MPI workers to
// rank 0 (probe_mpi.hpp); found by argument-dependent lookup, so each sits in its type's
// namespace. The structured bindings fail to compile when a member is added and not sent.
template <class A>
void io(A& a, RelaxSummary& s) {
  auto& [time, steps, ratio, converged] = s;
  a(time), a(steps), a(ratio), a(converged);
}
template <class A>
void io(A& a, MinimiseSummary& s) {
  auto& [converged, iterations, pair_rebuilds, max_force, mean_contact_force, elastic_energy,
         message, stalled_at, start_ratio] = s;
  a(converged), a(iterations), a(pair_rebuilds), a(max_force), a(mean_contact_force);
  a(elastic_energy), a(message), a(stalled_at), a(start_ratio);
}

namespace {

template <class A>
void io(A& a, ProbeOutcome& o) {
  auto& [d_stress, d_fabric, changes, backbone_changes, split] = o;
  a(d_stress), a(d_fabric), a(changes.first), a(changes.second);
  a(backbone_changes.first), a(backbone_changes.second);
  a(split.volume), a(split.rotation), a(split.contacts);
}

// What one probe of each method reports (ProbeOutcome plus the method's own diagnostics).
struct DynamicProbe {
  ProbeOutcome outcome;
  RelaxSummary relaxed;       // relax_method "dynamic"
  MinimiseSummary minimised;  // relax_method "fire"
  std::int64_t load_steps = 0;
  // Friction: the work the contacts dissipated by sliding during the probe (J) and the
  // fraction of contacts at the Coulomb limit once relaxed (zero without friction).
  double sliding_dissipation = 0;
  double sliding_fraction = 0;
};
template <class A>
void io(A& a, DynamicProbe& r) {
  a(r.outcome), a(r.relaxed), a(r.minimised), a(r.load_steps), a(r.sliding_dissipation);
  a(r.sliding_fraction);
}
struct MinimisationProbe {
  ProbeOutcome outcome;
  MinimiseSummary summary;
};
template <class A>
void io(A& a, MinimisationProbe& r) {
  a(r.outcome), a(r.summary);
}

// Probes 0..n-1 over the options' OpenMP team, one per task, taken in that order by whichever
// thread is free: run(q) computes probe q and keeps its record. A stop asked for skips the
// probes not yet begun (returns true); each probe's error is kept in errors[q].
template <class Run>
bool run_probe_tasks(const ProbeOptions& options, int n, std::vector<CaughtError>& errors,
                     Run&& run) {
  std::atomic<bool> stopped{false};
  const int team = task_team(options.threads, static_cast<std::size_t>(n));
#pragma omp parallel for schedule(dynamic, 1) num_threads(team)
  for (int q = 0; q < n; ++q) {
    if (stopped.load(std::memory_order_relaxed) || (options.stop && options.stop())) {
      stopped.store(true, std::memory_order_relaxed);
      continue;
    }
    try {
      run(q);
    } catch (...) {
      errors[static_cast<std::size_t>(q)] = CaughtError::current();
    }
    if (options.probe_done) options.probe_done();
  }
  return stopped;
}

// The probes of one envelope: this process's share of them (all of them on a single
// process, see probe_mpi.hpp) over its OpenMP team, one probe per task, each with
// compute(p). With MPI ranks the workers' records are sent to rank 0, which then holds every
// record in direction order. Returns false on a worker (nothing left to assemble there).
template <class Record, class Compute>
bool compute_probes(detail::ProbeTaskScope& scope, const ProbeOptions& options,
                    const std::string& method, std::vector<Record>& records, Compute&& compute) {
  const int m = static_cast<int>(records.size());
  const ProbeShare share = scope.share();
  std::vector<int> mine;
  for (int p = 0; p < m; ++p)
    if (share.owns(p)) mine.push_back(p);
  const int n = static_cast<int>(mine.size());
  std::vector<CaughtError> errors(m), mine_errors(n);
  const bool stopped =
      run_probe_tasks(options, n, mine_errors, [&](int q) { records[mine[q]] = compute(mine[q]); });
  for (int q = 0; q < n; ++q) errors[mine[q]] = std::move(mine_errors[q]);
  if (share.size > 1) {
    detail::ByteWriter w;
    for (int p : mine) w(p), w(errors[p]), w(records[p]);
    const std::vector<std::vector<char>> replies = scope.exchange(std::move(w.bytes()));
    if (scope.is_worker()) return false;
    for (const std::vector<char>& bytes : replies) {
      detail::ByteReader in(bytes);
      while (!in.done()) {
        int p = -1;
        in(p);
        if (p < 0 || p >= m || share.owns(p))
          throw std::runtime_error(method + " probes: a worker sent probe " + std::to_string(p));
        in(errors[p]), in(records[p]);
      }
    }
  }
  // After the exchange: the workers have finished their share and wait for the next task.
  if (stopped) throw Cancelled(method + " probes: stopped on request");
  rethrow_first(errors, method);
  return true;
}

}  // namespace

namespace {

// The dynamic envelope; given_is_reference: `given` is the reference already (an MPI worker
// gets it relaxed from rank 0, so the ranks do not each relax it again).
Envelope dynamic_envelope_of(const DemSystem& given, double amplitude,
                             const std::vector<double>& theta_deg, const ProbeOptions& options,
                             const ProbePlane& plane, bool given_is_reference) {
  check(options, amplitude, theta_deg);
  // The common reference is the given state relaxed to the probes' own criterion: otherwise
  // every probe also records the reference's continuing relaxation (from the states' looser
  // threshold down to the probes'), which shows up as a spurious centre shift of the elastic
  // envelope and a spurious deviatoric fabric change. Serial, like the probes, so that the
  // envelope does not depend on the thread count.
  DemSystem state = given;
  RelaxSummary reference;
  MinimiseSummary reference_minimised;
  // FIRE needs an energy to minimise: a frictional packing keeps the dynamic relaxation.
  const bool fire = options.relax_method == "fire" && !given.material().frictional();
  if (!given_is_reference && options.dt_factor > 0.0 &&
      options.dt_factor != given.options().dt_factor) {
    SystemOptions so = given.options();
    so.dt_factor = options.dt_factor;
    check_time_step(so.material, so.dt_factor, "probes.dt_factor");
    state = DemSystem::restore(given.save(), so);
  }
  if (!given_is_reference) {
    const int saved_threads = omp_get_max_threads();
    omp_set_num_threads(1);
    // The reference ends where its probes do: at a minimum for FIRE, else relaxed dynamically.
    if (fire) {
      reference_minimised = settle_at_minimum(state, options.minimise);
    } else {
      reference = relax(state, options.relax);
    }
    omp_set_num_threads(saved_threads);
    // Every probe would stall there too, and its envelope be made of unsettled probes.
    if (reference_minimised.stalled_at > 0.0)
      throw InputError("dynamic probes: " + round_off_refusal(reference_minimised,
                                                              "probes.force_tolerance",
                                                              options.minimise.force_tolerance));
  }
  detail::ProbeTaskScope scope("dynamic", plane.name, state, amplitude, theta_deg, options);
  const double rate = probe_rate(state, options);
  const Measures before = state.measure();
  const std::vector<Contact> contacts_before = state.contacts();
  const std::vector<std::uint64_t> keys_before = contact_keys(contacts_before);
  const std::vector<bool> backbone =
      non_rattlers(state.particles().size(), contacts_before,
                   rattler_min_contacts(state.material().frictional()));
  const PackingData packing_before = geometry_of(state);
  const std::vector<std::pair<int, int>> pairs_before = pairs_of(keys_before);
  const int m = static_cast<int>(theta_deg.size());
  std::vector<DynamicProbe> probes(m);
  const std::string rate_name = rate_key(options);  // for a refusal inside a probe task
  const bool assemble = compute_probes(scope, options, "dynamic", probes, [&](int p) {
    // The engine's own parallel loops run serially inside a probe (this task's ICV only):
    // its force sums are then the same whatever the campaign's team size, so the envelope
    // is bitwise independent of the thread count (also when a team of 1 would otherwise
    // let the engine's inner region go parallel).
    omp_set_num_threads(1);
    DynamicProbe r;
    DemSystem sys = state;
    const Eigen::Matrix3d d_eps = plane_strain(plane, theta_deg[p], amplitude);
    r.load_steps = impose_strain_increment(sys, d_eps.diagonal(), rate, rate_name);
    if (fire) {
      RelaxOptions first = options.relax;
      first.kinetic_to_elastic = options.relax_fire_from;
      r.relaxed = relax(sys, first);
      r.minimised = settle_at_minimum(sys, options.minimise);
    } else {
      r.relaxed = relax(sys, options.relax);
    }
    const Measures after = sys.measure();
    const std::vector<std::uint64_t> keys_after = contact_keys(sys.contacts());
    r.sliding_dissipation = after.sliding_dissipation - before.sliding_dissipation;
    r.sliding_fraction = after.sliding_fraction;
    const FabricSplit split = split_fabric_change(packing_before, geometry_of(sys), pairs_before,
                                                  before.fabric, after.fabric);
    r.outcome = outcome_of(after.stress - before.stress, after.fabric - before.fabric, keys_before,
                           keys_after, backbone, split);
    return r;
  });
  if (!assemble) return {};
  Envelope env =
      assemble_envelope("dynamic", plane, amplitude, state.material().k_star(), theta_deg, probes);
  auto& diag = env.diagnostics;
  for (const DynamicProbe& r : probes) {
    diag["load_steps"].push_back(static_cast<double>(r.load_steps));
    diag["relax_steps"].push_back(static_cast<double>(r.relaxed.steps));
    diag["relax_time"].push_back(r.relaxed.time);
    diag["kinetic_to_elastic"].push_back(r.relaxed.ratio);
    diag["relax_iterations"].push_back(static_cast<double>(r.minimised.iterations));
    diag["relax_converged"].push_back((fire ? r.minimised.converged : r.relaxed.converged) ? 1.0
                                                                                           : 0.0);
  }
  if (state.material().frictional()) {
    // Sliding makes the response depend on the direction of loading: an envelope whose probes
    // slid is not an elastic one, whatever its amplitude. The share of probes that slid, the
    // largest fraction of sliding contacts after one, and the state's own fraction.
    double slid = 0, most = 0;
    for (const DynamicProbe& r : probes) {
      diag["sliding_dissipation"].push_back(r.sliding_dissipation);
      diag["sliding_fraction"].push_back(r.sliding_fraction);
      slid += r.sliding_dissipation > 0 ? 1.0 : 0.0;
      most = std::max(most, r.sliding_fraction);
    }
    env.attributes["sliding_probes_fraction"] = slid / static_cast<double>(probes.size());
    env.attributes["sliding_fraction_max"] = most;
    env.attributes["sliding_fraction_before"] = before.sliding_fraction;
  }
  const Material& mat = state.material();
  env.attributes["rate"] = rate;
  env.attributes["inertial_number"] = inertial_number(mat, rate, before.pressure);
  env.attributes["relax_kinetic_to_elastic"] = options.relax.kinetic_to_elastic;
  env.attributes["relax_time_cap"] = options.relax.time_cap;
  env.attributes["dt"] = state.dt();
  env.attributes["kinetic_to_elastic_given"] = relax_ratio(given);
  env.attributes["kinetic_to_elastic_before"] = relax_ratio(state);
  env.attributes["reference_relax_steps"] = static_cast<double>(reference.steps);
  env.attributes["relax_fire"] = fire ? 1.0 : 0.0;
  env.attributes["reference_relax_iterations"] =
      static_cast<double>(reference_minimised.iterations);
  if (fire) {
    env.attributes["relax_fire_from"] = options.relax_fire_from;
    env.attributes["relax_force_tolerance"] = options.minimise.force_tolerance;
  }
  return env;
}

}  // namespace

Envelope dynamic_envelope(const DemSystem& given, double amplitude,
                          const std::vector<double>& theta_deg, const ProbeOptions& options,
                          const ProbePlane& plane) {
  return dynamic_envelope_of(given, amplitude, theta_deg, options, plane, false);
}

void compute_worker_share(const std::string& method, const std::string& plane_name,
                          const DemSystem& state, double amplitude,
                          const std::vector<double>& theta_deg, const ProbeOptions& options) {
  const std::optional<ProbePlane> plane = probe_plane_named(plane_name);
  if (!plane) throw std::runtime_error("unknown probe plane '" + plane_name + "' sent to a worker");
  if (method == "dynamic") {
    dynamic_envelope_of(state, amplitude, theta_deg, options, *plane, true);
  } else if (method == "minimisation") {
    minimisation_envelope(state, amplitude, theta_deg, options, *plane);
  } else {
    throw std::runtime_error("unknown probe method '" + method + "' sent to an MPI worker");
  }
}

PackingData geometry_of(const DemSystem& state) {
  const Particles& p = state.particles();
  const int n = static_cast<int>(p.size());
  Eigen::MatrixX3d x(n, 3);
  Eigen::VectorXd r(n);
  for (int i = 0; i < n; ++i) {
    x.row(i) << p.x[i], p.y[i], p.z[i];
    r(i) = p.radius[i];
  }
  return PackingData::orthorhombic(std::move(x), std::move(r), state.cell().lengths());
}

PackingData packing_of(const DemSystem& state) {
  // The energy-based static tools (energy minimisation, minimisation probes, the force balance
  // at rest) take their packing from here: an energy minimum has no meaning for a
  // path-dependent frictional contact. The linear response has its frictional path
  // (frictional_linear_response below).
  if (state.material().frictional()) {
    std::ostringstream s;
    s << "dem.friction = " << state.material().mu
      << ": the energy minimisation and minimisation probes model frictionless contacts only "
         "(an energy minimum has no meaning for a frictional contact); set dem.friction = 0 "
         "for them";
    throw InputError(s.str());
  }
  return geometry_of(state);
}

namespace {

// What every minimisation probe of a state starts from: the state's packing at its energy
// minimum, its stress, fabric and contacts there.
struct MinimisationBasis {
  MinimiseOptions mo;
  PackingData ref;
  MinimiseSummary summary;
  double min_overlap = 0;
  StressFabric before;
  std::vector<std::uint64_t> keys_before;
  std::vector<std::pair<int, int>> pairs_before;
  std::vector<bool> backbone;
  double k_star = 0;
};

MinimisationBasis minimisation_basis(const DemSystem& state, const ProbeOptions& options) {
  MinimisationBasis b;
  b.mo = options.minimise;
  b.mo.k = state.material().k;
  b.k_star = state.material().k_star();
  b.ref = packing_of(state);
  b.summary = minimise_energy(b.ref, b.mo);
  if (b.summary.stalled_at > 0.0)
    throw InputError("minimisation probes: " +
                     round_off_refusal(b.summary, "probes.force_tolerance", b.mo.force_tolerance));
  if (!b.summary.converged) {
    // Bad input, not a bug: the scenario chose a state without a contact network to probe.
    std::ostringstream why;
    why << "minimisation probes: the state reaches no force equilibrium at probes.force_tolerance "
        << b.mo.force_tolerance << " (" << b.summary.message
        << "); an unjammed or barely jammed state has none to probe: choose a jammed state (a "
           "larger isotropic.nu_max), a looser tolerance, or drop minimisation from "
           "probes.methods";
    throw InputError(why.str());
  }
  // Contacts are those whose force the minimiser resolves: overlap above
  // force_tolerance * mean contact force / k. A particle pushed by the relaxation of its
  // neighbours stops FIRE once its force is below the tolerance, still touching; counting
  // such force-free touches would make eq. 2 jump by a whole contact.
  b.min_overlap = b.mo.force_tolerance * b.summary.mean_contact_force / b.mo.k;
  b.before = measure_stress_fabric(b.ref, b.mo.k, nullptr, b.min_overlap);
  const std::vector<PairGeometry> pairs = find_pairs(b.ref, 0.0);
  b.keys_before = contact_keys(pairs, b.min_overlap);
  b.pairs_before = pairs_of(b.keys_before);
  std::vector<Contact> cs;
  for (const PairGeometry& c : pairs) {
    if (c.overlap > b.min_overlap)
      cs.push_back({c.i, c.j, c.l, c.overlap, 0.0});  // non_rattlers: pairs only
  }
  b.backbone = non_rattlers(b.ref.size(), cs);
  return b;
}

MinimisationProbe minimisation_probe(const MinimisationBasis& b, const ProbePlane& plane,
                                     double theta_deg, double amplitude) {
  MinimisationProbe r;
  PackingData probe = b.ref;
  probe.deform(exp_sym(-plane_strain(plane, theta_deg, amplitude)));
  r.summary = minimise_energy(probe, b.mo);
  const StressFabric after = measure_stress_fabric(probe, b.mo.k, nullptr, b.min_overlap);
  const std::vector<std::uint64_t> keys_after = contact_keys(find_pairs(probe, 0.0), b.min_overlap);
  const FabricSplit split =
      split_fabric_change(b.ref, probe, b.pairs_before, b.before.fabric, after.fabric);
  r.outcome = outcome_of(after.stress - b.before.stress, after.fabric - b.before.fabric,
                         b.keys_before, keys_after, b.backbone, split);
  return r;
}

Envelope minimisation_envelope_of(const MinimisationBasis& b, const ProbePlane& plane,
                                  double amplitude, const std::vector<double>& theta_deg,
                                  const std::vector<MinimisationProbe>& probes) {
  Envelope env = assemble_envelope("minimisation", plane, amplitude, b.k_star, theta_deg, probes);
  auto& diag = env.diagnostics;
  double affine = std::numeric_limits<double>::infinity();
  for (const MinimisationProbe& r : probes) {
    diag["iterations"].push_back(static_cast<double>(r.summary.iterations));
    diag["max_force"].push_back(r.summary.max_force);
    diag["converged"].push_back(r.summary.converged ? 1.0 : 0.0);
    affine = std::min(affine, r.summary.start_ratio);
  }
  env.attributes["affine_force_over_tolerance"] = affine / b.mo.force_tolerance;
  env.attributes["force_tolerance"] = b.mo.force_tolerance;
  env.attributes["min_overlap"] = b.min_overlap;
  env.attributes["reference_iterations"] = static_cast<double>(b.summary.iterations);
  return env;
}

}  // namespace

Envelope minimisation_envelope(const DemSystem& state, double amplitude,
                               const std::vector<double>& theta_deg, const ProbeOptions& options,
                               const ProbePlane& plane) {
  check(options, amplitude, theta_deg);
  // The workers are sent the task before this process finds the common minimum.
  detail::ProbeTaskScope scope("minimisation", plane.name, state, amplitude, theta_deg, options);
  const MinimisationBasis b = minimisation_basis(state, options);
  std::vector<MinimisationProbe> probes(theta_deg.size());
  const bool assemble = compute_probes(scope, options, "minimisation", probes, [&](int p) {
    return minimisation_probe(b, plane, theta_deg[static_cast<std::size_t>(p)], amplitude);
  });
  if (!assemble) return {};
  return minimisation_envelope_of(b, plane, amplitude, theta_deg, probes);
}

namespace {
// envelope(state, amplitude) for every state and amplitude in turn, each timed.
template <class EnvelopeOf>
std::vector<std::vector<Envelope>> envelope_by_envelope(const std::vector<const DemSystem*>& states,
                                                        const std::vector<double>& amplitudes,
                                                        const EnvelopeOf& envelope,
                                                        std::vector<std::vector<double>>* seconds) {
  const std::size_t S = states.size(), A = amplitudes.size();
  std::vector<std::vector<Envelope>> out(S, std::vector<Envelope>(A));
  std::vector<std::vector<double>> took(S, std::vector<double>(A, 0.0));
  for (std::size_t s = 0; s < S; ++s)
    for (std::size_t a = 0; a < A; ++a) {
      const auto t0 = std::chrono::steady_clock::now();
      out[s][a] = envelope(*states[s], amplitudes[a]);
      took[s][a] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
  if (seconds) *seconds = std::move(took);
  return out;
}
}  // namespace

std::vector<std::vector<Envelope>> dynamic_envelopes(const std::vector<const DemSystem*>& states,
                                                     const std::vector<double>& amplitudes,
                                                     const std::vector<double>& theta_deg,
                                                     const ProbeOptions& options,
                                                     const ProbePlane& plane,
                                                     std::vector<std::vector<double>>* seconds) {
  return envelope_by_envelope(
      states, amplitudes,
      [&](const DemSystem& state, double a) {
        return dynamic_envelope(state, a, theta_deg, options, plane);
      },
      seconds);
}

std::vector<std::vector<Envelope>> minimisation_envelopes(
    const std::vector<const DemSystem*>& states, const std::vector<double>& amplitudes,
    const std::vector<double>& theta_deg, const ProbeOptions& options, const ProbePlane& plane,
    std::vector<std::vector<double>>* seconds) {
  if (detail::probe_ranks() > 1) {
    // MPI ranks share each envelope's probes (probe_mpi.hpp): envelope by envelope.
    return envelope_by_envelope(
        states, amplitudes,
        [&](const DemSystem& state, double a) {
          return minimisation_envelope(state, a, theta_deg, options, plane);
        },
        seconds);
  }
  const std::size_t S = states.size(), A = amplitudes.size(), D = theta_deg.size();
  std::vector<std::vector<Envelope>> out(S, std::vector<Envelope>(A));
  std::vector<std::vector<double>> took(S, std::vector<double>(A, 0.0));
  using Clock = std::chrono::steady_clock;
  for (const double a : amplitudes) check(options, a, theta_deg);
  std::vector<MinimisationBasis> basis;
  basis.reserve(S);
  for (const DemSystem* state : states) basis.push_back(minimisation_basis(*state, options));
  // Every probe of every envelope one task, the largest amplitudes (the longest minimisations)
  // first, so that the last tasks to start are short ones. Each probe keeps its record in its
  // envelope's place, so the envelopes are those of minimisation_envelope, bit for bit.
  std::vector<std::vector<std::vector<MinimisationProbe>>> probes(
      S, std::vector<std::vector<MinimisationProbe>>(A, std::vector<MinimisationProbe>(D)));
  std::vector<std::vector<std::vector<double>>> wall(
      S, std::vector<std::vector<double>>(A, std::vector<double>(D, 0.0)));
  const int n = static_cast<int>(S * A * D);
  std::vector<CaughtError> errors(static_cast<std::size_t>(n));
  const bool stopped = run_probe_tasks(options, n, errors, [&](int q) {
    const std::size_t k = static_cast<std::size_t>(q);
    const std::size_t a = A - 1 - k / (S * D), s = k / D % S, d = k % D;
    const auto t0 = Clock::now();
    probes[s][a][d] = minimisation_probe(basis[s], plane, theta_deg[d], amplitudes[a]);
    wall[s][a][d] = std::chrono::duration<double>(Clock::now() - t0).count();
  });
  if (stopped) throw Cancelled("minimisation probes: stopped on request");
  rethrow_first(errors, "minimisation");
  for (std::size_t s = 0; s < S; ++s)
    for (std::size_t a = 0; a < A; ++a) {
      out[s][a] = minimisation_envelope_of(basis[s], plane, amplitudes[a], theta_deg, probes[s][a]);
      for (const double t : wall[s][a]) took[s][a] += t;
    }
  if (seconds) *seconds = std::move(took);
  return out;
}

LinearResponse state_linear_response(const DemSystem& state, const ProbeOptions& options) {
  LinearResponseOptions lo = options.linear;
  lo.k = state.material().k;
  if (state.material().frictional()) {
    // At rest, with the engine's springs (docs/probes.md "Linear response of a frictional
    // packing"); no minimisation to fall back on.
    const Material& m = state.material();
    lo.min_contacts = rattler_min_contacts(true);
    LinearFriction friction;
    friction.k_t = m.tangential().k_t;
    friction.mu = m.mu;
    friction.mu_r = m.mu_r;
    if (m.rolling()) friction.k_r = m.rolling_contact().k_t;
    for (const Contact& c : state.contacts()) {
      if (c.spring != Eigen::Vector3d::Zero()) friction.springs.push_back({c.i, c.j, c.spring});
      if (c.rolling_spring != Eigen::Vector3d::Zero())
        friction.rolling_springs.push_back({c.i, c.j, c.rolling_spring});
    }
    return linear_response(geometry_of(state), lo, friction);
  }
  PackingData packing = packing_of(state);
  LinearResponse lr = linear_response(packing, lo);
  if (!lr.ok) {
    // A dynamically relaxed state (E_kin / E_el below a threshold) is near, not at, its
    // energy minimum; the residual forces enter the geometric term and can make the Hessian
    // indefinite. The linear response is defined at mechanical equilibrium, so bring the
    // packing there (FIRE, as the minimisation probes do) and try once more.
    MinimiseOptions mo = options.minimise;
    mo.k = lo.k;
    const MinimiseSummary ms = minimise_energy(packing, mo);
    if (ms.stalled_at > 0.0)
      throw InputError(lr.message + "; minimising first: " +
                       round_off_refusal(ms, "probes.force_tolerance", mo.force_tolerance));
    if (!ms.converged)
      throw std::runtime_error(lr.message + "; minimising first did not converge (" + ms.message +
                               ")");
    lr = linear_response(packing, lo);
    lr.minimised_first = true;
    // FIRE stopped where the forces balance, and the Hessian there still has negative modes:
    // a saddle, which no relaxation from rest leaves. Say so, and where such states come from.
    if (!lr.ok && lr.n_negative_pivots > 0) {
      lr.message += "; its forces balance, so it is a saddle of its energy, not a minimum (copies ";
      lr.message += "of a smaller periodic packing side by side often are: docs/probes.md, ";
      lr.message += "\"Replicated packings\"; `rendulic probe --leave-saddle` moves it off)";
    }
  }
  return lr;
}

Envelope linear_response_envelope(const DemSystem& state, double amplitude,
                                  const std::vector<double>& theta_deg, const ProbeOptions& options,
                                  LinearResponse* response, const ProbePlane& plane) {
  check(options, amplitude, theta_deg);
  const LinearResponse lr = state_linear_response(state, options);
  if (response) *response = lr;
  if (!lr.ok) throw std::runtime_error(lr.message);
  return linear_response_envelope(lr, theta_deg, amplitude, state.material().k_star(), plane);
}

std::vector<Envelope> probe_campaign(const DemSystem& state,
                                     const std::vector<std::string>& methods,
                                     const ProbeOptions& options, const EnvelopeSink& sink,
                                     const LinearResponse* known) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  std::vector<Envelope> envelopes;
  for (const std::string& method : methods) {
    if (const std::string why = choice_refusal(method, kProbeMethods); !why.empty())
      throw InputError("probes.methods: " + why);
    LinearResponse lr = known && method == "linear_response" ? *known : LinearResponse{};
    for (const std::string& name : options.planes) {
      const ProbePlane plane = *probe_plane_named(name);  // IsValid checked the names
      const std::vector<double> theta = probe_directions(options.directions, plane);
      for (double amplitude : options.amplitudes) {
        Envelope env;
        if (method == "dynamic") {
          env = dynamic_envelope(state, amplitude, theta, options, plane);
        } else if (method == "minimisation") {
          env = minimisation_envelope(state, amplitude, theta, options, plane);
        } else if (!lr.ok) {
          env = linear_response_envelope(state, amplitude, theta, options, &lr, plane);
        } else {  // one factorisation serves every plane and amplitude
          env = linear_response_envelope(lr, theta, amplitude, state.material().k_star(), plane);
        }
        if (sink) sink(method, amplitude, env, method == "linear_response" ? &lr : nullptr);
        envelopes.push_back(std::move(env));
      }
    }
  }
  return envelopes;
}

const OptionTable<ProbeOptions>& probe_option_table() {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  static_assert(kElasticAmplitudeMax == 1e-4 && kPlasticAmplitudeMin == 1e-3,
                "the help of probes.amplitudes states the thresholds of core/conventions.hpp");
  using Row = OptionRow<ProbeOptions>;
  static const OptionTable<ProbeOptions> table({
      Row{{.path = "probes.directions",
           .unit = "-",
           .help = "Number of probe directions, equally spaced in each probe plane from its "
                   "start: in the Rendulic plane from 35.26 deg (isotropic compression), where a "
                   "multiple of 4 includes the isotropic and deviatoric directions.",
           .min = 3,
           .max = 3600},
          [](ProbeOptions& o) -> int& { return o.directions; }},
      Row{{.path = "probes.amplitudes",
           .unit = "-",
           .help = "Probe strain amplitudes |d_eps| (Frobenius): < 1e-4 elastic, > 1e-3 "
                   "elasto-plastic.",
           .min = 0.0,
           .max = 0.05,
           .min_open = true,
           .min_size = 1,
           .distinct = true},
          [](ProbeOptions& o) -> std::vector<double>& { return o.amplitudes; }},
      Row{{.path = "probes.planes",
           .unit = "-",
           .help = "Probe planes (docs/probes.md \"Probe planes\"): rendulic (axisymmetric, "
                   "the seed's), deviatoric (constant volume, from axial compression), "
                   "meridian_PHI (the isotropic axis and the deviatoric direction at Lode angle "
                   "PHI in [0, 180) deg, e.g. meridian_30); other planes' envelopes are named "
                   "method_plane_amplitude (dynamic_deviatoric_5e-05).",
           .min_size = 1,
           .distinct = true},
          [](ProbeOptions& o) -> std::vector<std::string>& { return o.planes; }},
      Row{{.path = "probes.inertial_number",
           .unit = "-",
           .help = "Inertial number that sets the dynamic probes' loading rate at the state's "
                   "pressure.",
           .min = 0.0,
           .max = 1e-2,
           .min_open = true},
          [](ProbeOptions& o) -> double& { return o.inertial_number; }},
      Row{{.path = "probes.rate",
           .unit = "1/s",
           .help = "Fixed loading rate of the largest strain component; 0 uses "
                   "probes.inertial_number.",
           .min = 0.0,
           .max = kInf},
          [](ProbeOptions& o) -> double& { return o.rate; }},
      Row{{.path = "probes.dt_factor",
           .unit = "t_c",
           .help = "Time step of the dynamic probes as a fraction of the smallest pair's contact "
                   "time; 0 keeps dem.dt_factor. Refused beyond the stability limit.",
           .min = 0.0,
           .max = kInf},
          [](ProbeOptions& o) -> double& { return o.dt_factor; }},
      Row{{.path = "probes.relax_kinetic_to_elastic",
           .unit = "-",
           .help = "Dynamic probes with probes.relax_method = dynamic relax at fixed cell until "
                   "kinetic/elastic energy is below this.",
           .min = 0.0,
           .max = 1.0,
           .min_open = true,
           .max_open = true},
          [](ProbeOptions& o) -> double& { return o.relax.kinetic_to_elastic; }},
      Row{{.path = "probes.relax_time_cap",
           .unit = "s",
           .help = "Longest relaxation of a dynamic probe (probes that hit it are flagged).",
           .min = 0.0,
           .max = kInf,
           .min_open = true},
          [](ProbeOptions& o) -> double& { return o.relax.time_cap; }},
      Row{{.path = "probes.relax_method",
           .unit = "-",
           .help = "How a dynamic probe relaxes after its loading, at fixed cell: fire (the engine "
                   "down to probes.relax_fire_from, then FIRE to probes.force_tolerance; a "
                   "frictional packing relaxes dynamically) or dynamic (the seed's: the engine "
                   "to probes.relax_kinetic_to_elastic).",
           .choices = {"dynamic", "fire"}},
          [](ProbeOptions& o) -> std::string& { return o.relax_method; }},
      Row{{.path = "probes.relax_fire_from",
           .unit = "-",
           .help = "probes.relax_method = fire: the engine's relaxation first runs down to this "
                   "kinetic/elastic energy, then FIRE takes over.",
           .min = 0.0,
           .max = 1.0,
           .min_open = true,
           .max_open = true},
          [](ProbeOptions& o) -> double& { return o.relax_fire_from; }},
      Row{{.path = "probes.force_tolerance",
           .unit = "-",
           .help = "Minimisation probes, and dynamic probes with probes.relax_method = fire, "
                   "stop when the largest net force is below this x mean contact force.",
           .min = 0.0,
           .max = 1.0,
           .min_open = true,
           .max_open = true},
          [](ProbeOptions& o) -> double& { return o.minimise.force_tolerance; }},
  });
  return table;
}

void register_probe_keys(ScenarioSchema& schema) {
  const OptionTable<ProbeOptions>& table = probe_option_table();
  for (const auto& row : table.rows()) {
    schema.add(row.key);
    // The campaign's methods (not a ProbeOptions member: every stage names its own) follow
    // the amplitudes, where they always stood in docs/scenario-keys.md.
    if (row.key.path == "probes.amplitudes")
      schema.add({.path = "probes.methods",
                  .type = KeyType::kStringList,
                  .default_value = std::vector<std::string>{"dynamic"},
                  .unit = "-",
                  .help = "Probe methods of the probes stage (dynamic, minimisation); the "
                          "linear_response stage adds the exact elastic envelopes for the same "
                          "directions and amplitudes.",
                  .choices = {"dynamic", "minimisation"},
                  .min_size = 1,
                  .distinct = true});
  }
  register_elastic_range_keys(schema);
}

ProbeOptions probe_options_from(const Scenario& scenario) {
  ProbeOptions o;
  probe_option_table().read(scenario, o);
  if (o.dt_factor > 0.0)
    check_time_step(material_from_scenario(scenario), o.dt_factor,
                    "probes.dt_factor (" + scenario.origin("probes.dt_factor") + ")");
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
  return o;
}

std::vector<std::string> probe_methods_from(const Scenario& scenario) {
  return scenario.get_strings("probes.methods");
}

}  // namespace rendulic::dem
