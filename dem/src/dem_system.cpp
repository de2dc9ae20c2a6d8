// The DEM engine's step, forces and measures (docs/physics.md sections 1-3; scheme in
// dem_system.hpp). The frictionless pair loop, the hot path, lives in pair_loop.cpp. With
// friction a contact costs ~7x more, and there the touching entries are compacted and the
// tangential law runs on four contacts at once, eight with AVX-512 (force_block_friction,
// docs/performance.md "Friction").
#include "rendulic/dem/dem_system.hpp"

#include <omp.h>

#if defined(__AVX__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "contacts_first.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/core/errors.hpp"
#include "vec4.hpp"

namespace rendulic::dem {
using namespace vec4;

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

namespace {

// Two particles at one point (a particle listed twice in a file, say) have no contact normal:
// their force was NaN, and the first step ended in "DEM integration diverged", an internal
// error (exit 1). Only equal wrapped positions are such a pair: any distance above zero has
// its normal.
void refuse_coincident(const Particles& p, const Eigen::Vector3d& L) {
  const std::size_t n = p.size();
  std::vector<std::array<double, 3>> q(n);
  for (std::size_t i = 0; i < n; ++i)
    q[i] = {wrap_coordinate(p.x[i], L[0]), wrap_coordinate(p.y[i], L[1]),
            wrap_coordinate(p.z[i], L[2])};
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return q[a] != q[b] ? q[a] < q[b] : a < b; });
  for (std::size_t k = 1; k < n; ++k) {
    const std::size_t i = order[k - 1], j = order[k];
    if (q[i] != q[j]) continue;
    throw InputError("DEM system: particles " + std::to_string(i) + " and " + std::to_string(j) +
                     " (counted from 0 in the packing's order) are both at (" + decimal_g(q[i][0]) +
                     ", " + decimal_g(q[i][1]) + ", " + decimal_g(q[i][2]) +
                     ") m: two spheres at one point have no contact normal (a particle listed "
                     "twice?)");
  }
}

}  // namespace

DemSystem::DemSystem(Particles particles, const PeriodicCell& cell, const SystemOptions& options)
    : p_(std::move(particles)), cell_(cell), options_(options) {
  std::string why;
  if (!options_.IsValid(&why)) throw InputError("DEM options: " + why);
  check_time_step(options_.material, options_.dt_factor, "dem.dt_factor");
  if (!cell_.is_orthorhombic() || !(cell_.lengths().minCoeff() > 0) || !cell_.h.allFinite())
    throw InputError("DEM system: the cell must be orthorhombic with positive finite lengths");
  if (p_.size() < 2) throw InputError("DEM system needs at least 2 particles");
  refuse_coincident(p_, cell_.lengths());
  dt_ = time_step(options_.material, options_.dt_factor);
  solid_volume_ = p_.total_volume();
  stress_scratch_.assign(3 * p_.size(), 0.0);
  init_rotations();
  rebuild_list();
  refresh_forces();
}

void DemSystem::init_rotations() {
  friction_ = options_.material.frictional();
  rolling_ = friction_ && options_.material.rolling();
  const std::size_t n = p_.size();
  for (auto* v : {&p_.wx, &p_.wy, &p_.wz, &p_.tx, &p_.ty, &p_.tz})
    if (v->size() != n) v->assign(n, 0.0);
  if (!friction_) return;
  inv_inertia_.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    inv_inertia_[i] = 2.5 * p_.inv_mass[i] / (p_.radius[i] * p_.radius[i]);
}

namespace {

// A saved state the engine cannot have made: the finite numbers of a damaged file. A particle
// beyond its cell by more than the cell's length (the list bins it at the cell's edge: -1e308 m
// crashed the packing's pair search), one that would cross its own radius in one time step (a
// velocity of -1e308 m/s ended in an internal error of the list), or a strain rate beyond one
// step's limit (last_D = -1e308 1/s: a diverged integration). Each is far beyond any state a
// run saves: the particles move 1e-4 of their radius per step in quick.toml's gas.
void check_saved_state(const State& s, double dt) {
  const Particles& p = s.particles;
  auto place = [](const char* what, std::size_t i, const std::vector<double>& x, int a,
                  const Eigen::Vector3d& L) {
    if (i >= x.size() || (x[i] >= -L[a] && x[i] < 2.0 * L[a])) return;
    throw InputError(std::string("DEM state: ") + what + " " + std::to_string(i) + " at " +
                     decimal_g(x[i]) + " m on axis " + "xyz"[a] + " lies beyond its cell [0, " +
                     decimal_g(L[a]) + ") by more than the cell's length");
  };
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      place("particle", i, a == 0 ? p.x : a == 1 ? p.y : p.z, a, s.lengths);
      place("the reference position of particle", i,
            a == 0   ? s.ref_x
            : a == 1 ? s.ref_y
                     : s.ref_z,
            a, s.ref_lengths);
    }
    const double speed = std::hypot(p.vx[i], p.vy[i], p.vz[i]);  // no overflow at 1e308
    if (!(speed * dt <= p.radius[i]))
      throw InputError("DEM state: particle " + std::to_string(i) + " moves " +
                       decimal_g(speed * dt) + " m per time step (|v| = " + decimal_g(speed) +
                       " m/s, dt = " + decimal_g(dt) + " s), more than its radius " +
                       decimal_g(p.radius[i]) + " m");
  }
  if (const std::string excess =
          DemSystem::strain_per_step_excess(s.last_D.cwiseAbs().maxCoeff(), dt);
      !excess.empty())
    throw InputError("DEM state: its last strain rate " + excess);
}

}  // namespace

std::string DemSystem::strain_per_step_excess(double rate, double dt) {
  if (const double strain = rate * dt; !(strain <= kMaxStrainPerStep))
    return "strains the cell by " + decimal_g(strain) + " per time step (dt = " + decimal_g(dt) +
           " s), more than " + decimal_g(kMaxStrainPerStep);
  return {};
}

DemSystem DemSystem::restore(const State& s, const SystemOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("DEM options: " + why);
  check_time_step(options.material, options.dt_factor, "dem.dt_factor");
  DemSystem d;
  d.options_ = options;
  d.p_ = s.particles;
  d.cell_ = PeriodicCell::orthorhombic(s.lengths);
  d.strain_E_ = s.strain_E;
  d.last_D_ = s.last_D;
  d.time_ = s.time;
  d.steps_ = s.steps;
  d.dt_ = time_step(options.material, options.dt_factor);
  check_saved_state(s, d.dt_);
  refuse_coincident(s.particles, s.lengths);
  d.solid_volume_ = d.p_.total_volume();
  d.stress_scratch_.assign(3 * d.p_.size(), 0.0);
  d.init_rotations();
  d.sliding_dissipation_ = s.sliding_dissipation;
  d.last_stress_diag_ = s.last_stress_diag;
  d.last_stress_known_ = s.last_stress_known;
  // The list is a pure function of the reference state: rebuild it from there.
  Particles ref = s.particles;
  ref.x = s.ref_x;
  ref.y = s.ref_y;
  ref.z = s.ref_z;
  const double skin = options.skin * options.material.r_mean;
  // A saved list's half skins fit the skin it was made with (the smallest is half of it): with
  // another dem.skin the saved list, and the springs kept per entry, cannot be rebuilt.
  if (!s.ref_half_skin.empty() &&
      !NeighborList::half_skins_fit(s.particles.radius, skin, s.ref_half_skin)) {
    const double smallest = *std::min_element(s.ref_half_skin.begin(), s.ref_half_skin.end());
    const double made = 2.0 * smallest / options.material.r_mean;
    // Half skins that fit no skin (a damaged file: -1e308 said "made with dem.skin = -inf")
    // are not a matter of the skin chosen.
    if (!(made > 0.0) || !NeighborList::half_skins_fit(
                             s.particles.radius, made * options.material.r_mean, s.ref_half_skin))
      throw InputError("DEM state: its neighbour list's half skins fit no skin (the smallest is " +
                       decimal_g(smallest) + " m): a damaged state");
    throw InputError("DEM state: its neighbour list was made with dem.skin = " + decimal_g(made) +
                     ", not " + decimal_g(options.skin) +
                     ": restart it with the skin of the run that saved it");
  }
  if (s.ref_half_skin.empty())
    d.list_.build(ref, s.ref_lengths, skin);
  else
    d.list_.build(ref, s.ref_lengths, skin, s.ref_half_skin);
  // A saved history (3 doubles per list entry), or none: springs from zero.
  auto history = [&](const std::vector<double>& saved, const char* what) {
    const std::size_t entries = 3 * d.list_.index.size();
    if (saved.empty()) return std::vector<double>(entries, 0.0);
    if (saved.size() != entries)
      throw InputError(std::string("DEM state: its ") + what +
                       " history does not match its neighbour list");
    return saved;
  };
  if (d.friction_) d.hist_ = history(s.tangential_history, "tangential");
  if (d.rolling_) d.hist_r_ = history(s.rolling_history, "rolling");
  d.note_list_built();
  d.particles_ahead_ = true;  // the saved forces into their records at the first step
  return d;
}

State DemSystem::save() const {
  sync_particles();
  State s;
  s.particles = p_;
  s.lengths = cell_.lengths();
  s.strain_E = strain_E_;
  s.last_D = last_D_;
  s.time = time_;
  s.steps = steps_;
  s.ref_x = list_.ref_x();
  s.ref_y = list_.ref_y();
  s.ref_z = list_.ref_z();
  s.ref_lengths = list_.ref_lengths();
  s.ref_half_skin = list_.half_skins();
  if (friction_) s.tangential_history = hist_;
  if (rolling_) s.rolling_history = hist_r_;
  s.last_stress_diag = last_stress_diag_;  // read only where last_stress_known says so
  s.last_stress_known = last_stress_known_;
  s.sliding_dissipation = sliding_dissipation_;
  return s;
}

void DemSystem::rebuild_list() {
  const int team = last_team_;
  sync_particles(team);  // positions (the forces are computed after the build)
  const Eigen::Vector3d L = cell_.lengths();
  const std::size_t n = p_.size();
  const double skin = options_.skin * options_.material.r_mean;
  double* pos[3] = {p_.x.data(), p_.y.data(), p_.z.data()};
  // Non-affine displacements of the interval that ends here choose the next skins.
  std::vector<double> u;
  if (list_.ref_x().size() == n) {
    u.resize(n);
    const std::vector<double>* ref[3] = {&list_.ref_x(), &list_.ref_y(), &list_.ref_z()};
    const Eigen::Vector3d S = L.cwiseQuotient(list_.ref_lengths());
#pragma omp parallel for schedule(static) num_threads(team) if (team > 1)
    for (std::size_t i = 0; i < n; ++i) {
      double u2 = 0;
      for (int a = 0; a < 3; ++a) {
        const double d = pos[a][i] - S[a] * (*ref[a])[i];
        u2 += d * d;
      }
      u[i] = std::sqrt(u2);
    }
  }
#pragma omp parallel for schedule(static) num_threads(team) if (team > 1)
  for (std::size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) pos[a][i] = wrap_coordinate(pos[a][i], L[a]);
  if (friction_) {
    const std::vector<std::int64_t> old_offset = list_.offset;
    const std::vector<std::int32_t> old_index = list_.index;
    const std::vector<double> old = std::move(hist_);
    const std::vector<double> old_rolling = std::move(hist_r_);
    list_.build(p_, L, skin, choose_half_skins(u, p_.radius, skin), team);
    carry_history(old_offset, old_index, old, old_rolling);
  } else {
    list_.build(p_, L, skin, choose_half_skins(u, p_.radius, skin), team);
  }
  note_list_built();
}

