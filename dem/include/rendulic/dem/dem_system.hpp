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
// Parallel (OpenMP) over particles with a half neighbour list: each thread accumulates pair
// forces into its own buffer, and the buffers are summed in thread order; every other
// reduction is serial or order-free (max). Results are therefore deterministic for a given
// thread count and bit-identical on restart (see State); different thread counts agree to
// round-off.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <string>
#include <vector>

#include "rendulic/dem/cell.hpp"
#include "rendulic/dem/contact.hpp"
#include "rendulic/dem/measures.hpp"
#include "rendulic/dem/neighbor_list.hpp"
#include "rendulic/dem/particles.hpp"

namespace rendulic::dem {

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
  template <bool kStress>
  void compute_forces(const double* vx, const double* vy, const double* vz);
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
  std::vector<double> stress_scratch_;
  std::vector<double> wx_, wy_, wz_;
  std::vector<double>
      force_buffer_;  // per-thread force accumulators (half list)  // predicted velocities of the
                      // dissipative forces  // per-particle diagonal stress (servo steps)
};

}  // namespace rendulic::dem
