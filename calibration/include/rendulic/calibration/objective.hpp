// The calibration objective (docs/calibration.md "Objectives, weights and normalisation"): one
// residual vector over the free parameters of a law, built from blocks
//   - envelope points: per state and envelope, the predicted minus measured Rendulic pair of
//     d_sigma (and, as a separate block, of d_F) for every probe direction;
//   - envelope features: the six numbers (centre c, matrix M) of the affine envelope
//     R(theta) = c + M u(theta) (core/affine_map.hpp), which carry the ellipse's axes,
//     inclination and shift; a projection of the points that ignores non-elliptic scatter
//     (for stress, and for fabric as "fabric_features" with weight_features * weight_fabric);
//   - the main path: predicted minus measured (iso, dev) pairs of stress and of fabric at the
//     measured eps_dev, from the undrained axisymmetric path of the law.
// Normalisation: every block is divided by its data scale (the rms norm of its measured pairs)
// and by sqrt(number of its residual pairs), then multiplied by sqrt(weight): each block counts
// with its weight, whatever its units (Pa or fabric) and its number of directions or samples.
//
// Parameters: a ParameterSpace picks the free parameters of the law (the others stay at fixed
// values) and maps them to unbounded-ish working coordinates z: log(p) for positive
// parameters whose bounds span two decades or more (moduli, rates), p itself otherwise. Bounds
// are kept in z. Prediction: envelopes of elastic amplitude are one evaluation of the rate law
// (exact for the incrementally linear response) for a law without a yield surface; larger
// probes, every probe of a law with a yield surface and the path are integrated with the
// models/ driver. The Jacobian is exact: Ceres Jets through the law's template and,
// for integrated predictions, through the driver's substeps (models/driver_core.hpp); central
// differences remain available (Derivatives::kCentral) as the independent check.
// Every block also carries a model-free estimate of the noise of its data (from the data's
// own roughness), which the likelihood of the model selection uses as a floor
// (docs/calibration.md "One yardstick").
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "rendulic/calibration/data.hpp"
#include "rendulic/models/driver.hpp"
#include "rendulic/models/law.hpp"

namespace rendulic::calibration {

struct FreeParameter {
  std::string name;
  int index = 0;       // in the law's parameter_info()
  bool log = false;    // z = log(p) when true, z = p otherwise
  double lower = 0.0;  // search bounds (physical units)
  double upper = 0.0;
};

class ParameterSpace {
 public:
  // `values` is the law's full parameter vector (fixed values and the start of the free ones);
  // `free` names the free parameters; `bounds` narrows their search boxes (within the law's
  // bounds). Throws InputError on an unknown name, a duplicate, or a box outside the bounds.
  ParameterSpace(const models::Law& law, const std::vector<double>& values,
                 const std::vector<std::string>& free,
                 const std::map<std::string, std::pair<double, double>>& bounds = {});

  int size() const { return static_cast<int>(free_.size()); }
  const std::vector<FreeParameter>& free() const { return free_; }
  const std::vector<double>& base() const { return base_; }
  std::vector<std::string> names() const;

  // Full parameter vector for working coordinates z (the fixed ones from base()).
  template <typename T>
  void full(const T* z, T* p) const {
    for (std::size_t i = 0; i < base_.size(); ++i) p[i] = T(base_[i]);
    for (std::size_t k = 0; k < free_.size(); ++k) {
      using std::exp;
      p[free_[k].index] = free_[k].log ? T(exp(z[k])) : z[k];
    }
  }
  std::vector<double> full(const std::vector<double>& z) const;
  std::vector<double> to_z(const std::vector<double>& full_values) const;
  double z_lower(int k) const;
  double z_upper(int k) const;
  // dp/dz of free parameter k at z.
  double dp_dz(int k, double z) const;