void DemSystem::carry_history(const std::vector<std::int64_t>& old_offset,
                              const std::vector<std::int32_t>& old_index,
                              const std::vector<double>& old,
                              const std::vector<double>& old_rolling) {
  // The history belongs to the pair, not to the list entry: the pairs in contact (a spring !=
  // 0; a pair that lost contact dropped its history in the force loop) keyed (min, max) with xi
  // as the lower index sees it, then looked up for every entry of the new list. A pair may
  // change its row between builds; xi then changes sign, the rolling spring does not (its
  // velocity, -a' n x (w_i - w_j), is the same for either order).
  const std::size_t n = p_.size();
  struct Kept {
    std::uint64_t key;
    double xi[3];
    double xr[3];
  };
  const bool roll = rolling_ && old_rolling.size() == old.size();
  std::vector<Kept> kept;
  if (old.size() == 3 * old_index.size() && old_offset.size() == n + 1)
    for (std::size_t i = 0; i < n; ++i)
      for (std::int64_t e = old_offset[i]; e < old_offset[i + 1]; ++e) {
        const double* x = old.data() + 3 * e;
        const double* r = roll ? old_rolling.data() + 3 * e : nullptr;
        const bool rolls = r && (r[0] != 0 || r[1] != 0 || r[2] != 0);
        if (x[0] == 0 && x[1] == 0 && x[2] == 0 && !rolls) continue;
        const std::size_t j = static_cast<std::size_t>(old_index[e]);
        const double sign = i < j ? 1.0 : -1.0;
        kept.push_back({std::min(i, j) * n + std::max(i, j),
                        {sign * x[0], sign * x[1], sign * x[2]},
                        {r ? r[0] : 0.0, r ? r[1] : 0.0, r ? r[2] : 0.0}});
      }
  std::sort(kept.begin(), kept.end(), [](const Kept& a, const Kept& b) { return a.key < b.key; });
  hist_.assign(3 * list_.index.size(), 0.0);
  if (rolling_) hist_r_.assign(3 * list_.index.size(), 0.0);
  if (kept.empty()) return;
  for (std::size_t i = 0; i < n; ++i)
    for (std::int64_t e = list_.offset[i]; e < list_.offset[i + 1]; ++e) {
      const std::size_t j = static_cast<std::size_t>(list_.index[e]);
      const std::uint64_t key = std::min(i, j) * n + std::max(i, j);
      const auto it = std::lower_bound(kept.begin(), kept.end(), key,
                                       [](const Kept& a, std::uint64_t k) { return a.key < k; });
      if (it == kept.end() || it->key != key) continue;
      const double sign = i < j ? 1.0 : -1.0;
      for (int a = 0; a < 3; ++a) hist_[3 * e + a] = sign * it->xi[a];
      if (rolling_)
        for (int a = 0; a < 3; ++a) hist_r_[3 * e + a] = it->xr[a];
    }
}

void DemSystem::note_list_built() {
  // The blocks first, so that each row's records below are written by the thread that kicks
  // it: written by one thread for all rows, every line of the other's rows crossed back at its
  // next kick (docs/performance.md "Hand-offs past the caches").
  make_blocks();
  const std::size_t n = p_.size();
  if (pos4_.size() < 4 * n) pos4_.resize(4 * n, 0.0);
  if (ref4_.size() != 4 * n) ref4_.assign(4 * n, 0.0);
  const int team = blocks_team();
#pragma omp parallel num_threads(team) if (team > 1)
  {
    const auto [lo, hi] = rows_of(static_cast<std::size_t>(omp_get_thread_num()),
                                  static_cast<std::size_t>(omp_get_num_threads()));
    pack_positions(lo, hi);
    // The rebuild rule's reference positions and half skins, read at every step: one record.
    double* __restrict r = ref4_.data();
    for (std::size_t i = lo; i < hi; ++i) {
      r[4 * i] = list_.ref_x()[i];
      r[4 * i + 1] = list_.ref_y()[i];
      r[4 * i + 2] = list_.ref_z()[i];
      r[4 * i + 3] = list_.half_skins()[i];
    }
  }
}

int DemSystem::blocks_team() const {
  return static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(std::max(last_team_, 1)),
                                                block_lo_.size() - 1));
}

std::pair<std::size_t, std::size_t> DemSystem::blocks_of(std::size_t t, std::size_t T) const {
  const std::size_t blocks = block_lo_.size() - 1;
  return {blocks * t / T, blocks * (t + 1) / T};
}

std::pair<std::size_t, std::size_t> DemSystem::rows_of(std::size_t t, std::size_t T) const {
  const std::size_t n = p_.size();
  if (block_lo_.size() < 2 || block_lo_.back() != n) return {n * t / T, n * (t + 1) / T};
  const auto [b0, b1] = blocks_of(t, T);
  return {block_lo_[b0], block_lo_[b1]};
}

void DemSystem::sync_particles(int team) const {
  if (!records_ahead_.ahead.load(std::memory_order_acquire)) return;
  const std::lock_guard<std::mutex> hold(records_ahead_.lock);
  if (!records_ahead_.ahead.load(std::memory_order_relaxed)) return;
  // The vectors' elements, not the vectors: writing them from a const member is defined (they
  // are not const objects).
  double* x[3] = {const_cast<double*>(p_.x.data()), const_cast<double*>(p_.y.data()),
                  const_cast<double*>(p_.z.data())};
  double* f[3] = {const_cast<double*>(p_.fx.data()), const_cast<double*>(p_.fy.data()),
                  const_cast<double*>(p_.fz.data())};
  const double* P = pos4_.data();
  const double* A = va8_.data() + 4;
#pragma omp parallel num_threads(team) if (team > 1)
  {
    const auto [lo, hi] = rows_of(static_cast<std::size_t>(omp_get_thread_num()),
                                  static_cast<std::size_t>(omp_get_num_threads()));
    for (std::size_t i = lo; i < hi; ++i)
      for (int c = 0; c < 3; ++c) {
        x[c][i] = P[4 * i + static_cast<std::size_t>(c)];
        f[c][i] = A[8 * i + static_cast<std::size_t>(c)];
      }
  }
  records_ahead_.ahead.store(false, std::memory_order_release);
}

void DemSystem::pack_particles() {
  const std::size_t n = p_.size();
  pack_positions();
  if (va8_.size() < 8 * n) va8_.resize(8 * n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    va8_[8 * i + 4] = p_.fx[i];
    va8_[8 * i + 5] = p_.fy[i];
    va8_[8 * i + 6] = p_.fz[i];
  }
  particles_ahead_ = false;
}

void DemSystem::pack_positions() {
  const std::size_t n = p_.size();
  if (pos4_.size() < 4 * n) pos4_.resize(4 * n, 0.0);
  pack_positions(0, n);
}

void DemSystem::pack_positions(std::size_t lo, std::size_t hi) {
  double* __restrict q = pos4_.data();
  for (std::size_t i = lo; i < hi; ++i) {
    q[4 * i] = p_.x[i];
    q[4 * i + 1] = p_.y[i];
    q[4 * i + 2] = p_.z[i];
    q[4 * i + 3] = p_.radius[i];
  }
}

void DemSystem::make_blocks() {
  // Blocks of equal list length (the work), their count a function of N only. Particles are
  // numbered along the bins, so a block is a slab of the cell and the partners outside it sit
  // near its two faces: few foreign slots, each shared by several entries.
  const std::size_t n = p_.size();
  const std::size_t blocks = block_count(n);
  const std::int64_t total = list_.offset[n];
  block_lo_.assign(blocks + 1, n);
  block_lo_[0] = 0;
  std::size_t i = 0;
  for (std::size_t b = 1; b < blocks; ++b) {
    const std::int64_t goal =
        total * static_cast<std::int64_t>(b) / static_cast<std::int64_t>(blocks);
    while (i < n && list_.offset[i] < goal) ++i;
    block_lo_[b] = i;
  }
  // Slots: per block the distinct (partner, periodic image) pairs of its entries whose partner
  // lies outside the block or is seen through another image, ascending, numbered after the N
  // rows. At the start of the block a slot receives a copy of the partner's velocity and its
  // position moved to the image (x_j - s L), and the force loop leaves the partner's share
  // there: partner_ is the list's index with every such entry sent to its slot, so the loop
  // needs neither the image code nor a shift (0.18 slots per particle at N = 9261, nu = 0.82,
  // for 0.44 entries with an image).
  constexpr std::uint8_t kNoShift = 13;  // NeighborList's code of s = (0, 0, 0)
  partner_.resize(list_.index.size());
  slot_lo_.assign(blocks + 1, 0);
  block_keys_.resize(blocks);
  // On the step's team, each thread the blocks whose rows it kicks: the blocks' slots are
  // independent but for where they start, so one barrier (the sizes' prefix) splits the work.
  // On one thread, while the other waited, it took 1.5 M cycles per rebuild at nu = 0.82,
  // N = 9261 (docs/performance.md "Two threads on one list").
  const int team = blocks_team();
  first_slot_of_.resize(static_cast<std::size_t>(team) * n);
#pragma omp parallel num_threads(team) if (team > 1)
  {
    const std::size_t t = static_cast<std::size_t>(omp_get_thread_num());
    const std::size_t T = static_cast<std::size_t>(omp_get_num_threads());
    const auto [b0, b1] = blocks_of(t, T);
    std::int32_t* first_slot_of = first_slot_of_.data() + t * n;
    const auto key = [&](std::int64_t e) {
      return 27 * static_cast<std::int64_t>(list_.index[e]) + list_.shift_code[e];
    };
    const auto inside = [&](std::int64_t e, std::size_t lo, std::size_t hi) {
      const std::size_t j = static_cast<std::size_t>(list_.index[e]);
      return j >= lo && j < hi && list_.shift_code[e] == kNoShift;
    };
    for (std::size_t b = b0; b < b1; ++b) {
      const std::size_t lo = block_lo_[b], hi = block_lo_[b + 1];
      auto& keys = block_keys_[b];  // 27 j + code
      keys.clear();
      for (std::int64_t e = list_.offset[lo]; e < list_.offset[hi]; ++e)
        if (!inside(e, lo, hi)) keys.push_back(key(e));
      std::sort(keys.begin(), keys.end());
      keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    }
#pragma omp barrier
#pragma omp single
    {
      for (std::size_t b = 0; b < blocks; ++b)
        slot_lo_[b + 1] = slot_lo_[b] + block_keys_[b].size();
      slot_particle_.resize(slot_lo_[blocks]);
      slot_code_.resize(slot_lo_[blocks]);
    }
    for (std::size_t b = b0; b < b1; ++b) {
      const std::size_t lo = block_lo_[b], hi = block_lo_[b + 1], first = slot_lo_[b];
      const auto& keys = block_keys_[b];
      for (std::size_t k = 0; k < keys.size(); ++k) {
        slot_particle_[first + k] = static_cast<std::int32_t>(keys[k] / 27);
        slot_code_[first + k] = static_cast<std::uint8_t>(keys[k] % 27);
      }
      // An entry's slot by the first slot of its partner (a particle has a slot per image, and
      // those of one particle are adjacent): a binary search per entry took half of this
      // function's time, on branches no predictor can learn.
      for (std::size_t k = keys.size(); k-- > 0;)
        first_slot_of[static_cast<std::size_t>(keys[k] / 27)] = static_cast<std::int32_t>(k);
      for (std::int64_t e = list_.offset[lo]; e < list_.offset[hi]; ++e) {
        if (inside(e, lo, hi)) {
          partner_[e] = list_.index[e];
          continue;
        }
        std::size_t k = static_cast<std::size_t>(first_slot_of[list_.index[e]]);
        while (keys[k] != key(e)) ++k;
        partner_[e] = static_cast<std::int32_t>(n + first + k);
      }
    }
  }
  reset_contacts_first();
  const std::size_t rows = n + slot_particle_.size();
  if (pos4_.size() < 4 * rows) pos4_.resize(4 * rows, 0.0);
  if (va8_.size() < 8 * rows) va8_.resize(8 * rows, 0.0);
  if (friction_) {
    if (rot16_.size() < 16 * rows) rot16_.resize(16 * rows, 0.0);
    block_dissipation_.assign(blocks, 0.0);
    if (hist_.size() != 3 * list_.index.size()) hist_.assign(3 * list_.index.size(), 0.0);
    if (rolling_ && hist_r_.size() != 3 * list_.index.size())
      hist_r_.assign(3 * list_.index.size(), 0.0);
  }
  blocks_builds_ = list_.builds();
}

