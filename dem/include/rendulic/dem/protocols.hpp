// Protocols of the reference experiment (docs/physics.md section 4, seed paper section 3) composed
// from a few primitives of DemSystem: a random gas, strain-controlled isotropic compression
// to a volume fraction (constant rate, or a rate that holds the inertial number), relaxation
// at fixed cell to a kinetic/elastic energy threshold with a time cap, and the constant-volume
// axisymmetric path with snapshots at given -eps_dev.
//
// Probe API (for probe campaigns, docs/physics.md section 5). A DemSystem is a value: copy a
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

// The random gas's volume fraction: random insertion needs room (0.4), and a sparser gas than
// 1e-6 only lengthens the compression to nu0 (its neighbour list is rebuilt almost every step:
// 1e-60 took 45 s at N = 250 where 1e-6 takes 1 s; 1e-300 had not ended after 30 s).
inline constexpr double kGasVolumeFractionMin = 1e-6, kGasVolumeFractionMax = 0.4;
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
// The overlap of E_floor, in units of <r>; its energy is the contact law's (NormalContact).
inline constexpr double kRelaxFloorOverlap = 1e-4;
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
// The progress of a relaxation: whichever is further, the decay of kinetic/elastic from
// `start_ratio` towards `target` (on a log scale, as it decays) or the time spent over the
// cap; in [0, 1].
double relax_fraction(double start_ratio, double ratio, double target, double time_fraction);
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
  // Copies of the system at these volume fractions on the way (strictly between the start and
  // the target), in loading order: CompressSummary::snapshots. Each is the loading's state
  // after the step that reaches it, taken back onto it exactly by a fraction of a step; the
  // loading itself goes on unchanged.
  std::vector<double> snapshot_nu;
  // > 0: a loading to a pressure. It stops as soon as P* = P / k* reaches this (checked every
  // few steps, so it overshoots by a few 1e-4 of P), and target_nu is then the bound it may
  // not pass (an InputError if it does; so are snapshots beyond the stop). The samples keep
  // their ln(nu) spacing up to the stop, where one more is taken.
  double target_pressure_star = 0;
  // The key that set rate_max, for the refusal of a loading that needs more than kMaxSteps.
  std::string rate_key = "the compression's rate_max";
  bool IsValid(std::string* why) const;
};
// The inertial number I = rate 2<r> sqrt(rho / P) of a strain rate (1/s, the largest |D_aa|)
// at pressure P (Pa), docs/physics.md section 4: 0 at rest, +inf for a positive rate at P <= 0.
// The protocols record it from the rate they impose, not from the last step's D: events
// (samples, snapshots, the end) are hit by shortening a step, and that step's D is not the
// rate of the loading.
double inertial_number(const Material& material, double rate, double pressure);
// Its inverse: the rate (1/s) that gives inertial number `inertial` at pressure P (0 at P <= 0).
double rate_for_inertial_number(const Material& material, double inertial, double pressure);

// Below this P* a packing counts as unjammed for the inertial-number bookkeeping: as P -> 0
// the inertial number diverges at any finite rate, and it means nothing for a fluid.
inline constexpr double kJammedPressureStar = 1e-4;
struct CompressSummary {
  double time = 0;
  std::int64_t steps = 0;
  double max_inertial_number = 0;    // over samples with P* > kJammedPressureStar
  std::vector<DemSystem> snapshots;  // at options.snapshot_nu, in loading order
};
CompressSummary compress_isotropic(DemSystem& sys, const CompressOptions& options,
                                   const SampleFn& sample = {}, const ProgressFn& progress = {});

// Relaxation at a held pressure: every axis follows the proportional-integral stress servo
// (cell.hpp) to sigma_aa = pressure, until the relax criterion holds and the pressure is within
// kPressureHold of its target, or the time cap. For a packing prepared to a pressure rather
// than a volume fraction (frictional packings reach different volume fractions at one P).
inline constexpr double kPressureHold = 1e-3;
RelaxSummary relax_at_pressure(DemSystem& sys, double pressure, const RelaxOptions& options,
                               const ServoOptions& servo, const ProgressFn& progress = {});

// The loading paths of the path stage (docs/dem.md "Paths"), each from the current state, with
// x the axial direction and y, z lateral. Strain-controlled paths impose a constant D:
//   undrained_extension / undrained_compression: D = +-rate diag(1, -1/2, -1/2) (constant
//     volume; the seed study's path is undrained_extension);
//   isotropic_unloading / isotropic_loading: D = +-rate diag(1, 1, 1);
//   proportional: D = rate d / max|d_a| for a principal strain-rate direction d (extension
//     positive, like D).
// Mixed paths impose D_xx = +-rate and hold the lateral stresses with the servo of cell.hpp
// (proportional-integral):
//   drained_extension / drained_compression: sigma_yy = sigma_zz = p0, the mean stress at the
//     start (the lateral stress of the triaxial test);
//   constant_p_extension / constant_p_compression: sigma_yy = sigma_zz = (3 p0 - sigma_xx) / 2,
//     so that the mean stress stays p0.
// The path's progress is its strain s: the norm |E| of the log strain since the start on the
// strain-controlled paths (= -eps_dev on the seed's path, sqrt(3) |E_xx| on the isotropic ones)
// and the axial strain |E_xx| on the mixed ones, whose volume the material decides. Samples,
// snapshots and the end are placed in s.
enum class PathKind { kUndrained, kIsotropic, kProportional, kDrained, kConstantMeanStress };
struct PathType {
  PathKind kind = PathKind::kUndrained;
  double sense = 1.0;  // +1: axial extension (isotropic: unloading); -1: compression
  bool mixed() const { return kind == PathKind::kDrained || kind == PathKind::kConstantMeanStress; }
};
// The names of the paths (the path.type key's choices) and their meaning.
const std::vector<std::string>& path_type_choices();
// Throws InputError naming the choices for an unknown name.
PathType path_type(const std::string& name);
// The path strain s of a path of this type from its strain tensor (epsilon = -E or E: the
// sign does not matter), for readers of a stored path; run_path measures the same s along
// one axis, scaled, so that it lands exactly on its events.
double path_strain(const PathType& type, const Eigen::Matrix3d& strain);

