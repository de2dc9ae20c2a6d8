// Small builders shared by the DEM tests: a two-particle collision set-up and a random gas
// (no overlaps) of the seed material. Not a mock: they build real DemSystems.
#pragma once

#include "rendulic/dem/dem_system.hpp"
#include "rendulic/dem/protocols.hpp"

namespace rendulic::dem::testing {

// Two equal spheres of radius r on the x axis, approaching at relative speed v_rel (m/s), in
// a cube large enough for one periodic image.
inline DemSystem two_spheres(const Material& mat, double r, double v_rel, double dt_factor,
                             double gap = 1e-6) {
  Particles p;
  p.resize(2);
  const double L = 40 * mat.r_mean;
  p.radius = {r, r};
  p.inv_mass = {1.0 / mat.sphere_mass(r), 1.0 / mat.sphere_mass(r)};
  p.x = {0.5 * L - r - 0.5 * gap, 0.5 * L + r + 0.5 * gap};
  p.y = {0.5 * L, 0.5 * L};
  p.z = {0.5 * L, 0.5 * L};
  p.vx = {0.5 * v_rel, -0.5 * v_rel};
  SystemOptions o;
  o.material = mat;
  o.dt_factor = dt_factor;
  return DemSystem(p, PeriodicCell::orthorhombic(Eigen::Vector3d::Constant(L)), o);
}

}  // namespace rendulic::dem::testing