int DemSystem::choose_team(bool* adaptive) {
  // Inside a parallel region (e.g. one probe per thread) a step runs on its caller's thread.
  const int threads = omp_in_parallel() ? 1 : omp_get_max_threads();
  const int most = max_team(p_.size(), fixed_team_ > 0 ? std::min(fixed_team_, threads) : threads);
  *adaptive = fixed_team_ == 0 && most > 1;
  return *adaptive ? controller_.choose(most) : most;
}

// force_block with friction (contact.hpp, TangentialContact; docs/physics.md section 1b). The
// same records and order, plus rot16_ (mid-step velocity, mid-step and predicted angular
// velocity, torque accumulator) and the history of each entry, which only this entry's row
// touches: the result does not depend on the team either. The contact point lies at a_i =
// r_i - delta / 2 from i's centre (a_i + a_j = |l|), for the torques and for the relative
// velocity alike, so that the torques do the work the tangential springs store.
//
// A contact's law costs ~150 flops, two square roots and three divisions, the frictionless
// one ~20: written per entry, the loop was bound by its scalar instruction count (3-4x the
// frictionless step, docs/performance.md "Friction"). So it runs in three passes over chunks
// of up to FrictionLanes::kLanes touching entries: (1) per row, the touching test and a copy
// of each touching entry's inputs into 4-double records; (2) the law across the chunk, four
// contacts at a time in the lanes of a V4, eight in those of a V8 with AVX-512 (the records of
// the lanes' entries transposed into one vector per component, the outputs transposed back),
// without branches (GCC does not vectorise a loop with std::sqrt, which may set errno);
// (3) the sums in the list's order, exactly as a per-entry loop would add them (the row's own
// sum kept across chunks, the partners' shares added at once), so that the result is still a
// function of the list alone.
namespace {
// kRolling adds the rolling spring (input and output, in place) and the rolling torque on i.
template <bool kRolling>
struct FrictionLanes {
  static constexpr std::size_t kLanes = 64;
  // Input records of an entry (x, y, z, fourth lane): the branch vector l (|l|^2), the relative
  // velocity at the step's end (r_i) and at mid-step (r_j), both with the affine part D l; the
  // stored spring xi (and the rolling one). The angular velocities pass (2) reads from rot16_
  // itself (the records of row and partner, still in the cache). Whole records rather than
  // one array per component: pass (1) writes a record with one vector store instead of three
  // scalar ones (each after an extraction from the vector), and the transposition in pass (2)
  // is ~3 instructions per record.
  enum In { kL, kVe, kVm, kXi, kIn, kXr = kIn, kRollingIn };
  // Outputs: the pair force f on i (a_i), n x f_t, the torques' direction (a_j), the spring
  // (the slip work); the rolling spring and the rolling torque on i.
  enum Out { kF, kNxf, kXiWork, kOut, kXrOut = kOut, kQ, kRollingOut };
  alignas(64) double in[kLanes][kRolling ? kRollingIn : kIn][4];
  alignas(64) double out[kLanes][kRolling ? kRollingOut : kOut][4];
  std::int64_t entry[kLanes];
  std::int32_t row[kLanes], partner[kLanes];
};

// Four consecutive doubles of a particle array (std::vector, 8-byte aligned).
typedef double V4u __attribute__((vector_size(32), aligned(8)));
inline V4 loadu4(const double* p) { return *reinterpret_cast<const V4u*>(p); }
inline void storeu4(double* p, V4 v) { *reinterpret_cast<V4u*>(p) = v; }

// Lanes 0-2 of a, lane 3 of b (one blend).
inline V4 fourth_of(V4 a, V4 b) { return __builtin_shuffle(a, b, Mask4{0, 1, 2, 7}); }
// The three doubles at p, the fourth lane 0: one masked load, which reads nothing past p[2].
inline V4 load3(const double* p) {
#if defined(__AVX__)
  return _mm256_maskload_pd(p, _mm256_set_epi64x(0, -1, -1, -1));
#else
  return V4{p[0], p[1], p[2], 0.0};
#endif
}
// Whether any bit of v is set (a spring of -0.0 counts, as a stored spring).
inline bool any_bits(V4 v) {
#if defined(__AVX__)
  const __m256i b = _mm256_castpd_si256(v);
  return !_mm256_testz_si256(b, b);
#else
  std::uint64_t bits[4];
  std::memcpy(bits, &v, sizeof bits);
  return (bits[0] | bits[1] | bits[2] | bits[3]) != 0;
#endif
}

// The lanes of the law (pass (2)): how many contacts at once, their square root, whether every
// lane of a mask is set, and the transpositions between the contacts' records and one vector
// per component.
template <class V>
struct Lanes;
template <>
struct Lanes<V4> {
  static constexpr std::size_t kN = 4;
  static V4 sqrt(V4 x) {
#if defined(__AVX__)
    return __builtin_ia32_sqrtpd256(x);
#else
    return V4{std::sqrt(x[0]), std::sqrt(x[1]), std::sqrt(x[2]), std::sqrt(x[3])};
#endif
  }
  template <class Mask>
  static bool all(Mask c) {
    return (c[0] & c[1] & c[2] & c[3]) != 0;
  }
  static std::array<V4, 4> gather(const double* const* p) {
    return components(p[0], p[1], p[2], p[3]);
  }
  static void scatter(V4 x, V4 y, V4 z, V4 w, double* const* p) {
    records(x, y, z, w, p[0], p[1], p[2], p[3]);
  }
  static V4 loadu(const double* p) { return loadu4(p); }
  static void storeu(double* p, V4 v) { storeu4(p, v); }
  template <class Mask>
  static bool any(Mask c) {
    return any_bits(reinterpret_cast<V4>(c));
  }
};
#if defined(__AVX512F__) && defined(__AVX512DQ__)
// With AVX-512, eight contacts at once (one zmm register per value). On four lanes the law
// waited on each quadruple's chain (square root, division, the turn's division); a Zen 4
// core takes a zmm operation in two passes through its 256-bit units, so the operations cost
// the same, but the out-of-order window now covers twice as many contacts' chains: the
// frictional step 3-10 % shorter (docs/performance.md "The law on eight lanes"). Without
// AVX-512, GCC passes 64-byte vectors through memory and the step took twice as long: four
// lanes there.
typedef double V8 __attribute__((vector_size(64)));
template <>
struct Lanes<V8> {
  static constexpr std::size_t kN = 8;
  static V8 sqrt(V8 x) {
    return reinterpret_cast<V8>(_mm512_sqrt_pd(reinterpret_cast<__m512d>(x)));
  }
  template <class Mask>
  static bool all(Mask c) {
    return _mm512_movepi64_mask(reinterpret_cast<__m512i>(c)) == 0xFF;
  }
  // The halves (x, y or z, fourth lane) of records first, first + 2, +4, +6 in the four
  // 128-bit lanes of one vector; then one in-lane interleave per component, as components()
  // does for four records.
  static __m512d halves(const double* const* p, int first, int at) {
    __m512d v = _mm512_castpd128_pd512(_mm_load_pd(p[first] + at));
    v = _mm512_insertf64x2(v, _mm_load_pd(p[first + 2] + at), 1);
    v = _mm512_insertf64x2(v, _mm_load_pd(p[first + 4] + at), 2);
    return _mm512_insertf64x2(v, _mm_load_pd(p[first + 6] + at), 3);
  }
  static std::array<V8, 4> gather(const double* const* p) {
    const __m512d e0 = halves(p, 0, 0), o0 = halves(p, 1, 0), e1 = halves(p, 0, 2),
                  o1 = halves(p, 1, 2);
    // The interleaves as shuffles (vunpck{l,h}pd): GCC 12's intrinsics for them warn of their own
    // undefined operand (-Wuninitialized) where they are inlined into the kick.
    using M8 = long long __attribute__((vector_size(64)));
    const auto lo = [](__m512d x, __m512d y) {
      return __builtin_shuffle(V8(x), V8(y), M8{0, 8, 2, 10, 4, 12, 6, 14});
    };
    const auto hi = [](__m512d x, __m512d y) {
      return __builtin_shuffle(V8(x), V8(y), M8{1, 9, 3, 11, 5, 13, 7, 15});
    };
    return {lo(e0, o0), hi(e0, o0), lo(e1, o1), hi(e1, o1)};
  }
  static void store_halves(__m512d v, double* const* p, int first, int at) {
    _mm_store_pd(p[first] + at, _mm512_castpd512_pd128(v));
    _mm_store_pd(p[first + 2] + at, _mm512_extractf64x2_pd(v, 1));
    _mm_store_pd(p[first + 4] + at, _mm512_extractf64x2_pd(v, 2));
    _mm_store_pd(p[first + 6] + at, _mm512_extractf64x2_pd(v, 3));
  }
  static void scatter(V8 x, V8 y, V8 z, V8 w, double* const* p) {
    const auto v = [](V8 a) { return reinterpret_cast<__m512d>(a); };
    store_halves(_mm512_unpacklo_pd(v(x), v(y)), p, 0, 0);
    store_halves(_mm512_unpackhi_pd(v(x), v(y)), p, 1, 0);
    store_halves(_mm512_unpacklo_pd(v(z), v(w)), p, 0, 2);
    store_halves(_mm512_unpackhi_pd(v(z), v(w)), p, 1, 2);
  }
};
using LawLanes = V8;
#else
using LawLanes = V4;
#endif

// TangentialContact's arithmetic on several contacts at once (contact.hpp, ScalarMath): a
// value is a vector of lanes, a condition a mask of lanes, and select a blend.
template <class V>
struct LaneMath {
  static V lanes(V a) { return a; }
  static V lanes(double a) { return a - V{}; }  // a broadcast (a - 0 is a, even -0)
  static V sqrt(V x) { return Lanes<V>::sqrt(x); }
  static V abs(V x) { return x < 0.0 ? -x : x; }
  template <class Mask, class A, class B>
  static V select(Mask c, A a, B b) {
    return c ? lanes(a) : lanes(b);
  }
  // The rare value only if some lane needs it (ScalarMath::unless): one branch per four (or
  // eight) contacts, rarely taken, instead of the value for all of them every time; then for
  // all lanes at once (a: lanes, or one value for all). Lane by lane instead (a branch per
  // lane, scalar divisions and square roots in series), the frictional step was 2 % slower;
  // in the benchmark's states one quadruple in nine has a sliding lane (docs/performance.md
  // "Friction").
  template <class Mask, class A, class F>
  static V unless(Mask c, A a, F rare, V x, V y) {
    if (!Lanes<V>::all(c)) [[unlikely]]
      return select(c, a, rare(x, y));
    return lanes(a);
  }
};

// Pass (2): the contact law of the chunk, Lanes<V>::kN contacts at a time; the lanes past
// `count` compute on stale inputs and are never read. Each lane is the scalar arithmetic of
// one contact, so four lanes or eight give the same bits.
// With kRolling, the rolling resistance too (docs/physics.md section 1b): the rolling velocity
// v_r = -a' n x (w_i - w_j), a' = a_i a_j / (a_i + a_j), goes through the tangential law with
// the rolling constants; its force f_r is no force but the torque a' n x f_r on i (-that on j).
template <bool kRolling, class V = LawLanes>
void friction_law(FrictionLanes<kRolling>& c, std::size_t count, const double* Q,
                  const NormalContact& law, const TangentialContact& tangential,
                  const TangentialContact& rolling, double dt) {
  using F = FrictionLanes<kRolling>;
  using A3 = std::array<V, 3>;
  using M = LaneMath<V>;
  constexpr std::size_t kN = Lanes<V>::kN;
  for (std::size_t k = 0; k < count; k += kN) {
    // The components of input record r of the lanes' entries.
    auto in = [&](int r) {
      const double* p[kN];
      for (std::size_t q = 0; q < kN; ++q) p[q] = c.in[k + q][r];
      return Lanes<V>::gather(p);
    };
    auto in3 = [&](int r) {
      const auto t = in(r);
      return A3{t[0], t[1], t[2]};
    };
    auto out = [&](int r, V x, V y, V z, V w) {
      double* p[kN];
      for (std::size_t q = 0; q < kN; ++q) p[q] = c.out[k + q][r];
      Lanes<V>::scatter(x, y, z, w, p);
    };
    const auto lr = in(F::kL), ve_ri = in(F::kVe), vm_rj = in(F::kVm);
    const A3 l = {lr[0], lr[1], lr[2]};
    const V ri = ve_ri[3], rj = vm_rj[3];
    const V d = M::sqrt(lr[3]);
    const V inv = 1.0 / d;
    const V delta = (ri + rj) - d;
    const A3 n = {l[0] * inv, l[1] * inv, l[2] * inv};
    const A3 ve = {ve_ri[0], ve_ri[1], ve_ri[2]};
    const V f_n = law.k * delta - law.gamma * (l[0] * ve[0] + l[1] * ve[1] + l[2] * ve[2]) * inv;
    // Contact-point velocities: v_rel - (a_i w_i + a_j w_j) x n, tangential part.
    const V ai = ri - 0.5 * delta, aj = rj - 0.5 * delta;
    auto contact_point = [&](const A3& u, const A3& wi, const A3& wj) {
      const A3 w = {ai * wi[0] + aj * wj[0], ai * wi[1] + aj * wj[1], ai * wi[2] + aj * wj[2]};
      A3 p = {u[0] - (w[1] * n[2] - w[2] * n[1]), u[1] - (w[2] * n[0] - w[0] * n[2]),
              u[2] - (w[0] * n[1] - w[1] * n[0])};
      const V pn = p[0] * n[0] + p[1] * n[1] + p[2] * n[2];
      for (int a = 0; a < 3; ++a) p[a] -= pn * n[a];
      return p;
    };
    // Angular velocities from rot16_: at +4 mid-step, at +8 predicted.
    auto rot = [&](const std::int32_t* who, int at) {
      const double* p[kN];
      for (std::size_t q = 0; q < kN; ++q) p[q] = Q + 16 * who[k + q] + at;
      const auto t = Lanes<V>::gather(p);
      return A3{t[0], t[1], t[2]};
    };
    const A3 wei = rot(c.row, 8), wej = rot(c.partner, 8), wmi = rot(c.row, 4),
             wmj = rot(c.partner, 4);
    const A3 c_end = contact_point(ve, wei, wej);
    const A3 c_mid = contact_point(A3{vm_rj[0], vm_rj[1], vm_rj[2]}, wmi, wmj);
    // The spring turned with the contact: back into the tangent plane, its length kept.
    A3 x = in3(F::kXi);
    TangentialContact::turn<A3, M>(x, n);
    A3 ft;
    V work{};
    tangential.force<A3, V, M>(x, c_mid, c_end, dt, f_n, &work, ft);
    if constexpr (kRolling) {
      const V ar = ai * aj / (ai + aj);
      auto rolling_velocity = [&](const A3& wi, const A3& wj) {
        const A3 w = {wi[0] - wj[0], wi[1] - wj[1], wi[2] - wj[2]};
        return A3{-ar * (n[1] * w[2] - n[2] * w[1]), -ar * (n[2] * w[0] - n[0] * w[2]),
                  -ar * (n[0] * w[1] - n[1] * w[0])};
      };
      const A3 r_end = rolling_velocity(wei, wej);
      const A3 r_mid = rolling_velocity(wmi, wmj);
      A3 xr = in3(F::kXr);
      TangentialContact::turn<A3, M>(xr, n);
      A3 fr;
      rolling.force<A3, V, M>(xr, r_mid, r_end, dt, f_n, &work, fr);
      out(F::kXrOut, xr[0], xr[1], xr[2], V{});
      out(F::kQ, ar * (n[1] * fr[2] - n[2] * fr[1]), ar * (n[2] * fr[0] - n[0] * fr[2]),
          ar * (n[0] * fr[1] - n[1] * fr[0]), V{});
    }
    out(F::kF, f_n * n[0] + ft[0], f_n * n[1] + ft[1], f_n * n[2] + ft[2], ai);
    out(F::kNxf, n[1] * ft[2] - n[2] * ft[1], n[2] * ft[0] - n[0] * ft[2],
        n[0] * ft[1] - n[1] * ft[0], aj);
    out(F::kXiWork, x[0], x[1], x[2], work);
  }
}

// The opening half kick and the drift of particles [lo, hi) (dem_system.hpp, the step), the
// rows' records for the force loop, and the rebuild rule's two largest excesses e1 >= e2
// (neighbor_list.hpp), carried in and out. Four particles at a time in the lanes of a V4, each
// lane the scalar arithmetic of one particle (the same bits): as scalar code this pass was 12 %
// of a frictionless step (docs/performance.md "The kick and drift in lanes"). Not eight in a
// V8 as the law: the pass is mostly transpositions, which a Zen 4 core takes in two passes for
// a zmm vector, and eight lanes made the frictionless step 3 % longer (docs/performance.md
// "The kick and drift on four lanes again"). A function of its own, with its pointers and
// constants as locals: inside the step's parallel region GCC read them from the region's
// shared block at every particle.
struct KickDrift {
  double* v[3];  // velocities
  const double *im, *ref;
  double *W, *P;  // the velocity (then force) and position records
  double h, dt;
  double s[3], sref[3];  // the cell's stretch over the step, and since the list's reference
  double s_min;
};

// Particles [i, hi) four at a time while four are left (i advances), each lane the scalar
// arithmetic of one particle.
void kick_drift_lanes(const KickDrift& k, std::size_t& i_io, std::size_t hi, double& e1_io,
                      double& e2_io) {
  using V = V4;
  using L = Lanes<V>;
  constexpr std::size_t kN = L::kN;
  double* __restrict vx = k.v[0];
  double* __restrict vy = k.v[1];
  double* __restrict vz = k.v[2];
  const double* __restrict im = k.im;
  const double* __restrict ref = k.ref;
  double* __restrict W = k.W;
  double* __restrict P = k.P;
  const double h = k.h, dt = k.dt, sx = k.s[0], sy = k.s[1], sz = k.s[2], rx = k.sref[0],
               ry = k.sref[1], rz = k.sref[2], s_min = k.s_min;
  double e1 = e1_io, e2 = e2_io;
  std::size_t i = i_io;
  for (; i + kN <= hi; i += kN) {
    const V hm = h * L::loadu(im + i);
    // The force from its record (beside the velocity record written below), the position from
    // its own: the step reads and writes no other copy of either.
    double* w[kN];
    double* p[kN];
    const double* a4[kN];
    const double* r[kN];
    for (std::size_t q = 0; q < kN; ++q)
      w[q] = W + 8 * (i + q), a4[q] = w[q] + 4, p[q] = P + 4 * (i + q), r[q] = ref + 4 * (i + q);
    const auto f = L::gather(a4);
    const V vxi = L::loadu(vx + i) + hm * f[0], vyi = L::loadu(vy + i) + hm * f[1],
            vzi = L::loadu(vz + i) + hm * f[2];
    L::storeu(vx + i, vxi);
    L::storeu(vy + i, vyi);
    L::storeu(vz + i, vzi);
    // Predicted v(t+dt) = v(t) + dt a(t), second-order accurate, for the dissipative forces.
    // The records' fourth lanes: 0 for the velocity, the radius for the position.
    L::scatter(vxi + hm * f[0], vyi + hm * f[1], vzi + hm * f[2], V{}, w);
    const auto x = L::gather(p);
    const V xi = sx * (x[0] + dt * vxi), yi = sy * (x[1] + dt * vyi), zi = sz * (x[2] + dt * vzi);
    L::scatter(xi, yi, zi, x[3], p);
    const auto a = L::gather(r);
    const V ux = xi - rx * a[0], uy = yi - ry * a[1], uz = zi - rz * a[2];
    const V u2 = ux * ux + uy * uy + uz * uz, th = s_min * a[3];
    // keep_two_largest_excess's own test against the e2 before these lanes: e2 only grows over
    // them, so a lane skipped here would be skipped there too, and the others go through it in
    // order (the same e1 and e2).
    const V b = (e2 + th) - 1e-12 * (std::abs(e2) + th);
    const auto reach = ~((b > 0.0) & (u2 < (1.0 - 1e-12) * (b * b)));
    if (L::any(reach)) [[unlikely]]
      for (std::size_t q = 0; q < kN; ++q)
        if (reach[q]) keep_two_largest_excess(u2[q], th[q], e1, e2);
  }
  i_io = i;
  e1_io = e1, e2_io = e2;
}

void kick_drift(const KickDrift& k, std::size_t lo, std::size_t hi, double& e1_io, double& e2_io) {
  std::size_t i = lo;
  kick_drift_lanes(k, i, hi, e1_io, e2_io);
  // The last particles, fewer than four, one by one with the same arithmetic.
  double e1 = e1_io, e2 = e2_io;
  for (; i < hi; ++i) {
    double v[3], x[3];
    const double hm = k.h * k.im[i];
    const double* f = k.W + 8 * i + 4;
    for (int c = 0; c < 3; ++c) {
      v[c] = k.v[c][i] + hm * f[c];
      k.v[c][i] = v[c];
      k.W[8 * i + c] = v[c] + hm * f[c];
    }
    for (int c = 0; c < 3; ++c) {
      x[c] = k.s[c] * (k.P[4 * i + c] + k.dt * v[c]);
      k.P[4 * i + c] = x[c];
    }
    const double* a = k.ref + 4 * i;
    const double ux = x[0] - k.sref[0] * a[0], uy = x[1] - k.sref[1] * a[1],
                 uz = x[2] - k.sref[2] * a[2];
    keep_two_largest_excess(ux * ux + uy * uy + uz * uz, k.s_min * a[3], e1, e2);
  }
  e1_io = e1, e2_io = e2;
}

// Rows [lo, hi) finished from their accumulator records (a stride apart): out = the record's
// sum, minus gamma times the damping record (the velocity) with kDamped, and, if half_kick != 0,
// the closing half kick vel += half_kick inv out. Without out (nullptr) the result replaces the
// record's sum (lanes 0-2; the forces, which the step keeps there). Four rows at a time, their
// records transposed into one vector per component, each lane the scalar arithmetic of the rest
// below (the same bits; as scalar code the forces' finish was 7 % of a frictionless step).
struct FinishRows {
  double* record;
  std::size_t stride;
  const double* damping;
  double gamma;
  double* out[3];
  double* vel[3];
  const double* inv;
};

template <bool kDamped>
void finish_rows(const FinishRows& r, double half_kick, std::size_t lo, std::size_t hi) {
  double* __restrict R = r.record;
  const double* __restrict D = r.damping;
  const std::size_t m = r.stride;
  const double gamma = r.gamma;
  double* __restrict ox = r.out[0];
  double* __restrict oy = r.out[1];
  double* __restrict oz = r.out[2];
  const bool in_place = ox == nullptr;
  double* __restrict vx = r.vel[0];
  double* __restrict vy = r.vel[1];
  double* __restrict vz = r.vel[2];
  const double* __restrict inv = r.inv;
  std::size_t i = lo;
  for (; i + 4 <= hi; i += 4) {
    auto f = components(R + m * i, R + m * (i + 1), R + m * (i + 2), R + m * (i + 3));
    if constexpr (kDamped) {
      const auto w = components(D + m * i, D + m * (i + 1), D + m * (i + 2), D + m * (i + 3));
      for (int c = 0; c < 3; ++c) f[c] = f[c] - gamma * w[c];
    }
    if (in_place) {
      records(f[0], f[1], f[2], f[3], R + m * i, R + m * (i + 1), R + m * (i + 2), R + m * (i + 3));
    } else {
      storeu4(ox + i, f[0]);
      storeu4(oy + i, f[1]);
      storeu4(oz + i, f[2]);
    }
    if (half_kick != 0) {
      const V4 h = half_kick * loadu4(inv + i);
      storeu4(vx + i, loadu4(vx + i) + h * f[0]);
      storeu4(vy + i, loadu4(vy + i) + h * f[1]);
      storeu4(vz + i, loadu4(vz + i) + h * f[2]);
    }
  }
  for (; i < hi; ++i) {
    V4 f = load4(R + m * i);
    if constexpr (kDamped) f = f - gamma * load4(D + m * i);
    if (in_place)
      store4(R + m * i, f);
    else
      ox[i] = f[0], oy[i] = f[1], oz[i] = f[2];
    if (half_kick != 0) {
      const double h = half_kick * inv[i];
      vx[i] += h * f[0];
      vy[i] += h * f[1];
      vz[i] += h * f[2];
    }
  }
}
}  // namespace

