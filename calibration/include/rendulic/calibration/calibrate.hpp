// The two-level calibration of docs/calibration.md "Two levels":
//  1. per state, model-free: B, G, A of the symmetric Rendulic stiffness from the elastic
//     envelope (stiffness.hpp), shift and thinning from the elasto-plastic one;
//  2. across states: the law's free parameters (state dependence of the moduli, anisotropy
//     coupling, evolution parameters beta_F, F_dev_max, ...) against every envelope of the
//     fitted states and the main path together, started from the level-1 numbers (median
//     moduli, beta_A by regression of A on F_dev B, c_F by regression of the fabric response),
//     with p_ref fixed at the median pressure of the fitted states;
// then uncertainty and identifiability at the optimum, and the held-out check: states listed
// in `holdout` are not fitted but predicted, and their misfit is reported beside the fitted one.
// The fit maximises the likelihood of selection.hpp (block weights iterated to convergence);
// a poor local fit is restarted from NLopt's global search; every law is then scored on the
// common yardstick of selection.hpp, so that laws compare.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rendulic/calibration/data.hpp"
#include "rendulic/calibration/objective.hpp"
#include "rendulic/calibration/selection.hpp"
#include "rendulic/calibration/solver.hpp"
#include "rendulic/calibration/stiffness.hpp"

namespace rendulic::calibration {

struct CalibrationOptions {
  std::string model;
  // States predicted, not fitted; {"auto"}: default_holdout() of the data.
  std::vector<std::string> holdout;
  std::vector<std::string> free;         // empty: default_free_parameters()
  std::map<std::string, double> values;  // start values of free / values of fixed parameters
  std::map<std::string, std::pair<double, double>> bounds;  // search boxes of free parameters
  bool level_one_start = true;  // start (and p_ref) from the per-state numbers
  // Elastic laws (isotropic_elastic, anisotropic_elastic) cannot describe the shift of
  // elasto-plastic envelopes or the non-linear main path. true: fit them to the elastic
  // envelopes only (a note in the warnings says so). By default they are fitted to every block
  // like the others: the likelihood lets a block a law cannot follow carry little weight, and
  // the selection compares every law on the same blocks.
  bool elastic_laws_use_elastic_data_only = false;
  // Maximum likelihood (selection.hpp; SolverOptions::likelihood): the block weights
  // N_b / sigma_b^2 follow the fit. false: least squares with the weights of `objective`
  // (every block counts with its weight).
  bool likelihood_weights = true;
  // A local fit that is poor (stopped by its budget or failed, a stress envelope predicted
  // worse than by no response, or a free parameter without effect on the data while a stress
  // envelope is still off by more than three times its noise) is repeated from
  // NLopt's global search (GN_CRS2_LM over the box, then BOBYQA, then Levenberg-Marquardt) with
  // this many evaluations; the better fit is kept (CalibrationSummary::global_start says).
  bool global_start = true;
  int global_start_evaluations = 400;
  ObjectiveOptions objective;
  SolverOptions solver;
  bool IsValid(std::string* why) const;
};

struct StateSummary {
  std::string label;
  bool held_out = false;
  double pressure = 0.0;  // Pa
  double f_dev = 0.0;     // signed fabric deviator (docs/physics.md section 3)
  double eps_dev = 0.0, volume_fraction = 0.0;
  bool has_elastic = false, has_plastic = false;
  RendulicStiffness elastic;  // level 1 from the data
  PlasticFeatures plastic;    // level 1 from the data
  // The same estimators applied to the fitted law's predicted envelopes at this state.
  bool has_model = false;
  RendulicStiffness model_elastic;
  PlasticFeatures model_plastic;
  // Relative rms misfit of this state's blocks at the fitted parameters:
  // sqrt(sum r^2 / sum w) = rms of (prediction - data) / data scale.
  double misfit = 0.0;
  std::vector<EnvelopeRecord> predicted;  // model envelopes for the data's probe sets
};

struct CalibrationSummary {
  std::string model;
  std::vector<std::string> param_names;  // every parameter of the law
  std::vector<std::string> param_units;  // their units, from the law's parameter table
  std::vector<bool> free_mask;
  std::vector<std::string> fitted_states, held_out_states;
  FitResult fit;
  std::vector<ResidualBlock> blocks;
  std::vector<StateSummary> states;
  // Relative rms misfit over the yardstick blocks the law predicts, fitted and held out.
  double fitted_misfit = 0.0;
  std::optional<double> held_out_misfit;
  double path_misfit = -1.0;  // relative rms of the path blocks; < 0 when not fitted
  std::vector<std::string> warnings;
  ModelScore score;          // on the common yardstick (fitted_misfit, held_out_misfit: its own)
  PathData predicted_path;   // the fitted law's undrained path (empty without path data)
  std::string global_start;  // "not needed", or "used (why): costs"
  // The objective's evaluations over the fit (local, global start, uncertainty): how many
  // failed, and how many on the driver's substep limit (a warning says so).
  EvaluationTally evaluations;
  std::vector<std::string> at_bound;      // free parameters on a bound of their box
  std::vector<std::string> undetermined;  // stderr infinite or above half the value
  // k* of the data (Pa): the model envelopes are stored starred like the DEM's (0: in Pa).
  double k_star = 0.0;
  std::string BriefReport() const;
};

// Throws InputError on bad input (unknown model, state, parameter; nothing to fit).
CalibrationSummary calibrate(const CalibrationData& data, const CalibrationOptions& options);

// The states held out by default: with three states or more, ordered along the path (|eps_dev|),
// every second one strictly inside (five states a..e: b and d), so that the held-out check
// interpolates between fitted states; none with fewer than three.
std::vector<std::string> default_holdout(const CalibrationData& data);

// The law `model` with the full parameter vector `params` scored on the common yardstick
// (selection.hpp) over the fitted and the held-out states (the path with the fitted ones);
// n_free is what the information criterion counts. calibrate() fills
// CalibrationSummary::score with it; it also scores parameters from elsewhere.
ModelScore yardstick_score(const CalibrationData& data, const std::string& model,
                           const std::vector<double>& params, int n_free,
                           const std::vector<std::string>& fitted,
                           const std::vector<std::string>& held_out,
                           const models::StepOptions& step = ObjectiveOptions{}.step);

// Level one only (no law): per-state stiffness and plastic features of every state.
std::vector<StateSummary> per_state_analysis(const CalibrationData& data);

}  // namespace rendulic::calibration
