// TOML readers for law parameters and material-point states (material_io.hpp).
#include "rendulic/models/material_io.hpp"

#include <toml++/toml.h>

#include <Eigen/Eigenvalues>
#include <cmath>

#include "rendulic/core/errors.hpp"
#include "rendulic/core/text_file.hpp"
#include "toml_input.hpp"

namespace rendulic::models {

toml::table parse_toml_input(const std::string& path, const std::string& what,
                             const std::string* text) {
  constexpr std::size_t kMaxBytes = std::size_t{1} << 20;  // a few lines of numbers
  const std::string read = text ? std::string() : read_input_text(path, what, kMaxBytes);
  try {
    return toml::parse(text ? *text : read, path);
  } catch (const toml::parse_error& e) {
    const auto& where = e.source().begin;
    throw InputError(path + ":" + std::to_string(where.line) + ": " + std::string(e.description()));
  }
}

namespace {

double number(const toml::node& node, const std::string& key, const std::string& path) {
  const std::optional<double> v = node.value<double>();
  if (!v || !std::isfinite(*v))
    throw InputError(path + ": key '" + key + "' must be a finite number");
  return *v;
}

Eigen::Matrix3d matrix3(const toml::node& node, const std::string& key, const std::string& path) {
  const toml::array* rows = node.as_array();
  if (!rows || rows->size() != 3)
    throw InputError(path + ": key '" + key + "' must be a 3x3 array of numbers");
  Eigen::Matrix3d m;
  for (int i = 0; i < 3; ++i) {
    const toml::array* row = (*rows)[i].as_array();
    if (!row || row->size() != 3)
      throw InputError(path + ": key '" + key + "' must be a 3x3 array of numbers");
    for (int j = 0; j < 3; ++j)
      m(i, j) =
          number((*row)[j], key + "[" + std::to_string(i) + "][" + std::to_string(j) + "]", path);
  }
  // Stress and fabric are symmetric; an asymmetric input is a typo, not something to average.
  const double scale = std::max(m.norm(), 1e-300);
  if ((m - m.transpose()).norm() > 1e-12 * scale)
    throw InputError(path + ": key '" + key + "' must be a symmetric 3x3 tensor");
  return m;
}

}  // namespace

void load_parameters_toml(const std::string& path, Law* law) {
  parse_parameters_toml("", path, law, false);
}
MaterialState load_state_toml(const std::string& path, const Law& law) {
  return parse_state_toml("", path, law, false);
}

void parse_parameters_toml(const std::string& text, const std::string& path, Law* law,
                           bool from_text) {
  const toml::table tbl = parse_toml_input(path, "parameter file", from_text ? &text : nullptr);
  std::vector<double> values = law->parameters();
  for (const auto& [k, node] : tbl) {
    const std::string key(k.str());
    const int i = law->parameter_index(key);
    if (i < 0) {
      throw InputError(path + ": " + law->unknown_parameter(key));
    }
    const double v = number(node, key, path);
    const ParameterInfo& info = law->parameter_info()[i];
    if (v < info.lower || v > info.upper) throw InputError(path + ": " + info.out_of_bounds(v));
    values[i] = v;
  }
  std::string why;
  if (!law->set_parameters(values, &why)) throw InputError(path + ": " + why);
}

MaterialState parse_state_toml(const std::string& text, const std::string& path, const Law& law,
                               bool from_text) {
  const toml::table tbl = parse_toml_input(path, "state file", from_text ? &text : nullptr);
  Eigen::Matrix3d stress, fabric = Eigen::Matrix3d::Zero();
  double nu = 0.0;
  bool have_stress = false;
  for (const auto& [k, node] : tbl) {
    const std::string key(k.str());
    if (key == "stress") {
      stress = matrix3(node, key, path);
      have_stress = true;
    } else if (key == "fabric") {
      fabric = matrix3(node, key, path);
      // A second moment of contact normals has no negative eigenvalue. diag(-1, 0.5, 0.5) (trace
      // 0) failed every probe with "substep below 1e-10 ... (law too stiff or undefined)": the
      // elastic fabric increment F / tr(F) switches branch where tr(F) crosses 0.
      const Eigen::Vector3d eig =
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(fabric, Eigen::EigenvaluesOnly)
              .eigenvalues();
      if (eig.minCoeff() < -1e-12 * eig.cwiseAbs().maxCoeff())
        throw InputError(path +
                         ": key 'fabric' must be positive semi-definite (a second moment of "
                         "contact normals), got eigenvalues " +
                         format_g(eig[0]) + ", " + format_g(eig[1]) + ", " + format_g(eig[2]));
    } else if (key == "volume_fraction") {
      nu = number(node, key, path);
      if (!(nu >= 0.0 && nu < 1.0))
        throw InputError(path + ": key 'volume_fraction' must be in [0, 1)");
    } else {
      throw InputError(path + ": unknown key '" + key +
                       "' (a state has stress, fabric, volume_fraction)");
    }
  }
  if (!have_stress) throw InputError(path + ": missing key 'stress' (3x3, Pa)");
  return law.make_state(stress, fabric, nu);
}

}  // namespace rendulic::models
