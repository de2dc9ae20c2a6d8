// The DEM engine's step, forces and measures (physics.md sections 1-3; scheme in
// dem_system.hpp). The contact loop is the hot path: a per-particle gather over the half
// neighbour list from packed records (position + radius, velocity, force accumulator: three
// cache lines per partner), with the periodic image taken from a 27-entry shift table rather
// than a rounding per pair. Measured alternatives that lost (docs/performance.md): a
// branch-free first pass that compacts the touching pairs, and an AVX-512 gather version of
// the pair loop; rows are ~9 entries long, too short for either to pay.
#include "rendulic/dem/dem_system.hpp"

#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "rendulic/core/conventions.hpp"
#include "rendulic/core/errors.hpp"

namespace rendulic::dem {
namespace {
// Below this many particles a parallel region costs more than it saves.
constexpr std::size_t kSerialBelow = 256;

// e1 >= e2 stay the two largest values seen.
inline void keep_two_largest(double e, double& e1, double& e2) {
  if (e > e1)
    e2 = e1, e1 = e;
  else if (e > e2)
    e2 = e;
}
}  // namespace

bool SystemOptions::IsValid(std::string* why) const {
  if (!material.IsValid(why)) return false;
  if (!(dt_factor > 0 && std::isfinite(dt_factor))) {
    if (why) *why = "dt_factor must be positive";
    return false;
  }
  if (!(skin > 0 && std::isfinite(skin))) {
    if (why) *why = "skin must be positive";
    return false;
  }
  return true;
}

DemSystem::DemSystem(Particles particles, const PeriodicCell& cell, const SystemOptions& options)
    : p_(std::move(particles)), cell_(cell), options_(options) {
  std::string why;
  if (!options_.IsValid(&why)) throw InputError("DEM options: " + why);
  check_time_step(options_.material, options_.dt_factor, "dem.dt_factor");
  if (p_.size() < 2) throw InputError("DEM system needs at least 2 particles");
  dt_ = time_step(options_.material, options_.dt_factor);
  solid_volume_ = p_.total_volume();
  stress_scratch_.assign(3 * p_.size(), 0.0);
  rebuild_list();
  refresh_forces();
}

DemSystem DemSystem::restore(const State& s, const SystemOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("DEM options: " + why);
  check_time_step(options.material, options.dt_factor, "dem.dt_factor");
  DemSystem d;
  d.options_ = options;
  d.p_ = s.particles;
  d.cell_.lengths = s.lengths;
  d.strain_E_ = s.strain_E;
  d.last_D_ = s.last_D;
  d.time_ = s.time;
  d.steps_ = s.steps;
  d.dt_ = time_step(options.material, options.dt_factor);
  d.solid_volume_ = d.p_.total_volume();
  d.stress_scratch_.assign(3 * d.p_.size(), 0.0);
  // The list is a pure function of the reference state: rebuild it from there.
  Particles ref = s.particles;
  ref.x = s.ref_x;
  ref.y = s.ref_y;
  ref.z = s.ref_z;
  const double skin = options.skin * options.material.r_mean;
  if (s.ref_half_skin.empty())
    d.list_.build(ref, s.ref_lengths, skin);
  else
    d.list_.build(ref, s.ref_lengths, skin, s.ref_half_skin);
  d.note_list_built();
  return d;
}

State DemSystem::save() const {
  State s;
  s.particles = p_;
  s.lengths = cell_.lengths;
  s.strain_E = strain_E_;
  s.last_D = last_D_;
  s.time = time_;
  s.steps = steps_;
  s.ref_x = list_.ref_x();
  s.ref_y = list_.ref_y();
  s.ref_z = list_.ref_z();
  s.ref_lengths = list_.ref_lengths();
  s.ref_half_skin = list_.half_skins();
  return s;
}

void DemSystem::rebuild_list() {
  const Eigen::Vector3d L = cell_.lengths;
  const std::size_t n = p_.size();
  const double skin = options_.skin * options_.material.r_mean;
  double* pos[3] = {p_.x.data(), p_.y.data(), p_.z.data()};
  // Non-affine displacements of the interval that ends here choose the next skins.
  std::vector<double> u;
  if (list_.ref_x().size() == n) {
    u.resize(n);
    const std::vector<double>* ref[3] = {&list_.ref_x(), &list_.ref_y(), &list_.ref_z()};
    const Eigen::Vector3d S = L.cwiseQuotient(list_.ref_lengths());
#pragma omp parallel for schedule(static) if (n > kSerialBelow)
    for (std::size_t i = 0; i < n; ++i) {
      double u2 = 0;
      for (int a = 0; a < 3; ++a) {
        const double d = pos[a][i] - S[a] * (*ref[a])[i];
        u2 += d * d;
      }
      u[i] = std::sqrt(u2);
    }
  }
#pragma omp parallel for schedule(static) if (n > kSerialBelow)
  for (std::size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      double q = pos[a][i] - L[a] * std::floor(pos[a][i] / L[a]);
      if (q >= L[a]) q -= L[a];  // floor rounding can leave q == L
      if (q < 0) q = 0;
      pos[a][i] = q;
    }
  list_.build(p_, L, skin, choose_half_skins(u, p_.radius, skin));
  note_list_built();
}

void DemSystem::note_list_built() { pack_positions(); }

void DemSystem::pack_positions() {
  const std::size_t n = p_.size();
  if (pos4_.size() != 4 * n) pos4_.assign(4 * n, 0.0);
  double* __restrict q = pos4_.data();
#pragma omp parallel for schedule(static) if (n > kSerialBelow)
  for (std::size_t i = 0; i < n; ++i) {
    q[4 * i] = p_.x[i];
    q[4 * i + 1] = p_.y[i];
    q[4 * i + 2] = p_.z[i];
    q[4 * i + 3] = p_.radius[i];
  }
}

void DemSystem::partition_rows(int threads) {
  // Contiguous row ranges of equal list length (the work), and for each thread the partners
  // outside its range: particles are numbered along the bins, so a range is a slab of the cell
  // and its foreign partners sit on the slab's two faces only.
  const std::size_t n = p_.size();
  const std::int64_t total = list_.offset[n];
  parts_.assign(static_cast<std::size_t>(threads), {});
  std::size_t i = 0;
  for (int t = 0; t < threads; ++t) {
    RowPart& part = parts_[static_cast<std::size_t>(t)];
    part.lo = i;
    const std::int64_t target = total * (t + 1) / threads;
    while (i < n && (t == threads - 1 || list_.offset[i + 1] <= target)) ++i;
    part.hi = t == threads - 1 ? n : i;
    i = part.hi;
  }
  for (RowPart& part : parts_) {
    part.foreign.clear();
    for (std::size_t r = part.lo; r < part.hi; ++r)
      for (std::int64_t e = list_.offset[r]; e < list_.offset[r + 1]; ++e) {
        const std::size_t j = static_cast<std::size_t>(list_.index[e]);
        if (j < part.lo || j >= part.hi) part.foreign.push_back(static_cast<std::int32_t>(j));
      }
    std::sort(part.foreign.begin(), part.foreign.end());
    part.foreign.erase(std::unique(part.foreign.begin(), part.foreign.end()), part.foreign.end());
  }
  parts_builds_ = list_.builds();
}

template <bool kStress>
void DemSystem::compute_forces(double half_kick) {
  const std::size_t n = p_.size();
  const Eigen::Vector3d L = cell_.lengths;
  double tx[27], ty[27], tz[27];
  for (int c = 0; c < 27; ++c) {
    const Eigen::Vector3d s = NeighborList::shift(static_cast<std::uint8_t>(c));
    tx[c] = s[0] * L[0];
    ty[c] = s[1] * L[1];
    tz[c] = s[2] * L[2];
  }
  const double k = options_.material.k, gamma = options_.material.gamma;
  const double gamma_b = options_.material.gamma_b;
  const double Dx = last_D_[0], Dy = last_D_[1], Dz = last_D_[2];
  const int threads = n > kSerialBelow ? omp_get_max_threads() : 1;
  if (parts_builds_ != list_.builds() || parts_.size() != static_cast<std::size_t>(threads))
    partition_rows(threads);
  const std::size_t stride = 4 * n;
  if (acc4_.size() < threads * stride) acc4_.assign(threads * stride, 0.0);
  const double* __restrict P = pos4_.data();
  const double* __restrict W = vel4_.data();
  double* __restrict fxo = p_.fx.data();
  double* __restrict fyo = p_.fy.data();
  double* __restrict fzo = p_.fz.data();
  double* __restrict vxo = p_.vx.data();
  double* __restrict vyo = p_.vy.data();
  double* __restrict vzo = p_.vz.data();
  const double* __restrict im = p_.inv_mass.data();
  const std::int64_t* __restrict off = list_.offset.data();
  const std::int32_t* __restrict idx = list_.index.data();
  const std::uint8_t* __restrict code = list_.shift_code.data();
  double* __restrict sd = stress_scratch_.data();

  // Half list: each pair once, its force added to i and subtracted from j. Each thread owns a
  // range of rows and scatters into its own accumulator; of that accumulator only its range and
  // its foreign partners (outside the range) are ever written, so only they are cleared, and
  // the owner of a range adds the others' foreign parts in thread order. Deterministic for a
  // given thread count, no full-size clear or sum per thread, and pair forces are exact
  // opposites (momentum conserved to round-off).
#pragma omp parallel num_threads(threads) if (threads > 1)
  {
    const int t = omp_get_thread_num();
    const RowPart& part = parts_[static_cast<std::size_t>(t)];
    const std::size_t lo = part.lo, hi = part.hi;
    double* __restrict A = acc4_.data() + static_cast<std::size_t>(t) * stride;
    std::fill(A + 4 * lo, A + 4 * hi, 0.0);
    for (const std::int32_t j : part.foreign)
      std::fill_n(A + 4 * static_cast<std::size_t>(j), 3, 0.0);
    for (std::size_t i = lo; i < hi; ++i) {
      const double xi = P[4 * i], yi = P[4 * i + 1], zi = P[4 * i + 2], ri = P[4 * i + 3];
      const double vxi = W[4 * i], vyi = W[4 * i + 1], vzi = W[4 * i + 2];
      double fx = 0, fy = 0, fz = 0, sxx = 0, syy = 0, szz = 0;
      for (std::int64_t e = off[i]; e < off[i + 1]; ++e) {
        const std::size_t j = 4 * static_cast<std::size_t>(idx[e]);
        const std::uint8_t c = code[e];
        const double dx = xi - P[j] + tx[c];
        const double dy = yi - P[j + 1] + ty[c];
        const double dz = zi - P[j + 2] + tz[c];
        const double R = ri + P[j + 3];
        const double r2 = dx * dx + dy * dy + dz * dz;
        if (r2 >= R * R) continue;
        const double d = std::sqrt(r2);
        const double inv = 1.0 / d;
        const double nx = dx * inv, ny = dy * inv, nz = dz * inv;
        // True relative velocity: peculiar part plus the affine part D l.
        const double ddot = -(nx * (vxi - W[j] + Dx * dx) + ny * (vyi - W[j + 1] + Dy * dy) +
                              nz * (vzi - W[j + 2] + Dz * dz));
        const double fn = k * (R - d) + gamma * ddot;
        const double gx = fn * nx, gy = fn * ny, gz = fn * nz;
        fx += gx;
        fy += gy;
        fz += gz;
        A[j] -= gx;
        A[j + 1] -= gy;
        A[j + 2] -= gz;
        if constexpr (kStress) {
          sxx += dx * gx;
          syy += dy * gy;
          szz += dz * gz;
        }
      }
      A[4 * i] += fx;
      A[4 * i + 1] += fy;
      A[4 * i + 2] += fz;
      if constexpr (kStress) {
        sd[3 * i] = sxx;
        sd[3 * i + 1] = syy;
        sd[3 * i + 2] = szz;
      }
    }
    if (threads > 1) {
#pragma omp barrier
      // Foreign contributions to this range, in thread order.
      for (int u = 0; u < threads; ++u) {
        if (u == t) continue;
        const std::vector<std::int32_t>& f = parts_[static_cast<std::size_t>(u)].foreign;
        const double* B = acc4_.data() + static_cast<std::size_t>(u) * stride;
        for (auto it = std::lower_bound(f.begin(), f.end(), static_cast<std::int32_t>(lo));
             it != f.end() && static_cast<std::size_t>(*it) < hi; ++it) {
          const std::size_t j = 4 * static_cast<std::size_t>(*it);
          A[j] += B[j];
          A[j + 1] += B[j + 1];
          A[j + 2] += B[j + 2];
        }
      }
    }
    for (std::size_t i = lo; i < hi; ++i) {
      fxo[i] = A[4 * i] - gamma_b * W[4 * i];
      fyo[i] = A[4 * i + 1] - gamma_b * W[4 * i + 1];
      fzo[i] = A[4 * i + 2] - gamma_b * W[4 * i + 2];
    }
    // The closing half kick of the step, here rather than in a region of its own: one
    // parallel region (and barrier) less per step, which matters at small N.
    if (half_kick != 0)
      for (std::size_t i = lo; i < hi; ++i) {
        const double hm = half_kick * im[i];
        vxo[i] += hm * fxo[i];
        vyo[i] += hm * fyo[i];
        vzo[i] += hm * fzo[i];
      }
  }
  if constexpr (kStress) {
    // Serial sum in particle order: independent of the thread count.
    Eigen::Vector3d s = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < n; ++i)
      s += Eigen::Vector3d(sd[3 * i], sd[3 * i + 1], sd[3 * i + 2]);
    last_stress_diag_ = s / cell_.volume();
  }
}

