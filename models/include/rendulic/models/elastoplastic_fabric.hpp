// Family 4 of docs/models.md: an elasto-plastic rate law with fabric evolution, in the spirit of
// Imole et al. (2013) and Kumar et al. (2014). Our own minimal design, documented in
// docs/models.md:
// - elastic part: the anisotropic_elastic operator (same first nine parameters);
// - stress ratio r = sigma^D / P; an elastic domain |r - alpha| <= m of small radius m
//   around a back ratio alpha (internal variables: alpha in Mandel form), so that small
//   probes are elastic and large ones are not;
// - plastic strain d_eps_p = lambda n, n = (r - alpha)/|r - alpha| (deviatoric, no plastic
//   volume change: frictionless packings deform at constant volume in the main test);
// - hardening makes the deviatoric stress ratio approach its steady value M exponentially
//   with plastic deviatoric strain: n : dr = beta_s (M - r : n) lambda (alpha follows,
//   d_alpha = beta_s (M - r : n) lambda n, so |r - alpha| stays m);
// - fabric: d_F = c_F tr(d_eps) F/tr(F) + beta_F (F_dev_max n - F^D) lambda, i.e. the fabric
//   deviator approaches its steady value exponentially,
//   dF_dev = beta_F (F_dev_max - F_dev) |d_eps_dev|, driven by the plastic deviatoric strain
//   (no deviatoric fabric change while elastic, seed Fig. 4).
// At the steady state (r : n = M) the plastic modulus vanishes: loading probes give no change
// of the stress ratio, so the envelope collapses toward a line (seed Fig. 5e).
// A state read from a file (stress and fabric only) is taken as relaxed: alpha = r, the
// centre of its elastic domain.
#pragma once

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "rendulic/models/elastic_laws.hpp"

namespace rendulic::models {

struct ElastoplasticFabric {
  static constexpr std::string_view kName = "elastoplastic_fabric";
  // The first nine indices coincide with AnisotropicElastic's (its moduli() is reused).
  enum : int {
    kB,
    kG,
    kBetaA,
    kNp,
    kPref,
    kAg,
    kCf,
    kNnu,
    kNuRef,
    kM,
    kMss,
    kBetaS,
    kBetaF,
    kFmax,
    kWyield,
    kCount
  };
  static_assert(int{kNuRef} == int{AnisotropicElastic::kNuRef} &&
                int{kM} == int{AnisotropicElastic::kCount});
  static const std::vector<ParameterInfo>& parameter_info();
  static const std::vector<std::string>& internal_names();

  template <typename T>
  struct Plastic {
    bool loading = false;
    T share = T(0);   // plastic_share of the yield function (1 on the surface)
    T lambda = T(0);  // plastic multiplier: share times the consistent one
    T hardening = T(0);
    T denominator = T(1);
    Mat3<T> n = Mat3<T>::Zero();
    Mat3<T> d_n = Mat3<T>::Zero();  // elastic operator applied to n
    Mat3<T> nf = Mat3<T>::Zero();   // yield-function gradient d f / d sigma
  };

  template <typename T>
  static Plastic<T> plastic_part(const T* p, const StateT<T>& s, const T& b, const T& g,
                                 const Mat3<T>& f_dev, const Mat3<T>& d_sigma_e) {
    Plastic<T> out;
    const T pr = trace(s.stress) / T(3);
    if (!(pr > T(0))) return out;
    const Mat3<T> r = dev(s.stress) / pr;
    const Mat3<T> xi = r - from_mandel<T>(s.internal);
    const T xi_norm = safe_norm(xi);
    if (!(xi_norm > T(0))) return out;
    const T share = plastic_share((xi_norm - p[kM]) / p[kM], p[kWyield]);
    if (!(share > T(0))) return out;
    out.n = xi / xi_norm;
    const T r_n = ddot(r, out.n);
    out.nf = (out.n - (r_n / T(3)) * identity3<T>()) / pr;
    out.d_n = detail::anisotropic_apply(b, g, p[kBetaA], f_dev, out.n);
    out.hardening = p[kBetaS] * (p[kMss] - r_n);
    out.denominator = out.hardening + ddot(out.nf, out.d_n);
    // A softening modulus larger than the elastic one would make the step ill-posed; the
    // floor keeps lambda finite (the driver's error control then shortens the step).
    const T floor = T(1e-6) * T(2) * g / pr;
    if (out.denominator < floor) out.denominator = floor;
    const T lambda = ddot(out.nf, d_sigma_e) / out.denominator;
    if (lambda > T(0)) {
      out.loading = true;
      out.share = share;
      out.lambda = share * lambda;
    }
    return out;
  }

