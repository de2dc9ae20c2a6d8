// The common yardstick and the choice of model (docs/calibration.md "One yardstick" and "Model
// selection"). Every calibrated law is scored on the same blocks of data, each normalised by
// its data scale only (never by anything of the model), so that the numbers compare across
// laws: per state and envelope the stress response and, where the law predicts fabric, the
// fabric response; the main path's stress and fabric. Per block b with N_b residual components
// (two per Rendulic pair) the misfit m_b is the rms norm of (prediction - data) over the
// block's pairs divided by the block's data scale, and nu_b is the data's own noise on the same
// scale (a model-free estimate from the data's roughness).
//
// Likelihood: within a block the residual components are independent Gaussian with one
// standard deviation, sigma_b / sqrt(2) on the scale of the data, where sigma_b = max(m_b,
// nu_b): estimated from the residuals (its maximum-likelihood value) but never below the
// data's noise, so that fitting a block more closely than its noise earns nothing. Then
//   -2 ln L = sum_b N_b [ ln(pi sigma_b^2) + m_b^2 / sigma_b^2 ],
// over the fitted blocks, and the information criterion is BIC = -2 ln L + k ln N with k the
// number of free parameters and N = sum_b N_b. Calibration maximises this likelihood (the
// block weights N_b / sigma_b^2 are iterated to convergence), so the criterion is evaluated at
// its own optimum.
//
// Held-out score: the same per-block terms on the held-out states, summarised as the geometric
// mean of max(m_b, nu_b) weighted by N_b, exp(sum_b N_b ln max(m_b, nu_b) / sum_b N_b). Each
// block counts by its relative change, so that a block the data's noise dominates (a misfit
// near 1 for every law) cannot outweigh the others, as it would in an rms.
//
// Selection rule: among the laws that predict every block of the set, keep those whose
// held-out score is within `held_out_tolerance` (relative) of the best; among those, keep the
// ones whose BIC is within `bic_tolerance` of the lowest; select the one with the fewest free
// parameters (ties: the lower BIC). Done twice: on every block (laws without fabric cannot
// compete where the data have fabric) and on the stress blocks alone.
#pragma once

#include <limits>
#include <map>
#include <string>
#include <vector>

#include "rendulic/calibration/objective.hpp"

namespace rendulic::calibration {

// The six kinds of yardstick blocks: stress_elastic, stress_plastic, fabric_elastic,
// fabric_plastic (envelopes below 1e-4 and above), path_stress, path_fabric.
std::string yardstick_kind(const ResidualBlock& b);
const std::vector<std::string>& yardstick_kinds();
bool is_stress_kind(const std::string& kind);

// The options of the yardstick objective: every envelope (the linear response only at elastic
// amplitude), the path, unit weights, no features; `step` for the integrated predictions.
ObjectiveOptions yardstick_options(const models::StepOptions& step, bool path);

struct BlockScore {
  std::string id;  // "<state>/<envelope>/<kind>", or "path/<kind>"
  std::string state, envelope, kind;
  bool held_out = false;
  int components = 0;   // residual components: 2 per Rendulic pair
  double scale = 0.0;   // data scale (Pa for stress)
  double noise = 0.0;   // nu_b, relative to the scale
  double misfit = 0.0;  // m_b, relative to the scale
};

// -2 ln L of one block (the formula above).
double block_deviance(const BlockScore& b);

struct ModelScore {
  std::string model;
  int n_free = 0;
  std::vector<std::string> fitted_states, held_out_states;
  std::vector<BlockScore> blocks;  // yardstick blocks of the fitted and held-out states
};

enum class BlockSet { kAll, kStress };

struct SetScore {
  int n = 0;  // residual components of the fitted blocks
  double deviance = std::numeric_limits<double>::quiet_NaN();  // -2 ln L
  double bic = std::numeric_limits<double>::quiet_NaN();
  double fitted_misfit = std::numeric_limits<double>::quiet_NaN();  // sqrt(mean m_b^2)
  double held_out_misfit = std::numeric_limits<double>::quiet_NaN();
  double held_out_score = std::numeric_limits<double>::quiet_NaN();  // geometric mean (above)
  std::map<std::string, double> fitted_by_kind, held_out_by_kind;    // sqrt(mean m_b^2) per kind
  std::vector<std::string> ids;  // the fitted and held-out block ids scored
};

SetScore score_set(const ModelScore& m, BlockSet set);

struct SelectionRule {
  double bic_tolerance = 6.0;        // "strong" evidence (Kass and Raftery 1995) needed
  double held_out_tolerance = 0.10;  // relative to the best held-out misfit
  bool IsValid(std::string* why) const;
};

struct SelectionRow {
  std::string model;
  int n_free = 0;
  SetScore all, stress;
  bool covers_all = false;  // predicts every block of the union (fabric included)
  std::string note;         // why a law is not a candidate, if it is not
};

struct Selection {
  std::string selected;         // on every block ("" when no law qualifies)
  std::string selected_stress;  // on the stress blocks alone
  std::string sentence;         // which law this scene needs, and why (report.md)
  std::string rule;             // the rule in words
  std::vector<SelectionRow> rows;
};

// Laws whose fitted and held-out states differ from the majority's are left out (their
// numbers do not compare) with a note in their row.
Selection select_model(const std::vector<ModelScore>& models, const SelectionRule& rule = {});

}  // namespace rendulic::calibration
