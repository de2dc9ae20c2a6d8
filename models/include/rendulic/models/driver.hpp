// Material-point driver (docs/models.md "Material-point driver"; a step is plain data:
// docs/architecture.md "Design choices"): integrates a Law over one strain increment with
// sub-stepping, either
// - kModifiedEuler: Heun's method with the embedded forward-Euler error estimate and automatic
//   substep control (Sloan 1987; Sloan, Abbo and Sheng 2001): a substep is accepted when the
//   local relative error estimate R = |y_heun - y_euler| / |y| is below `tolerance`;
// - kBogackiShampine: the third-order Runge-Kutta pair of Bogacki and Shampine (1989) under
//   the same control, its embedded second-order solution giving R (adaptive only): for a
//   smooth law such as hypoplastic_wu 5-10x fewer rate evaluations at the same global error;
//   across a yield surface no cheaper than modified Euler (docs/models.md "Tolerance");
// - kAuto: Bogacki-Shampine for a law without a yield surface (yield_function -inf at the
//   start), modified Euler for one with it: the calibration's default (adaptive only);
// - kExplicitEuler: the plain explicit scheme with a fixed number of substeps, kept so that its
//   failures can be shown: the same error estimate is computed (one extra rate evaluation per
//   substep) and the result says whether it exceeded the tolerance.
// Mixed control: stress-controlled Mandel components are solved by Newton iterations with the
// law's tangent. Nothing here throws: every call returns success or a reason.
#pragma once

#include <array>
#include <string>

#include "rendulic/models/law.hpp"

namespace rendulic::models {

enum class Scheme { kModifiedEuler, kExplicitEuler, kBogackiShampine, kAuto };
// The schemes' names on the command line and in scenario keys, in the enum's order.
inline constexpr std::array<const char*, 4> kSchemeNames = {"modified-euler", "explicit",
                                                            "bogacki-shampine", "auto"};
// The scheme of a name of kSchemeNames; false for any other.
bool scheme_from_name(const std::string& name, Scheme* scheme);

struct StepOptions {
  Scheme scheme = Scheme::kModifiedEuler;
  // Local relative error per substep (stress and fabric relative to their norms, internal
  // variables absolute: they are dimensionless ratios). The measured global relative stress
  // error is about 0.3 x tolerance (docs/models.md, "Tolerance").
  double tolerance = 1e-6;
  // false: modified Euler with `fixed_substeps` equal substeps and no control (order tests);
  // kBogackiShampine and kAuto are adaptive only.
  bool adaptive = true;
  // Substeps of the explicit scheme, and of modified Euler when !adaptive.
  int fixed_substeps = 1;
  int max_substeps = 100000;
  double min_fraction = 1e-10;  // smallest substep, as a fraction of the increment
  bool IsValid(std::string* why) const;
};

template <typename T>
struct StepResultT {
  bool success = false;
  // Why it failed; on success empty, except when a fixed-step scheme exceeded the tolerance
  // (within_tolerance false): then it says so.
  std::string reason;
  StateT<T> end;
  // Largest local error estimate over the accepted substeps (modified Euler) or over all
  // substeps (explicit). within_tolerance is false when an explicit step exceeded it.
  double error_estimate = 0.0;
  bool within_tolerance = true;
  int substeps = 0;
  int rejected = 0;
  int rate_evaluations = 0;
  // True when the integration stopped on StepOptions::max_substeps: the one failure a larger
  // cap cures (the calibration counts and reports these apart, docs/calibration.md).
  bool on_substep_limit = false;
  // Substeps tried, accepted or rejected: what max_substeps bounds.
  int attempted() const { return substeps + rejected; }
};
using StepResult = StepResultT<double>;

// Integrates `law` from `start` over the strain increment d_eps (compression positive).
// The volume fraction follows the kinematics: d nu = nu tr(d_eps) per substep.
StepResult integrate(const Law& law, const MaterialState& start, const Eigen::Matrix3d& d_eps,
                     const StepOptions& options = {});

// Mixed control in Mandel components: where stress_controlled[i], the stress increment
// component i is prescribed (stress_increment(i)) and the strain component is unknown; elsewhere
// the strain component strain_increment(i) is prescribed.
struct MixedControl {
  std::array<bool, 6> stress_controlled{};
  Vector6d strain_increment = Vector6d::Zero();
  Vector6d stress_increment = Vector6d::Zero();
};

struct MixedOptions {
  StepOptions step;
  int max_iterations = 50;
  // Convergence: |residual| <= stress_tolerance_abs + stress_tolerance_rel * |sigma_end| on the
  // controlled components. 1e-9 relative sits three orders above the integrator's
  // reproducibility for the laws at their stress scale; elastoplastic_fabric far below its
  // scale is noisier (3e-7, docs/models.md "Paths"), and its load steps are halved until met.
  double stress_tolerance_rel = 1e-9;
  double stress_tolerance_abs = 1e-6;  // Pa
  // The increment is applied in this many equal load steps, each solved by Newton; a load step
  // that fails is halved and tried again (down to 1e-6 of the increment).
  int load_steps = 1;
  bool IsValid(std::string* why) const;
};

// On failure `step.end` is the state after the last load step that converged, and
// strain_increment and fraction_done are the part of the increment applied up to it.
struct MixedResult {
  StepResult step;  // of the last load step, with `end` the final state
  Vector6d strain_increment = Vector6d::Zero();  // the solved increment applied (Mandel)
  double fraction_done = 0.0;                    // of the prescribed increments applied
  int load_steps_taken = 0;                      // converged load steps
  int load_step_cuts = 0;                        // load steps halved after a failure
  int iterations = 0;                            // Newton iterations, summed over load steps
  double stress_residual = 0.0;                  // largest final residual over load steps (Pa)
  int substeps = 0;                 // of the converged load steps' integrations, summed
  double max_error_estimate = 0.0;  // of the converged load steps' integrations, largest
};

MixedResult integrate_mixed(const Law& law, const MaterialState& start, const MixedControl& control,
                            const MixedOptions& options = {});

}  // namespace rendulic::models
