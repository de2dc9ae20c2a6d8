// Particle arrays and seeded radii (docs/physics.md section 1).
#include "rendulic/dem/particles.hpp"

#include <cmath>
#include <numbers>

namespace rendulic::dem {

void Particles::resize(std::size_t n) {
  for (auto* v :
       {&x, &y, &z, &vx, &vy, &vz, &fx, &fy, &fz, &radius, &inv_mass, &wx, &wy, &wz, &tx, &ty, &tz})
    v->assign(n, 0.0);
}

double Particles::total_volume() const {
  double v = 0;
  for (double r : radius) v += 4.0 / 3.0 * std::numbers::pi * r * r * r;
  return v;
}

std::uint64_t Rng::next() {
  std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

double Rng::normal() {
  // 1 - uniform() lies in (0, 1]: the log is finite.
  const double u1 = 1.0 - uniform(), u2 = uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

Particles make_particles(const Material& material, std::size_t n, Rng& rng) {
  Particles p;
  p.resize(n);
  const double a = material.r_min(), b = material.r_max();
  for (std::size_t i = 0; i < n; ++i) {
    p.radius[i] = rng.uniform(a, b);
    p.inv_mass[i] = 1.0 / material.sphere_mass(p.radius[i]);
  }
  return p;
}

}  // namespace rendulic::dem
