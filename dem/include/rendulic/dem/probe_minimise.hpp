// Energy minimisation of a periodic packing of frictionless linear-spring spheres (the contact
// law of docs/physics.md section 1 without damping: U = sum k delta^2 / 2) at a fixed cell, by
// FIRE 2.0 (Guenole et al., Comput. Mater. Sci. 175, 2020: semi-implicit Euler, velocity
// mixing, restart with half-step back-off on uphill power). Used by the quasi-static probe
// method (affine step, then minimise: docs/physics.md section 5), to generate
// jammed test packings without the DEM engine, and as the independent finite-difference check
// of the linear response. Particle masses are all 1 in the minimiser: FIRE only needs a
// descent dynamics, and equal masses keep its time step scale-free (units of 1/sqrt(k)).
#pragma once

#include <cstdint>
#include <string>

#include "rendulic/dem/probe_geometry.hpp"

namespace rendulic::dem {

struct MinimiseOptions {
  double k = 1e8;  // normal stiffness, kg/s^2
  // Converged when the largest net force on a particle is below force_tolerance times the
  // mean contact force (k <r> where there are no contacts).
  double force_tolerance = 1e-9;
  std::int64_t max_iterations = 1000000;
  // Verlet skin in units of the mean radius; pairs are rebuilt when a particle has moved more
  // than half of it. Only the cost depends on it (every touching pair is in the list either
  // way, visited in the same order): on quick.toml's state a, the minimisation probes took
  // 2.82, 2.46, 2.27, 2.13, 2.21 s of CPU at 0.2, 0.3, 0.4, 0.6, 0.8, with bitwise the same
  // results (docs/performance.md "The probe tools' pair search and FIRE").
  double skin = 0.5;
  bool IsValid(std::string* why) const;
};

struct MinimiseSummary {
  bool converged = false;
  std::int64_t iterations = 0;
  int pair_rebuilds = 0;
  double max_force = 0.0;           // N, largest net force on a particle at the end
  double mean_contact_force = 0.0;  // N
  double elastic_energy = 0.0;      // J
  std::string message;              // why it stopped
  // Where the largest net force stalled, as a fraction of the mean contact force, when the
  // tolerance lies below the round-off floor of the forces (0: it did not stall there).
  double stalled_at = 0.0;
  // The largest net force before the first iteration, as a fraction of the mean contact force:
  // where it is not well above force_tolerance the minimiser barely moves the particles (a probe
  // of a tiny amplitude keeps its affine, too stiff response).
  double start_ratio = 0.0;
};

// The one-line refusal of a tolerance below the round-off floor that `summary` stalled at:
// names `key` (states.force_tolerance, probes.force_tolerance) and a tolerance that is reached.
std::string round_off_refusal(const MinimiseSummary& summary, const std::string& key,
                              double tolerance);

// Minimises the elastic energy over the particle positions at the fixed cell of `packing`.
// Positions are updated in place (not wrapped into the cell).
MinimiseSummary minimise_energy(PackingData& packing, const MinimiseOptions& options);

// Homogeneous deformation of positions and cell by the small strain eps (compression
// positive, docs/physics.md section 2): x -> (I - eps) x, h -> (I - eps) h.
void apply_affine_strain(PackingData& packing, const Eigen::Matrix3d& eps);

// A random packing for tests and benchmarks without the DEM engine: N spheres with radii
// uniform in [r_min, w r_min] (mean r_mean), placed uniformly at random in a cube at the
// given volume fraction and minimised at fixed cell. Above jamming (nu > ~0.66 for w = 3) it
// is a jammed, over-compressed packing in mechanical equilibrium.
struct GeneratedPackingOptions {
  int n = 256;
  double w = 3.0;
  double r_mean = 1e-3;  // m
  double volume_fraction = 0.70;
  std::uint64_t seed = 1;
  MinimiseOptions minimise;
  bool IsValid(std::string* why) const;
};
PackingData generate_packing(const GeneratedPackingOptions& options, MinimiseSummary* summary);

}  // namespace rendulic::dem
