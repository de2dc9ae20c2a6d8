// The adaptive integrators of driver.hpp (modified Euler, Bogacki-Shampine 3(2)) written once for
// any scalar type, so that the same substeps that integrate a law in double precision also carry
// derivatives with respect to its parameters when the scalar is an automatic-differentiation type
// (Ceres Jets; docs/models.md "Exact derivatives through the driver"). Every control decision
// (substep size, acceptance, the event location where an elastic substep meets the yield surface,
// loading or unloading) is taken on the values only, so the derivative is that of the
// integrator with its accepted substeps frozen; the one step whose length depends smoothly on
// the parameters, the one that ends on the yield surface, gets its derivative from the implicit
// function theorem (f(c(p), p) = 0 gives dc/dp = -f_p / f_c). With T = double this is exactly
// the integrator of driver.cpp (which calls it).
//
// A law is seen through an Ops object:
//   using Scalar = T;
//   RateT<T> rate(const StateT<T>&, const Mat3<T>& d_eps) const;
//   void correct(StateT<T>*, bool on_surface) const;
//   T yield_function(const StateT<T>&) const;                    (-inf: no yield surface)
//   LawRate value_rate(const MaterialState&, const Eigen::Matrix3d&) const;   the same in double
//   void value_correct(MaterialState*, bool on_surface) const;
//   double value_yield_function(const MaterialState&) const;
//   bool admissible(const MaterialState&, std::string* why) const;
#pragma once

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "rendulic/models/driver.hpp"