template <bool kStress, bool kRolling>
void DemSystem::force_block_friction(std::size_t b, bool handed) {
  using F = FrictionLanes<kRolling>;
  const std::size_t n = p_.size();
  const Eigen::Vector3d L = cell_.lengths();
  V4 shift[27];
  image_shifts(L, shift);
  const NormalContact law = options_.material.contact();
  const TangentialContact tangential = options_.material.tangential();
  const TangentialContact rolling = options_.material.rolling_contact();
  const bool advance = advancing_;
  const double dt = advance ? dt_ : 0.0;
  const V4 D = {last_D_[0], last_D_[1], last_D_[2], 0.0};
  double* __restrict P = pos4_.data();
  double* __restrict W = va8_.data();
  double* __restrict A = va8_.data() + 4;
  double* __restrict Q = rot16_.data();
  double* __restrict H = hist_.data();
  double* __restrict HR = hist_r_.data();
  const std::int64_t* __restrict off = list_.offset.data();
  const std::int32_t* __restrict idx = partner_.data();
  double* __restrict sd = stress_scratch_.data();
  const std::size_t lo = block_lo_[b], hi = block_lo_[b + 1];
  // The rows' force and torque accumulators were cleared by pack_rotations.
  if constexpr (kStress)
    for (std::size_t i = lo; i < hi; ++i) sd[3 * i] = sd[3 * i + 1] = sd[3 * i + 2] = 0.0;
  const double* __restrict X = slot_in_.data();
  for (std::size_t s = slot_lo_[b]; s < slot_lo_[b + 1]; ++s) {
    const std::size_t r = n + s, j = static_cast<std::size_t>(slot_particle_[s]);
    if (handed && slot_handed_[s]) {
      const double* x = X + 24 * s;
      store4(P + 4 * r, load4(x) - shift[slot_code_[s]]);
      store4(W + 8 * r, load4(x + 4));
      for (int q = 0; q < 12; q += 4) store4(Q + 16 * r + q, load4(x + 8 + q));
    } else {
      store4(P + 4 * r, load4(P + 4 * j) - shift[slot_code_[s]]);
      store4(W + 8 * r, load4(W + 8 * j));
      for (int q = 0; q < 12; q += 4) store4(Q + 16 * r + q, load4(Q + 16 * j + q));
    }
    store4(A + 8 * r, V4{});
    store4(Q + 16 * r + 12, V4{});
  }
  F lanes{};
  std::size_t count = 0;
  double dissipated = 0;
  // Pass (3)'s running sums of the current row, kept across chunks (a row may span two).
  std::size_t row = n;
  V4 fi = {}, ti = {}, si = {};
  auto finish_row = [&] {
    if (row == n) return;
    store4(A + 8 * row, load4(A + 8 * row) + fi);
    store4(Q + 16 * row + 12, load4(Q + 16 * row + 12) + ti);
    if constexpr (kStress) {
      sd[3 * row] = si[0];
      sd[3 * row + 1] = si[1];
      sd[3 * row + 2] = si[2];
    }
    fi = ti = si = V4{};
  };
  auto run_chunk = [&] {
    friction_law<kRolling>(lanes, count, Q, law, tangential, rolling, dt);
    for (std::size_t k = 0; k < count; ++k) {
      const std::size_t i = static_cast<std::size_t>(lanes.row[k]);
      if (i != row) {
        finish_row();
        row = i;
      }
      const std::size_t j = static_cast<std::size_t>(lanes.partner[k]);
      // The fourth lanes carry a_i and a_j: cleared, so that the sums' fourth lanes stay 0.
      V4 f = load4(lanes.out[k][F::kF]), nxf = load4(lanes.out[k][F::kNxf]);
      const double ai = f[3], aj = nxf[3];
      f[3] = nxf[3] = 0.0;
      fi += f;
      store4(A + 8 * j, load4(A + 8 * j) - f);
      ti -= ai * nxf;
      store4(Q + 16 * j + 12, load4(Q + 16 * j + 12) - aj * nxf);
      if constexpr (kStress) {
        V4 l = load4(lanes.in[k][F::kL]);
        l[3] = 0.0;
        si += l * f;
      }
      if constexpr (kRolling) {
        const V4 q = load4(lanes.out[k][F::kQ]);
        ti += q;
        store4(Q + 16 * j + 12, load4(Q + 16 * j + 12) - q);
      }
      if (advance) {
        const double* o = lanes.out[k][F::kXiWork];
        double* xi = H + 3 * lanes.entry[k];
        xi[0] = o[0], xi[1] = o[1], xi[2] = o[2];
        if constexpr (kRolling) {
          const double* orr = lanes.out[k][F::kXrOut];
          double* xr = HR + 3 * lanes.entry[k];
          xr[0] = orr[0], xr[1] = orr[1], xr[2] = orr[2];
        }
        dissipated += o[3];
      }
    }
    count = 0;
  };
  // Pass (1). A row's entries that did not touch when the row was last ordered are skipped
  // after one test (below). The others' records are written to the next free place and only a
  // touching one advances it: no branch on the touching test, which a loop over 2.6 touching
  // entries of 4.4 (nu = 0.64) would mispredict at every third entry. Each record is one vector (a
  // blend supplies its fourth lane; the radii come with the position records) and the spring one
  // masked load, tested for any bit with one instruction: ~55 instructions per entry where GCC's
  // code for the per-component form was ~75 (docs/performance.md "Issue #17, pass (1) without
  // prefetches"). No software prefetch of the partners' records: on this loop they cost more than
  // they saved.
  const bool listed = compact_;
  std::int32_t* __restrict order = entry_first_.data();
  std::int64_t* __restrict split_of = first_end_.data();
  for (std::size_t i = lo; i < hi; ++i) {
    const V4 pi = load4(P + 4 * i), vi = load4(W + 8 * i);
    const V4 vmi = load4(Q + 16 * i);
    const double ri = pi[3];
    const std::int32_t row = static_cast<std::int32_t>(i);
    const std::int64_t begin = off[i], end = off[i + 1], split = split_of[i];
    // Entry e's pair: partner record, branch vector (fourth lane r_i - r_j, which D, 0 there,
    // and the blends drop), |l|^2 with the FMAs GCC had made of l0 l0 + l1 l1 + l2 l2 before
    // (the same bits), and whether it touches.
    struct Pair {
      V4 pj, l;
      double r2;
      bool touching;
    };
    const auto pair = [&](std::int64_t e) {
      const V4 pj = load4(P + 4 * static_cast<std::size_t>(idx[e]));
      const V4 l = pi - pj;
      const double r2 = std::fma(l[2], l[2], std::fma(l[0], l[0], l[1] * l[1]));
      return Pair{pj, l, r2, r2 < (ri + pj[3]) * (ri + pj[3])};
    };
    const auto touches = [&](std::int64_t e) { return pair(e).touching; };
    // Entry e's records; whether it touches.
    const auto gather = [&](std::int64_t e) {
      const std::int32_t partner = idx[e];
      const std::size_t j = static_cast<std::size_t>(partner);
      const auto [pj, l, r2, touching] = pair(e);
      double(*rec)[4] = lanes.in[count];
      store4(rec[F::kL], fourth_of(l, V4{r2, r2, r2, r2}));
      store4(rec[F::kVe], fourth_of(vi - load4(W + 8 * j) + D * l, pi));
      store4(rec[F::kVm], fourth_of(vmi - load4(Q + 16 * j) + D * l, pj));
      double* xi = H + 3 * e;
      const V4 spring = load3(xi);
      store4(rec[F::kXi], spring);
      bool any = any_bits(spring);
      if constexpr (kRolling) {
        const V4 xr = load3(HR + 3 * e);
        store4(rec[F::kXr], xr);
        any |= any_bits(xr);
      }
      lanes.entry[count] = e;
      lanes.row[count] = row;
      lanes.partner[count] = partner;
      // Contact lost: so is its history (stored only if there was one: most entries of the
      // list never touch). A rare branch, well predicted. Apart, the Coulomb limit is zero, so
      // the springs slide back to nothing: what they held is the slip's work (left out, it was
      // 5 % of the slip's work at mu = 10, where a spring can still be long when f_n vanishes).
      if (advance & !touching & any) {
        dissipated += tangential.energy(spring[0] * spring[0] + spring[1] * spring[1] +
                                        spring[2] * spring[2]);
        xi[0] = xi[1] = xi[2] = 0.0;
        if constexpr (kRolling) {
          const double* xr = HR + 3 * e;
          dissipated += rolling.energy(xr[0] * xr[0] + xr[1] * xr[1] + xr[2] * xr[2]);
          HR[3 * e] = HR[3 * e + 1] = HR[3 * e + 2] = 0.0;
        }
      }
      count += touching;
      if (count == F::kLanes) run_chunk();
      return touching;
    };
    // The row's contacts first (entry_first_, ordered at advancing steps only): an entry of the
    // second part did not touch then, so its history was cleared in that step, and while it
    // does not touch, gather would write nothing that counts: one test skips it. If one
    // touches (late), the row goes through the list's order; a row with a late or a lost
    // (stale) contact is ordered again. The records are the touching entries in the list's
    // order either way: the same sums, the same bits.
    // The compact form (set_fixed_loop(2), tests): every row in the list's order, unordered.
    bool late = listed;
    if (!listed)
      for (std::int64_t k = split; k < end; ++k) late |= touches(order[k]);
    bool stale = false;
    if (!late) [[likely]] {
      for (std::int64_t k = begin; k < split; ++k) stale |= !gather(order[k]);
    } else {
      for (std::int64_t e = begin; e < end; ++e) gather(e);
    }
    if ((late | stale) & advance & !listed) [[unlikely]]
      split_of[i] = contacts_first(
          order, begin, end, [](std::int64_t e) { return static_cast<std::int32_t>(e); }, touches);
  }
  run_chunk();
  finish_row();
  if (advance) block_dissipation_[b] = dissipated;
}

