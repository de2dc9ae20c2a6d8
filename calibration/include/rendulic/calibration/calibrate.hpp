// The two-level calibration of models.md "Calibration" (docs/calibration.md):
//  1. per state, model-free: B, G, A of the symmetric Rendulic stiffness from the elastic
//     envelope (stiffness.hpp), shift and thinning from the elasto-plastic one;
//  2. across states: the law's free parameters (state dependence of the moduli, anisotropy
//     coupling, evolution parameters beta_F, F_dev_max, ...) against every envelope of the
//     fitted states and the main path together, started from the level-1 numbers (median
//     moduli, beta_A by regression of A on F_dev B, c_F by regression of the fabric response),
//     with p_ref fixed at the median pressure of the fitted states;
// then uncertainty and identifiability at the optimum, and the held-out check: states listed
// in `holdout` are not fitted but predicted, and their misfit is reported beside the fitted one.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rendulic/calibration/data.hpp"
#include "rendulic/calibration/objective.hpp"
#include "rendulic/calibration/solver.hpp"
#include "rendulic/calibration/stiffness.hpp"

namespace rendulic::calibration {

struct CalibrationOptions {
  std::string model;
  std::vector<std::string> holdout;      // states predicted, not fitted
  std::vector<std::string> free;         // empty: default_free_parameters()
  std::map<std::string, double> values;  // start values of free / values of fixed parameters
  std::map<std::string, std::pair<double, double>> bounds;  // search boxes of free parameters
  bool level_one_start = true;  // start (and p_ref) from the per-state numbers
  // Elastic laws (isotropic_elastic, anisotropic_elastic) cannot describe the shift of
  // elasto-plastic envelopes or the non-linear main path; by default they are fitted to the
  // elastic envelopes only (a note in the warnings says so). false: use what `objective` says.
  bool elastic_laws_use_elastic_data_only = true;
  ObjectiveOptions objective;
  SolverOptions solver;
  bool IsValid(std::string* why) const;
};

struct StateSummary {
  std::string label;
  bool held_out = false;
  double pressure = 0.0;  // Pa
  double f_dev = 0.0;     // signed fabric deviator (physics.md 3)
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
  std::vector<EnvelopeData> predicted;  // model envelopes for the data's probe sets
};

struct CalibrationSummary {
  std::string model;
  std::vector<std::string> param_names;  // every parameter of the law
  std::vector<bool> free_mask;
  std::vector<std::string> fitted_states, held_out_states;
  FitResult fit;
  std::vector<ResidualBlock> blocks;
  std::vector<StateSummary> states;
  double fitted_misfit = 0.0;  // relative rms over all fitted blocks
  std::optional<double> held_out_misfit;
  double path_misfit = -1.0;  // relative rms of the path blocks; < 0 when not fitted
  std::vector<std::string> warnings;
  std::string BriefReport() const;
};

// Throws InputError on bad input (unknown model, state, parameter; nothing to fit).
CalibrationSummary calibrate(const CalibrationData& data, const CalibrationOptions& options);

// Level one only (no law): per-state stiffness and plastic features of every state.
std::vector<StateSummary> per_state_analysis(const CalibrationData& data);

}  // namespace rendulic::calibration