namespace rendulic::models {

// The value of a scalar: itself for arithmetic types, the value part `.a` otherwise (the
// convention of Ceres Jets).
template <typename T>
double value_of(const T& x) {
  if constexpr (std::is_arithmetic_v<T>) {
    return static_cast<double>(x);
  } else {
    return x.a;
  }
}

template <typename T>
MaterialState value_state(const StateT<T>& s) {
  if constexpr (std::is_same_v<T, double>) {
    return s;
  } else {
    MaterialState v;
    v.stress = s.stress.unaryExpr([](const T& x) { return x.a; });
    v.fabric = s.fabric.unaryExpr([](const T& x) { return x.a; });
    v.internal = s.internal.unaryExpr([](const T& x) { return x.a; });
    v.volume_fraction = s.volume_fraction.a;
    return v;
  }
}

template <typename T>
LawRate value_rate(const RateT<T>& r) {
  if constexpr (std::is_same_v<T, double>) {
    return r;
  } else {
    LawRate v;
    v.d_stress = r.d_stress.unaryExpr([](const T& x) { return x.a; });
    v.d_fabric = r.d_fabric.unaryExpr([](const T& x) { return x.a; });
    v.d_internal = r.d_internal.unaryExpr([](const T& x) { return x.a; });
    v.plastic = r.plastic;
    return v;
  }
}

template <typename T>
StateT<T> state_cast(const MaterialState& s) {
  StateT<T> o;
  o.stress = s.stress.template cast<T>();
  o.fabric = s.fabric.template cast<T>();
  o.internal = s.internal.template cast<T>();
  o.volume_fraction = T(s.volume_fraction);
  return o;
}

namespace driver_detail {

inline bool finite(const LawRate& r) {
  return r.d_stress.allFinite() && r.d_fabric.allFinite() && r.d_internal.allFinite();
}

template <typename T>
StateT<T> advance(const StateT<T>& s, const RateT<T>& r, const T& tr_de) {
  using std::exp;
  StateT<T> o = s;
  o.stress += r.d_stress;
  o.fabric += r.d_fabric;
  o.internal += r.d_internal;
  o.volume_fraction = s.volume_fraction * exp(tr_de);  // nu V = const, eps_v log strain
  return o;
}

template <typename T>
StateT<T> advance_heun(const StateT<T>& s, const RateT<T>& r1, const RateT<T>& r2, const T& tr_de) {
  using std::exp;
  StateT<T> o = s;
  o.stress += T(0.5) * (r1.d_stress + r2.d_stress);
  o.fabric += T(0.5) * (r1.d_fabric + r2.d_fabric);
  o.internal += T(0.5) * (r1.d_internal + r2.d_internal);
  o.volume_fraction = s.volume_fraction * exp(tr_de);
  return o;
}

// The local error of a difference d = y_high - y_low of the two solutions of an embedded
// pair: relative for stress and fabric, absolute for the (dimensionless) internal variables;
// the worst block counts. The stress's is relative to the larger of the end's and the
// substep start's |sigma| (`start`), which is positive unless the stress is zero throughout
// (then so is d). A floor in Pa, as there was (1 Pa), made the substeps of a stress passing
// near zero depend on the unit system (tests/app/units_system_test.cpp).
inline double difference_error(const LawRate& d, const MaterialState& y, double start) {
  const double e_s =
      d.d_stress.norm() / std::max({y.stress.norm(), start, std::numeric_limits<double>::min()});
  const double e_f = d.d_fabric.norm() / std::max(y.fabric.norm(), 1e-12);
  const double e_q = d.d_internal.lpNorm<Eigen::Infinity>();
  return std::max({e_s, e_f, e_q});
}

// Modified Euler's: |y_heun - y_euler| = |r2 - r1| / 2 (the halving is exact, so this is the
// same number as halving the norms).
inline double error_estimate(const LawRate& r1, const LawRate& r2, const MaterialState& y,
                             double start) {
  LawRate d;
  d.d_stress = 0.5 * (r2.d_stress - r1.d_stress);
  d.d_fabric = 0.5 * (r2.d_fabric - r1.d_fabric);
  d.d_internal = 0.5 * (r2.d_internal - r1.d_internal);
  return difference_error(d, y, start);
}

inline std::string fmt(double v) {
  std::ostringstream os;
  os.precision(3);
  os << v;
  return os.str();
}

// A stress below this fraction of the increment's start has "all but vanished": where the
// substeps then shrink below min_fraction the failure names the law's domain (integrate_adaptive).
inline constexpr double kVanishingStress = 1e-3;

// One Heun trial over the strain increment de from y.
template <typename T>
struct Trial {
  bool ok = false;
  StateT<T> yh;
  double err = 0.0;
  bool plastic = false;
};

template <typename T, class RateF, class CorrectF, class AdmissibleF>
Trial<T> heun_trial(const StateT<T>& y, const Mat3<T>& de, const RateF& rate,
                    const CorrectF& correct, const AdmissibleF& admissible, int* evaluations) {
  Trial<T> tr;
  const T tr_de = de.trace();
  const RateT<T> r1 = rate(y, de);
  ++*evaluations;
  const LawRate v1 = value_rate(r1);
  if (!finite(v1)) return tr;
  StateT<T> y1 = advance(y, r1, tr_de);
  // A plastic predictor stays on the yield surface (consistency), up to its O(h^2) drift;
  // without this the corrector could see the predictor a hair inside and switch branch.
  correct(&y1, r1.plastic);
  if (!admissible(value_state(y1))) return tr;
  const RateT<T> r2 = rate(y1, de);
  ++*evaluations;
  const LawRate v2 = value_rate(r2);
  if (!finite(v2)) return tr;
  tr.yh = advance_heun(y, r1, r2, tr_de);
  const MaterialState vh = value_state(tr.yh);
  tr.ok = admissible(vh);
  tr.plastic = r1.plastic;
  tr.err = error_estimate(v1, v2, vh, value_state(y).stress.norm());
  tr.ok = tr.ok && std::isfinite(tr.err);
  return tr;
}

// y + sum_k a_k r_k over the stages given (a zero coefficient skips its rate), the volume
// fraction following the kinematics over the stage's strain, whose trace is tr_de.
template <typename T>
StateT<T> advance_stages(const StateT<T>& s, std::initializer_list<double> a,
                         std::initializer_list<const RateT<T>*> r, const T& tr_de) {
  using std::exp;
  StateT<T> o = s;
  auto ri = r.begin();
  for (double ak : a) {
    const RateT<T>& rk = **ri++;
    if (ak == 0.0) continue;
    o.stress += T(ak) * rk.d_stress;
    o.fabric += T(ak) * rk.d_fabric;
    o.internal += T(ak) * rk.d_internal;
  }
  o.volume_fraction = s.volume_fraction * exp(tr_de);
  return o;
}

// One Bogacki-Shampine 3(2) trial over de from y (Bogacki and Shampine 1989): three stages give
// the third-order end point, a fourth rate there the embedded second-order one; their
// difference is the local error estimate, of third order where Heun's is of second. The stage
// states of a plastic step are corrected onto the surface as Heun's predictor is.
template <typename T, class RateF, class CorrectF, class AdmissibleF>
Trial<T> bs32_trial(const StateT<T>& y, const Mat3<T>& de, const RateF& rate,
                    const CorrectF& correct, const AdmissibleF& admissible, int* evaluations) {
  Trial<T> tr;
  const T tr_de = de.trace();
  const auto stage = [&](const StateT<T>& ys, RateT<T>* r) {
    if (!admissible(value_state(ys))) return false;
    *r = rate(ys, de);
    ++*evaluations;
    return finite(value_rate(*r));
  };
  RateT<T> r1, r2, r3, r4;
  if (!stage(y, &r1)) return tr;
  const bool plastic = r1.plastic;
  StateT<T> y2 = advance_stages<T>(y, {0.5}, {&r1}, T(0.5) * tr_de);
  correct(&y2, plastic);
  if (!stage(y2, &r2)) return tr;
  StateT<T> y3 = advance_stages<T>(y, {0.0, 0.75}, {&r1, &r2}, T(0.75) * tr_de);
  correct(&y3, plastic);
  if (!stage(y3, &r3)) return tr;
  tr.yh = advance_stages<T>(y, {2.0 / 9.0, 1.0 / 3.0, 4.0 / 9.0}, {&r1, &r2, &r3}, tr_de);
  StateT<T> y4 = tr.yh;
  correct(&y4, plastic);
  if (!stage(y4, &r4)) return tr;
  // y3 - y2 = -5/72 r1 + 1/12 r2 + 1/9 r3 - 1/8 r4.
  const LawRate v1 = value_rate(r1), v2 = value_rate(r2), v3 = value_rate(r3), v4 = value_rate(r4);
  LawRate d;
  d.d_stress = -5.0 / 72.0 * v1.d_stress + 1.0 / 12.0 * v2.d_stress + 1.0 / 9.0 * v3.d_stress -
               0.125 * v4.d_stress;
  d.d_fabric = -5.0 / 72.0 * v1.d_fabric + 1.0 / 12.0 * v2.d_fabric + 1.0 / 9.0 * v3.d_fabric -
               0.125 * v4.d_fabric;
  d.d_internal = -5.0 / 72.0 * v1.d_internal + 1.0 / 12.0 * v2.d_internal +
                 1.0 / 9.0 * v3.d_internal - 0.125 * v4.d_internal;
  const MaterialState vh = value_state(tr.yh);
  tr.ok = admissible(vh);
  tr.plastic = plastic;
  tr.err = difference_error(d, vh, value_state(y).stress.norm());
  tr.ok = tr.ok && std::isfinite(tr.err);
  return tr;
}

}  // namespace driver_detail

// Modified Euler or Bogacki-Shampine 3(2) (o.scheme; kAuto picks by the law) with error control
// over the increment d_eps (docs/models.md "Material-point driver"). See the file comment for what
// is differentiated.
template <class Ops>
StepResultT<typename Ops::Scalar> integrate_adaptive(const Ops& law,
                                                     const StateT<typename Ops::Scalar>& start,
                                                     const Eigen::Matrix3d& d_eps,
                                                     const StepOptions& o) {
  using T = typename Ops::Scalar;
  using driver_detail::fmt;
  StepResultT<T> res;
  StateT<T> y = start;
  const Mat3<T> d_eps_t = d_eps.template cast<T>();
  // t is the fraction of the increment done; it carries a derivative only through the step
  // that ends on the yield surface (and then through the last step, which ends at 1).
  T t = T(0.0);
  double dt = 1.0;
  bool rejected_last = false;
  const auto rate = [&](const StateT<T>& s, const Mat3<T>& de) { return law.rate(s, de); };
  const auto correct = [&](StateT<T>* s, bool on) { law.correct(s, on); };
  const auto admissible = [&](const MaterialState& s) { return law.admissible(s, nullptr); };
  const auto vrate = [&](const MaterialState& s, const Eigen::Matrix3d& de) {
    return law.value_rate(s, de);
  };
  const auto vcorrect = [&](MaterialState* s, bool on) { law.value_correct(s, on); };
  // kAuto: the third-order pair where the law is smooth (no yield surface to locate), modified
  // Euler across a surface, where the third order buys nothing (docs/models.md "Tolerance").
  const bool third = o.scheme == Scheme::kBogackiShampine ||
                     (o.scheme == Scheme::kAuto && law.value_yield_function(value_state(start)) ==
                                                       -std::numeric_limits<double>::infinity());
  const char* const scheme = third ? "Bogacki-Shampine" : "modified Euler";
  // Value-only trial over the fraction h of the increment (event location, on doubles).
  const auto value_trial = [&](const MaterialState& yv, double h) {
    const Eigen::Matrix3d de = h * d_eps;
    return third ? driver_detail::bs32_trial<double>(yv, de, vrate, vcorrect, admissible,
                                                     &res.rate_evaluations)
                 : driver_detail::heun_trial<double>(yv, de, vrate, vcorrect, admissible,
                                                     &res.rate_evaluations);
  };
  // The trial over the (possibly parameter-dependent) fraction h.
  const auto trial = [&](const T& h) {
    const Mat3<T> de = h * d_eps_t;
    return third ? driver_detail::bs32_trial<T>(y, de, rate, correct, admissible,
                                                &res.rate_evaluations)
                 : driver_detail::heun_trial<T>(y, de, rate, correct, admissible,
                                                &res.rate_evaluations);
  };
  // Why the substeps shrank without end. Where the stress has all but vanished the relative error
  // has no scale left, and a law that ends at P = 0 is approached in ever shorter substeps: an
  // unloading probe of the fabric law at 1e5 Pa stopped at P = 0.65 Pa, its reason "law too stiff
  // or undefined". Then the law's own reason is named, from one trial over the rest of the
  // increment at the rate there.
  const double start_stress = value_state(start).stress.norm();
  const auto vanishing_stress = [&](const MaterialState& yv, double rest) {
    const double fallen = yv.stress.norm() / start_stress;
    if (!(fallen < driver_detail::kVanishingStress))
      return std::string(" (law too stiff or undefined)");
    std::string why;
    const auto asking = [&](const MaterialState& s) { return law.admissible(s, &why); };
    int evaluations = 0;
    (void)driver_detail::heun_trial<double>(yv, rest * d_eps, vrate, vcorrect, asking,
                                            &evaluations);
    return ", where the stress has fallen to " + fmt(fallen) + " of its start" +
           (why.empty() ? std::string()
                        : "; the rest of the increment at the rate there leaves the law's "
                          "domain: " +
                              why);
  };
  // Sloan's factor q = 0.9 (TOL/R)^(1/p), p the order of the local error estimate.
  const auto factor = [&](double err) {
    return third ? 0.9 * std::cbrt(o.tolerance / err) : 0.9 * std::sqrt(o.tolerance / err);
  };
  while (value_of(t) < 1.0) {
    if (res.attempted() >= o.max_substeps) {
      res.on_substep_limit = true;
      res.reason = std::string(scheme) + ": more than " + std::to_string(o.max_substeps) +
                   " substeps (reached fraction " + fmt(value_of(t)) + " of the increment)";
      res.end = y;
      return res;
    }
    if (dt < o.min_fraction) {
      res.reason = std::string(scheme) + ": substep below " + fmt(o.min_fraction) +
                   " of the increment at fraction " + fmt(value_of(t)) +
                   vanishing_stress(value_state(y), 1.0 - value_of(t));
      res.end = y;
      return res;
    }
    const MaterialState yv = value_state(y);
    std::string why;
    if (!law.admissible(yv, &why)) {
      res.reason = "at fraction " + fmt(value_of(t)) + " of the increment: " + why;
      res.end = y;
      return res;
    }
    // The last step ends exactly at 1, which carries the derivative of an earlier event step.
    const bool last = 1.0 - (value_of(t) + dt) < 1e-12 && value_of(t) + dt >= 1.0 - 1e-12;
    T h = last ? T(1.0) - t : T(dt);
    driver_detail::Trial<T> tr = trial(h);
    // Elastic-to-plastic transition inside the substep: shorten it to end on the yield
    // surface (bisection on the elastic trial; Sloan 1987), so that no substep averages the
    // elastic and the plastic rate across the kink.
    const double f0 = law.value_yield_function(yv);
    if (tr.ok && f0 < -kYieldSurfaceBand && std::isfinite(f0) &&
        law.value_yield_function(value_state(tr.yh)) > 0.0) {
      // Illinois (modified regula falsi) on f(c) = yield_function(trial(c dt)), bracketing
      // f(lo) <= 0 < f(hi); it stops once the inside end is within the surface band, which is
      // what the law needs to see the next substep as plastic loading.
      double lo = 0.0, hi = 1.0, f_lo = f0, f_hi = law.value_yield_function(value_state(tr.yh));
      int side = 0;
      for (int it = 0; it < 100 && hi - lo > 1e-15; ++it) {
        double c = lo - f_lo * (hi - lo) / (f_hi - f_lo);
        if (!(c > lo && c < hi)) c = 0.5 * (lo + hi);
        const auto tc = value_trial(yv, c * dt);
        const double fc = tc.ok ? law.value_yield_function(tc.yh) : 1.0;
        if (fc <= 0.0) {
          lo = c;
          f_lo = fc;
          if (fc >= -kYieldSurfaceBand) break;
          if (side == -1) f_hi *= 0.5;
          side = -1;
        } else {
          hi = c;
          f_hi = fc;
          if (side == 1) f_lo *= 0.5;
          side = 1;
        }
      }
      // lo = 0 means the state was already within rounding of the surface: step just past it.
      dt *= lo > 0.0 ? lo : hi;
      h = T(dt);
      if constexpr (!std::is_same_v<T, double>) {
        if (lo > 0.0) {
          // dc/dp = -f_p / f_c at the crossing: the value of h stays dt, its derivative is that
          // of the crossing point. f_c by a central difference of the value trial.
          const double dc = 1e-6 * dt;
          const auto tp = value_trial(yv, dt + dc), tm = value_trial(yv, dt - dc);
          if (tp.ok && tm.ok) {
            const double f_c =
                (law.value_yield_function(tp.yh) - law.value_yield_function(tm.yh)) / (2.0 * dc);
            const driver_detail::Trial<T> at = trial(h);
            if (at.ok && f_c > 0.0) {
              const T f = law.yield_function(at.yh);
              h = h - (f - T(value_of(f))) / f_c;
            }
          }
        }
      }
      tr = trial(h);
    }
    const bool ok = tr.ok;
    const double err = tr.err;
    if (!ok || err > o.tolerance) {
      // Sloan's factor (above), never below 0.1.
      const double q = ok ? std::max(factor(err), 0.1) : 0.1;
      dt = value_of(h) * q;
      ++res.rejected;
      rejected_last = true;
      continue;
    }
    y = tr.yh;
    law.correct(&y, tr.plastic);
    t += h;
    dt = value_of(h);
    ++res.substeps;
    res.error_estimate = std::max(res.error_estimate, err);
    double q = err > 0.0 ? factor(err) : 2.0;
    q = std::min(q, rejected_last ? 1.0 : 2.0);  // no growth right after a rejection
    rejected_last = false;
    dt = q * dt;
    if (value_of(t) + dt > 1.0 || 1.0 - (value_of(t) + dt) < 1e-12) dt = 1.0 - value_of(t);
    if (1.0 - value_of(t) < 1e-14) break;
  }
  res.end = y;
  res.success = true;
  res.within_tolerance = true;
  return res;
}

// `steps` equal increments of `total` from `start`, each integrated with error control; the
// state after every increment is appended to *states (the start first). false with *reason
// when an increment fails.
template <class Ops>
bool integrate_steps(const Ops& law, const StateT<typename Ops::Scalar>& start,
                     const Eigen::Matrix3d& total, int steps, const StepOptions& o,
                     std::vector<StateT<typename Ops::Scalar>>* states, std::string* reason,
                     std::vector<StepResultT<typename Ops::Scalar>>* results = nullptr) {
  const Eigen::Matrix3d de = total / steps;
  StateT<typename Ops::Scalar> y = start;
  states->push_back(y);
  for (int k = 0; k < steps; ++k) {
    auto r = integrate_adaptive(law, y, de, o);
    if (!r.success) {
      if (reason)
        *reason =
            "step " + std::to_string(k + 1) + " of " + std::to_string(steps) + ": " + r.reason;
      return false;
    }
    y = r.end;
    states->push_back(y);
    if (results) results->push_back(std::move(r));
  }
  return true;
}

}  // namespace rendulic::models