void DemSystem::pack_rotations(std::size_t lo, std::size_t hi, double half_kick,
                               bool opening_kick) {
  // Mid-step velocities, and angular ones: mid-step, then predicted at the step's end as the
  // translational ones are (w + dt/2 tau / I). With opening_kick, the rotations' opening half
  // kick first, in the same pass: as a pass of its own it read w, tau and 1 / I once more. The
  // torque accumulator, in the same cache line as the predicted angular velocity, and the
  // force accumulator, beside the velocity the kick has just written, are cleared here for
  // force_block_friction: there, as a pass of their own, the two stores per row cost 7 % of
  // the step (each line fetched again).
  double* __restrict Q = rot16_.data();
  double* __restrict A = va8_.data() + 4;
  double* __restrict wx = p_.wx.data();
  double* __restrict wy = p_.wy.data();
  double* __restrict wz = p_.wz.data();
  const double* __restrict tx = p_.tx.data();
  const double* __restrict ty = p_.ty.data();
  const double* __restrict tz = p_.tz.data();
  const double* __restrict vx = p_.vx.data();
  const double* __restrict vy = p_.vy.data();
  const double* __restrict vz = p_.vz.data();
  const double* __restrict ii = inv_inertia_.data();
  // Four rows at a time, the records written from one vector per component (the same
  // arithmetic per lane as the scalar rest below; their fourth lanes 0, which no reader uses).
  std::size_t i = lo;
  for (; i + 4 <= hi; i += 4) {
    const V4 hi_ = half_kick * loadu4(ii + i);
    const V4 txi = loadu4(tx + i), tyi = loadu4(ty + i), tzi = loadu4(tz + i);
    V4 wxi = loadu4(wx + i), wyi = loadu4(wy + i), wzi = loadu4(wz + i);
    if (opening_kick) {
      wxi += hi_ * txi;
      wyi += hi_ * tyi;
      wzi += hi_ * tzi;
      storeu4(wx + i, wxi);
      storeu4(wy + i, wyi);
      storeu4(wz + i, wzi);
    }
    double* q = Q + 16 * i;
    for (int k = 0; k < 4; ++k) {
      store4(A + 8 * (i + k), V4{});
      store4(q + 16 * k + 12, V4{});
    }
    records(loadu4(vx + i), loadu4(vy + i), loadu4(vz + i), V4{}, q, q + 16, q + 32, q + 48);
    records(wxi, wyi, wzi, V4{}, q + 4, q + 20, q + 36, q + 52);
    records(wxi + hi_ * txi, wyi + hi_ * tyi, wzi + hi_ * tzi, V4{}, q + 8, q + 24, q + 40, q + 56);
  }
  for (; i < hi; ++i) {
    const double hi_ = half_kick * ii[i];
    if (opening_kick) {
      wx[i] += hi_ * tx[i];
      wy[i] += hi_ * ty[i];
      wz[i] += hi_ * tz[i];
    }
    double* q = Q + 16 * i;
    store4(A + 8 * i, V4{});
    store4(q + 12, V4{});
    q[0] = vx[i], q[1] = vy[i], q[2] = vz[i];
    q[4] = wx[i], q[5] = wy[i], q[6] = wz[i];
    q[8] = wx[i] + hi_ * tx[i];
    q[9] = wy[i] + hi_ * ty[i];
    q[10] = wz[i] + hi_ * tz[i];
  }
}

