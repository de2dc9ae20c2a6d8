// Protocols of the reference experiment (physics.md section 4, seed paper section 3) composed
// from a few primitives of DemSystem: a random gas, strain-controlled isotropic compression
// to a volume fraction (constant rate, or a rate that holds the inertial number), relaxation
// at fixed cell to a kinetic/elastic energy threshold with a time cap, and the constant-volume
// axisymmetric path with snapshots at given -eps_dev.
//
// Probe API (for probe campaigns, physics.md section 5). A DemSystem is a value: copy a
// relaxed state, then
//   impose_strain_increment(sys, d_eps, rate)  -- the strain increment (compression positive)
//   relax(sys, RelaxOptions{...})              -- fixed cell, to the energy threshold or cap
//   sys.measure() / sys.stress() / sys.fabric() / sys.contacts()
// Every copy is independent, so probes from one state can run concurrently (each then runs
// its own OpenMP loops; call them from a parallel region with nested parallelism off, or
// sequentially with all threads).
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "rendulic/dem/dem_system.hpp"

namespace rendulic::dem {

// Called with the completed fraction of a protocol, in [0, 1].
using ProgressFn = std::function<void(double)>;
// Called with every recorded sample.
using SampleFn = std::function<void(const Measures&)>;

struct GasOptions {
  std::size_t n_particles = 9261;
  double volume_fraction = 0.3;
  double velocity = 10.0;  // rms of each peculiar velocity component, m/s
  bool IsValid(std::string* why) const;
};
// Random sequential insertion without overlap (largest first) in a cube at the given volume
// fraction, Gaussian random velocities; seeded. Throws InputError if insertion fails.
DemSystem make_gas(const SystemOptions& options, const GasOptions& gas, std::uint64_t seed);

// Relaxation at fixed cell. Converged when E_kin / max(E_el, E_floor) < kinetic_to_elastic,
// with E_floor = N k (1e-4 <r>)^2 / 2: an unjammed packing (no elastic energy) counts as at
// rest once its kinetic energy per particle is below kinetic_to_elastic times the elastic
// energy of a 1e-4 <r> overlap (for the seed, 5e-7 J: with the default 1e-5, velocities of
// ~1e-3 m/s, small against the affine velocities of the loading that follows). Jammed states
// have E_el >> E_floor, so for them this is the plain E_kin / E_el.
struct RelaxOptions {
  double kinetic_to_elastic = 1e-6;
  double time_cap = 1e-3;          // s; reported if hit
  std::int64_t check_every = 200;  // steps between energy checks
  bool IsValid(std::string* why) const;
};
struct RelaxSummary {
  double time = 0;  // s spent relaxing
  std::int64_t steps = 0;
  double ratio = 0;  // the criterion's value at the end
  bool converged = false;
};
RelaxSummary relax(DemSystem& sys, const RelaxOptions& options, const ProgressFn& progress = {});
double relax_ratio(const DemSystem& sys);  // E_kin / max(E_el, E_floor)

// Isotropic strain-controlled compression (or expansion) to `target_nu`, landing exactly on
// it. With inertial_number > 0 the rate is chosen every few steps as
// clamp(I_target sqrt(P/rho) / (2<r>), rate_min, rate_max); otherwise it is rate_max.
struct CompressOptions {
  double target_nu = 0.64;
  double rate_max = 1e3;       // 1/s
  double rate_min = 50.0;      // 1/s
  double inertial_number = 0;  // 0: constant rate_max
  int samples = 0;             // samples equally spaced in ln(nu), both ends included
  bool IsValid(std::string* why) const;
};
// Below this P* a packing counts as unjammed for the inertial-number bookkeeping: as P -> 0
// the inertial number diverges at any finite rate, and it means nothing for a fluid.
inline constexpr double kJammedPressureStar = 1e-4;
struct CompressSummary {
  double time = 0;
  std::int64_t steps = 0;
  double max_inertial_number = 0;  // over samples with P* > kJammedPressureStar
};
CompressSummary compress_isotropic(DemSystem& sys, const CompressOptions& options,
                                   const SampleFn& sample = {}, const ProgressFn& progress = {});

// Constant-volume axisymmetric extension along x, D = rate diag(1, -1/2, -1/2), from the
// current state to -eps_dev = eps_dev_max (strain counted from the start of the path).
// Snapshots (copies) are taken exactly at each requested -eps_dev.
struct PathOptions {
  double rate = 500.0;  // D_xx, 1/s
  double eps_dev_max = 0.32;
  int samples = 200;  // equally spaced in -eps_dev, both ends included
  std::vector<double> snapshot_eps_dev = {0.006, 0.021, 0.043, 0.068, 0.32};
  bool IsValid(std::string* why) const;
};
struct PathSummary {
  double time = 0;
  std::int64_t steps = 0;
  double max_inertial_number = 0;
  std::vector<DemSystem> snapshots;  // in the order of snapshot_eps_dev
};
PathSummary undrained_extension(DemSystem& sys, const PathOptions& options,
                                const SampleFn& sample = {}, const ProgressFn& progress = {});

// Imposes the diagonal strain increment d_eps (compression positive, physics.md section 5)
// in whole steps at constant D, the largest component advancing at `rate` (1/s) at most.
// Returns the number of steps.
std::int64_t impose_strain_increment(DemSystem& sys, const Eigen::Vector3d& d_eps, double rate);

// A system from stored positions [N,3], radii [N] and cell lengths (e.g. a /states/<label>
// of a results file), at rest.
DemSystem system_from_positions(const Eigen::MatrixXd& positions, const std::vector<double>& radii,
                                const Eigen::Vector3d& lengths, const SystemOptions& options);

}  // namespace rendulic::dem
