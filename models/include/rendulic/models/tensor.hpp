// Scalar-generic tensor helpers for the constitutive laws (docs/models.md "Coordinates"). The laws
// are templates on the scalar type so that the calibration layer can push Ceres Jets through
// them; core/conventions.hpp is the reference for doubles and these helpers follow it exactly
// (trace, deviator, double contraction). Only the operations a law needs are here; signs,
// Rendulic pairs and the Mandel form (to_mandel<T>, from_mandel<T>) stay in conventions.hpp.
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

}  // namespace rendulic::models