 private:
  std::vector<double> base_;
  std::vector<FreeParameter> free_;
};

enum class Prediction { kAuto, kRate, kIntegrated };
enum class Derivatives { kExact, kCentral };

struct ObjectiveOptions {
  bool envelope_points = true;
  bool envelope_features = false;
  bool path = true;  // used when the data has a path
  // Which envelopes enter: elastic ones (amplitude < 1e-4) and larger, elasto-plastic ones.
  bool elastic_envelopes = true;
  bool plastic_envelopes = true;
  // A linear-response envelope above the elastic amplitude is the elastic one scaled (no
  // contact opens, closes or slides): it repeats the elastic data and is not elasto-plastic
  // data, so it is left out.
  bool linear_response_elastic_only = true;
  // Block weights (see the file comment); 0 drops a block.
  double weight_stress = 1.0;
  double weight_fabric = 1.0;
  double weight_features = 1.0;
  double weight_path_stress = 1.0;
  double weight_path_fabric = 1.0;
  // Fabric blocks are skipped for laws that carry no fabric (hypoplastic_wu) and where the
  // measured fabric response is below this scale (nothing to fit, and its scale would divide
  // by ~0).
  double fabric_scale_min = 1e-14;
  // kAuto: rate evaluation for elastic amplitudes (< 1e-4) of a law without a yield surface
  // (and of a UMAT, which cannot say), integration otherwise: a small elastic range can make a
  // 5e-5 probe plastic (docs/calibration.md "Predictions and derivatives").
  Prediction prediction = Prediction::kAuto;
  Derivatives derivatives = Derivatives::kExact;
  // Driver settings for integrated predictions. The driver's local tolerance 1e-6 (relative
  // to the stress) puts the error of a 2e-3 probe response near 1e-5 of the response, far
  // below the noise of DEM envelopes (docs/calibration.md "Predictions and derivatives"); with
  // central differences use 1e-10, which their relative step 1e-6 needs.
  // A prediction that needs more than 1000 substeps fails (an infinite cost), which keeps trial
  // points where the law is stiff cheap. A fit may end on that limit: calibrate() warns when its
  // optimum needs half of it or more (DriverLoad), and calibration.max_substeps sets it.
  // kAuto integrates a law without a yield surface with the third-order pair, which needs ~20x
  // fewer substeps there: with modified Euler the limit had kept quick.toml's hypoplastic_wu
  // fit out of its better basin (docs/calibration.md "Predictions and derivatives").
  models::StepOptions step = [] {
    models::StepOptions s;
    s.tolerance = 1e-6;
    s.max_substeps = 1000;
    s.scheme = models::Scheme::kAuto;
    return s;
  }();
  bool IsValid(std::string* why) const;
};

// The integrated prediction that takes the driver the most substeps at a parameter vector
// (Objective::driver_load): a fit whose optimum sits where one needs nearly all of
// ObjectiveOptions::step.max_substeps may have ended on that limit (trial points beyond fail),
// not at the data's optimum (docs/calibration.md "When to stop").
struct DriverLoad {
  bool ok = true;     // false: some prediction could not be integrated
  int substeps = 0;   // accepted + rejected substeps of that prediction (0: none integrated)
  int limit = 0;      // the driver's cap, ObjectiveOptions::step.max_substeps
  std::string where;  // "the probe at theta = 290.264 deg of state e's envelope dynamic_0.02"
};

// The objective's evaluations since it was built (Objective::tally): each call of residuals(),
// jacobian() or a cost function's Evaluate (Ceres's trial points and Jacobians, NLopt's points,
// each central difference) is one. Trial points that fail on the driver's substep limit count
// as an infinite cost, which steers a fit away from them: calibrate() says how many there were
// (docs/calibration.md "When to stop").
struct EvaluationTally {
  long evaluations = 0;
  long failed = 0;  // the law could not be evaluated (any reason)
  // Of those, the ones whose first failing part, in the evaluation's order, needed more than
  // step.max_substeps (the same on any number of threads).
  long failed_on_limit = 0;
};

// One block of the residual vector, for reports and for per-state errors.
struct ResidualBlock {
  std::string state;  // label, or "path"
  std::string kind;   // "stress", "fabric", "features", "path_stress", "path_fabric"
  std::string envelope;
  double amplitude = 0.0;  // of the envelope; 0 for the path
  int offset = 0;
  int size = 0;
  double scale = 1.0;  // data scale (Pa for stress, 1 for fabric)
  double weight = 1.0;
  bool integrated = false;
  // Model-free noise of the block's data, as a relative rms pair norm (the units of the
  // misfit): from the second differences of the data around their own smooth curve.
  double noise = 0.0;
};

// Where a stream of evaluations (one optimiser's run: a Ceres fit, NLopt's points) last failed:
// the part (-1 the path, k the k-th envelope task; -2 none) and the probe. The stream's next
// evaluations start there, so that a trial point failing where the last one did fails before
// the other predictions are integrated. Each stream keeps its own: the order, and with it
// which failure a failed evaluation reports (EvaluationTally::failed_on_limit), then depends
// on no other stream's timing (docs/calibration.md "When to stop").
struct FailureHint {
  int part = -2;
  int probe = 0;
};

class Objective {
 public:
  // Throws InputError: unknown law, a state label not in `data`, nothing to fit.
  Objective(std::string law_name, const CalibrationData& data,
            const std::vector<std::string>& states, ParameterSpace space,
            const ObjectiveOptions& options = {});
  ~Objective();
  Objective(Objective&&) noexcept;

