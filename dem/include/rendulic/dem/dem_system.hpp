// The DEM engine: particles in a deforming orthorhombic periodic cell, integrated with
// velocity Verlet in peculiar-velocity form (physics.md sections 1-3, seed paper section 2).
//
// Scheme (one step of length dt, imposed diagonal velocity gradient D, S = exp(D dt)):
//   1. v' <- v' + dt/2 * F(t)/m                       (half kick)
//   2. x  <- S (x + dt v')                            (peculiar drift, then exact affine map)
//      L  <- S L, E <- E + D dt                       (log strain: trace-free D keeps V exactly)
//   3. F(t+dt) = sum_contacts (k delta + gamma d(delta)/dt) n - gamma_b v'
//      with d(delta)/dt = -n . (v'_i - v'_j + D l): the true relative normal velocity,
//      including the affine part; the velocities of the dissipative terms are predicted
//      as v'(t) + dt F(t)/m (second order; plain half-step velocities would lag by dt/2
//      and shift the contact duration and restitution at first order)
//   4. v' <- v' + dt/2 * F(t+dt)/m                    (half kick)
// The inertial terms -D v' - D^2 x of the peculiar equation of motion are dropped (as in
// LAMMPS `fix deform remap x` and MercuryDPM's Lees-Edwards boxes); relative to the contact
// forces they are O(D t_c) ~ 1e-6 at the rates of this mission. The conservative part is the
// symplectic Verlet scheme; the dissipative part is explicit with a second-order predictor.
//
// Parallel (OpenMP) over particles with a half neighbour list: each thread owns a contiguous
// range of rows (equal list length) and accumulates pair forces into its own buffer, of which
// only its range and its few partners outside it are touched; the owner of a range adds the
// other threads' contributions in thread order. Every other reduction is serial or order-free
// (max). Results are therefore deterministic for a given
// thread count and bit-identical on restart (see State); different thread counts agree to
// round-off.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <new>
#include <string>
#include <vector>

#include "rendulic/dem/cell.hpp"
#include "rendulic/dem/contact.hpp"
#include "rendulic/dem/measures.hpp"
#include "rendulic/dem/neighbor_list.hpp"
#include "rendulic/dem/particles.hpp"

namespace rendulic::dem {

// 64-byte aligned doubles: packed 4-double records then never straddle a cache line.
template <class T>
struct CacheAlignedAllocator {
  using value_type = T;
  CacheAlignedAllocator() = default;
  template <class U>
  CacheAlignedAllocator(const CacheAlignedAllocator<U>&) {}
  T* allocate(std::size_t n) {
    return static_cast<T*>(::operator new (n * sizeof(T), std::align_val_t{64}));
  }
  void deallocate(T* p, std::size_t) { ::operator delete (p, std::align_val_t{64}); }
  bool operator==(const CacheAlignedAllocator&) const { return true; }
};
using AlignedVector = std::vector<double, CacheAlignedAllocator<double>>;

struct SystemOptions {
  Material material{};
  double dt_factor = 1.0 / 50.0;  // dt = dt_factor * t_c of the smallest pair
  double skin = 0.3;              // Verlet skin in units of <r>
  bool IsValid(std::string* why) const;
};

// Everything needed to continue a run bit-identically (same build, same thread count): the
// particle arrays, the cell, the clocks and the neighbour list's reference state (the list is
// a pure function of it, so a restored run rebuilds exactly the same list).
struct State {
  Particles particles;
  Eigen::Vector3d lengths = Eigen::Vector3d::Ones();
  Eigen::Vector3d strain_E = Eigen::Vector3d::Zero();  // accumulated log strain diag(E)
  Eigen::Vector3d last_D = Eigen::Vector3d::Zero();
  double time = 0;
  std::int64_t steps = 0;
  std::vector<double> ref_x, ref_y, ref_z;
  Eigen::Vector3d ref_lengths = Eigen::Vector3d::Ones();
  // Per-particle half skins of the list (neighbor_list.hpp); empty means skin / 2 for all.
  std::vector<double> ref_half_skin;
};

class DemSystem {
 public:
  // Throws InputError if the options are invalid (including dt beyond the stability limit)
  // or the particles do not fit the cell. Positions are wrapped into the cell.
  DemSystem(Particles particles, const PeriodicCell& cell, const SystemOptions& options);
  static DemSystem restore(const State& state, const SystemOptions& options);
  State save() const;