void DemSystem::refresh_forces() {
  const std::size_t n = p_.size();
  pack_positions();
  if (vel4_.size() != 4 * n) vel4_.assign(4 * n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    vel4_[4 * i] = p_.vx[i];
    vel4_[4 * i + 1] = p_.vy[i];
    vel4_[4 * i + 2] = p_.vz[i];
  }
  compute_forces<true>(0.0);
}

void DemSystem::zero_velocities() {
  std::fill(p_.vx.begin(), p_.vx.end(), 0.0);
  std::fill(p_.vy.begin(), p_.vy.end(), 0.0);
  std::fill(p_.vz.begin(), p_.vz.end(), 0.0);
  refresh_forces();
}

void DemSystem::step(const Eigen::Vector3d& D) { step_impl<false>(D); }

template <bool kStress>
void DemSystem::step_impl(const Eigen::Vector3d& D) {
  const std::size_t n = p_.size();
  const double dt = dt_, h = 0.5 * dt_;
  const Eigen::Vector3d s = (D * dt).array().exp();
  const Eigen::Vector3d L = cell_.lengths.cwiseProduct(s);
  const Eigen::Vector3d sref = L.cwiseQuotient(list_.ref_lengths());
  const double s_min = list_.s_min(L);
  const double sx = s[0], sy = s[1], sz = s[2];
  const double rx = sref[0], ry = sref[1], rz = sref[2];
  double* __restrict x = p_.x.data();
  double* __restrict y = p_.y.data();
  double* __restrict z = p_.z.data();
  double* __restrict vx = p_.vx.data();
  double* __restrict vy = p_.vy.data();
  double* __restrict vz = p_.vz.data();
  const double* __restrict fx = p_.fx.data();
  const double* __restrict fy = p_.fy.data();
  const double* __restrict fz = p_.fz.data();
  const double* __restrict im = p_.inv_mass.data();
  const double* __restrict ax = list_.ref_x().data();
  const double* __restrict ay = list_.ref_y().data();
  const double* __restrict az = list_.ref_z().data();
  const double* __restrict hs = list_.half_skins().data();
  if (vel4_.size() != 4 * n) vel4_.assign(4 * n, 0.0);
  if (pos4_.size() != 4 * n) pack_positions();
  double* __restrict W = vel4_.data();
  double* __restrict P = pos4_.data();
  // The two largest excesses e_i = u_i - s_min h_i (rebuild rule of neighbor_list.hpp), per
  // thread, then merged: the pair of values is independent of the order of the merge.
  const int threads = n > kSerialBelow ? omp_get_max_threads() : 1;
  std::vector<std::array<double, 2>> top(threads, {-1e300, -1e300});
#pragma omp parallel num_threads(threads) if (threads > 1)
  {
    double e1 = -1e300, e2 = -1e300;
#pragma omp for schedule(static)
    for (std::size_t i = 0; i < n; ++i) {
      const double hm = h * im[i];
      const double vxi = vx[i] + hm * fx[i], vyi = vy[i] + hm * fy[i], vzi = vz[i] + hm * fz[i];
      vx[i] = vxi;
      vy[i] = vyi;
      vz[i] = vzi;
      // Predicted v(t+dt) = v(t) + dt a(t), second-order accurate, for the dissipative forces.
      W[4 * i] = vxi + hm * fx[i];
      W[4 * i + 1] = vyi + hm * fy[i];
      W[4 * i + 2] = vzi + hm * fz[i];
      const double xi = sx * (x[i] + dt * vxi), yi = sy * (y[i] + dt * vyi),
                   zi = sz * (z[i] + dt * vzi);
      x[i] = xi;
      y[i] = yi;
      z[i] = zi;
      P[4 * i] = xi;
      P[4 * i + 1] = yi;
      P[4 * i + 2] = zi;
      const double ux = xi - rx * ax[i], uy = yi - ry * ay[i], uz = zi - rz * az[i];
      keep_two_largest(std::sqrt(ux * ux + uy * uy + uz * uz) - s_min * hs[i], e1, e2);
    }
    top[omp_get_thread_num()] = {e1, e2};
  }
  double e1 = -1e300, e2 = -1e300;
  for (const auto& [a, b] : top) keep_two_largest(a, e1, e2), keep_two_largest(b, e1, e2);
  cell_.lengths = L;
  strain_E_ += D * dt;
  time_ += dt;
  last_D_ = D;
  if (list_.must_rebuild(e1, e2, L)) rebuild_list();
  compute_forces<kStress>(h);
  ++steps_;
}

