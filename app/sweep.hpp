// The speed-versus-accuracy sweep of the probe methods (docs/physics.md section 5,
// docs/accuracy.md). From the first relaxed state of a scenario's own protocol (gas, nu0,
// isotropic loading to nu_max, undrained path to the first states.eps_dev, relaxation), one
// factor at a time is varied around the scenario's settings: the DEM time-step factor, the
// number of particles N, the probes' inertial number (loading rate), the relaxation threshold
// of the dynamic probes, and the method (dynamic, minimisation, linear response). Every setting
// gives an elastic envelope over a fixed set of directions (the method and inertial-number
// points also the elasto-plastic one), compared with a converged reference of the same state:
//  - elastic: the linear response of that state (exact in the small-strain limit);
//  - elasto-plastic: the minimisation probes (quasi-static, rate-free) of that state.
// The error of an envelope is max over directions of |d_sigma* - d_sigma*_ref| / a_ref
// (a_ref: the reference's fitted semi-major axis); the fitted features (axes, inclination,
// centre) are compared too. Costs are the wall and CPU time of making the envelope.
// The path's rate (factor path_rate) is swept on its own: from the isotropic state at nu_max
// the undrained path runs at each rate, and its steady-state stress ratio |sigma_dev|/P (the
// mean over the steady-state window with its batch-means standard error, protocols.hpp) is
// compared with the run 4x slower; the fastest rate within 2 % of it is quasi-static.
// Settings that cannot run are reported, never crashed on: a time step beyond the engine's
// stability bound is "refused" (the engine's own check), a run whose energy grows is
// "diverged", any other failure "failed" with the message.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "rendulic/core/result_paths.hpp"
#include "rendulic/core/results.hpp"
#include "rendulic/core/scenario.hpp"