  const std::string& law_name() const;
  const ParameterSpace& space() const;
  const std::vector<ResidualBlock>& blocks() const;
  int num_residuals() const;
  int num_parameters() const;
  bool exact_derivatives() const;  // Jacobian by Jets (else central differences)
  bool integrated() const;         // some prediction goes through the driver

  // Residuals at working coordinates z; false where the law cannot be evaluated (inadmissible
  // state, driver failure): back ends treat that as an infinite cost. With `hint`, the
  // evaluation starts where the hint's stream last failed and updates it; without, it starts
  // at the first part.
  bool residuals(const double* z, double* r, FailureHint* hint = nullptr) const;
  // Residuals and the Jacobian dr/dz (Jets or central differences: exact_derivatives()).
  bool jacobian(const double* z, Eigen::VectorXd* r, Eigen::MatrixXd* J) const;
  // A Ceres cost function over the one parameter block z (the caller's problem owns it).
  ceres::CostFunction* make_cost_function() const;

  // Model envelope at the state of `state` for the probe set of `probes`, with full parameter
  // vector p. The returned data has stress and fabric filled in; ok=false on a model failure.
  EnvelopeRecord predict_envelope(const std::vector<double>& p, const StateData& state,
                                  const EnvelopeRecord& probes, bool* ok) const;
  // The law's undrained path from the data's first path row, at the data's eps_dev (signed);
  // false without a path or on a model failure.
  bool predict_path(const std::vector<double>& p, PathData* out) const;
  // Over the fitted states' integrated predictions and the path, at full parameter vector p:
  // the one that needs the driver's most substeps (a UMAT: substeps 0, not counted).
  DriverLoad driver_load(const std::vector<double>& p) const;
  // Evaluations so far (thread-safe: the fit's two starts share the objective).
  EvaluationTally tally() const;
  // Where and why the last failed evaluation failed, if the law says (a UMAT: "state 'a',
  // probe 3: the UMAT returned NaN or inf in STRESS ..."); "" for the built-in laws.
  std::string failure() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

// Default free parameters of a law for calibration with `n_states` states (docs/calibration.md):
// moduli and the anisotropy coupling always; pressure and fabric dependence of the moduli
// (n_p, a_G) only from three states on; p_ref never (it is a unit of pressure, degenerate with
// B and G: it is fixed at the median pressure of the states instead).
std::vector<std::string> default_free_parameters(const std::string& law_name, int n_states,
                                                 bool has_path, bool has_plastic);

}  // namespace rendulic::calibration
