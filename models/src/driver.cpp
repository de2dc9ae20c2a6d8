// Material-point driver: modified Euler or Bogacki-Shampine 3(2) with error control, the plain
// explicit scheme with an error report, and mixed strain/stress control (docs/models.md
// "Material-point driver"; see driver.hpp for the schemes and their sources).
#include "rendulic/models/driver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

#include "rendulic/models/driver_core.hpp"
#include "rendulic/models/umat.hpp"

namespace rendulic::models {
namespace {

using driver_detail::advance;
using driver_detail::advance_heun;
using driver_detail::error_estimate;
using driver_detail::finite;
using driver_detail::fmt;

// The run-time Law as the Ops of driver_core.hpp (double precision).
struct VirtualLawOps {
  using Scalar = double;
  const Law& law;
  LawRate rate(const MaterialState& s, const Eigen::Matrix3d& de) const { return law.rate(s, de); }
  void correct(MaterialState* s, bool on_surface) const { law.correct(s, on_surface); }
  double yield_function(const MaterialState& s) const { return law.yield_function(s); }
  LawRate value_rate(const MaterialState& s, const Eigen::Matrix3d& de) const {
    return law.rate(s, de);
  }
  void value_correct(MaterialState* s, bool on_surface) const { law.correct(s, on_surface); }
  double value_yield_function(const MaterialState& s) const { return law.yield_function(s); }
  bool admissible(const MaterialState& s, std::string* why) const { return law.admissible(s, why); }
};

StepResult integrate_fixed(const Law& law, const MaterialState& start, const Eigen::Matrix3d& d_eps,
                           const StepOptions& o) {
  StepResult res;
  const int n = o.fixed_substeps;
  const Eigen::Matrix3d de = d_eps / n;
  const double tr_de = de.trace();
  MaterialState y = start;
  const bool heun = o.scheme == Scheme::kModifiedEuler;
  for (int k = 0; k < n; ++k) {
    std::string why;
    if (!law.admissible(y, &why)) {
      res.reason = "substep " + std::to_string(k + 1) + " of " + std::to_string(n) + ": " + why;
      res.end = y;
      return res;
    }
    const LawRate r1 = law.rate(y, de);
    ++res.rate_evaluations;
    MaterialState y1 = advance(y, r1, tr_de);
    // A plastic predictor stays on the yield surface (consistency), up to its O(h^2) drift;
    // without this the corrector could see the predictor a hair inside and switch branch.
    if (heun) law.correct(&y1, r1.plastic);
    if (!finite(r1)) {
      res.reason = "non-finite rate at substep " + std::to_string(k + 1);
      res.end = y;
      return res;
    }
    // The error estimate needs the rate at the Euler end point; where the law is undefined
    // there, the explicit step has certainly left its accuracy (estimate = infinity).
    double err = std::numeric_limits<double>::infinity();
    LawRate r2;
    const bool second = law.admissible(y1, nullptr);
    if (second) {
      r2 = law.rate(y1, de);
      ++res.rate_evaluations;
      if (finite(r2)) err = error_estimate(r1, r2, y1, y.stress.norm());
    }
    if (heun) {
      if (!second || !finite(r2)) {
        res.reason = "modified Euler: law undefined at the predictor of substep " +
                     std::to_string(k + 1) + " (use adaptive stepping)";
        res.end = y;
        return res;
      }
      y = advance_heun(y, r1, r2, tr_de);
    } else {
      y = y1;
    }
    law.correct(&y, r1.plastic);
    res.error_estimate = std::max(res.error_estimate, err);
    ++res.substeps;
    if (!law.admissible(y, &why)) {
      res.reason = std::string(heun ? "fixed modified Euler" : "explicit Euler") + " substep " +
                   std::to_string(k + 1) + " left the law's domain: " + why;
      res.end = y;
      return res;
    }
  }
  res.end = y;
  res.within_tolerance = res.error_estimate <= o.tolerance;
  res.success = true;
  if (!res.within_tolerance)
    res.reason = std::string(heun ? "fixed modified Euler" : "explicit Euler") +
                 ": local error estimate " + fmt(res.error_estimate) + " exceeds tolerance " +
                 fmt(o.tolerance) + " (use adaptive modified Euler or more substeps)";
  return res;
}

}  // namespace

bool scheme_from_name(const std::string& name, Scheme* scheme) {
  for (std::size_t k = 0; k < kSchemeNames.size(); ++k)
    if (name == kSchemeNames[k]) {
      *scheme = static_cast<Scheme>(k);
      return true;
    }
  return false;
}

bool StepOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!(tolerance > 0.0 && tolerance < 1.0)) return fail("tolerance must be in (0, 1)");
  if (fixed_substeps < 1) return fail("fixed_substeps must be >= 1");
  if (max_substeps < 1) return fail("max_substeps must be >= 1");
  // The cap holds fixed substeps too: --substeps 2000000000 ran for ever, 36 probes of 2e9.
  if ((scheme == Scheme::kExplicitEuler || !adaptive) && fixed_substeps > max_substeps)
    return fail("fixed_substeps (" + std::to_string(fixed_substeps) +
                ") must not exceed max_substeps (" + std::to_string(max_substeps) + ")");
  if (!(min_fraction > 0.0 && min_fraction < 1.0)) return fail("min_fraction must be in (0, 1)");
  if ((scheme == Scheme::kBogackiShampine || scheme == Scheme::kAuto) && !adaptive)
    return fail(std::string("scheme ") + kSchemeNames[static_cast<int>(scheme)] +
                " is adaptive only (fixed substeps: modified or explicit Euler)");
  return true;
}

