// Parameter tables (names, units, defaults, bounds) of the four laws, the Law base methods and
// the registry (law.hpp; defaults and sources are discussed in docs/models.md).
#include <cmath>
#include <limits>
#include <ranges>

#include "rendulic/core/comma_list.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/models/elastic_laws.hpp"
#include "rendulic/models/elastoplastic_fabric.hpp"
#include "rendulic/models/hypoplastic_wu.hpp"
#include "rendulic/models/law_model.hpp"
#include "rendulic/models/umat.hpp"

namespace rendulic::models {

// Elastic defaults are of the order of the frictionless DEM of docs/physics.md at nu = 0.82
// (k* = k / 2<r> = 5e10 Pa; B/k* = 0.4, G/k* = 0.05: narrow envelopes, seed section 4); they
// are starting points for the calibration, not measured values.
const std::vector<ParameterInfo>& IsotropicElastic::parameter_info() {
  static const std::vector<ParameterInfo> info = {
      {"K", "Pa", 2.0e10, 1.0, 1e13, "bulk modulus at p_ref"},
      {"G", "Pa", 2.5e9, 1.0, 1e13, "shear modulus at p_ref"},
      {"n_p", "1", 0.0, 0.0, 1.0, "pressure exponent: moduli scale with (P/p_ref)^n_p"},
      {"p_ref", "Pa", 1e9, 1.0, 1e12, "reference pressure of the moduli"},
      {"c_F", "1", 5.0, 0.0, 1e3, "d tr(F) / d eps_v: isotropic fabric growth"},
      {"n_nu", "1", 0.0, 0.0, 50.0, "volume-fraction exponent: moduli scale with (nu/nu_ref)^n_nu"},
      {"nu_ref", "1", 0.82, 0.3, 0.95, "reference volume fraction of the moduli"},
  };
  return info;
}
const std::vector<std::string>& IsotropicElastic::internal_names() {
  static const std::vector<std::string> names;
  return names;
}

const std::vector<ParameterInfo>& AnisotropicElastic::parameter_info() {
  static const std::vector<ParameterInfo> info = {
      {"B", "Pa", 2.0e10, 1.0, 1e13, "bulk modulus at p_ref"},
      {"G", "Pa", 2.5e9, 1.0, 1e13, "shear modulus at p_ref and isotropic fabric"},
      {"beta_A", "1", 0.5, -10.0, 10.0, "anisotropy coupling: A = beta_A F_dev B"},
      {"n_p", "1", 0.0, 0.0, 1.0, "pressure exponent: B, G scale with (P/p_ref)^n_p"},
      {"p_ref", "Pa", 1e9, 1.0, 1e12, "reference pressure of the moduli"},
      {"a_G", "1", 0.0, 0.0, 1e3, "shear softening by anisotropy: G / (1 + a_G F^D:F^D)"},
      {"c_F", "1", 5.0, 0.0, 1e3, "d tr(F) / d eps_v: isotropic fabric growth"},
      {"n_nu", "1", 0.0, 0.0, 50.0, "volume-fraction exponent: B, G scale with (nu/nu_ref)^n_nu"},
      {"nu_ref", "1", 0.82, 0.3, 0.95, "reference volume fraction of the moduli"},
  };
  return info;
}
const std::vector<std::string>& AnisotropicElastic::internal_names() {
  static const std::vector<std::string> names;
  return names;
}

// Wu and Bauer (1994), Karlsruhe medium sand, as restated by Wu, Bauer and Kolymbas (1996):
// c1 = -101.2, c2 = -962.1, c3 = -877.7, c4 = 1229.2 (dimensionless, tension-positive signs).
const std::vector<ParameterInfo>& HypoplasticWu::parameter_info() {
  static const std::vector<ParameterInfo> info = {
      {"c1", "1", -101.2, -1e5, 0.0, "linear term c1 tr(T) D"},
      {"c2", "1", -962.1, -1e5, 0.0, "linear term c2 tr(TD)/tr(T) T"},
      {"c3", "1", -877.7, -1e5, 1e5, "non-linear term c3 T^2/tr(T) |D|"},
      {"c4", "1", 1229.2, -1e5, 1e5, "non-linear term c4 T*^2/tr(T) |D|"},
  };
  return info;
}
const std::vector<std::string>& HypoplasticWu::internal_names() {
  static const std::vector<std::string> names;
  return names;
}

const std::vector<ParameterInfo>& ElastoplasticFabric::parameter_info() {
  static const std::vector<ParameterInfo> info = [] {
    std::vector<ParameterInfo> v = AnisotropicElastic::parameter_info();
    v.push_back(
        {"m_e", "1", 1e-3, 1e-8, 0.5, "elastic range: radius of |r - alpha| (r = sigma^D/P)"});
    v.push_back({"M_ss", "1", 0.2, 1e-3, 3.0, "steady-state stress ratio |sigma^D|/P"});
    v.push_back({"beta_s", "1", 10.0, 1e-2, 1e5,
                 "rate of approach of the stress ratio to M_ss per plastic strain"});
    v.push_back(
        {"beta_F", "1", 30.0, 0.0, 1e5, "rate of approach of F^D to F_dev_max per plastic strain"});
    v.push_back({"F_dev_max", "1", 0.5, 0.0, 10.0, "steady-state fabric deviator |F^D|"});
    v.push_back({"w_yield", "1", 0.02, 0.0, 0.5,
                 "width of the elastic-to-plastic transition below the yield surface, in units of "
                 "the elastic range (0: a sharp switch)"});
    return v;
  }();
  return info;
}
const std::vector<std::string>& ElastoplasticFabric::internal_names() {
  static const std::vector<std::string> names = {
      "alpha_xx", "alpha_yy", "alpha_zz", "alpha_yz_mandel", "alpha_xz_mandel", "alpha_xy_mandel"};
  return names;
}

std::string ParameterInfo::out_of_bounds(double value) const {
  return "parameter '" + name + "' = " + format_g(value) + " is outside its bounds [" +
         format_g(lower) + ", " + format_g(upper) + "]" + (unit.empty() ? "" : " " + unit);
}

bool Law::set_parameters(const std::vector<double>& values, std::string* why) {
  const auto& info = parameter_info();
  if (values.size() != info.size()) {
    if (why)
      *why = std::string(name()) + " takes " + std::to_string(info.size()) + " parameters, got " +
             std::to_string(values.size());
    return false;
  }
  for (size_t i = 0; i < info.size(); ++i) {
    const double v = values[i];
    if (!std::isfinite(v) || v < info[i].lower || v > info[i].upper) {
      if (why) *why = info[i].out_of_bounds(v);
      return false;
    }
  }
  params_ = values;
  return true;
}

std::string Law::unknown_parameter(std::string_view pname) const {
  const auto names =
      parameter_info() |
      std::views::transform([](const ParameterInfo& p) -> const std::string& { return p.name; });
  return "unknown parameter '" + std::string(pname) + "' of " + std::string(name()) +
         " (known: " + comma_list(names) + ")";
}

bool Law::set_parameter(std::string_view pname, double value, std::string* why) {
  const int i = parameter_index(pname);
  if (i < 0) {
    if (why) *why = unknown_parameter(pname);
    return false;
  }
  std::vector<double> v = params_;
  v[i] = value;
  return set_parameters(v, why);
}

int Law::parameter_index(std::string_view pname) const {
  const auto& info = parameter_info();
  for (size_t i = 0; i < info.size(); ++i)
    if (info[i].name == pname) return static_cast<int>(i);
  return -1;
}

double Law::parameter(std::string_view pname) const {
  const int i = parameter_index(pname);
  return i < 0 ? std::numeric_limits<double>::quiet_NaN() : params_[i];
}

std::vector<double> Law::default_parameters() const {
  std::vector<double> v;
  for (const auto& p : parameter_info()) v.push_back(p.default_value);
  return v;
}

MaterialState Law::make_state(const Eigen::Matrix3d& stress, const Eigen::Matrix3d& fabric,
                              double volume_fraction) const {
  MaterialState s;
  s.stress = stress;
  s.fabric = fabric;
  s.volume_fraction = volume_fraction;
  s.internal = initial_internal(stress, fabric);
  return s;
}

// Numbers in messages: shortest readable form (1e+13, not 10000000000000.000000).
std::string format_g(double v) { return decimal_g(v); }

std::vector<std::string> law_names() {
  return {std::string(IsotropicElastic::kName), std::string(AnisotropicElastic::kName),
          std::string(HypoplasticWu::kName), std::string(ElastoplasticFabric::kName)};
}

std::unique_ptr<Law> make_law(std::string_view name) {
  if (name == IsotropicElastic::kName) return std::make_unique<LawModel<IsotropicElastic>>();
  if (name == AnisotropicElastic::kName) return std::make_unique<LawModel<AnisotropicElastic>>();
  if (name == HypoplasticWu::kName) return std::make_unique<LawModel<HypoplasticWu>>();
  if (name == ElastoplasticFabric::kName) return std::make_unique<LawModel<ElastoplasticFabric>>();
  // A user's UMAT, once a run has loaded one (umat.hpp).
  if (name == "umat")
    if (const auto u = session_umat()) return std::make_unique<UmatLaw>(*u);
  return nullptr;
}

}  // namespace rendulic::models
