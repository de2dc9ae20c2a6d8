// Back ends behind the one Objective (models.md "Calibration"; docs/calibration.md "Back
// ends"): all minimise 0.5 |r(z)|^2 inside the bounds of the ParameterSpace.
//   kCeres      Levenberg-Marquardt (Ceres), bounds as box constraints; Jacobian by autodiff
//               or central differences (Objective::autodiff()). Fast and precise, local.
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

// Ceres's function tolerance for DEM data (the `run` stage and `rendulic calibrate`): stop when
// an iteration lowers the cost by less than 0.1 %. The integrated laws' objectives are not
// smooth (loading/unloading switches), so after the first few iterations Levenberg-Marquardt
// crawls (trust-region ratio ~1e-2). Measured on quick.toml's elastoplastic_fabric fit: 21 s
// instead of 918 s for 200 iterations, cost 0.4 % higher, every parameter within 0.44 of its
// standard error of the long fit (docs/calibration.md).
inline constexpr double kDemFunctionTolerance = 1e-3;

struct SolverOptions {
  Backend backend = Backend::kCeres;
  std::string global_algorithm = "GN_CRS2_LM";  // or GN_ISRES, GN_MLSL_LDS
  int global_evaluations = 3000;
  int local_evaluations = 2000;
  int starts = 8;  // kMultiStart
  std::uint64_t seed = 20261121;
  int max_iterations = 200;  // Ceres
  // Ceres tolerances: tight, because noiseless model data must be recovered to 1e-6.
  double function_tolerance = 1e-15;
  double gradient_tolerance = 1e-15;
  double parameter_tolerance = 1e-12;
  bool polish = true;     // Ceres after the NLopt stages
  bool progress = false;  // Ceres prints one line per iteration (cost, step) to stdout
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
  double cost = 0.0;  // 0.5 |r|^2 at the optimum
  double rms = 0.0;   // sqrt(|r|^2 / n): normalised rms misfit (1 = data-scale misfit)
  bool converged = false;
  std::string backend;
  std::string jacobian;  // "autodiff" or "numeric (central differences)"
  std::string report;    // one paragraph: stages, evaluations, termination
  int evaluations = 0;   // objective evaluations (NLopt stages) + Ceres iterations
  double seconds = 0.0;
};

// z0: start in working coordinates (ParameterSpace::to_z). Never throws on a model failure;
// converged = false and `report` says why.
FitResult solve(const Objective& objective, const std::vector<double>& z0,
                const SolverOptions& options = {});

// 0.5 |r|^2 at z (+inf where the model fails).
double objective_cost(const Objective& objective, const std::vector<double>& z);

}  // namespace rendulic::calibration
