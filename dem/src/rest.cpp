// The equilibrium criterion and states brought to rest (see rest.hpp; docs/dem.md "States at
// rest").
#include "rendulic/dem/rest.hpp"

#include <cmath>
#include <stdexcept>

#include "rendulic/core/errors.hpp"
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

bool RestOptions::IsValid(std::string* why) const {
  return relax.IsValid(why) && minimise.IsValid(why);
}

RestSummary bring_to_rest(DemSystem& sys, const RestOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("states: " + why);
  RestSummary s;
  s.relaxed = relax(sys, options.relax);
  const double k = sys.material().k;
  PackingData packing = packing_of(sys);
  s.after_relax = force_balance(packing, k);
  const Eigen::MatrixX3d start = packing.positions;
  const Eigen::Matrix3d stress_relaxed = sys.stress();
  MinimiseOptions mo = options.minimise;
  mo.k = k;
  s.minimised = minimise_energy(packing, mo);
  if (!s.minimised.converged)
    throw std::runtime_error("states: the energy minimisation did not converge (" +
                             s.minimised.message + ")");
  s.max_displacement = (packing.positions - start).rowwise().norm().maxCoeff();
  // The minimum becomes the state: positions wrapped into the cell, at rest, and a neighbour
  // list built afresh from there (restore() builds it from the reference positions).
  State st = sys.save();
  const Eigen::Vector3d L = sys.cell().lengths();
  Particles& p = st.particles;
  for (int i = 0; i < packing.size(); ++i) {
    const auto u = static_cast<std::size_t>(i);
    double* x[3] = {&p.x[u], &p.y[u], &p.z[u]};
    for (int a = 0; a < 3; ++a) {
      double w = packing.positions(i, a) - L[a] * std::floor(packing.positions(i, a) / L[a]);
      if (w >= L[a]) w -= L[a];  // a tiny negative coordinate rounds to L
      *x[a] = w;
    }
    p.vx[u] = p.vy[u] = p.vz[u] = 0.0;
  }
  st.ref_x = p.x;
  st.ref_y = p.y;
  st.ref_z = p.z;
  st.ref_lengths = L;
  st.ref_half_skin.clear();
  sys = DemSystem::restore(st, sys.options());
  sys.zero_velocities();  // recomputes the forces at the new positions
  s.at_rest = force_balance(packing_of(sys), k);
  s.stress_change = sys.stress() - stress_relaxed;
  return s;
}

}  // namespace rendulic::dem
