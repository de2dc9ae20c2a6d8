// The constitutive-law interface of models/ (docs/models.md "The law interface": a law has a state,
// parameters with bounds, the stress and fabric increments for a strain increment, and its
// tangent). A material point is plain data (docs/architecture.md "Design choices"): MaterialState
// holds stress, fabric, up to six scalar internal variables and the volume fraction. A Law owns a
// flat parameter vector whose names, units, defaults and bounds it publishes, so that a calibration
// layer can treat any law as "a vector of bounded numbers". Compression positive throughout.
//
// Every law is also written as a template on the scalar type (see law_model.hpp and the
// *_law.hpp headers); this class is the double-precision, run-time polymorphic face of it.
#pragma once

#include <Eigen/Dense>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "rendulic/core/conventions.hpp"
#include "rendulic/models/tensor.hpp"

namespace rendulic::models {

inline constexpr int kMaxInternal = 6;

// Yield functions are normalised by the size of the elastic domain; a state with
// f >= -kYieldSurfaceBand counts as on the surface (rounding after a drift correction or after
// the driver's bisection onto the surface).
inline constexpr double kYieldSurfaceBand = 1e-9;

// State of a material point. `internal` holds a law's scalar internal variables (the number
// and meaning are the law's: Law::internal_names()); unused entries stay zero.
template <typename T>
struct StateT {
  Mat3<T> stress = Mat3<T>::Zero();  // Pa, compression positive
  Mat3<T> fabric = Mat3<T>::Zero();  // dimensionless (docs/physics.md section 3, seed eq. 2)
  Vec6<T> internal = Vec6<T>::Zero();
  T volume_fraction = T(0);
};
using MaterialState = StateT<double>;

// Increments of the state for one strain increment, evaluated at the start state (the rate
// equation times the increment). The volume fraction is kinematics, so the driver updates it.
template <typename T>
struct RateT {
  Mat3<T> d_stress = Mat3<T>::Zero();
  Mat3<T> d_fabric = Mat3<T>::Zero();
  Vec6<T> d_internal = Vec6<T>::Zero();
  bool plastic = false;  // the plastic (loading) branch was active
};
using LawRate = RateT<double>;

// The parts of a scalar-generic law (law_model.hpp) that a law without plasticity and without
// internal variables shares: no internal variables, every state admissible, nothing to
// correct, no yield surface (f = -inf). Such a law derives from it and states the rest (its
// parameters, rate and tangent); one that needs its own admissible() still writes that.
struct WithoutPlasticity {
  static Vector6d initial_internal(const double*, const Eigen::Matrix3d&, const Eigen::Matrix3d&) {
    return Vector6d::Zero();
  }
  static bool admissible(const double*, const MaterialState&, std::string*) { return true; }
  template <typename T>
  static void correct(const T*, StateT<T>*, bool) {}
  template <typename T>
  static T yield_function(const T*, const StateT<T>&) {
    return T(-std::numeric_limits<double>::infinity());
  }
};

// Whether a scalar-generic law M has an elastic domain bounded by a yield surface: every law
// without one derives from WithoutPlasticity. For such a law a probe of any amplitude may leave
// the elastic domain, so no amplitude is elastic by its size alone (docs/calibration.md
// "Predictions and derivatives").
template <class M>
inline constexpr bool kHasYieldSurface = !std::is_base_of_v<WithoutPlasticity, M>;

struct ParameterInfo {
  std::string name;
  std::string unit;
  double default_value;
  double lower;  // inclusive bounds
  double upper;
  std::string help;
  // "parameter 'K' = -5 is outside its bounds [1, 1e+13] Pa": the one wording of a value out of
  // bounds, wherever it came from (a parameters file, set_parameters, calibrate --value).
  std::string out_of_bounds(double value) const;
};

class Law {
 public:
  virtual ~Law() = default;

  virtual std::string_view name() const = 0;
  virtual const std::vector<ParameterInfo>& parameter_info() const = 0;
  virtual const std::vector<std::string>& internal_names() const = 0;

  // Increments of stress, fabric and internal variables for the strain increment d_eps
  // evaluated at `state` (one explicit evaluation of the rate law; the driver integrates).
  virtual LawRate rate(const MaterialState& state, const Eigen::Matrix3d& d_eps) const = 0;
  // Analytic tangent d(d_stress)/d(d_eps) in Mandel form at `state`. Rate-independent laws
  // are homogeneous of degree one in d_eps, so the tangent depends on its direction only
  // (hypoplasticity: L + N (x) d_eps/|d_eps|; elasto-plasticity: loading or unloading branch).
  virtual Matrix6d tangent(const MaterialState& state, const Eigen::Matrix3d& d_eps) const = 0;
  // Internal variables of a relaxed state given only stress and fabric (what a state file or
  // a DEM snapshot provides).
  virtual Vector6d initial_internal(const Eigen::Matrix3d& stress,
                                    const Eigen::Matrix3d& fabric) const = 0;
  // Whether the law is defined at `state` (e.g. hypoplasticity needs tr(sigma) > 0).
  virtual bool admissible(const MaterialState& state, std::string* why) const = 0;
  // Correction of yield-surface drift after an explicit (sub)step: a state outside the
  // surface is brought back onto it; with `on_surface` (the step was plastic loading, so the
  // exact solution stays on the surface) a state slightly inside is brought onto it as well.
  // A no-op for laws without an elastic domain.
  virtual void correct(MaterialState* state, bool on_surface) const = 0;
  // Yield function f (f < 0 elastic, f = 0 on the surface, normalised: f = -1 at the centre of
  // the elastic domain) for laws with one; -infinity for laws without one. The driver uses it to
  // end a substep where an elastic step meets the surface (Sloan 1987), instead of averaging across
  // the kink.
  virtual double yield_function(const MaterialState& state) const = 0;

  // Parameters in parameter_info() order.
  const std::vector<double>& parameters() const { return params_; }
  // Sets all parameters after checking count, finiteness and bounds; on failure nothing
  // changes and *why names the offending parameter.
  bool set_parameters(const std::vector<double>& values, std::string* why);
  bool set_parameter(std::string_view name, double value, std::string* why);
  double parameter(std::string_view name) const;     // NaN if unknown
  int parameter_index(std::string_view name) const;  // -1 if unknown
  // The refusal of a name parameter_index does not know, with the names it does:
  // "unknown parameter 'x' of isotropic_elastic (known: B, nu)".
  std::string unknown_parameter(std::string_view name) const;
  std::vector<double> default_parameters() const;

  // A state with the law's initial internal variables.
  MaterialState make_state(const Eigen::Matrix3d& stress, const Eigen::Matrix3d& fabric,
                           double volume_fraction) const;

 protected:
  std::vector<double> params_;
};

// Numbers in messages, shortest readable form ("%g").
std::string format_g(double v);

// Names accepted by make_law: isotropic_elastic, anisotropic_elastic, hypoplastic_wu,
// elastoplastic_fabric.
std::vector<std::string> law_names();
// A law with its default parameters, or nullptr for an unknown name.
std::unique_ptr<Law> make_law(std::string_view name);

}  // namespace rendulic::models