// Thread t of T: the pair forces of its contiguous run of blocks, then, after one barrier, its
// rows finished: to each row's own accumulator it adds the foreign slots that hold a share of
// it, block by block (the same order for any team), then the background damping, and, if
// half_kick != 0, the closing half kick of the step. Half list: each pair once, its force added
// to i and subtracted from j (momentum conserved to round-off).
template <bool kStress>
void DemSystem::forces_of_thread(std::size_t t, std::size_t T, double half_kick) {
  const std::size_t n = p_.size();
  const std::size_t blocks = block_lo_.size() - 1;
  const auto [b0, b1] = blocks_of(t, T);
  using Clock = std::chrono::steady_clock;
  const bool clocked = phase_timing_;
  const auto c0 = clocked ? Clock::now() : Clock::time_point{};
  const bool handed = hands_off(T);
  if (rolling_)
    for (std::size_t b = b0; b < b1; ++b) force_block_friction<kStress, true>(b, handed);
  else if (friction_)
    for (std::size_t b = b0; b < b1; ++b) force_block_friction<kStress, false>(b, handed);
  else if (compact_)
    for (std::size_t b = b0; b < b1; ++b) force_block<kStress, true>(b, handed);
  else
    for (std::size_t b = b0; b < b1; ++b) force_block<kStress, false>(b, handed);
  if (handed) hand_out(t);
  const auto c1 = clocked ? Clock::now() : c0;
  if (T > 1) barrier_.arrive_and_wait(T);
  const auto c2 = clocked ? Clock::now() : c0;
  const double gamma_b = options_.material.gamma_b;
  const double* __restrict W = va8_.data();
  double* __restrict A = va8_.data() + 4;
  const std::int32_t* __restrict sp = slot_particle_.data();
  const std::size_t lo = block_lo_[b0], hi = block_lo_[b1];
  for (std::size_t c = 0; c < blocks; ++c) {
    // The slots of block c are sorted by particle: those of rows [lo, hi) form one run.
    const std::int32_t* first = sp + slot_lo_[c];
    const std::int32_t* last = sp + slot_lo_[c + 1];
    first = std::lower_bound(first, last, static_cast<std::int32_t>(lo));
    // Another thread's block returned its shares of these rows through slot_out_.
    const bool out = handed && (c < b0 || c >= b1);
    const double* __restrict S = out ? slot_out_.data() : A + 8 * n;
    const std::size_t so = out ? share_stride() : 8;
    for (const std::int32_t* q = first; q != last && static_cast<std::size_t>(*q) < hi; ++q) {
      double* a = A + 8 * static_cast<std::size_t>(*q);
      store4(a, load4(a) + load4(S + so * static_cast<std::size_t>(q - sp)));
    }
    if (friction_) {
      double* Q = rot16_.data() + 12;
      for (const std::int32_t* q = first; q != last && static_cast<std::size_t>(*q) < hi; ++q) {
        double* a = Q + 16 * static_cast<std::size_t>(*q);
        const auto u = static_cast<std::size_t>(q - sp);
        store4(a, load4(a) + load4(out ? slot_out_.data() + so * u + 4 : Q + 16 * (n + u)));
      }
    }
  }
  // The torques, without background damping, and the rotations' closing half kick; the forces
  // with it, and the translations' closing half kick.
  if (friction_)
    finish_rows<false>(FinishRows{rot16_.data() + 12,
                                  16,
                                  nullptr,
                                  0.0,
                                  {p_.tx.data(), p_.ty.data(), p_.tz.data()},
                                  {p_.wx.data(), p_.wy.data(), p_.wz.data()},
                                  inv_inertia_.data()},
                       half_kick, lo, hi);
  finish_rows<true>(FinishRows{A,
                               8,
                               W,
                               gamma_b,
                               {nullptr, nullptr, nullptr},
                               {p_.vx.data(), p_.vy.data(), p_.vz.data()},
                               p_.inv_mass.data()},
                    half_kick, lo, hi);
  if (clocked) {
    Phases& ph = phase_clocks_[t].p;
    ph.forces += std::chrono::duration<double>(c1 - c0).count();
    ph.wait_forces += std::chrono::duration<double>(c2 - c1).count();
    ph.finish += std::chrono::duration<double>(Clock::now() - c2).count();
  }
}

// Which slots cross between the threads of a team of `team` (dem_system.hpp, the hand-offs):
// a slot of block c whose particle lies in another thread's rows. Recomputed when the blocks or
// the team change; a thread then fills and returns its own lists, no line written by two.
void DemSystem::prepare_handoffs(int team) {
  const int T = team;
  if (handoff_team_ == T && handoff_builds_ == blocks_builds_) return;
  handoff_team_ = T;
  handoff_builds_ = blocks_builds_;
  const std::size_t blocks = block_lo_.size() - 1, S = slot_particle_.size();
  const std::size_t U = static_cast<std::size_t>(T);
  slot_handed_.assign(S, 0);
  fills_.assign(U, {});
  returns_.assign(U, {});
  if (T < 2) return;
  std::vector<std::size_t> thread_of(blocks);
  for (std::size_t t = 0; t < U; ++t)
    for (auto [c, c1] = blocks_of(t, U); c < c1; ++c) thread_of[c] = t;
  for (std::size_t c = 0; c < blocks; ++c)
    for (std::size_t s = slot_lo_[c]; s < slot_lo_[c + 1]; ++s) {
      const auto j = static_cast<std::size_t>(slot_particle_[s]);
      const std::size_t cj = static_cast<std::size_t>(
          std::upper_bound(block_lo_.begin(), block_lo_.end(), j) - block_lo_.begin() - 1);
      if (thread_of[cj] == thread_of[c]) continue;
      slot_handed_[s] = 1;
      fills_[thread_of[cj]].push_back(static_cast<std::int32_t>(s));
      returns_[thread_of[c]].push_back(static_cast<std::int32_t>(s));
    }
  if (slot_in_.size() < 24 * S) slot_in_.resize(24 * S, 0.0);
  if (slot_out_.size() < 8 * S) slot_out_.resize(8 * S, 0.0);
}

bool DemSystem::hands_off(std::size_t T) const {
  return T > 1 && T == static_cast<std::size_t>(handoff_team_);
}