namespace rendulic::app {

// Factors of the sweep, in the order they run.
// dt_factor_tight: the time-step series again at the relaxation threshold tight_relax, where
// the relaxation no longer hides the integrator's own error.
inline const std::vector<std::string> kSweepFactors = {
    "dt_factor",       "n_particles", "inertial_number", "relax",
    "dt_factor_tight", "method",      "path_rate"};

struct SweepOptions {
  bool quick = false;  // the small variant (system test): N 250, 8 directions, few values
  std::vector<std::string> factors = kSweepFactors;
  int threads = 0;  // OpenMP threads of the probe teams; 0: OpenMP's default
  // An envelope meets the accuracy target when its error, and the relative errors of both
  // fitted semi-axes, are at most this.
  double target = 0.02;
  // Filled from `quick` by SweepOptions::preset(); may be edited afterwards.
  int base_n = 1000;
  int directions = 0;  // 0: the scenario's probes.directions
  std::vector<double> dt_factors, n_particles, inertial_numbers, relax_thresholds;
  std::vector<double> path_rates;  // 1/s (path.rate), each run from the same isotropic state
  double path_rate_target = 0.02;  // steady-state ratio within this of the run 4x slower
  int path_seeds = 1;  // independent packings (seeds run.seed, run.seed + 1, ...) per rate
  std::vector<std::string> methods{kProbeMethods.begin(), kProbeMethods.end()};
  double tight_relax = 1e-9;  // the threshold of the dt_factor_tight series
  static SweepOptions preset(bool quick);
  bool IsValid(std::string* why) const;
};

// The state one N is probed from.
struct SweepState {
  int n_particles = 0;
  double volume_fraction = 0, pressure_star = 0, eps_dev = 0, coordination = 0;
  double prepare_wall_s = 0, prepare_cpu_s = 0;
  // The linear-response (elastic reference) features of this state's stress envelope.
  double ref_major = 0, ref_minor = 0, ref_inclination_deg = 0;
};

struct SweepPoint {
  std::string factor;                // one of kSweepFactors
  double value = 0;                  // the factor's value (method points: 0)
  std::string method;                // dynamic | minimisation | linear_response
  std::string envelope = "elastic";  // elastic | plastic
  // ok | refused (beyond the stability bound) | diverged | failed
  std::string status = "ok";
  std::string note;
  int n_particles = 0;
  double dt_factor = 0, inertial_number = 0, relax = 0, amplitude = 0;
  double wall_s = 0, cpu_s = 0;  // making the envelope (reference relaxation included)
  double error = 0;              // max_p |d_sigma*_p - ref_p| / a_ref
  double error_rms = 0;
  double major = 0, minor = 0, inclination_deg = 0;  // fitted stress-envelope features
  double center_x = 0, center_y = 0;
  double err_major = 0, err_minor = 0;  // relative to the reference's axes
  double err_inclination_deg = 0;       // |difference| modulo 180
  double err_center = 0;                // |c - c_ref| / a_ref
  double converged_fraction = 1;        // probes that met their stopping rule
  double steps_per_probe = 0;           // dynamic: DEM steps (loading + relaxation)
  // dynamic: steps relaxing the given state to the probes' threshold first (once per
  // envelope, serial; part of cpu_s)
  double reference_relax_steps = 0;
  bool meets_target = false;
  bool pareto = false;  // on the error-cost Pareto front of the elastic points
  std::vector<double> theta_deg;
  std::vector<double> stress_star_x, stress_star_y;  // the envelope (status ok)
};

// One run of the undrained path (factor path_rate).
struct PathRatePoint {
  double rate = 0;             // 1/s (D_xx)
  double inertial_number = 0;  // mean over the steady-state window, at the samples' pressure
  // Steady-state |sigma_dev| / P: mean over the seeds, and its standard error (the spread of
  // the seeds' means; with one seed, its batch-means error).
  double ratio = 0, ratio_stderr = 0;
  std::vector<double> ratio_per_seed, ratio_stderr_per_seed;
  int window_samples = 0;
  std::int64_t steps = 0;
  double wall_s = 0, cpu_s = 0;
  // Against the run at rate / 4 when it was swept (else has_slower = false):
  bool has_slower = false;
  double change_4x = 0;    // |ratio - ratio(rate/4)| / ratio(rate/4)
  bool converged = false;  // change_4x <= path_rate_target
  std::string status = "ok", note;
};

struct SweepSummary {
  SweepOptions options;
  std::string scenario_toml;
  double elastic_amplitude = 0, plastic_amplitude = 0;
  double stability_limit_factor = 0;  // the engine's bound on dt / t_c
  std::vector<SweepState> states;
  std::vector<SweepPoint> points;
  std::vector<PathRatePoint> path_points;  // by decreasing rate
  // One line per finding of where a method breaks (refused or diverged steps, the noise floor
  // of the relaxation, rate effects, the linear response at plastic amplitudes).
  std::vector<std::string> breaks;
  // The cheapest value of each factor that meets the target, the others at their defaults.
  std::vector<std::string> recommendations;
  double wall_s = 0, cpu_s = 0;
};

using SweepProgress = std::function<void(const std::string&)>;

// Checks the options and the scenario (the same rules as run_sweep) without simulating.
void check_sweep_inputs(const Scenario& scenario, const SweepOptions& options);
// Runs the sweep. InputError on invalid options or scenario (before any simulation).
SweepSummary run_sweep(const Scenario& scenario, const SweepOptions& options,
                       const SweepProgress& progress = {});

// Marks the Pareto front (error, cpu_s) among the elastic points with status ok, the
// reference method (linear response) left out: a point is on it when no other point is at
// most as costly and at most as wrong, and strictly better in one.
void mark_pareto(std::vector<SweepPoint>& points);
// Fills summary.breaks and summary.recommendations from the points.
void describe_breaks(SweepSummary& summary);

// Fills change_4x and converged of each path point from the point at a quarter of its rate.
void compare_path_rates(std::vector<PathRatePoint>& points, double target);

// sweep.h5 (docs/results.md "Sweep file") through the atomic writer, and sweep.csv.
void write_sweep_h5(const SweepSummary& summary, ResultsWriter& out);
std::string sweep_csv(const SweepSummary& summary);
// The path_rate points, one row each (sweep_path.csv; empty when none was swept).
std::string sweep_path_csv(const SweepSummary& summary);

}  // namespace rendulic::app
