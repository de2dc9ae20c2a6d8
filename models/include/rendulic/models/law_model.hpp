// Bridges a scalar-generic law (a struct of static functions, one per *_law.hpp) to the
// run-time Law interface (law.hpp). A model M provides:
//   kName, parameter_info(), internal_names(),
//   template <class T> static RateT<T> rate(const T* p, const StateT<T>& s, const Mat3<T>& de)
//   static Matrix6d tangent(const double* p, const MaterialState& s, const Matrix3d& de)
//   static Vector6d initial_internal(const double* p, const Matrix3d& stress, const Matrix3d& F)
//   static bool admissible(const double* p, const MaterialState& s, std::string* why)
//   static void correct(const double* p, MaterialState* s, bool on_surface)
//   static double yield_function(const double* p, const MaterialState& s)  (-inf: none)
// so that calibration code can call M::rate<ceres::Jet<...>> directly (models.md
// "Calibration": autodiff through the law where the law is smooth).
#pragma once

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

}  // namespace rendulic::models