void DemSystem::advance(std::int64_t n, const Eigen::Vector3d& D) {
  for (std::int64_t k = 0; k < n; ++k) step(D);
}

void DemSystem::step(const CellControl& control) {
  if (!control.needs_stress()) {
    Eigen::Vector3d D;
    for (int a = 0; a < 3; ++a) D[a] = control.axis[a].rate;
    step(D);
    return;
  }
  // The servo reads the stress of the previous force evaluation (one step of lag).
  step_impl<true>(control.velocity_gradient(last_stress_diag_, options_.material.k_star()));
}

std::vector<Contact> DemSystem::contacts() const {
  std::vector<Contact> out;
  const std::size_t n = p_.size();
  const Eigen::Vector3d L = cell_.lengths;
  const double k = options_.material.k, gamma = options_.material.gamma;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::int64_t e = list_.offset[i]; e < list_.offset[i + 1]; ++e) {
      const std::int32_t j = list_.index[e];
      const Eigen::Vector3d l = p_.position(i) - p_.position(j) +
                                NeighborList::shift(list_.shift_code[e]).cwiseProduct(L);
      const double R = p_.radius[i] + p_.radius[j];
      const double d = l.norm();
      if (d >= R) continue;
      const Eigen::Vector3d nrm = l / d;
      const Eigen::Vector3d vrel = p_.velocity(i) - p_.velocity(j) + last_D_.cwiseProduct(l);
      Contact c;
      // Reported with i < j (the list stores each pair once, in either order).
      const bool swap = static_cast<std::size_t>(j) < i;
      c.i = swap ? j : static_cast<std::int32_t>(i);
      c.j = swap ? static_cast<std::int32_t>(i) : j;
      c.branch = swap ? Eigen::Vector3d(-l) : l;
      c.overlap = R - d;
      c.force = k * c.overlap + gamma * (-nrm.dot(vrel));
      out.push_back(c);
    }
  }
  return out;
}

