// A user's Abaqus UMAT as a rendulic law (docs/umat.md): the shared library is opened with
// dlopen and its standard UMAT entry (Fortran `umat_`, else C `umat`) is called with the standard
// argument list. rendulic's compression-positive tensors are converted to the UMAT's
// tension-positive Voigt vectors (11, 22, 33, 12, 13, 23; engineering shear strains) and back,
// DDSDDE included.
//
// A UMAT is an incremental stress update, not a rate law, so it has a driver of its own
// (UmatLaw::integrate): the strain increment is applied in UMAT increments with step-doubling
// error control on the stress (the tolerance of StepOptions) and local (Richardson) extrapolation
// of the stress, PNEWDT < 1 cuts an increment and
// retries it (at most kUmatMaxCutbacks times in a row), and NaN or inf in what the UMAT returns
// is an error naming the increment. The Law interface's rate() and tangent() use DDSDDE (the rate
// envelope is DDSDDE : d_eps at the start state). STATEV may be longer than MaterialState's six
// internal variables: UmatState carries the whole vector beside the material point, and
// MaterialState::internal mirrors STATEV(1..6) so that the built-in laws' state stays as it was.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "rendulic/models/driver.hpp"
#include "rendulic/models/law.hpp"
#include "rendulic/models/paths.hpp"

namespace rendulic::models {

// Consecutive PNEWDT cuts of one increment before the driver gives up.
inline constexpr int kUmatMaxCutbacks = 30;
// |DSTRAN| of the call that asks the UMAT for its tangent at a state (rate(), tangent()): small
// enough that the tangent is the one at the start of the increment, large enough that a UMAT
// that normalises DSTRAN (hypoplasticity: d_eps / |d_eps|) sees a direction.
inline constexpr double kUmatTangentProbe = 1e-9;

// What the parameters file of a UMAT holds (load_umat_parameters_toml).
struct UmatSpec {
  std::vector<double> props;
  std::vector<std::string> prop_names;  // default prop1, prop2, ...
  std::vector<double> lower, upper;     // search bounds; +-infinity where none was given
  int nstatv = 0;
  std::vector<double> statev;  // initial STATEV (nstatv entries)
  std::string cmname = "RENDULIC";
};

// Throws InputError naming the file and the key.
UmatSpec load_umat_parameters_toml(const std::string& path);

// A material point of a UMAT: the point itself, the whole STATEV, the strain accumulated since
// the start (STRAN) and the specific energies the UMAT keeps (SSE, SPD, SCD).
struct UmatState {
  MaterialState point;
  std::vector<double> statev;
  Eigen::Matrix3d strain = Eigen::Matrix3d::Zero();  // compression positive
  double sse = 0.0, spd = 0.0, scd = 0.0;
  double time = 0.0;  // pseudo time: 1 per strain increment driven
};

// One call of the UMAT over d_eps from `start`.
struct UmatCall {
  bool finite = true;  // false: *reason says what was not finite
  std::string reason;
  UmatState end;
  Matrix6d tangent = Matrix6d::Zero();  // DDSDDE in Mandel form, compression positive
  double pnewdt = 0.0;
};

// The accepted increments of one integration, as fractions of the strain increment: recorded
// by a controlled integration and replayed without control, so that finite differences with
// respect to PROPS see the integrator with its increments frozen (the rule the built-in laws'
// exact derivatives follow, docs/models.md "Exact derivatives through the driver").
struct UmatSchedule {
  std::vector<double> fractions;
  bool replay = false;
};

class UmatLibrary;

class UmatLaw final : public Law {
 public:
  // Opens `library` and finds its entry; InputError on a missing file or symbol.
  UmatLaw(const std::string& library, UmatSpec spec);
  UmatLaw(const UmatLaw&) = default;
  ~UmatLaw() override;

  std::string_view name() const override { return "umat"; }
  const std::vector<ParameterInfo>& parameter_info() const override { return info_; }
  const std::vector<std::string>& internal_names() const override { return internal_names_; }
  // DDSDDE : d_eps, DDSDDE from a call of |DSTRAN| = kUmatTangentProbe in the direction of d_eps.
  LawRate rate(const MaterialState& state, const Eigen::Matrix3d& d_eps) const override;
  Matrix6d tangent(const MaterialState& state, const Eigen::Matrix3d& d_eps) const override;
  // rate() that says why it failed (the UMAT's NaN or inf) instead of returning NaN.
  bool rate_checked(const MaterialState& state, const Eigen::Matrix3d& d_eps, LawRate* rate,
                    std::string* why) const;
  Vector6d initial_internal(const Eigen::Matrix3d& stress,
                            const Eigen::Matrix3d& fabric) const override;
  // A UMAT says where it is undefined by NaN or PNEWDT, so every state is admissible here.
  bool admissible(const MaterialState&, std::string*) const override { return true; }
  void correct(MaterialState*, bool) const override {}
  double yield_function(const MaterialState&) const override;

  const std::string& library() const { return library_path_; }
  const std::string& symbol() const;
  int nstatv() const { return spec_.nstatv; }
  const UmatSpec& spec() const { return spec_; }

  // The UMAT state of a material point: STATEV(1..6) from point.internal, the rest initial.
  UmatState umat_state(const MaterialState& point) const;
  // One UMAT call; `kinc` is what the UMAT sees as KINC, dtime as DTIME.
  UmatCall call(const UmatState& start, const Eigen::Matrix3d& d_eps, double dtime, int kinc) const;
  // The driver (see the file comment): the result's `end` is the point; *end_state (if given)
  // receives the whole UMAT state. Nothing throws.
  // With `schedule`: its increments are recorded, or (schedule->replay) replayed.
  StepResult integrate(const UmatState& start, const Eigen::Matrix3d& d_eps,
                       const StepOptions& options, UmatState* end_state = nullptr,
                       UmatSchedule* schedule = nullptr) const;
  // PROPS set as given, without the bound check (finite differences step a hair past a bound).
  void set_props_unchecked(const std::vector<double>& props) { params_ = props; }
  // A strain path in `steps` equal increments of `total` (paths.hpp), STATEV carried whole.
  PathSeries run_path(const MaterialState& start, const Eigen::Matrix3d& total,
                      const PathOptions& options, UmatState* end_state = nullptr) const;

 private:
  std::string library_path_;
  std::shared_ptr<UmatLibrary> lib_;
  UmatSpec spec_;
  std::vector<ParameterInfo> info_;
  std::vector<std::string> internal_names_;
};

// A UmatLaw for `library` with the parameters file `params` (both required).
std::unique_ptr<UmatLaw> make_umat_law(const std::string& library, const std::string& params);

// The UMAT a run calibrates under the model name "umat" (one per process: a run names one
// --umat), so that everything that makes a law by name (make_law("umat"), the calibration's
// objective and yardstick) finds it. nullptr clears it.
void set_session_umat(std::shared_ptr<const UmatLaw> law);
std::shared_ptr<const UmatLaw> session_umat();

}  // namespace rendulic::models
