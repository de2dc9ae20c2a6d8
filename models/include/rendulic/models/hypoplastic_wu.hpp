// Family 3 of docs/models.md: the four-constant hypoplastic law of Wu and Bauer (1994) as used in
// Wu, Bauer and Kolymbas (1996, Mech. Mater. 23:45-69) with the density factor set to one,
// and the envelope theory of Gudehus (1979) and Wu (2000). In the authors' tension-positive
// notation (T stress, D stretching):
//   T' = c1 tr(T) D + c2 tr(T D)/tr(T) T + (c3 T^2 + c4 T*^2)/tr(T) |D|.
// With sigma = -T and d_eps = -D dt (compression positive, docs/physics.md section 2) this reads
//   d_sigma = L(sigma) : d_eps + N(sigma) |d_eps|,
//   L : x = -c1 tr(sigma) x - c2 (sigma : x)/tr(sigma) sigma,
//   N     = (c3 sigma^2 + c4 (sigma^D)^2) / tr(sigma),
// so the constants keep the signs and values published for sand (c1, c2, c3 < 0, c4 > 0).
// The envelope of one increment is the ellipse of L shifted by N |d_eps| (docs/models.md).
// The law carries no fabric: d_F = 0 (its fabric envelope is the origin).
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "rendulic/models/law.hpp"

namespace rendulic::models {

// Rate-independent but without a yield surface: admissible is its own (tr(sigma) > 0).
struct HypoplasticWu : WithoutPlasticity {
  static constexpr std::string_view kName = "hypoplastic_wu";
  enum : int { kC1, kC2, kC3, kC4, kCount };
  static const std::vector<ParameterInfo>& parameter_info();
  static const std::vector<std::string>& internal_names();

  template <typename T>
  static Mat3<T> nonlinear_term(const T* p, const Mat3<T>& sigma) {
    const Mat3<T> s_dev = dev(sigma);
    return (p[kC3] * sigma * sigma + p[kC4] * s_dev * s_dev) / trace(sigma);
  }

  template <typename T>
  static RateT<T> rate(const T* p, const StateT<T>& s, const Mat3<T>& de) {
    const T tr_s = trace(s.stress);
    RateT<T> r;
    r.d_stress = -p[kC1] * tr_s * de - p[kC2] * ddot(s.stress, de) / tr_s * s.stress +
                 nonlinear_term(p, s.stress) * safe_norm(de);
    return r;
  }
  // L (the linear part) in Mandel form.
  static Matrix6d linear_matrix(const double* p, const Eigen::Matrix3d& sigma) {
    const double tr_s = sigma.trace();
    const Vector6d s6 = to_mandel(sigma);
    return -p[kC1] * tr_s * Matrix6d::Identity() - p[kC2] / tr_s * s6 * s6.transpose();
  }
  static Matrix6d tangent(const double* p, const MaterialState& s, const Eigen::Matrix3d& de) {
    Matrix6d t = linear_matrix(p, s.stress);
    const double n = de.norm();
    if (n > 0.0) t += to_mandel(nonlinear_term(p, s.stress)) * to_mandel(de).transpose() / n;
    return t;
  }
  static bool admissible(const double*, const MaterialState& s, std::string* why) {
    if (s.stress.trace() > 0.0) return true;
    if (why)
      *why = "hypoplastic_wu needs tr(sigma) > 0 (compression), got " + format_g(s.stress.trace()) +
             " Pa";
    return false;
  }
};

}  // namespace rendulic::models