void DemSystem::hand_in(std::size_t t) {
  const double* __restrict P = pos4_.data();
  const double* __restrict W = va8_.data();
  double* __restrict X = slot_in_.data();
  if (!friction_) {
    for (const std::int32_t s : fills_[t]) {
      const auto j = static_cast<std::size_t>(slot_particle_[static_cast<std::size_t>(s)]);
      stream_line(X + 8 * static_cast<std::size_t>(s), load4(P + 4 * j), load4(W + 8 * j));
    }
  } else {
    // Three lines: position and velocity; the mid-step velocity and angular velocity; the
    // predicted angular velocity (rot16_'s first twelve doubles).
    const double* __restrict Q = rot16_.data();
    for (const std::int32_t s : fills_[t]) {
      const auto j = static_cast<std::size_t>(slot_particle_[static_cast<std::size_t>(s)]);
      double* x = X + 24 * static_cast<std::size_t>(s);
      stream_line(x, load4(P + 4 * j), load4(W + 8 * j));
      stream_line(x + 8, load4(Q + 16 * j), load4(Q + 16 * j + 4));
      stream_line(x + 16, load4(Q + 16 * j + 8), V4{});
    }
  }
  stream_fence();
}

void DemSystem::hand_out(std::size_t t) {
  const std::size_t n = p_.size();
  const double* __restrict A = va8_.data() + 4;
  double* __restrict Y = slot_out_.data();
  // The force share, and with friction the torque share (rot16_ at +12) in the same line;
  // without friction two slots' force shares a line (dem_system.hpp, slot_out_).
  const double* __restrict Q = friction_ ? rot16_.data() + 12 : nullptr;
  const std::size_t so = share_stride();
  for (const std::int32_t s : returns_[t]) {
    const auto u = static_cast<std::size_t>(s);
    stream_half_line(Y + so * u, load4(A + 8 * (n + u)));
    if (Q) stream_half_line(Y + so * u + 4, load4(Q + 16 * (n + u)));
  }
  stream_fence();
}

void DemSystem::sum_stress() {
  // Serial sum in particle order: independent of the thread count.
  const std::size_t n = p_.size();
  const double* sd = stress_scratch_.data();
  Eigen::Vector3d s = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) s += Eigen::Vector3d(sd[3 * i], sd[3 * i + 1], sd[3 * i + 2]);
  last_stress_diag_ = s / volume();
  last_stress_known_ = true;
}

void DemSystem::set_phase_timing(bool on) {
  phase_timing_ = on;
  phase_clocks_.assign(on ? static_cast<std::size_t>(std::max(last_team_, 1)) : 0, PhaseClock{});
}

void DemSystem::clock_phases_of(int team) {
  if (phase_timing_ && phase_clocks_.size() < static_cast<std::size_t>(team))
    phase_clocks_.resize(static_cast<std::size_t>(team));
}

std::vector<DemSystem::Phases> DemSystem::phases() const {
  std::vector<Phases> out;
  for (const PhaseClock& c : phase_clocks_) out.push_back(c.p);
  return out;
}

template <bool kStress>
void DemSystem::compute_forces(double half_kick, int team) {
  if (blocks_builds_ != list_.builds()) make_blocks();
  prepare_handoffs(team);
  clock_phases_of(team);
#pragma omp parallel num_threads(team) if (team > 1)
  {
    const std::size_t t = static_cast<std::size_t>(omp_get_thread_num());
    const std::size_t T = static_cast<std::size_t>(omp_get_num_threads());
    if (hands_off(T)) {
      hand_in(t);
      barrier_.arrive_and_wait(T);
    }
    forces_of_thread<kStress>(t, T, half_kick);
  }
  if constexpr (kStress) sum_stress();
  // The force records are now ahead of p_ again, also in a step whose list build copied them
  // out before these forces existed (rebuild_list): without this, a save or an unedited
  // mutable_particles() right after such a step carried the forces the step started from.
  records_ahead_.ahead.store(true, std::memory_order_release);
}

void DemSystem::refresh_forces() {
  const std::size_t n = p_.size();
  sync_particles();
  particles_ahead_ = false;
  pack_positions();
  if (va8_.size() < 8 * n) va8_.resize(8 * n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    va8_[8 * i] = p_.vx[i];
    va8_[8 * i + 1] = p_.vy[i];
    va8_[8 * i + 2] = p_.vz[i];
  }
  if (friction_) {
    if (blocks_builds_ != list_.builds()) make_blocks();
    pack_rotations(0, n, 0.0, false);
  }
  advancing_ = false;  // the forces of the current state: the history stays
  compute_forces<true>(0.0, 1);
}

void DemSystem::zero_velocities() {
  std::fill(p_.vx.begin(), p_.vx.end(), 0.0);
  std::fill(p_.vy.begin(), p_.vy.end(), 0.0);
  std::fill(p_.vz.begin(), p_.vz.end(), 0.0);
  for (auto* w : {&p_.wx, &p_.wy, &p_.wz}) std::fill(w->begin(), w->end(), 0.0);
  refresh_forces();
}

void DemSystem::step(const Eigen::Vector3d& D) { step_impl<false>(D); }
void DemSystem::step_measuring_stress(const Eigen::Vector3d& D) { step_impl<true>(D); }

template <bool kStress>
void DemSystem::step_impl(const Eigen::Vector3d& D) {
  // Checked before the step changes anything: a rate the step cannot follow (a NaN from a
  // servo, or a material whose contact time makes dt huge: density 1e300 gave dt ~ 1e139 s,
  // infinite cell lengths and an internal error of the list) is bad input, not NaN states.
  // (allFinite first: Eigen's maxCoeff may pass over a NaN that is not in the first lane.)
  const double rate =
      D.allFinite() ? D.cwiseAbs().maxCoeff() : std::numeric_limits<double>::quiet_NaN();
  if (!(rate * dt_ <= kMaxStrainPerStep)) {  // the words only when refused: this is every step
    throw InputError("DEM: the imposed strain rate " + decimal_g(rate) + " 1/s " +
                     strain_per_step_excess(rate, dt_) +
                     ": lower the rate, or check the material (k, density and r_mean set dt)");
  }
  if constexpr (!kStress) last_stress_known_ = false;  // sum_stress sets it on a measuring step
  // Step times (wall, without list builds) feed the team controller when it has a choice, and
  // the choice of the frictionless pair loop's form (force_block): the branchy one (1) or the
  // compact one (2), which give the same bits, chosen by the same kind of timed windows.
  // The two controllers try their alternatives one at a time: while the team controller tries
  // another size the loop keeps its current form, and the steps of the loop's tries do not
  // count for the team. Both start together, so without this the team's first try ran with the
  // loop's first try of the other form (at N = 1000, nu = 0.64: 1.37x dearer) and lost against
  // one thread with the current form (docs/performance.md "The two controllers' tries").
  bool timed = false;
  const int team = choose_team(&timed);
  const bool team_trying = timed && team != controller_.current();
  const bool loop_timed = !friction_ && fixed_loop_ == 0;
  const int loop_form = !loop_timed   ? 0
                        : team_trying ? loop_controller_.current()
                                      : loop_controller_.choose(2);
  const bool loop_trying = loop_timed && !team_trying && loop_form != loop_controller_.current();
  compact_ = fixed_loop_ > 0 ? fixed_loop_ == 2 : loop_form == 2;
  const bool clocked = timed || loop_timed;
  const auto start =
      clocked ? std::chrono::steady_clock::now() : std::chrono::steady_clock::time_point{};
  last_team_ = team;
  // The system's first step on a team is not timed: on this project's VM it took 11-15 ms in
  // about one process of three (the second core's first work; the same team's later steps 9-11
  // us), which made the controller's first try lose by far and never come back in quick.toml's
  // preparation (docs/performance.md "The team's first step").
  const bool first_team_step = team > 1 && !team_started_;
  if (team > 1) team_started_ = true;
  const double dt = dt_, h = 0.5 * dt_;
  const Eigen::Vector3d s = (D * dt).array().exp();
  const Eigen::Vector3d L = cell_.lengths().cwiseProduct(s);
  const Eigen::Vector3d sref = L.cwiseQuotient(list_.ref_lengths());
  if (blocks_builds_ != list_.builds()) make_blocks();
  prepare_handoffs(team);
  // After make_blocks, which may grow the records.
  if (particles_ahead_) pack_particles();
  const KickDrift kick{{p_.vx.data(), p_.vy.data(), p_.vz.data()},
                       p_.inv_mass.data(),
                       ref4_.data(),
                       va8_.data(),
                       pos4_.data(),
                       h,
                       dt,
                       {s[0], s[1], s[2]},
                       {sref[0], sref[1], sref[2]},
                       list_.s_min(L)};
  cell_.h.diagonal() = L;
  strain_E_ += D * dt;
  time_ += dt;
  last_D_ = D;
  advancing_ = true;
  // One parallel region per step: the kick and drift of a thread's rows (those of the blocks it
  // computes forces for, still in its cache then) with the two largest excesses e_i = u_i -
  // s_min h_i of the rebuild rule (neighbor_list.hpp); one barrier; every thread merges the
  // team's pairs in the same order, so all take the same decision. Without a rebuild (the
  // common case) the forces follow in the same region; a rebuild leaves the region, and the
  // forces get one of their own.
  if (tops_.size() < static_cast<std::size_t>(team)) tops_.resize(static_cast<std::size_t>(team));
  clock_phases_of(team);
  bool rebuild = false;
  // From the kick on, p_'s positions and forces lag the records (a rebuild copies them first).
  records_ahead_.ahead.store(true, std::memory_order_release);
#pragma omp parallel num_threads(team) if (team > 1)
  {
    const std::size_t t = static_cast<std::size_t>(omp_get_thread_num());
    const std::size_t T = static_cast<std::size_t>(omp_get_num_threads());
    double e1 = -1e300, e2 = -1e300;
    const auto [lo, hi] = rows_of(t, T);
    using Clock = std::chrono::steady_clock;
    const auto c0 = phase_timing_ ? Clock::now() : Clock::time_point{};
    kick_drift(kick, lo, hi, e1, e2);
    // The rotations' half kick, then the rows' records for the force loop.
    if (friction_) pack_rotations(lo, hi, h, true);
    if (hands_off(T)) hand_in(t);
    tops_[t] = {e1, e2};
    const auto c1 = phase_timing_ ? Clock::now() : c0;
    if (T > 1) barrier_.arrive_and_wait(T);
    if (phase_timing_) {
      Phases& ph = phase_clocks_[t].p;
      ph.kick += std::chrono::duration<double>(c1 - c0).count();
      ph.wait_kick += std::chrono::duration<double>(Clock::now() - c1).count();
      ++ph.steps;
    }
    e1 = e2 = -1e300;
    for (std::size_t u = 0; u < T; ++u) {
      keep_two_largest(tops_[u].e1, e1, e2);
      keep_two_largest(tops_[u].e2, e1, e2);
    }
    const bool must = list_.must_rebuild(e1, e2, L);
    if (t == 0) rebuild = must;
    if (!must) forces_of_thread<kStress>(t, T, h);
  }
  double rebuild_seconds = 0;
  if (rebuild) {
    const auto r0 = clocked || phase_timing_ ? std::chrono::steady_clock::now() : start;
    rebuild_list();
    if (clocked || phase_timing_)
      rebuild_seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - r0).count();
    if (phase_timing_) phase_clocks_[0].p.list += rebuild_seconds;
    compute_forces<kStress>(h, team);
  } else if constexpr (kStress) {
    sum_stress();
  }
  if (friction_)  // in block order: the same sum on any team
    for (const double e : block_dissipation_) sliding_dissipation_ += e;
  ++steps_;
  if (clocked) {
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() -
        rebuild_seconds;
    if (timed && !first_team_step && !loop_trying) controller_.record(team, seconds);
    if (loop_timed && !team_trying) loop_controller_.record(compact_ ? 2 : 1, seconds);
  }
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
  // The servo reads the stress of the previous force evaluation (one step of lag), which a
  // plain step did not sum: then it measures the stress now (the protocols' servos do the same
  // at their start). A restored state carries the summed one, so a restored run continues.
  const Eigen::Vector3d sd = last_stress_known_ ? last_stress_diag_ : stress().diagonal();
  step_impl<true>(control.velocity_gradient(sd, options_.material.k_star()));
}