bool MixedOptions::IsValid(std::string* why) const {
  if (!step.IsValid(why)) return false;
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (max_iterations < 1) return fail("max_iterations must be >= 1");
  if (!(stress_tolerance_rel >= 0.0) || !(stress_tolerance_abs >= 0.0))
    return fail("stress tolerances must be >= 0");
  if (stress_tolerance_rel == 0.0 && stress_tolerance_abs == 0.0)
    return fail("at least one stress tolerance must be > 0");
  if (load_steps < 1) return fail("load_steps must be >= 1");
  return true;
}

StepResult integrate(const Law& law, const MaterialState& start, const Eigen::Matrix3d& d_eps,
                     const StepOptions& options) {
  StepResult res;
  std::string why;
  if (!options.IsValid(&why)) {
    res.reason = "invalid step options: " + why;
    res.end = start;
    return res;
  }
  if (!d_eps.allFinite()) {
    res.reason = "non-finite strain increment";
    res.end = start;
    return res;
  }
  if (!start.stress.allFinite() || !start.fabric.allFinite() || !start.internal.allFinite() ||
      !std::isfinite(start.volume_fraction)) {
    res.reason = "non-finite start state (stress, fabric or internal variables)";
    res.end = start;
    return res;
  }
  // A UMAT is an incremental update with a driver of its own (umat.hpp).
  if (const auto* umat = dynamic_cast<const UmatLaw*>(&law))
    return umat->integrate(umat->umat_state(start), d_eps, options);
  if (options.scheme == Scheme::kExplicitEuler || !options.adaptive)
    return integrate_fixed(law, start, d_eps, options);
  return integrate_adaptive(VirtualLawOps{law}, start, d_eps, options);
}

namespace {

// One load step of mixed control: Newton on the unknown strain components from the state y.
// `target`: the stress increment wanted on the controlled components. On failure `reason`
// says why and the step changes nothing.
struct LoadStep {
  bool ok = false;
  std::string reason;
  StepResult res;
  Vector6d e = Vector6d::Zero();
  int iterations = 0;
  double residual = 0.0;
};

LoadStep mixed_load_step(const Law& law, const MaterialState& y, const MixedControl& control,
                         const MixedOptions& options, const std::vector<int>& s_idx,
                         const std::vector<int>& e_idx, double fraction, const Vector6d& target) {
  LoadStep out;
  Vector6d e = control.strain_increment * fraction;
  const int ns = static_cast<int>(s_idx.size());
  if (ns == 0) {
    out.res = integrate(law, y, from_mandel(e), options.step);
    out.ok = out.res.success;
    out.reason = out.res.reason;
    out.e = e;
    return out;
  }
  auto solve_update = [&](const Matrix6d& c, const Eigen::VectorXd& rhs,
                          Eigen::VectorXd* dx) -> bool {
    Eigen::MatrixXd css(ns, ns);
    for (int a = 0; a < ns; ++a)
      for (int b = 0; b < ns; ++b) css(a, b) = c(s_idx[a], s_idx[b]);
    Eigen::FullPivLU<Eigen::MatrixXd> lu(css);
    if (!lu.isInvertible()) return false;
    *dx = lu.solve(rhs);
    return true;
  };
  const std::string singular = "tangent singular on the stress-controlled components";
  // Predictor from the tangent at the start, in the direction of the prescribed strain.
  for (int i : s_idx) e(i) = 0.0;
  Matrix6d c = law.tangent(y, from_mandel(e));
  Eigen::VectorXd rhs(ns), dx;
  for (int a = 0; a < ns; ++a) {
    double v = target(s_idx[a]);
    for (int j : e_idx) v -= c(s_idx[a], j) * e(j);
    rhs(a) = v;
  }
  if (!solve_update(c, rhs, &dx)) {
    out.reason = singular;
    return out;
  }
  for (int a = 0; a < ns; ++a) e(s_idx[a]) = dx(a);
  for (int it = 0; it < options.max_iterations; ++it) {
    out.res = integrate(law, y, from_mandel(e), options.step);
    ++out.iterations;
    if (!out.res.success) {
      out.reason = "iteration " + std::to_string(it + 1) + ": " + out.res.reason;
      return out;
    }
    const Vector6d ds = to_mandel(Eigen::Matrix3d(out.res.end.stress - y.stress));
    Eigen::VectorXd r(ns);
    for (int a = 0; a < ns; ++a) r(a) = ds(s_idx[a]) - target(s_idx[a]);
    out.residual = r.lpNorm<Eigen::Infinity>();
    if (out.residual <=
        options.stress_tolerance_abs + options.stress_tolerance_rel * out.res.end.stress.norm()) {
      out.ok = true;
      out.e = e;
      return out;
    }
    // The secant through the increment is best approximated by the mean of the tangents
    // at its two ends (exact for a tangent that varies linearly along the step).
    const Eigen::Matrix3d de = from_mandel(e);
    c = 0.5 * (law.tangent(y, de) + law.tangent(out.res.end, de));
    if (!solve_update(c, r, &dx)) {
      out.reason = singular;
      return out;
    }
    for (int a = 0; a < ns; ++a) e(s_idx[a]) -= dx(a);
  }
  out.reason = "Newton did not converge in " + std::to_string(options.max_iterations) +
               " iterations (residual " + fmt(out.residual) + " Pa)";
  return out;
}

}  // namespace