  // The share of the consistent plastic multiplier at yield-function value f = (|r - alpha| -
  // m_e) / m_e: 0 for f <= -w, 1 on and beyond the surface, in between the quintic smoothstep
  // x^3 (10 - 15 x + 6 x^2), x = (f + w) / w (continuous with two derivatives); w = w_yield.
  // A sharp switch at f = 0 makes the response of a finite probe a non-differentiable function
  // of the parameters where the probe just reaches the surface; the default w = 0.02 keeps it
  // smooth at the price of a little plastic flow within the last 2 % of the elastic range
  // (docs/models.md section 4). w = 0 is the sharp switch (a state within kYieldSurfaceBand of
  // the surface counts as on it).
  template <typename T>
  static T plastic_share(const T& f, const T& w) {
    const T width = w > T(kYieldSurfaceBand) ? w : T(kYieldSurfaceBand);
    if (!(f > -width)) return T(0);
    if (!(f < T(0)) || w <= T(kYieldSurfaceBand)) return T(1);
    const T x = (f + width) / width;
    return x * x * x * (T(10) - T(15) * x + T(6) * x * x);
  }

  template <typename T>
  static RateT<T> rate(const T* p, const StateT<T>& s, const Mat3<T>& de) {
    T b, g;
    AnisotropicElastic::moduli(p, s, &b, &g);
    const Mat3<T> f_dev = dev(s.fabric);
    RateT<T> r;
    r.d_stress = detail::anisotropic_apply(b, g, p[kBetaA], f_dev, de);
    r.d_fabric = detail::elastic_fabric_increment(s.fabric, p[kCf], de);
    const Plastic<T> pl = plastic_part(p, s, b, g, f_dev, r.d_stress);
    if (pl.loading) {
      r.plastic = true;
      r.d_stress -= pl.lambda * pl.d_n;
      r.d_internal = to_mandel<T>((pl.hardening * pl.lambda) * pl.n);
      r.d_fabric += (p[kBetaF] * pl.lambda) * (p[kFmax] * pl.n - f_dev);
    }
    return r;
  }

  static Matrix6d tangent(const double* p, const MaterialState& s, const Eigen::Matrix3d& de) {
    double b, g;
    AnisotropicElastic::moduli(p, s, &b, &g);
    const Eigen::Matrix3d f_dev = dev(s.fabric);
    const Matrix6d d = detail::anisotropic_matrix(b, g, p[kBetaA], f_dev);
    const Eigen::Matrix3d d_sigma_e =
        detail::anisotropic_apply(b, g, p[kBetaA], f_dev, Eigen::Matrix3d(de));
    const Plastic<double> pl = plastic_part(p, s, b, g, f_dev, d_sigma_e);
    if (!pl.loading) return d;
    const Vector6d dn = to_mandel(pl.d_n);
    const Vector6d nf = to_mandel(pl.nf);
    return d - pl.share * dn * (d.transpose() * nf).transpose() / pl.denominator;
  }

  static Vector6d initial_internal(const double*, const Eigen::Matrix3d& stress,
                                   const Eigen::Matrix3d&) {
    const double pr = stress.trace() / 3.0;
    if (!(pr > 0.0)) return Vector6d::Zero();
    return to_mandel(deviator(stress) / pr);
  }

  static bool admissible(const double*, const MaterialState& s, std::string* why) {
    if (s.stress.trace() > 0.0) return true;
    if (why)
      *why = "elastoplastic_fabric needs P > 0 (its yield function uses sigma^D / P), got P = " +
             format_g(s.stress.trace() / 3.0) + " Pa";
    return false;
  }

  // f = (|r - alpha| - m_e) / m_e; -infinity where P <= 0 (the law is then inadmissible).
  // Templated so that the driver can differentiate where a substep meets the surface.
  template <typename T>
  static T yield_function(const T* p, const StateT<T>& s) {
    const T pr = trace(s.stress) / T(3);
    if (!(pr > T(0))) return T(-std::numeric_limits<double>::infinity());
    return (safe_norm(Mat3<T>(dev(s.stress) / pr - from_mandel<T>(s.internal))) - p[kM]) / p[kM];
  }

  // Drift correction after an explicit substep: a state outside the surface has its alpha moved
  // along n until |r - alpha| = m. Only the back ratio changes, never stress or fabric, so the
  // correction cannot create stress that the strain did not cause. Inward drift after plastic
  // loading (`on_surface`) is corrected only with the sharp switch (w_yield = 0), where a state
  // a hair inside would turn elastic; with the smooth transition (plastic_share) such a state
  // is still plastic, and pulling it back onto the surface would make the step a non-smooth
  // function of the parameters.
  template <typename T>
  static void correct(const T* p, StateT<T>* s, bool on_surface) {
    const T pr = trace(s->stress) / T(3);
    if (!(pr > T(0))) return;
    const Mat3<T> xi = dev(s->stress) / pr - from_mandel<T>(s->internal);
    const T xi_norm = safe_norm(xi);
    const T f = xi_norm - p[kM];
    const bool sharp = !(p[kWyield] > T(kYieldSurfaceBand));
    if ((f > T(0) || (on_surface && sharp)) && xi_norm > T(0))
      s->internal += to_mandel<T>(Mat3<T>(xi * (f / xi_norm)));
  }
};

}  // namespace rendulic::models
