// Compile-time access to the scalar-generic laws of models/ (law_model.hpp) from a run-time name,
// so that calibration can push Ceres Jets through M::rate<T> (docs/calibration.md "Predictions and
// derivatives": autodiff through the law where the law is smooth), and a Law whose parameters
// calibration sets without the bound check (central differences step a hair past a bound).
#pragma once

#include <string_view>
#include <type_traits>

#include "rendulic/core/comma_list.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/models/elastic_laws.hpp"
#include "rendulic/models/elastoplastic_fabric.hpp"
#include "rendulic/models/hypoplastic_wu.hpp"
#include "rendulic/models/law.hpp"

namespace rendulic::calibration::detail {

template <class M>
struct LawTag {
  using type = M;
};

// Calls f(LawTag<M>{}) for the law named `name`; InputError for an unknown name.
template <class F>
decltype(auto) dispatch_law(std::string_view name, F&& f) {
  using namespace rendulic::models;
  if (name == IsotropicElastic::kName) return f(LawTag<IsotropicElastic>{});
  if (name == AnisotropicElastic::kName) return f(LawTag<AnisotropicElastic>{});
  if (name == HypoplasticWu::kName) return f(LawTag<HypoplasticWu>{});
  if (name == ElastoplasticFabric::kName) return f(LawTag<ElastoplasticFabric>{});
  throw InputError("unknown model '" + std::string(name) + "' (known: " + comma_list(law_names()) +
                   ")");
}

// Whether the law carries a fabric response at all.
template <class M>
constexpr bool kHasFabric = !std::is_same_v<M, models::HypoplasticWu>;

// The law M with parameters set as given (the calibration keeps them inside the search box
// itself; only finite-difference steps cross a bound, by ~1e-6 relative).
template <class M>
class ParamLaw final : public models::Law {
 public:
  explicit ParamLaw(const double* p) { params_.assign(p, p + M::kCount); }
  std::string_view name() const override { return M::kName; }
  const std::vector<models::ParameterInfo>& parameter_info() const override {
    return M::parameter_info();
  }
  const std::vector<std::string>& internal_names() const override { return M::internal_names(); }
  models::LawRate rate(const models::MaterialState& s, const Eigen::Matrix3d& de) const override {
    return M::template rate<double>(params_.data(), s, de);
  }
  Matrix6d tangent(const models::MaterialState& s, const Eigen::Matrix3d& de) const override {
    return M::tangent(params_.data(), s, de);
  }
  Vector6d initial_internal(const Eigen::Matrix3d& stress,
                            const Eigen::Matrix3d& fabric) const override {
    return M::initial_internal(params_.data(), stress, fabric);
  }
  bool admissible(const models::MaterialState& s, std::string* why) const override {
    return M::admissible(params_.data(), s, why);
  }
  void correct(models::MaterialState* s, bool on_surface) const override {
    M::correct(params_.data(), s, on_surface);
  }
  double yield_function(const models::MaterialState& s) const override {
    return M::yield_function(params_.data(), s);
  }
};

}  // namespace rendulic::calibration::detail
