// Back ends behind the one Objective (docs/calibration.md "Back
// ends"): all minimise 0.5 |r(z)|^2 inside the bounds of the ParameterSpace.
//   kCeres      Levenberg-Marquardt (Ceres), bounds as box constraints; Jacobian by autodiff
//               (through the driver for integrated predictions) or central differences
//               (Objective::exact_derivatives()). Fast and precise, local.
//   kMultiStart Ceres from the given start and from `starts - 1` points drawn uniformly in
//               the (working-coordinate) box; the best wins. Local minima, cheap insurance.
//   kGlobal     NLopt global stage (GN_CRS2_LM by default, or GN_ISRES, GN_MLSL_LDS) over the
//               box, then the local derivative-free LN_BOBYQA from its best point, then a Ceres
//               polish for full precision and the Jacobian. For non-smooth laws, plateaus and
//               poor starts.
//   kLocalNlopt LN_BOBYQA alone from the start (derivative-free, local), then Ceres polish.
// Every result carries the uncertainty of uncertainty.hpp at its optimum.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "rendulic/calibration/objective.hpp"
#include "rendulic/calibration/uncertainty.hpp"

namespace rendulic::calibration {

enum class Backend { kCeres, kMultiStart, kGlobal, kLocalNlopt };
std::string to_string(Backend b);
Backend backend_from_string(const std::string& name);  // InputError on an unknown name

// Ceres's function tolerance for DEM data (the `run` stage and `rendulic calibrate`). With
// exact derivatives through the driver, Levenberg-Marquardt on DEM data stops by its gradient
// or parameter tolerance; the function tolerance is only a backstop against a crawl (an
// iteration that lowers the cost by less than 1e-16 of it, i.e. not at all). It used to be 1e-3,
// when central differences through the driver left the fits crawling (docs/calibration.md "When to
// stop").
inline constexpr double kDemFunctionTolerance = 1e-16;
// Gradient tolerance for DEM data, relative to the cost at the start: the gradient (per unit
// of the working coordinates, i.e. per e-fold change of a log parameter) is 1e-8 of that cost.
inline constexpr double kDemGradientTolerance = 1e-8;

struct SolverOptions {
  Backend backend = Backend::kCeres;
  std::string global_algorithm = "GN_CRS2_LM";  // or GN_ISRES, GN_MLSL_LDS
  int global_evaluations = 3000;
  int local_evaluations = 2000;
  int starts = 8;  // kMultiStart
  std::uint64_t seed = 20261121;
  int max_iterations = 200;  // Ceres
  // Ceres tolerances: tight, because noiseless model data must be recovered to 1e-6. The
  // parameter tolerance is relative to |z| (working coordinates): 1e-8 stops once the
  // parameters move by less than ~1e-8 of themselves, far inside any standard error and above
  // the objective's own noise (the driver's tolerance), which would otherwise keep rejecting
  // steps.
  // The gradient tolerance is relative to the cost at the start (max-norm of the gradient in
  // working coordinates).
  double function_tolerance = 1e-15;
  double gradient_tolerance = 1e-15;
  double parameter_tolerance = 1e-8;
  // Minimise -2 ln L of selection.hpp (each block's variance profiled, never below the data's
  // noise) instead of 0.5 |r|^2: one Ceres block per block (likelihood_block_model), the block
  // weights updated at every iteration; the standard errors are those of the block-weighted
  // problem at the optimum.
  bool likelihood = false;
  bool polish = true;     // Ceres after the NLopt stages
  bool progress = false;  // Ceres prints one line per iteration (cost, step) to stdout
  // Cores the fit may use (0: all): the likelihood's two starts side by side and the exact
  // Jacobian's passes on a free core (docs/calibration.md "Threads"); 1 runs everything on the
  // caller's thread. The results do not depend on it.
  int threads = 0;
  IdentifiabilityOptions identifiability;
  bool IsValid(std::string* why) const;
};

struct FitResult {
  std::vector<std::string> names;  // free parameters
  std::vector<double> z;           // working coordinates at the optimum
  std::vector<double> values;      // free parameter values
  std::vector<double> stderr_;     // 1-sigma, physical units (+inf where undetermined)
  std::vector<double> params;      // the law's full parameter vector
  Eigen::MatrixXd correlation;
  Uncertainty uncertainty;
  double cost = 0.0;  // 0.5 |r|^2 at the optimum (0.5 sum_b rho_b with the likelihood)
  double rms = 0.0;   // sqrt(|r|^2 / n): normalised rms misfit (1 = data-scale misfit)
  bool converged = false;
  std::string backend;
  std::string jacobian;  // "autodiff" or "numeric (central differences)"
  std::string report;    // one paragraph: stages, evaluations, termination
  // What stopped the final Levenberg-Marquardt stage: "gradient", "parameter" or "function"
  // (its tolerances), "budget" (max_iterations, or NLopt's evaluations without a polish),
  // "failure" (the model could not be evaluated).
  std::string termination;
  std::vector<std::string> at_bound;  // free parameters held on a bound of their box
  int evaluations = 0;                // objective evaluations (NLopt stages) + Ceres iterations
  double seconds = 0.0;
};

// z0: start in working coordinates (ParameterSpace::to_z). Never throws on a model failure;
// converged = false and `report` says why.
FitResult solve(const Objective& objective, const std::vector<double>& z0,
                const SolverOptions& options = {});

// One block of the likelihood (SolverOptions::likelihood) as Levenberg-Marquardt sees it: the
// block's m residuals r and its m x p Jacobian J (row-major; may be null) become, in place,
// residuals of norm sqrt(rho(s)) along r, s = |r|^2, and the Jacobian
// sqrt(rho') [J - (1 - beta) rhat (rhat^T J)], beta = sqrt(rho' s / rho). The cost rho / 2 and
// its gradient rho' J^T r are exact; the model's curvature along the block's own residual is
// rho' beta^2 (beta^2 = 1 / (ln x + 1) where the block's sigma is profiled, x = s / floor2),
// the least a sum of squares with that cost and gradient can have. Below the noise floor
// (x < 1, rho linear in s) a plain scaling by sqrt(rho'). n: the block's components N_b;
// floor2: its weighted noise floor w nu_b^2 (docs/calibration.md "The likelihood's curvature").
void likelihood_block_model(double n, double floor2, int m, int p, double* r, double* J);

// 0.5 |r|^2 at z (+inf where the model fails).
double objective_cost(const Objective& objective, const std::vector<double>& z,
                      FailureHint* hint = nullptr);

// Ceres reports a failed evaluation (a law that cannot integrate a trial point) through glog
// at ERROR level whatever its logging_type says: a raw line on stderr that reads like a
// failure of the run while the fit goes on and reports its own termination. Call once at
// start-up, before any thread (the executable's main, the Python module's import): glog then
// prints fatal messages only. Ceres's progress (--progress) goes to stdout and still shows.
void quiet_solver_logging();

}  // namespace rendulic::calibration
