// Bridges a scalar-generic law (a struct of static functions, one per *_law.hpp) to the
// run-time Law interface (law.hpp). A model M provides:
//   kName, parameter_info(), internal_names(),
//   template <class T> static RateT<T> rate(const T* p, const StateT<T>& s, const Mat3<T>& de)
//   static Matrix6d tangent(const double* p, const MaterialState& s, const Matrix3d& de)
//   static Vector6d initial_internal(const double* p, const Matrix3d& stress, const Matrix3d& F)
//   static bool admissible(const double* p, const MaterialState& s, std::string* why)
//   template <class T> static void correct(const T* p, StateT<T>* s, bool on_surface)
//   template <class T> static T yield_function(const T* p, const StateT<T>& s)  (-inf: none)
// (a law without plasticity takes the last four from WithoutPlasticity, law.hpp)
// so that calibration code can call M::rate<ceres::Jet<...>> directly (docs/calibration.md
// "Predictions and derivatives": autodiff through the law where the law is smooth), and integrate
// the law with Jets through the driver (driver_core.hpp) via StaticLawOps.
#pragma once

#include <string>

#include "rendulic/models/law.hpp"

namespace rendulic::models {

template <class M>
class LawModel final : public Law {
 public:
  LawModel() { params_ = default_parameters(); }
  std::string_view name() const override { return M::kName; }
  const std::vector<ParameterInfo>& parameter_info() const override { return M::parameter_info(); }
  const std::vector<std::string>& internal_names() const override { return M::internal_names(); }
  LawRate rate(const MaterialState& s, const Eigen::Matrix3d& de) const override {
    return M::template rate<double>(params_.data(), s, de);
  }
  Matrix6d tangent(const MaterialState& s, const Eigen::Matrix3d& de) const override {
    return M::tangent(params_.data(), s, de);
  }
  Vector6d initial_internal(const Eigen::Matrix3d& stress,
                            const Eigen::Matrix3d& fabric) const override {
    return M::initial_internal(params_.data(), stress, fabric);
  }
  bool admissible(const MaterialState& s, std::string* why) const override {
    return M::admissible(params_.data(), s, why);
  }
  void correct(MaterialState* s, bool on_surface) const override {
    M::correct(params_.data(), s, on_surface);
  }
  double yield_function(const MaterialState& s) const override {
    return M::yield_function(params_.data(), s);
  }
};

// The law M with parameters p (scalar T: double, or Jets for derivatives) and their values pd,
// as the Ops of driver_core.hpp's integrator. With T = double, p and pd are the same.
template <class M, typename T>
struct StaticLawOps {
  using Scalar = T;
  const T* p;
  const double* pd;
  RateT<T> rate(const StateT<T>& s, const Mat3<T>& de) const {
    return M::template rate<T>(p, s, de);
  }
  void correct(StateT<T>* s, bool on_surface) const { M::correct(p, s, on_surface); }
  T yield_function(const StateT<T>& s) const { return M::yield_function(p, s); }
  LawRate value_rate(const MaterialState& s, const Eigen::Matrix3d& de) const {
    return M::template rate<double>(pd, s, de);
  }
  void value_correct(MaterialState* s, bool on_surface) const { M::correct(pd, s, on_surface); }
  double value_yield_function(const MaterialState& s) const { return M::yield_function(pd, s); }
  bool admissible(const MaterialState& s, std::string* why) const {
    return M::admissible(pd, s, why);
  }
};

}  // namespace rendulic::models