Eigen::Matrix3d DemSystem::stress() const {
  Eigen::Matrix3d s = Eigen::Matrix3d::Zero();
  for (const Contact& c : contacts())
    s += c.force / c.branch.norm() * c.branch * c.branch.transpose();
  return s / cell_.volume();
}

Eigen::Matrix3d DemSystem::fabric() const {
  Eigen::Matrix3d f = Eigen::Matrix3d::Zero();
  const double c43 = 4.0 / 3.0 * std::numbers::pi;
  for (const Contact& c : contacts()) {
    const double ri = p_.radius[c.i], rj = p_.radius[c.j];
    const Eigen::Vector3d nrm = c.branch.normalized();
    f += c43 * (ri * ri * ri + rj * rj * rj) * nrm * nrm.transpose();
  }
  return f / cell_.volume();
}

double DemSystem::kinetic_energy() const {
  double e = 0;
  for (std::size_t i = 0; i < p_.size(); ++i)
    e += 0.5 * p_.mass(i) * (p_.vx[i] * p_.vx[i] + p_.vy[i] * p_.vy[i] + p_.vz[i] * p_.vz[i]);
  return e;
}

double DemSystem::elastic_energy() const {
  double e = 0;
  for (const Contact& c : contacts()) e += 0.5 * options_.material.k * c.overlap * c.overlap;
  return e;
}

