// The DEM engine's step, forces and measures (physics.md sections 1-3; scheme in
// dem_system.hpp). The contact loop is the hot path: a per-particle gather over the full
// neighbour list, with the periodic image taken from a 27-entry shift table rather than a
// rounding per pair.
#include "rendulic/dem/dem_system.hpp"

#include <omp.h>

#include <algorithm>
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
  d.list_.build(ref, s.ref_lengths, options.skin * options.material.r_mean);
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
  return s;
}

void DemSystem::rebuild_list() {
  const Eigen::Vector3d L = cell_.lengths;
  const std::size_t n = p_.size();
  double* pos[3] = {p_.x.data(), p_.y.data(), p_.z.data()};
#pragma omp parallel for schedule(static) if (n > kSerialBelow)
  for (std::size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      double q = pos[a][i] - L[a] * std::floor(pos[a][i] / L[a]);
      if (q >= L[a]) q -= L[a];  // floor rounding can leave q == L
      if (q < 0) q = 0;
      pos[a][i] = q;
    }
  list_.build(p_, L, options_.skin * options_.material.r_mean);
}

template <bool kStress>
void DemSystem::compute_forces(const double* __restrict vx, const double* __restrict vy,
                               const double* __restrict vz) {
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
  const double* __restrict x = p_.x.data();
  const double* __restrict y = p_.y.data();
  const double* __restrict z = p_.z.data();
  const double* __restrict rad = p_.radius.data();
  double* __restrict fxo = p_.fx.data();
  double* __restrict fyo = p_.fy.data();
  double* __restrict fzo = p_.fz.data();
  const std::int64_t* __restrict off = list_.offset.data();
  const std::int32_t* __restrict idx = list_.index.data();
  const std::uint8_t* __restrict code = list_.shift_code.data();
  double* __restrict sd = stress_scratch_.data();

  // Half list: each pair once, its force added to i and subtracted from j. Threads scatter
  // into private buffers that are summed in thread order: deterministic for a given thread
  // count (and pair forces are exact opposites, so momentum is conserved to round-off).
  const int threads = n > kSerialBelow ? omp_get_max_threads() : 1;
  const std::size_t stride = 3 * n;
  if (force_buffer_.size() < static_cast<std::size_t>(threads) * stride)
    force_buffer_.resize(static_cast<std::size_t>(threads) * stride);
  double* const buffers = force_buffer_.data();

#pragma omp parallel num_threads(threads) if (threads > 1)
  {
    double* __restrict bx = buffers + static_cast<std::size_t>(omp_get_thread_num()) * stride;
    double* __restrict by = bx + n;
    double* __restrict bz = by + n;
    std::fill(bx, bx + stride, 0.0);
#pragma omp for schedule(static)
    for (std::size_t i = 0; i < n; ++i) {
      const double xi = x[i], yi = y[i], zi = z[i];
      const double vxi = vx[i], vyi = vy[i], vzi = vz[i], ri = rad[i];
      double fx = 0, fy = 0, fz = 0, sxx = 0, syy = 0, szz = 0;
      for (std::int64_t e = off[i]; e < off[i + 1]; ++e) {
        const std::int32_t j = idx[e];
        const std::uint8_t c = code[e];
        const double dx = xi - x[j] + tx[c];
        const double dy = yi - y[j] + ty[c];
        const double dz = zi - z[j] + tz[c];
        const double R = ri + rad[j];
        const double r2 = dx * dx + dy * dy + dz * dz;
        if (r2 >= R * R) continue;
        const double d = std::sqrt(r2);
        const double inv = 1.0 / d;
        const double nx = dx * inv, ny = dy * inv, nz = dz * inv;
        // True relative velocity: peculiar part plus the affine part D l.
        const double ddot = -(nx * (vxi - vx[j] + Dx * dx) + ny * (vyi - vy[j] + Dy * dy) +
                              nz * (vzi - vz[j] + Dz * dz));
        const double fn = k * (R - d) + gamma * ddot;
        const double gx = fn * nx, gy = fn * ny, gz = fn * nz;
        fx += gx;
        fy += gy;
        fz += gz;
        bx[j] -= gx;
        by[j] -= gy;
        bz[j] -= gz;
        if constexpr (kStress) {
          sxx += dx * gx;
          syy += dy * gy;
          szz += dz * gz;
        }
      }
      bx[i] += fx;
      by[i] += fy;
      bz[i] += fz;
      if constexpr (kStress) {
        sd[3 * i] = sxx;
        sd[3 * i + 1] = syy;
        sd[3 * i + 2] = szz;
      }
    }
    // (implicit barrier: every buffer is complete)
#pragma omp for schedule(static)
    for (std::size_t i = 0; i < n; ++i) {
      double fx = 0, fy = 0, fz = 0;
      for (int t = 0; t < threads; ++t) {
        const double* b = buffers + static_cast<std::size_t>(t) * stride;
        fx += b[i];
        fy += b[n + i];
        fz += b[2 * n + i];
      }
      fxo[i] = fx - gamma_b * vx[i];
      fyo[i] = fy - gamma_b * vy[i];
      fzo[i] = fz - gamma_b * vz[i];
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

void DemSystem::refresh_forces() { compute_forces<true>(p_.vx.data(), p_.vy.data(), p_.vz.data()); }

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
  const std::size_t nw = n;
  if (wx_.size() != nw) wx_.resize(nw), wy_.resize(nw), wz_.resize(nw);
  double* __restrict wx = wx_.data();
  double* __restrict wy = wy_.data();
  double* __restrict wz = wz_.data();
  double u2max = 0;
#pragma omp parallel for schedule(static) reduction(max : u2max) if (n > kSerialBelow)
  for (std::size_t i = 0; i < n; ++i) {
    const double hm = h * im[i];
    const double vxi = vx[i] + hm * fx[i], vyi = vy[i] + hm * fy[i], vzi = vz[i] + hm * fz[i];
    vx[i] = vxi;
    vy[i] = vyi;
    vz[i] = vzi;
    // Predicted v(t+dt) = v(t) + dt a(t), second-order accurate, for the dissipative forces.
    wx[i] = vxi + hm * fx[i];
    wy[i] = vyi + hm * fy[i];
    wz[i] = vzi + hm * fz[i];
    const double xi = sx * (x[i] + dt * vxi), yi = sy * (y[i] + dt * vyi),
                 zi = sz * (z[i] + dt * vzi);
    x[i] = xi;
    y[i] = yi;
    z[i] = zi;
    const double ux = xi - rx * ax[i], uy = yi - ry * ay[i], uz = zi - rz * az[i];
    u2max = std::max(u2max, ux * ux + uy * uy + uz * uz);
  }
  cell_.lengths = L;
  strain_E_ += D * dt;
  time_ += dt;
  last_D_ = D;
  if (list_.must_rebuild(std::sqrt(u2max), L)) rebuild_list();
  compute_forces<kStress>(wx, wy, wz);
#pragma omp parallel for schedule(static) if (n > kSerialBelow)
  for (std::size_t i = 0; i < n; ++i) {
    const double hm = h * im[i];
    vx[i] += hm * fx[i];
    vy[i] += hm * fy[i];
    vz[i] += hm * fz[i];
  }
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
