// The equilibrium criterion and states brought to rest (see rest.hpp; docs/dem.md "States at
// rest").
#include "rendulic/dem/rest.hpp"

#include <cmath>
#include <stdexcept>

#include "rendulic/core/errors.hpp"
#include "rendulic/dem/linear_response.hpp"
#include "rendulic/dem/measures.hpp"
#include "rendulic/dem/probe_campaign.hpp"

namespace rendulic::dem {

ForceBalance force_balance(const PackingData& packing, double k) {
  const int n = packing.size();
  const NormalContact law{k, 0.0};  // at rest: the spring alone
  std::vector<Contact> contacts;
  for (const PairGeometry& p : find_pairs(packing, 0.0))
    if (p.overlap > 0.0)
      contacts.push_back({p.i, p.j, p.l, p.overlap, law.elastic_force(p.overlap)});
  const std::vector<bool> keep = non_rattlers(static_cast<std::size_t>(n), contacts);
  Eigen::MatrixX3d net = Eigen::MatrixX3d::Zero(n, 3);
  ForceBalance b;
  double sum = 0.0;
  b.all_contacts = static_cast<int>(contacts.size());
  for (const Contact& c : contacts) {
    const Eigen::RowVector3d f = (c.force / c.branch.norm()) * c.branch.transpose();
    net.row(c.i) += f;
    net.row(c.j) -= f;
    if (keep[c.i] && keep[c.j]) {
      sum += c.force;
      ++b.contacts;
    }
  }
  for (int p = 0; p < n; ++p) {
    if (!keep[p]) continue;
    ++b.non_rattlers;
    b.max_net_force = std::max(b.max_net_force, net.row(p).norm());
  }
  if (b.contacts > 0) {
    b.mean_contact_force = sum / b.contacts;
    b.ratio = b.max_net_force / b.mean_contact_force;
  }
  return b;
}

ForceBalance force_balance(const DemSystem& sys) {
  const std::vector<Contact> contacts = sys.contacts();
  const Particles& p = sys.particles();
  const int n = static_cast<int>(p.size());
  const int min_contacts = rattler_min_contacts(sys.material().frictional());
  const std::vector<bool> keep = non_rattlers(static_cast<std::size_t>(n), contacts, min_contacts);
  Eigen::MatrixX3d net = Eigen::MatrixX3d::Zero(n, 3), torque = Eigen::MatrixX3d::Zero(n, 3);
  ForceBalance b;
  b.all_contacts = static_cast<int>(contacts.size());
  double sum = 0.0;
  for (const Contact& c : contacts) {
    const double d = c.branch.norm();
    const Eigen::Vector3d nrm = c.branch / d;
    const Eigen::Vector3d f = c.force * nrm + c.tangential;
    net.row(c.i) += f.transpose();
    net.row(c.j) -= f.transpose();
    // Levers as the engine's (docs/dem.md "Friction"): r - delta/2 from each centre to the
    // contact point, -n from i and +n from j; the tangential force alone has a moment.
    const Eigen::Vector3d m = -nrm.cross(c.tangential);
    torque.row(c.i) += ((p.radius[c.i] - 0.5 * c.overlap) * m + c.rolling_torque).transpose();
    torque.row(c.j) += ((p.radius[c.j] - 0.5 * c.overlap) * m - c.rolling_torque).transpose();
    if (keep[c.i] && keep[c.j]) {
      sum += std::abs(c.force);
      ++b.contacts;
    }
  }
  for (int i = 0; i < n; ++i) {
    if (!keep[i]) continue;
    ++b.non_rattlers;
    b.max_net_force = std::max(b.max_net_force, net.row(i).norm());
    b.max_net_torque = std::max(b.max_net_torque, torque.row(i).norm());
  }
  if (b.contacts > 0) {
    b.mean_contact_force = sum / b.contacts;
    b.ratio = b.max_net_force / b.mean_contact_force;
    b.torque_ratio = b.max_net_torque / (b.mean_contact_force * sys.material().r_mean);
  }
  return b;
}

namespace {

// A frictional state at rest: the dynamic relaxation, then on in intervals of the same length
// until the forces and torques balance, within the relaxation's time cap.
RestSummary rest_frictional(DemSystem& sys, const RestOptions& options) {
  RestSummary s;
  const double t0 = sys.time();
  s.relaxed = relax(sys, options.relax);
  s.after_relax = force_balance(sys);
  const Eigen::Matrix3d stress_relaxed = sys.stress();
  ForceBalance b = s.after_relax;
  while (!(b.ratio < kEquilibrium && b.torque_ratio < kEquilibrium) &&
         sys.time() - t0 < options.relax.time_cap) {
    sys.advance(options.relax.check_every, Eigen::Vector3d::Zero());
    b = force_balance(sys);
  }
  s.relaxed.time = sys.time() - t0;
  sys.zero_velocities();
  s.at_rest = force_balance(sys);
  s.stress_change = sys.stress() - stress_relaxed;
  return s;
}

}  // namespace

bool RestOptions::IsValid(std::string* why) const {
  return relax.IsValid(why) && minimise.IsValid(why);
}

namespace {

// The packing's positions become the state's: wrapped into the cell, at rest, and a neighbour
// list built afresh from there (restore() builds it from the reference positions).
void put_at(DemSystem& sys, const PackingData& packing) {
  State st = sys.save();
  const Eigen::Vector3d L = sys.cell().lengths();
  Particles& p = st.particles;
  for (int i = 0; i < packing.size(); ++i) {
    const auto u = static_cast<std::size_t>(i);
    double* x[3] = {&p.x[u], &p.y[u], &p.z[u]};
    for (int a = 0; a < 3; ++a) *x[a] = wrap_coordinate(packing.positions(i, a), L[a]);
    p.vx[u] = p.vy[u] = p.vz[u] = 0.0;
  }
  st.ref_x = p.x;
  st.ref_y = p.y;
  st.ref_z = p.z;
  st.ref_lengths = L;
  st.ref_half_skin.clear();
  // At rest the cell stands still too: the dashpots see the last imposed strain rate (a probe's
  // loading, about 1.6 % of an elastic probe's stress response at quick.toml's rate).
  st.last_D = Eigen::Vector3d::Zero();
  sys = DemSystem::restore(st, sys.options());
  sys.zero_velocities();  // recomputes the forces at the new positions
}

}  // namespace

MinimiseSummary settle_at_minimum(DemSystem& sys, const MinimiseOptions& options,
                                  double* max_displacement) {
  MinimiseOptions mo = options;
  mo.k = sys.material().k;
  PackingData packing = packing_of(sys);
  const Eigen::MatrixX3d start = packing.positions;
  const MinimiseSummary summary = minimise_energy(packing, mo);
  if (max_displacement) *max_displacement = (packing.positions - start).rowwise().norm().maxCoeff();
  put_at(sys, packing);  // the minimum becomes the state
  return summary;
}

SaddleEscape leave_saddle(DemSystem& sys, const MinimiseOptions& options, int max_rounds) {
  SaddleEscape e;
  MinimiseOptions mo = options;
  mo.k = sys.material().k;
  LinearResponseOptions lo;
  lo.k = mo.k;
  // A minimum is told by the fastest factorisation (CHOLMOD where the build has it); a saddle's
  // modes are counted, and its direction found, by the simplicial LDL^T, which counts them at any
  // size (a failed CHOLMOD is diagnosed only up to diagnose_max_dof) but takes longer: a 40 s
  // rest stage for 8000 spheres, whose response CHOLMOD gives in 2 s (docs/probes.md).
  LinearResponseOptions ldlt = lo;
  ldlt.solver = LinearSolver::kSimplicialLdlt;
  PackingData packing = packing_of(sys);
  const Eigen::MatrixX3d start = packing.positions;
  bool ok = false;
  for (;;) {
    LinearResponse lr = linear_response(packing, lo);
    if (!lr.ok && lr.negative_direction.rows() == 0) lr = linear_response(packing, ldlt);
    if (e.rounds == 0) e.negative_modes = lr.n_negative_pivots;
    e.remaining = lr.n_negative_pivots;
    e.message = lr.message;
    ok = lr.ok;
    if (lr.ok || lr.n_negative_pivots <= 0 || lr.negative_direction.rows() == 0 ||
        e.rounds == max_rounds)
      break;
    // At a saddle the forces balance, so FIRE from there does not move: step off it first, by
    // the mean overlap at the particle that moves most (the energy falls either way, by
    // |D_r| / 2 per unit of the direction squared), far enough for the forces to exceed FIRE's
    // tolerance by orders of magnitude and small enough to stay near the saddle's contacts.
    const double overlap = force_balance(packing, mo.k).mean_contact_force / mo.k;
    const double largest = lr.negative_direction.rowwise().norm().maxCoeff();
    packing.positions += (overlap / largest) * lr.negative_direction;
    const MinimiseSummary m = minimise_energy(packing, mo);
    ++e.rounds;
    e.iterations += m.iterations;
    if (!m.converged) {
      e.message = "minimising after the step off the saddle: " + m.message;
      break;
    }
  }
  e.left = e.negative_modes > 0 && ok;
  e.max_displacement = (packing.positions - start).rowwise().norm().maxCoeff();
  if (e.rounds > 0) put_at(sys, packing);
  return e;
}

RestSummary bring_to_rest(DemSystem& sys, const RestOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("states: " + why);
  if (sys.material().frictional()) return rest_frictional(sys, options);
  RestSummary s;
  s.relaxed = relax(sys, options.relax);
  const double k = sys.material().k;
  s.after_relax = force_balance(packing_of(sys), k);
  const Eigen::Matrix3d stress_relaxed = sys.stress();
  s.minimised = settle_at_minimum(sys, options.minimise, &s.max_displacement);
  if (s.minimised.stalled_at > 0.0)
    throw InputError(
        round_off_refusal(s.minimised, "states.force_tolerance", options.minimise.force_tolerance));
  if (!s.minimised.converged)
    throw std::runtime_error("states: the energy minimisation did not converge (" +
                             s.minimised.message + ")");
  s.at_rest = force_balance(packing_of(sys), k);
  s.stress_change = sys.stress() - stress_relaxed;
  return s;
}

}  // namespace rendulic::dem