std::vector<bool> non_rattlers(std::size_t n, const std::vector<Contact>& contacts,
                               int min_contacts) {
  std::vector<int> z(n, 0);
  std::vector<std::vector<std::int32_t>> adj(n);
  for (const Contact& c : contacts) {
    ++z[c.i], ++z[c.j];
    adj[c.i].push_back(c.j);
    adj[c.j].push_back(c.i);
  }
  std::vector<bool> keep(n, true);
  std::vector<std::size_t> queue;
  for (std::size_t i = 0; i < n; ++i)
    if (z[i] < min_contacts) keep[i] = false, queue.push_back(i);
  // Removing a rattler takes its contacts away from its partners, which may become rattlers.
  while (!queue.empty()) {
    const std::size_t i = queue.back();
    queue.pop_back();
    for (std::int32_t j : adj[i])
      if (keep[j] && --z[j] < min_contacts) keep[j] = false, queue.push_back(j);
  }
  return keep;
}

Measures DemSystem::measure() const {
  Measures m;
  const std::vector<Contact> cs = contacts();
  const double V = cell_.volume();
  const double k = options_.material.k;
  const double c43 = 4.0 / 3.0 * std::numbers::pi;
  m.time = time_;
  for (const Contact& c : cs) {
    const double d = c.branch.norm();
    const Eigen::Vector3d nrm = c.branch / d;
    m.stress += c.force * d * nrm * nrm.transpose();
    const double ri = p_.radius[c.i], rj = p_.radius[c.j];
    m.fabric += c43 * (ri * ri * ri + rj * rj * rj) * nrm * nrm.transpose();
    m.elastic_energy += 0.5 * k * c.overlap * c.overlap;
  }
  m.stress /= V;
  m.fabric /= V;
  m.stress_star = m.stress / options_.material.k_star();
  m.pressure = pressure(m.stress);
  m.pressure_star = m.pressure / options_.material.k_star();
  m.strain = strain_from_kinematic(strain_E_.asDiagonal().toDenseMatrix());
  m.eps_v = volumetric_strain(m.strain);
  m.eps_dev = signed_deviator(m.strain);
  m.volume_fraction = volume_fraction();
  const std::size_t n = p_.size();
  m.contacts = static_cast<std::int64_t>(cs.size());
  m.coordination = 2.0 * static_cast<double>(cs.size()) / static_cast<double>(n);
  // C* counts contacts among non-rattlers only (rattlers removed iteratively).
  const std::vector<bool> keep = non_rattlers(n, cs);
  std::size_t n_keep = 0, m_keep = 0;
  for (std::size_t i = 0; i < n; ++i) n_keep += keep[i];
  for (const Contact& c : cs) m_keep += keep[c.i] && keep[c.j];
  m.coordination_nonrattler = n_keep ? 2.0 * static_cast<double>(m_keep) / n_keep : 0.0;
  m.rattler_fraction = 1.0 - static_cast<double>(n_keep) / static_cast<double>(n);
  m.kinetic_energy = kinetic_energy();
  m.kinetic_to_elastic =
      m.elastic_energy > 0 ? m.kinetic_energy / m.elastic_energy
                           : (m.kinetic_energy > 0 ? std::numeric_limits<double>::infinity() : 0.0);
  m.strain_rate = last_D_.cwiseAbs().maxCoeff();
  const Material& mat = options_.material;
  if (m.strain_rate == 0)
    m.inertial_number = 0;
  else if (m.pressure > 0)
    m.inertial_number = m.strain_rate * 2.0 * mat.r_mean * std::sqrt(mat.density / m.pressure);
  else
    m.inertial_number = std::numeric_limits<double>::infinity();
  if (!std::isfinite(m.kinetic_energy) || !std::isfinite(m.elastic_energy) || !m.stress.allFinite())
    throw std::runtime_error("DEM integration diverged (non-finite energy or stress) at t = " +
                             std::to_string(time_) + " s");
  return m;
}

}  // namespace rendulic::dem