Eigen::Vector3d DemSystem::branch(std::size_t i, std::int64_t e, const Eigen::Vector3d& L) const {
  return p_.position(i) - p_.position(list_.index[e]) +
         NeighborList::shift(list_.shift_code[e]).cwiseProduct(L);
}

// Whether the last force evaluation held contact (i, j) at the Coulomb limit: the law again
// with that evaluation's own inputs, the predicted velocities, which the step leaves in the
// rows' records (va8_, rot16_ at +8; a refresh puts the current ones there). With the final
// velocities instead, the dashpots' share of their difference moved sliding contacts off the
// limit by more than kSlidingTolerance, and the count missed a sixth to a half of them
// (docs/frictional.md "The sliding fraction"). A function of its own, outside contacts(): the
// reported forces keep the bits they had before it existed (an ulp there changes where the
// isotropic loading stops, and so the trajectory after it).
bool DemSystem::held_at_limit(std::size_t i, std::size_t j, const Eigen::Vector3d& l,
                              const Eigen::Vector3d& nrm, double overlap,
                              const Eigen::Vector3d& spring) const {
  const auto record = [](const AlignedVector& r, std::size_t at) {
    return Eigen::Vector3d(r[at], r[at + 1], r[at + 2]);
  };
  const NormalContact law = options_.material.contact();
  const TangentialContact tan = options_.material.tangential();
  const Eigen::Vector3d u = record(va8_, 8 * i) - record(va8_, 8 * j) + last_D_.cwiseProduct(l);
  const double f_n = std::fma(law.gamma, -nrm.dot(u), law.k * overlap);
  const double ai = p_.radius[i] - 0.5 * overlap, aj = p_.radius[j] - 0.5 * overlap;
  Eigen::Vector3d vc =
      u - (ai * record(rot16_, 16 * i + 8) + aj * record(rot16_, 16 * j + 8)).cross(nrm);
  vc -= vc.dot(nrm) * nrm;
  Eigen::Vector3d xi = spring, ft;
  double unused = 0;
  tan.force(xi, Eigen::Vector3d(Eigen::Vector3d::Zero()), vc, 0.0, f_n, &unused, ft);
  const double limit = tan.mu * std::abs(f_n);
  return limit > 0 && ft.norm() >= (1.0 - kSlidingTolerance) * limit;
}

std::vector<Contact> DemSystem::contacts() const {
  sync_particles();
  const std::size_t n = p_.size();
  const Eigen::Vector3d L = cell_.lengths();
  const NormalContact law = options_.material.contact();
  // Room for half the list's entries at once: growing by copies cost a tenth to a fifth of
  // the call (BM_Stress, docs/performance.md "The isotropic stage's pressure").
  std::vector<Contact> out;
  out.reserve(static_cast<std::size_t>(list_.offset[n]) / 2);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::int64_t e = list_.offset[i]; e < list_.offset[i + 1]; ++e) {
      const std::int32_t j = list_.index[e];
      const Eigen::Vector3d l = branch(i, e, L);
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
      // The law of contact.hpp written out with its k and gamma, and its one fused product
      // (FMA) written out too: the compiler fused one product or the other depending on
      // where this loop was inlined, one ulp apart, and the stress servo of the isotropic
      // stage turns that into another trajectory.
      c.force = std::fma(law.gamma, -nrm.dot(vrel), law.k * c.overlap);
      if (friction_) {
        // The stored spring (already in this tangent plane) and the current velocities, held
        // at the Coulomb limit as the force loop holds them; nothing advances here.
        const TangentialContact tan = options_.material.tangential();
        const double ai = p_.radius[i] - 0.5 * c.overlap, aj = p_.radius[j] - 0.5 * c.overlap;
        const Eigen::Vector3d wi(p_.wx[i], p_.wy[i], p_.wz[i]), wj(p_.wx[j], p_.wy[j], p_.wz[j]);
        Eigen::Vector3d vc = vrel - (ai * wi + aj * wj).cross(nrm);
        vc -= vc.dot(nrm) * nrm;
        Eigen::Vector3d xi(hist_[3 * e], hist_[3 * e + 1], hist_[3 * e + 2]);
        double unused = 0;
        Eigen::Vector3d ft;
        tan.force(xi, Eigen::Vector3d(Eigen::Vector3d::Zero()), vc, 0.0, c.force, &unused, ft);
        c.tangential = swap ? Eigen::Vector3d(-ft) : ft;
        const Eigen::Vector3d spring(hist_[3 * e], hist_[3 * e + 1], hist_[3 * e + 2]);
        c.spring = swap ? Eigen::Vector3d(-spring) : spring;
        c.sliding = held_at_limit(i, static_cast<std::size_t>(j), l, nrm, c.overlap, spring);
        if (rolling_) {
          // The rolling law as the force loop states it (friction_law): v_r = -a' n x (w_i -
          // w_j), its spring held at its limit, the torque a' n x f_r on the row's i. v_r and
          // f_r do not depend on the pair's order; the torque on the reported i does.
          const double ar = ai * aj / (ai + aj);
          const Eigen::Vector3d vr = -ar * nrm.cross(wi - wj);
          c.rolling_spring =
              Eigen::Vector3d(hist_r_[3 * e], hist_r_[3 * e + 1], hist_r_[3 * e + 2]);
          Eigen::Vector3d xr = c.rolling_spring;
          Eigen::Vector3d fr;
          options_.material.rolling_contact().force(xr, Eigen::Vector3d(Eigen::Vector3d::Zero()),
                                                    vr, 0.0, c.force, &unused, fr);
          const Eigen::Vector3d q = ar * nrm.cross(fr);
          c.rolling_torque = swap ? Eigen::Vector3d(-q) : q;
        }
      }
      out.push_back(c);
    }
  }
  return out;
}

Eigen::Matrix3d DemSystem::stress() const {
  Eigen::Matrix3d s = Eigen::Matrix3d::Zero();
  for (const Contact& c : contacts()) {
    s += c.force / c.branch.norm() * c.branch * c.branch.transpose();
    if (friction_) s += c.branch * c.tangential.transpose();
  }
  return s / volume();
}

Eigen::Matrix3d DemSystem::fabric() const {
  Eigen::Matrix3d f = Eigen::Matrix3d::Zero();
  const double c43 = 4.0 / 3.0 * std::numbers::pi;
  for (const Contact& c : contacts()) {
    const double ri = p_.radius[c.i], rj = p_.radius[c.j];
    const Eigen::Vector3d nrm = c.branch.normalized();
    f += c43 * (ri * ri * ri + rj * rj * rj) * nrm * nrm.transpose();
  }
  return f / volume();
}

double DemSystem::kinetic_energy() const {
  double e = 0;
  for (std::size_t i = 0; i < p_.size(); ++i)
    e += 0.5 * p_.mass(i) * (p_.vx[i] * p_.vx[i] + p_.vy[i] * p_.vy[i] + p_.vz[i] * p_.vz[i]);
  return e;
}

namespace {
// The rolling springs' energy, summed apart from the other springs (in the contacts' order).
double rolling_energy(const std::vector<Contact>& contacts, const TangentialContact& roll) {
  double e = 0;
  for (const Contact& c : contacts) e += roll.energy(c.rolling_spring.squaredNorm());
  return e;
}
}  // namespace

double DemSystem::elastic_energy() const {
  sync_particles();
  // The sums of the contacts() records (in their order: normal and tangential springs per
  // contact, the rolling springs apart), taken from the list without building the records,
  // which cost half (frictionless) to three quarters (friction) of the call: relax() asks
  // for this every check_every steps (docs/performance.md "The relaxation's elastic energy").
  const std::size_t n = p_.size();
  const Eigen::Vector3d L = cell_.lengths();
  const NormalContact law = options_.material.contact();
  const TangentialContact tan = options_.material.tangential();
  const TangentialContact roll = options_.material.rolling_contact();
  auto spring2 = [](const std::vector<double>& h, std::int64_t e) {
    return h[3 * e] * h[3 * e] + h[3 * e + 1] * h[3 * e + 1] + h[3 * e + 2] * h[3 * e + 2];
  };
  double e_springs = 0, e_rolling = 0;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::int64_t e = list_.offset[i]; e < list_.offset[i + 1]; ++e) {
      const std::int32_t j = list_.index[e];
      const double d = branch(i, e, L).norm();
      const double R = p_.radius[i] + p_.radius[j];
      if (d >= R) continue;
      e_springs += law.energy(R - d);
      if (friction_) e_springs += tan.energy(spring2(hist_, e));
      if (rolling_) e_rolling += roll.energy(spring2(hist_r_, e));
    }
  }
  return rolling_ ? e_springs + e_rolling : e_springs;
}

double DemSystem::rotational_energy() const {
  double e = 0;
  if (!friction_) return e;
  for (std::size_t i = 0; i < p_.size(); ++i)
    e += 0.5 / inv_inertia_[i] * (p_.wx[i] * p_.wx[i] + p_.wy[i] * p_.wy[i] + p_.wz[i] * p_.wz[i]);
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
  const double V = volume();
  const NormalContact law = options_.material.contact();
  const double c43 = 4.0 / 3.0 * std::numbers::pi;
  m.time = time_;
  for (const Contact& c : cs) {
    const double d = c.branch.norm();
    const Eigen::Vector3d nrm = c.branch / d;
    m.stress += c.force * d * nrm * nrm.transpose();
    const double ri = p_.radius[c.i], rj = p_.radius[c.j];
    m.fabric += c43 * (ri * ri * ri + rj * rj * rj) * nrm * nrm.transpose();
    m.elastic_energy += law.energy(c.overlap);
    if (friction_) {
      m.stress += c.branch * c.tangential.transpose();
      m.tangential_energy += options_.material.tangential().energy(c.spring.squaredNorm());
      m.sliding_fraction += c.sliding ? 1.0 : 0.0;
    }
  }
  if (friction_) {
    m.elastic_energy += m.tangential_energy;
    if (rolling_) m.elastic_energy += rolling_energy(cs, options_.material.rolling_contact());
    m.rotational_energy = rotational_energy();
    m.sliding_dissipation = sliding_dissipation_;
    if (!cs.empty()) m.sliding_fraction /= static_cast<double>(cs.size());
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
  // C* counts contacts among non-rattlers only (rattlers removed iteratively, by the rule of
  // the packing: frictionless or frictional).
  const std::vector<bool> keep = non_rattlers(n, cs, rattler_min_contacts(friction_));
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
    throw std::runtime_error(
        "DEM integration diverged (non-finite energy or stress) at t = " + decimal_g(time_) + " s");
  return m;
}

}  // namespace rendulic::dem