struct PathOptions {
  std::string type = "undrained_extension";  // one of path_type_choices()
  double rate = 500.0;                       // largest |D_aa| of the strain-controlled axes, 1/s
  // > 0: the rate follows the pressure so that the path holds this inertial number, between
  // rate_min and rate (rate_for_inertial_number, updated every few steps); 0: `rate` throughout.
  double inertial_number = 0;
  double rate_min = 1.0;  // 1/s, the floor where p is small (a liquefied packing)
  // The principal strain-rate direction of a proportional path (D's diagonal up to a positive
  // factor, extension positive); not used by the other paths.
  std::vector<double> direction = {1.0, -0.5, -0.5};
  double eps_dev_max = 0.32;  // the path's strain s at its end
  int samples = 200;          // equally spaced in s, both ends included
  std::vector<double> snapshot_eps_dev = {0.006, 0.021, 0.043, 0.068, 0.32};  // in s
  // The lateral servo of the mixed paths (its max_rate is max_rate_factor x rate) and the
  // largest relative error of what the path holds (drained: |sigma_yy - p0| and |sigma_zz - p0|;
  // constant p: |p - p0|; over p0) at a sample after the first tenth of the path; a larger one
  // is reported (PathSummary::servo_error).
  // The gains are in units of the contact duration t_c (contact_duration): gain x t_c and
  // integral_gain x t_c^2, so that the servo acts alike in any units and on any material's
  // time scale (an absolute gain in 1/s that suits one material's step is beyond the explicit
  // limit on a softer or heavier one). They make the servo critically damped for K* ~ 0.45
  // (the affine stiffness of the states of this mission) with the closed-loop rate gain
  // K* gain ~ 0.31 / t_c (1.3e6 1/s on the seed's material): thousands of times the path's
  // rate, yet K* gain dt = 0.31 dem.dt_factor ~ 6e-3 per step, far inside the explicit limit
  // of 2 (the cell's strain reaches the stress at once, through the affine remap).
  double servo_gain = 0.68;            // x 1/t_c
  double servo_integral_gain = 0.052;  // x 1/t_c^2; 0: proportional only
  double servo_max_rate_factor = 2.0;
  double servo_tolerance = 0.02;
  bool IsValid(std::string* why) const;
  // The servo in SI units for a packing of material m, its rate bound servo_max_rate_factor x
  // rate.
  ServoOptions servo(const Material& m) const;
};
struct PathSummary {
  double time = 0;
  std::int64_t steps = 0;
  double max_inertial_number = 0;
  std::vector<DemSystem> snapshots;  // in the order of snapshot_eps_dev
  // Mixed paths: the largest relative error of the held stress (PathOptions::servo_tolerance)
  // at a sample after the first tenth of the path (0 on strain-controlled paths), and whether
  // it is within servo_tolerance.
  double servo_error = 0;
  bool servo_held = true;
};
// The path of options.type from the current state to s = eps_dev_max. Snapshots (copies) are
// taken exactly at each requested s (on mixed paths: at the step's axial strain, exactly too).
PathSummary run_path(DemSystem& sys, const PathOptions& options, const SampleFn& sample = {},
                     const ProgressFn& progress = {});

// The mean of a path series over a window of the path and its standard error (docs/dem.md
// "Steady state and plateau means"): the samples y with x in [x_lo, x_hi] (e.g. x = -eps_dev),
// cut into `batches` contiguous batches of equal count; the standard error is the standard
// deviation of the batch means over sqrt(batches) (batch means: neighbouring samples of a
// path are correlated, so the plain standard error of the samples would be too small).
// ok = false (and standard_error 0) when the window holds fewer than 2 samples per batch.
// The steady state of the undrained path: -eps_dev from this fraction of the path's end on
// ([0.2, 0.32] for the seed's path, where its Fig. 1 has reached the asymptote).
inline constexpr double kSteadyStateFrom = 0.625;

struct WindowMean {
  double mean = 0.0;
  double standard_error = 0.0;
  int samples = 0;
  bool ok = false;
};
WindowMean window_mean(const std::vector<double>& x, const std::vector<double>& y, double x_lo,
                       double x_hi, int batches = 5);

// A number of time steps computed from a span and a rate, as an integer. Beyond kMaxSteps
// (1e15: months on the smallest packing) no run finishes, and the conversion would overflow:
// InputError "<what> needs N time steps, more than 1e15" instead.
inline constexpr double kMaxSteps = 1e15;
std::int64_t step_count(double steps, const std::string& what);

// Imposes the diagonal strain increment d_eps (compression positive, docs/physics.md section 5)
// in whole steps at constant D, the largest component advancing at `rate` (1/s) at most.
// Returns the number of steps. `rate_name` names the rate where more than kMaxSteps steps are
// refused (the key that set it).
std::int64_t impose_strain_increment(DemSystem& sys, const Eigen::Vector3d& d_eps, double rate,
                                     const std::string& rate_name = "this rate");

// A system from stored positions [N,3], radii [N] and cell lengths (e.g. a /states/<label>
// of a results file), at rest.
DemSystem system_from_positions(const Eigen::MatrixXd& positions, const std::vector<double>& radii,
                                const Eigen::Vector3d& lengths, const SystemOptions& options);

}  // namespace rendulic::dem
