// Scalar-generic tensor helpers for the constitutive laws (docs/models.md "Coordinates"). The laws
// are templates on the scalar type so that the calibration layer can push Ceres Jets through
// them; core/conventions.hpp is the reference for doubles and these helpers follow it exactly
// (trace, deviator, double contraction, Mandel order xx, yy, zz, sqrt2 yz, sqrt2 xz, sqrt2 xy).
// Only the operations a law needs are here; signs and Rendulic pairs stay in conventions.hpp.
#pragma once

#include <Eigen/Dense>
#include <cmath>

namespace rendulic::models {

template <typename T>
using Mat3 = Eigen::Matrix<T, 3, 3>;
template <typename T>
using Vec6 = Eigen::Matrix<T, 6, 1>;

template <typename T>
T trace(const Mat3<T>& a) {
  return a(0, 0) + a(1, 1) + a(2, 2);
}

template <typename T>
Mat3<T> dev(const Mat3<T>& a) {
  Mat3<T> d = a;
  const T m = trace(a) / T(3);
  d(0, 0) -= m;
  d(1, 1) -= m;
  d(2, 2) -= m;
  return d;
}

// A : B for 3x3 tensors.
template <typename T>
T ddot(const Mat3<T>& a, const Mat3<T>& b) {
  return (a.array() * b.array()).sum();
}

// Frobenius norm that is zero (with zero derivative) at the zero tensor: sqrt has an infinite
// derivative at 0, which would poison a Jet even where the norm is multiplied by zero.
template <typename T>
T safe_norm(const Mat3<T>& a) {
  using std::sqrt;
  const T s = ddot(a, a);
  return s > T(0) ? T(sqrt(s)) : T(0);
}

template <typename T>
Mat3<T> identity3() {
  return Mat3<T>::Identity();
}

template <typename T>
Vec6<T> mandel_of(const Mat3<T>& q) {
  const T r2 = T(std::sqrt(2.0));
  Vec6<T> v;
  v << q(0, 0), q(1, 1), q(2, 2), r2 * q(1, 2), r2 * q(0, 2), r2 * q(0, 1);
  return v;
}

template <typename T>
Mat3<T> tensor_of(const Vec6<T>& v) {
  const T r2 = T(std::sqrt(2.0));
  const T yz = v(3) / r2, xz = v(4) / r2, xy = v(5) / r2;
  Mat3<T> q;
  q << v(0), xy, xz, xy, v(1), yz, xz, yz, v(2);
  return q;
}

}  // namespace rendulic::models
