// Particle data of the DEM engine as separate arrays (structure of arrays, docs/architecture.md
// "Design choices"): positions, peculiar velocities (relative to the imposed homogeneous flow,
// docs/physics.md section 1), forces, radii and inverse masses. Radii are drawn number-weighted
// uniform in [r_min, r_max] from a seeded generator (docs/physics.md section 1).
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <vector>

#include "rendulic/dem/contact.hpp"

namespace rendulic::dem {

struct Particles {
  std::vector<double> x, y, z;     // positions, m (the cell spans [0, L_a) on each axis)
  std::vector<double> vx, vy, vz;  // peculiar velocities v' = v - D x, m/s
  std::vector<double> fx, fy, fz;  // total force of the last step (contacts + background), N
  std::vector<double> radius;      // m
  std::vector<double> inv_mass;    // 1/kg
  // Rotations (frictional contacts only; the frictionless engine leaves them zero): angular
  // velocities, rad/s, and the torques of the last step, N m. Moment of inertia 2/5 m r^2.
  std::vector<double> wx, wy, wz;
  std::vector<double> tx, ty, tz;

  std::size_t size() const { return radius.size(); }
  void resize(std::size_t n);
  double mass(std::size_t i) const { return 1.0 / inv_mass[i]; }
  Eigen::Vector3d position(std::size_t i) const { return {x[i], y[i], z[i]}; }
  Eigen::Vector3d velocity(std::size_t i) const { return {vx[i], vy[i], vz[i]}; }
  double total_volume() const;  // sum of sphere volumes, m^3
};

// Small deterministic generator (splitmix64): the same seed gives the same numbers on every
// platform, which std::uniform_real_distribution does not promise.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next();
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double a, double b) { return a + (b - a) * uniform(); }
  double normal();  // Box-Muller, standard normal

 private:
  std::uint64_t state_;
};

// N radii uniform in [r_min, r_max] of the material; masses from the density.
Particles make_particles(const Material& material, std::size_t n, Rng& rng);

}  // namespace rendulic::dem