MixedResult integrate_mixed(const Law& law, const MaterialState& start, const MixedControl& control,
                            const MixedOptions& options) {
  MixedResult out;
  out.step.end = start;
  std::string why;
  if (!options.IsValid(&why)) {
    out.step.reason = "invalid mixed options: " + why;
    return out;
  }
  std::vector<int> s_idx, e_idx;
  for (int i = 0; i < 6; ++i) (control.stress_controlled[i] ? s_idx : e_idx).push_back(i);
  MaterialState y = start;
  const Vector6d start_stress = to_mandel(start.stress);
  // A load step that fails is halved and tried again: Newton's secant loses its way on a large
  // step, and near a limit state a step must shrink to follow the curve (the sand's drained
  // stress-controlled triaxial needed 20 steps by hand for 2e5 Pa). A step that still fails
  // below kMinLoadFraction of the increment means the target cannot be followed: beyond the
  // law's strength, typically, where no strain gives the prescribed stress.
  constexpr double kMinLoadFraction = 1e-6;
  const double nominal = 1.0 / options.load_steps;
  double h = nominal;
  while (out.fraction_done < 1.0) {
    h = std::min(h, 1.0 - out.fraction_done);
    // The last step takes the remainder exactly: rounding must not leave a sliver.
    if (1.0 - out.fraction_done - h < 1e-12) h = 1.0 - out.fraction_done;
    // The controlled components aim at the start's stress plus the increment's share done
    // after this step, not at h times the increment: the load steps' residuals do not add up.
    const double after = 1.0 - out.fraction_done - h <= 0.0 ? 1.0 : out.fraction_done + h;
    const Vector6d target = start_stress + after * control.stress_increment - to_mandel(y.stress);
    const LoadStep ls = mixed_load_step(law, y, control, options, s_idx, e_idx, h, target);
    out.iterations += ls.iterations;
    if (!ls.ok) {
      if (h * 0.5 >= kMinLoadFraction) {
        h *= 0.5;
        ++out.load_step_cuts;
        continue;
      }
      out.step = ls.res;
      out.step.success = false;
      out.step.end = y;
      out.step.reason = "mixed control: a load step of " + fmt(h) + " of the increment fails at " +
                        fmt(out.fraction_done) + " of it (" + ls.reason + ")" +
                        (s_idx.empty() ? ""
                                       : "; typically the stress target is beyond the law's "
                                         "strength, where no strain gives it");
      return out;
    }
    out.strain_increment += ls.e;
    out.stress_residual = std::max(out.stress_residual, ls.residual);
    out.substeps += ls.res.substeps;
    out.max_error_estimate = std::max(out.max_error_estimate, ls.res.error_estimate);
    out.fraction_done = after;
    ++out.load_steps_taken;
    y = ls.res.end;
    out.step = ls.res;
    h = std::min(2.0 * h, nominal);  // grow back after a cut
  }
  out.step.end = y;
  return out;
}

}  // namespace rendulic::models
