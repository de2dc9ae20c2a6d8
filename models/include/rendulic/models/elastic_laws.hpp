// The two elastic families of docs/models.md: (1) isotropic hypoelasticity with optionally
// pressure-dependent moduli, (2) the anisotropic elasticity of Kumar, Luding and Magnanimo
// (Acta Mech. 225, 2014) in exactly the tensor form pinned by docs/models.md:
//   d_sigma = B tr(d_eps) I + 2G d_eps^D + beta_A B [ (F^D : d_eps) I + F^D tr(d_eps) ],
// which on axisymmetric states gives dP = B d_eps_v + A d_eps_dev,
// d_sigma_dev = A d_eps_v + 2G d_eps_dev with A = beta_A F_dev B.
// State dependence (documented in docs/models.md): B and G scale with (P/p_ref)^n_p and with
// (nu/nu_ref)^n_nu, and G is
// divided by (1 + a_G F^D:F^D) (shear stiffness falls as fabric anisotropy grows, seed paper
// section 4.1). With the defaults n_p = 0, a_G = 0 the moduli are constants and the pinned
// form holds literally. Fabric: d_F = c_F tr(d_eps) F / tr(F) (no deviatoric fabric change in
// the elastic regime, seed paper Fig. 4; the isotropic part grows with compression).
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>
#include <vector>

#include "rendulic/models/law.hpp"

namespace rendulic::models {

namespace detail {

// (max(P, p_floor)/p_ref)^n: the floor keeps the factor finite at zero or tensile pressure.
template <typename T>
T pressure_factor(const Mat3<T>& stress, const T& n_p, const T& p_ref) {
  using std::pow;
  // pow is most of a rate evaluation; skip it for doubles at the default exponent 0 (not for
  // Jets: d/dn x^n at n = 0 is ln x, which calibration needs).
  if constexpr (std::is_same_v<T, double>) {
    if (n_p == 0.0) return 1.0;
  }
  T p = trace(stress) / T(3);
  const T p_floor = T(1e-6) * p_ref;
  if (p < p_floor) p = p_floor;
  return pow(p / p_ref, n_p);
}

// (nu / nu_ref)^n_nu where the state carries a volume fraction; 1 where it does not (nu = 0).
template <typename T>
T volume_factor(const T& nu, const T& n_nu, const T& nu_ref) {
  using std::pow;
  if (!(nu > T(0))) return T(1);
  if constexpr (std::is_same_v<T, double>) {
    if (n_nu == 0.0) return 1.0;
  }
  return pow(nu / nu_ref, n_nu);
}

// Elastic fabric increment c_F tr(d_eps) F / tr(F); an empty fabric grows isotropically.
template <typename T>
Mat3<T> elastic_fabric_increment(const Mat3<T>& fabric, const T& c_f, const Mat3<T>& de) {
  const T tr_f = trace(fabric);
  const T dv = trace(de);
  if (tr_f > T(0)) return (c_f * dv / tr_f) * fabric;
  return (c_f * dv / T(3)) * identity3<T>();
}

// The pinned anisotropic elastic operator applied to a tensor x.
template <typename T>
Mat3<T> anisotropic_apply(const T& b, const T& g, const T& beta_a, const Mat3<T>& f_dev,
                          const Mat3<T>& x) {
  const T tr_x = trace(x);
  return b * tr_x * identity3<T>() + T(2) * g * dev(x) +
         beta_a * b * (ddot(f_dev, x) * identity3<T>() + f_dev * tr_x);
}

inline Matrix6d anisotropic_matrix(double b, double g, double beta_a,
                                   const Eigen::Matrix3d& f_dev) {
  Vector6d one;
  one << 1, 1, 1, 0, 0, 0;
  const Vector6d f = to_mandel(f_dev);
  const Matrix6d i_dev = Matrix6d::Identity() - one * one.transpose() / 3.0;
  return b * one * one.transpose() + 2.0 * g * i_dev +
         beta_a * b * (one * f.transpose() + f * one.transpose());
}

}  // namespace detail

// Family 1: d_sigma = K tr(d_eps) I + 2 G d_eps^D, K and G times (P/p_ref)^n_p.
struct IsotropicElastic : WithoutPlasticity {
  static constexpr std::string_view kName = "isotropic_elastic";
  enum : int { kK, kG, kNp, kPref, kCf, kNnu, kNuRef, kCount };
  static const std::vector<ParameterInfo>& parameter_info();
  static const std::vector<std::string>& internal_names();

  template <typename T>
  static void moduli(const T* p, const StateT<T>& s, T* k, T* g) {
    const T factor = detail::pressure_factor(s.stress, p[kNp], p[kPref]) *
                     detail::volume_factor(s.volume_fraction, p[kNnu], p[kNuRef]);
    *k = p[kK] * factor;
    *g = p[kG] * factor;
  }

  template <typename T>
  static RateT<T> rate(const T* p, const StateT<T>& s, const Mat3<T>& de) {
    T k, g;
    moduli(p, s, &k, &g);
    RateT<T> r;
    r.d_stress = k * trace(de) * identity3<T>() + T(2) * g * dev(de);
    r.d_fabric = detail::elastic_fabric_increment(s.fabric, p[kCf], de);
    return r;
  }
  static Matrix6d tangent(const double* p, const MaterialState& s, const Eigen::Matrix3d&) {
    double k, g;
    moduli(p, s, &k, &g);
    return detail::anisotropic_matrix(k, g, 0.0, Eigen::Matrix3d::Zero());
  }
};

// Family 2 (Kumar, Luding, Magnanimo 2014), see the file comment.
struct AnisotropicElastic : WithoutPlasticity {
  static constexpr std::string_view kName = "anisotropic_elastic";
  enum : int { kB, kG, kBetaA, kNp, kPref, kAg, kCf, kNnu, kNuRef, kCount };
  static const std::vector<ParameterInfo>& parameter_info();
  static const std::vector<std::string>& internal_names();

  // Effective B and G at the state (the "documented state dependence").
  template <typename T>
  static void moduli(const T* p, const StateT<T>& s, T* b, T* g) {
    const T factor = detail::pressure_factor(s.stress, p[kNp], p[kPref]) *
                     detail::volume_factor(s.volume_fraction, p[kNnu], p[kNuRef]);
    const Mat3<T> f_dev = dev(s.fabric);
    *b = p[kB] * factor;
    *g = p[kG] * factor / (T(1) + p[kAg] * ddot(f_dev, f_dev));
  }

  template <typename T>
  static RateT<T> rate(const T* p, const StateT<T>& s, const Mat3<T>& de) {
    T b, g;
    moduli(p, s, &b, &g);
    RateT<T> r;
    r.d_stress = detail::anisotropic_apply(b, g, p[kBetaA], dev(s.fabric), de);
    r.d_fabric = detail::elastic_fabric_increment(s.fabric, p[kCf], de);
    return r;
  }
  static Matrix6d tangent(const double* p, const MaterialState& s, const Eigen::Matrix3d&) {
    double b, g;
    moduli(p, s, &b, &g);
    return detail::anisotropic_matrix(b, g, p[kBetaA], dev(s.fabric));
  }
};

}  // namespace rendulic::models