  // One step with the imposed velocity gradient diag(D) (1/s, positive = extension).
  void step(const Eigen::Vector3d& D);
  void advance(std::int64_t n, const Eigen::Vector3d& D);
  // One step whose D comes from a cell control (servo axes use the stress of the last step).
  void step(const CellControl& control);

  Measures measure() const;
  std::vector<Contact> contacts() const;
  Eigen::Matrix3d stress() const;  // eq. 1, Pa
  Eigen::Matrix3d fabric() const;  // eq. 2
  double kinetic_energy() const;
  double elastic_energy() const;
  double volume_fraction() const { return solid_volume_ / cell_.volume(); }

  const Particles& particles() const { return p_; }
  Particles& mutable_particles() { return p_; }  // e.g. to set gas velocities; forces stale
  const PeriodicCell& cell() const { return cell_; }
  const SystemOptions& options() const { return options_; }
  const Material& material() const { return options_.material; }
  double dt() const { return dt_; }
  double time() const { return time_; }
  std::int64_t steps() const { return steps_; }
  // Accumulated log strain E (diagonal; extension positive). epsilon = -E.
  Eigen::Vector3d strain_E() const { return strain_E_; }
  Eigen::Vector3d last_D() const { return last_D_; }
  std::int64_t list_builds() const { return list_.builds(); }
  // Diagonal of the stress from the last force evaluation that computed it (servo steps).
  Eigen::Vector3d last_stress_diag() const { return last_stress_diag_; }

  // Makes the current configuration the origin of strain_E() (e.g. at the start of a path).
  void reset_strain() { strain_E_.setZero(); }
  // Sets every peculiar velocity to zero (a relaxed snapshot for probing starts at rest).
  void zero_velocities();
  // Recomputes forces at the current positions/velocities (after editing particles).
  void refresh_forces();

 private:
  DemSystem() = default;
  void rebuild_list();
  // Copies positions and radii into the packed array the force loop gathers from.
  void pack_positions();
  void note_list_built();  // after every build: the longest row, the packed positions
  void partition_rows(int threads);
  template <bool kStress>
  void compute_forces();
  template <bool kStress>
  void step_impl(const Eigen::Vector3d& D);

  Particles p_;
  PeriodicCell cell_;
  SystemOptions options_;
  NeighborList list_;
  double dt_ = 0;
  double time_ = 0;
  std::int64_t steps_ = 0;
  double solid_volume_ = 0;
  Eigen::Vector3d strain_E_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d last_D_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d last_stress_diag_ = Eigen::Vector3d::Zero();
  std::vector<double> stress_scratch_;  // per-particle diagonal stress (servo steps)
  // The force loop gathers partner j's data at random: packed, one partner costs three cache
  // lines (position + radius, velocity, force buffer) instead of ten separate arrays.
  AlignedVector pos4_;  // x, y, z, radius per particle
  AlignedVector vel4_;  // velocities of the dissipative forces (x, y, z, unused)
  AlignedVector acc4_;  // per-thread pair-force accumulators (x, y, z, unused)
  // A thread's rows of the list and the partners outside them (compute_forces).
  struct RowPart {
    std::size_t lo = 0, hi = 0;
    std::vector<std::int32_t> foreign;  // sorted partner indices outside [lo, hi)
  };
  std::vector<RowPart> parts_;
  std::int64_t parts_builds_ = -1;  // list build the partition belongs to
};

}  // namespace rendulic::dem
