// Measured quantities of a packing (docs/physics.md section 3; seed paper eqs. 1 and 2): static
// stress, fabric, coordination C and C* (rattlers, fewer than 4 contacts, removed
// iteratively), volume fraction, kinetic and elastic energy, inertial number and the strains.
// Plain data, filled by DemSystem::measure(); signs follow core/conventions.hpp.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <vector>

namespace rendulic::dem {

struct Measures {
  double time = 0;                                        // s
  Eigen::Matrix3d stress = Eigen::Matrix3d::Zero();       // Pa, compression positive (eq. 1)
  Eigen::Matrix3d stress_star = Eigen::Matrix3d::Zero();  // stress / k*
  Eigen::Matrix3d fabric = Eigen::Matrix3d::Zero();       // eq. 2 (all contacts)
  Eigen::Matrix3d strain = Eigen::Matrix3d::Zero();       // epsilon = -E (log strain)
  double pressure = 0;                                    // Pa
  double pressure_star = 0;                               // P / k*
  double eps_v = 0;                                       // -tr(E)
  double eps_dev = 0;                                     // signed sqrt(2 J2) of -E
  double volume_fraction = 0;
  std::int64_t contacts = 0;
  double coordination = 0;             // C = 2M/N
  double coordination_nonrattler = 0;  // C* over non-rattlers (0 when all are rattlers)
  double rattler_fraction = 0;
  double kinetic_energy = 0;      // J, of the peculiar velocities
  double elastic_energy = 0;      // J, sum k delta^2 / 2 (+ the tangential springs' energy)
  double kinetic_to_elastic = 0;  // +inf when there is kinetic but no elastic energy
  double inertial_number = 0;     // rate 2<r> sqrt(rho / P); +inf when P <= 0 and rate > 0
  double strain_rate = 0;         // max_a |D_aa| of the last step, 1/s
  // Frictional contacts only (zero without friction): the rotations' kinetic energy (not in
  // kinetic_energy), the tangential springs' energy sum k_t |xi|^2 / 2 (in elastic_energy
  // too), and the work the Coulomb limit has dissipated by sliding since the system was made.
  double rotational_energy = 0;    // J
  double tangential_energy = 0;    // J
  double sliding_dissipation = 0;  // J
  // Fraction of the contacts that the last force evaluation held at the Coulomb limit mu |f_n|
  // (within kSlidingTolerance): the contacts that slide.
  double sliding_fraction = 0;
};

// One contact of the current configuration (i < j).
struct Contact {
  std::int32_t i = 0, j = 0;
  Eigen::Vector3d branch = Eigen::Vector3d::Zero();  // l = x_i - x_j (minimum image), m
  double overlap = 0;                                // m
  double force = 0;                                  // normal force on i along l/|l|, N
  // Frictional contacts: the tangential force on i and the tangential spring xi (the
  // displacement of i's contact point relative to j's), both in the tangent plane.
  Eigen::Vector3d tangential = Eigen::Vector3d::Zero();  // N
  Eigen::Vector3d spring = Eigen::Vector3d::Zero();      // m
  // With rolling resistance: the rolling spring (the same for either order of the pair), m,
  // and the rolling torque on i (that on j is its opposite), N m.
  Eigen::Vector3d rolling_spring = Eigen::Vector3d::Zero();
  Eigen::Vector3d rolling_torque = Eigen::Vector3d::Zero();
  bool sliding = false;  // held at the Coulomb limit by the last force evaluation
};

// A contact slides when the last force evaluation held it at the Coulomb limit: |f_t| >= (1 -
// kSlidingTolerance) mu |f_n|, both from that evaluation's own inputs (the predicted
// velocities, DemSystem::held_at_limit). The limit is applied by rescaling, so a sliding contact
// sits on it to round-off; the tolerance only takes in sticking contacts within 1e-6 of it
// (1 in 74 000 contacts of a sheared packing, tests/dem/friction_system_test.cpp).
inline constexpr double kSlidingTolerance = 1e-6;

// The fewest contacts a particle keeps to bear load (docs/dem.md "States at rest"): d + 1 = 4
// for frictionless spheres, whose contacts carry normal forces only; 2 with friction, where a
// sphere can hold balanced forces on two contacts. The frictionless count applied to a
// frictional packing near its jamming point removes it almost whole (C = 3.66 at P* = 1e-3,
// mu = 0.5: no particle kept).
inline constexpr int kFrictionlessMinContacts = 4;
inline constexpr int kFrictionalMinContacts = 2;
inline int rattler_min_contacts(bool frictional) {
  return frictional ? kFrictionalMinContacts : kFrictionlessMinContacts;
}

// Iterative rattler removal: true for particles that keep at least `min_contacts` contacts
// among non-rattlers. Pure function of the contact list, so it is unit-testable.
std::vector<bool> non_rattlers(std::size_t n, const std::vector<Contact>& contacts,
                               int min_contacts = kFrictionlessMinContacts);

}  // namespace rendulic::dem
