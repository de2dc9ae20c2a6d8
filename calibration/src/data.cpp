// Loading calibration data from a results file (data.hpp; docs/results.md).
#include "rendulic/calibration/data.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>

#include "rendulic/core/comma_list.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/core/envelope_io.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/log.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/core/results.hpp"
#include "rendulic/models/paths.hpp"

namespace rendulic::calibration {

bool is_valid_envelope(const EnvelopeRecord& e, std::string* why) {
  auto fail = [&](const std::string& m) {
    if (why) *why = "envelope '" + e.name + "': " + m;
    return false;
  };
  const std::size_t m = e.stress.size();
  if (m < 3) return fail("fewer than 3 probe directions");
  if (e.strain.size() != m || e.theta_deg.size() != m)
    return fail("strain, directions and stress have different lengths");
  if (!e.fabric.empty() && e.fabric.size() != m) return fail("fabric and stress differ in length");
  if (!(e.amplitude > 0.0) || !std::isfinite(e.amplitude)) return fail("amplitude must be > 0");
  for (std::size_t i = 0; i < m; ++i) {
    if (!e.stress[i].allFinite() || !e.strain[i].allFinite() || !std::isfinite(e.theta_deg[i]) ||
        (!e.fabric.empty() && !e.fabric[i].allFinite()))
      return fail(std::string("non-finite value in probe ") + std::to_string(i));
  }
  return true;
}

const EnvelopeRecord* StateData::elastic_envelope() const {
  const EnvelopeRecord* best = nullptr;
  for (const auto& e : envelopes)
    if (e.elastic() && (!best || e.amplitude < best->amplitude)) best = &e;
  return best;
}

const EnvelopeRecord* StateData::plastic_envelope() const {
  const EnvelopeRecord* best = nullptr;
  for (const auto& e : envelopes)
    if (!e.elastic() && (!best || e.amplitude > best->amplitude)) best = &e;
  return best;
}

const StateData* CalibrationData::find(const std::string& label) const {
  for (const auto& s : states)
    if (s.label == label) return &s;
  return nullptr;
}

std::vector<std::string> CalibrationData::labels() const {
  std::vector<std::string> out;
  for (const auto& s : states) out.push_back(s.label);
  return out;
}

bool LoadOptions::IsValid(std::string* why) const {
  if (max_path_samples < 2) {
    if (why) *why = "max_path_samples must be >= 2";
    return false;
  }
  return true;
}

EnvelopeRecord probe_set(const std::string& name, double amplitude, int directions) {
  EnvelopeRecord e;
  e.name = name;
  e.method = "model";
  e.amplitude = amplitude;
  const Eigen::VectorXd th = probe_directions_deg(directions);
  for (int i = 0; i < directions; ++i) {
    e.theta_deg.push_back(th(i));
    e.strain.push_back(rendulic_pair(probe_strain(th(i), amplitude)));
  }
  return e;
}

namespace {

std::string join(const std::vector<std::string>& v) { return comma_list(v, "(none)"); }

// A stored envelope (core/envelope_record.hpp) with what the calibration works with filled
// in: stress pairs in Pa (stress_star times /material k_star, or from the d_stress tensors of a
// file without pairs), fabric pairs (or from d_fabric), strain pairs (or from the directions)
// and the directions (or from the strain).
EnvelopeRecord calibration_envelope(const ResultsReader& r, const std::string& group,
                                    double k_star) {
  const std::string file = r.path().string();
  const double amplitude = r.attr_double(group, "amplitude");  // required here
  EnvelopeRecord e = read_envelope(r, group);
  e.amplitude = amplitude;
  if (e.method.empty()) e.method = "unknown";
  e.stress.clear();
  if (!e.stress_star.empty()) {
    for (const auto& p : e.stress_star) e.stress.push_back(p * k_star);
  } else if (!e.d_stress.empty()) {
    for (const auto& t : e.d_stress) e.stress.push_back(rendulic_pair(t));
  } else {
    throw InputError(file + ": envelope " + group + " has neither stress_star nor d_stress");
  }
  if (e.fabric.empty())
    for (const auto& t : e.d_fabric) e.fabric.push_back(rendulic_pair(t));
  if (e.strain.empty()) {
    if (e.theta_deg.empty())
      throw InputError(file + ": envelope " + group + " has neither strain nor theta_deg");
    for (double t : e.theta_deg) e.strain.push_back(rendulic_pair(probe_strain(t, e.amplitude)));
  }
  if (e.theta_deg.empty())
    for (const auto& s : e.strain) e.theta_deg.push_back(probe_direction_deg(s));
  std::string why;
  if (!is_valid_envelope(e, &why)) throw InputError(file + ": " + group + ": " + why);
  return e;
}

}  // namespace

CalibrationData load_calibration_data(const std::filesystem::path& file,
                                      const LoadOptions& options) {
  return load_calibration_data(ResultsReader(file), options);
}

CalibrationData load_calibration_data(const ResultsReader& r, const LoadOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("calibration data: " + why);
  const std::string name = r.path().string();
  CalibrationData data;
  data.source = name;
  if (!r.exists(paths::kMaterial)) throw InputError(name + ": no /material group");
  data.k_star = r.attr_double(paths::kMaterial, "k_star");
  if (!(data.k_star > 0.0) || !std::isfinite(data.k_star))
    throw InputError(name + ": /material k_star must be a positive number");
  if (!r.exists(paths::kStates)) throw InputError(name + ": no /states group (no relaxed states)");
  const std::vector<std::string> all = r.children(paths::kStates);
  auto has_envelopes = [&](const std::string& l) {
    const std::string g = paths::envelopes(paths::state(l));
    return r.exists(g) && !r.children(g).empty();
  };
  std::vector<std::string> wanted = options.states;
  if (wanted.empty()) {
    for (const auto& l : all)
      if (has_envelopes(l)) wanted.push_back(l);
    if (wanted.empty())
      throw InputError(name + ": no state has envelopes (states: " + join(all) + ")");
  }
  for (const auto& l : wanted) {
    if (std::find(all.begin(), all.end(), l) == all.end())
      throw InputError(name + ": no state '" + l + "' (states: " + join(all) + ")");
    if (!has_envelopes(l)) throw InputError(name + ": state '" + l + "' has no envelopes");
    const std::string g = paths::state(l);
    StateData s;
    s.label = l;
    s.stress = r.read_tensor(g + datasets::kStress);
    s.fabric = r.exists(g + datasets::kFabric) ? r.read_tensor(g + datasets::kFabric)
                                               : Eigen::Matrix3d::Zero();
    s.volume_fraction = r.has_attr(g, "volume_fraction") ? r.attr_double(g, "volume_fraction") : 0;
    s.eps_dev = r.has_attr(g, "eps_dev") ? r.attr_double(g, "eps_dev") : 0.0;
    if (!s.stress.allFinite() || !s.fabric.allFinite())
      throw InputError(name + ": state '" + l + "' has non-finite stress or fabric");
    // The laws' density terms read them: NaN or 1e300 changed the fit without a word.
    if (!(s.volume_fraction >= 0.0 && s.volume_fraction < 1.0))
      throw InputError(name + ":" + g + "@volume_fraction is " + decimal_g(s.volume_fraction) +
                       ", outside [0, 1)");
    if (!std::isfinite(s.eps_dev))
      throw InputError(name + ":" + g + "@eps_dev is not a finite number");
    for (const auto& e : r.children(paths::envelopes(g))) {
      // An envelope that could not be measured (e.g. no linear response of an unstable
      // network) carries only an `error` attribute: there is nothing to fit.
      if (r.has_attr(paths::envelope(g, e), "error")) continue;
      EnvelopeRecord env = calibration_envelope(r, paths::envelope(g, e), data.k_star);
      // The models' envelopes are Rendulic pairs (objective.cpp): an envelope of another probe
      // plane (docs/probes.md "Probe planes") is not calibration data.
      if (!env.plane.rendulic()) {
        log::info(name, ": envelope ", l, "/", e, " is in the ", env.plane.name,
                  " probe plane: not used by the calibration");
        continue;
      }
      s.envelopes.push_back(std::move(env));
    }
    data.states.push_back(std::move(s));
  }
  const std::string path = paths::kPath;
  // The path block drives the laws along the path's strain (PathData::increment): the
  // undrained axisymmetric one of eps_dev on the seed's paths, the DEM's stored strain on the
  // others (docs/dem.md "Paths").
  bool undrained_path = true;
  if (r.exists(path) && r.has_attr(path, "type"))
    undrained_path = r.attr_string(path, "type").rfind("undrained_", 0) == 0;
  if (options.load_path && r.exists(path + datasets::kEpsDev) &&
      r.exists(path + datasets::kStress) && r.exists(path + datasets::kFabric) &&
      (undrained_path || r.exists(path + datasets::kStrain))) {
    const auto e = r.read_vector(path + datasets::kEpsDev);
    const auto st = r.read_tensors(path + datasets::kStress);
    const auto fb = r.read_tensors(path + datasets::kFabric);
    std::vector<Eigen::Matrix3d> eps;
    if (!undrained_path) eps = r.read_tensors(path + datasets::kStrain);
    if (e.size() != st.size() || e.size() != fb.size() ||
        (!undrained_path && eps.size() != e.size()))
      throw InputError(name + ": /path eps_dev, strain, stress and fabric differ in length");
    // Every row, not only those sampled below: a NaN in eps_dev would stop the sampling there
    // and silently drop the rest of the path.
    auto finite_rows = [&](const auto& rows, const char* dataset) {
      for (std::size_t j = 0; j < rows.size(); ++j) {
        bool ok;
        if constexpr (std::is_same_v<std::decay_t<decltype(rows[j])>, double>)
          ok = std::isfinite(rows[j]);
        else
          ok = rows[j].allFinite();
        if (!ok)
          throw InputError(name + ": " + path + dataset + " row " + std::to_string(j) +
                           " is not finite");
      }
    };
    finite_rows(e, datasets::kEpsDev);
    finite_rows(st, datasets::kStress);
    finite_rows(fb, datasets::kFabric);
    finite_rows(eps, datasets::kStrain);
    if (e.size() >= 2) {
      // Even subsampling along the path keeps the cost of the path block bounded while
      // covering the whole curve; the start row is always kept (it seeds the model path). The
      // path's progress: |eps_dev| on the undrained paths, the norm of the strain on the others
      // (an isotropic path has no eps_dev).
      std::vector<double> x(e.size());
      for (std::size_t j = 0; j < e.size(); ++j)
        x[j] = undrained_path ? std::abs(e[j] - e.front()) : (eps[j] - eps.front()).norm();
      const double span = x.back();
      const int n = options.max_path_samples;
      std::size_t j = 0;
      bool first = true;
      double last = 0;
      for (int k = 0; k < n; ++k) {
        const double target = span * k / (n - 1);
        while (j + 1 < e.size() && x[j + 1] <= target) ++j;
        if (!first && x[j] <= last) continue;
        first = false;
        last = x[j];
        data.path.eps_dev.push_back(e[j] - e.front());
        data.path.stress.push_back(st[j]);
        data.path.fabric.push_back(fb[j]);
        if (!undrained_path) data.path.strain.push_back(eps[j] - eps.front());
      }
      if (r.exists(path + datasets::kVolumeFraction)) {
        const auto nu = r.read_vector(path + datasets::kVolumeFraction);
        if (nu.empty()) throw InputError(name + ": /path/volume_fraction is empty");
        if (!std::isfinite(nu.front()))
          throw InputError(name + ": /path/volume_fraction row 0 is not finite");
        data.path.volume_fraction = nu.front();
      }
    }
  }
  return data;
}

Eigen::Matrix3d PathData::increment(std::size_t k) const {
  if (strain.empty()) return models::undrained_axisymmetric_strain(eps_dev[k] - eps_dev[k - 1]);
  return strain[k] - strain[k - 1];
}

}  // namespace rendulic::calibration
