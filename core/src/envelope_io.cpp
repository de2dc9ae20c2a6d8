// The writer and reader of the envelope record in the results file (envelope_io.hpp;
// docs/results.md).
#include "rendulic/core/envelope_io.hpp"

#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "rendulic/core/conventions.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/result_paths.hpp"

namespace rendulic {

void write_envelope(ResultsWriter& out, const std::string& group, const EnvelopeRecord& envelope) {
  const std::size_t m = envelope.size();
  // The tensors are all or nothing: a prediction made in the Rendulic plane has only pairs.
  const bool tensors = !envelope.d_stress.empty() || !envelope.d_fabric.empty();
  if (envelope.strain.size() != m || envelope.stress_star.size() != m ||
      envelope.fabric.size() != m ||
      (tensors && (envelope.d_stress.size() != m || envelope.d_fabric.size() != m))) {
    throw std::logic_error("write_envelope: inconsistent envelope sizes");
  }
  out.create_group(group);
  out.attr(group, "amplitude", envelope.amplitude);
  out.attr(group, "method", envelope.method);
  out.attr(group, "directions", static_cast<std::int64_t>(m));
  out.attr(group, "k_star", envelope.k_star);
  out.attr(group, "plane", envelope.plane.name);
  const Eigen::Vector3d &u = envelope.plane.u, &v = envelope.plane.v;
  out.attr(group, "plane_basis", std::vector<double>{u.x(), u.y(), u.z(), v.x(), v.y(), v.z()});
  out.write(group + datasets::kThetaDeg, envelope.theta_deg);
  out.write(group + datasets::kStrain, envelope.strain);
  out.write(group + datasets::kStressStar, envelope.stress_star);
  out.write(group + datasets::kFabric, envelope.fabric);
  if (tensors) {
    out.write(group + datasets::kDStress, envelope.d_stress);
    out.write(group + datasets::kDFabric, envelope.d_fabric);
  }
  if (!envelope.d_fabric_volume.empty()) {
    if (envelope.d_fabric_volume.size() != m || envelope.d_fabric_rotation.size() != m ||
        envelope.d_fabric_contacts.size() != m)
      throw std::logic_error("write_envelope: inconsistent fabric split sizes");
    out.write(group + datasets::kDFabricVolume, envelope.d_fabric_volume);
    out.write(group + datasets::kDFabricRotation, envelope.d_fabric_rotation);
    out.write(group + datasets::kDFabricContacts, envelope.d_fabric_contacts);
  }
  std::vector<std::string> names;
  for (const auto& [name, values] : envelope.diagnostics) {
    if (values.size() != m) throw std::logic_error("write_envelope: diagnostic " + name);
    out.write(group + "/" + name, values);
    names.push_back(name);
  }
  out.attr(group, "diagnostics", names);
  names.clear();
  for (const auto& [name, value] : envelope.attributes) {
    out.attr(group, name, value);
    names.push_back(name);
  }
  out.attr(group, "attributes", names);
}

EnvelopeRecord read_envelope(const ResultsReader& in, const std::string& group) {
  const std::string where = in.path().string() + ": envelope " + group;
  if (!in.exists(group)) throw InputError(in.path().string() + ": no envelope at " + group);
  EnvelopeRecord env;
  env.name = group.substr(group.find_last_of('/') + 1);
  env.amplitude = in.has_attr(group, "amplitude") ? in.attr_double(group, "amplitude")
                                                  : std::numeric_limits<double>::quiet_NaN();
  // Readers divide by it and sort envelopes into elastic and plastic by it: 0 made the report
  // call an envelope elastic and its stiffness inf, without a word. (An envelope that could not
  // be measured may have no amplitude: NaN, nothing to divide.)
  if (in.has_attr(group, "amplitude") && !(env.amplitude > 0.0 && std::isfinite(env.amplitude))) {
    std::ostringstream why;
    why << where << ": @amplitude is " << env.amplitude << ", not a positive finite strain";
    throw InputError(why.str());
  }
  if (in.has_attr(group, "method")) env.method = in.attr_string(group, "method");
  if (in.has_attr(group, "k_star")) env.k_star = in.attr_double(group, "k_star");
  if (in.has_attr(group, "plane")) {
    // The name fixes the basis (core/conventions.hpp); plane_basis is for other readers.
    const std::string plane = in.attr_string(group, "plane");
    const std::optional<ProbePlane> known = probe_plane_named(plane);
    if (!known)
      throw InputError(where + ": unknown probe plane '" + plane + "' (" + kProbePlaneNames + ")");
    env.plane = *known;
  }
  auto vector = [&](const char* name, std::vector<double>& v) {
    if (in.exists(group + name)) v = in.read_vector(group + name);
  };
  auto pairs = [&](const char* name, std::vector<Eigen::Vector2d>& v) {
    if (in.exists(group + name)) v = in.read_pairs(group + name);
  };
  auto tensors = [&](const char* name, std::vector<Eigen::Matrix3d>& v) {
    if (in.exists(group + name)) v = in.read_tensors(group + name);
  };
  vector(datasets::kThetaDeg, env.theta_deg);
  pairs(datasets::kStrain, env.strain);
  pairs(datasets::kStressStar, env.stress_star);
  pairs(datasets::kFabric, env.fabric);
  tensors(datasets::kDStress, env.d_stress);
  tensors(datasets::kDFabric, env.d_fabric);
  tensors(datasets::kDFabricVolume, env.d_fabric_volume);
  tensors(datasets::kDFabricRotation, env.d_fabric_rotation);
  tensors(datasets::kDFabricContacts, env.d_fabric_contacts);
  if (in.has_attr(group, "diagnostics")) {
    for (const std::string& name : in.attr_strings(group, "diagnostics")) {
      env.diagnostics[name] = in.read_vector(group + "/" + name);
    }
  }
  if (in.has_attr(group, "attributes")) {
    for (const std::string& name : in.attr_strings(group, "attributes")) {
      env.attributes[name] = in.attr_double(group, name);
    }
  }
  // Every probe has one entry in each per-probe dataset that is stored.
  std::size_t m = 0;
  bool agree = true;
  auto count = [&](std::size_t n) {
    if (n == 0) return;
    if (m == 0) m = n;
    agree = agree && n == m;
  };
  for (std::size_t n :
       {env.theta_deg.size(), env.strain.size(), env.stress_star.size(), env.fabric.size(),
        env.d_stress.size(), env.d_fabric.size(), env.d_fabric_volume.size(),
        env.d_fabric_rotation.size(), env.d_fabric_contacts.size()})
    count(n);
  for (const auto& [name, values] : env.diagnostics) count(values.size());
  if (in.has_attr(group, "directions") && m > 0)
    agree = agree && in.attr_int(group, "directions") == static_cast<std::int64_t>(m);
  if (!agree) throw InputError(where + " has datasets of different lengths");
  // rendulic never stores a pair that is not finite (a probe that fails fails its campaign): a
  // nan or inf here is damage. The report's claims fitted such pairs and ended in "internal
  // error: fit_rendulic_map: strain pairs are collinear", exit 1.
  auto finite_pairs = [&](const char* name, const std::vector<Eigen::Vector2d>& v) {
    for (std::size_t i = 0; i < v.size(); ++i)
      if (!v[i].allFinite())
        throw InputError(where + name + ": probe " + std::to_string(i) + " is not finite");
  };
  for (std::size_t i = 0; i < env.theta_deg.size(); ++i)
    if (!std::isfinite(env.theta_deg[i]))
      throw InputError(where + datasets::kThetaDeg + ": probe " + std::to_string(i) +
                       " is not finite");
  finite_pairs(datasets::kStrain, env.strain);
  finite_pairs(datasets::kStressStar, env.stress_star);
  finite_pairs(datasets::kFabric, env.fabric);
  // Nor a response pair beyond the span an envelope can hold (kMaxEnvelopeSpan): 1e290 in a
  // stress pair silenced its envelope in a calibration (its block's scale swamped) with exit 0,
  // and fitted as a line through it with rms 0.
  for (const auto& [name, pairs] : {std::pair{datasets::kStressStar, &env.stress_star},
                                    std::pair{datasets::kFabric, &env.fabric}})
    if (const std::optional<SpanExcess> x = span_excess(*pairs))
      throw InputError(where + name + ": probe " + std::to_string(x->index) + " reaches " +
                       decimal_g(x->size) + ", more than " + decimal_g(kMaxEnvelopeSpan) +
                       " times the median probe's " + decimal_g(x->median) + ": damaged");
  // The strain pair of probe i is amplitude (cos t_i, sin t_i) in every plane (docs/probes.md),
  // to round-off as rendulic writes it (8e-16 of the amplitude at most in the files measured).
  // A finite pair that is not is damage too: -1e308 there gave a calibration of NaN (exit 0)
  // and the report's fit an internal error.
  if (std::isfinite(env.amplitude)) {
    const bool directions = env.theta_deg.size() == env.strain.size();
    for (std::size_t i = 0; i < env.strain.size(); ++i) {
      const double t = directions ? deg_to_rad(env.theta_deg[i]) : 0.0;
      const double off =
          directions
              ? (env.strain[i] - env.amplitude * Eigen::Vector2d(std::cos(t), std::sin(t))).norm()
              : std::abs(env.strain[i].norm() - env.amplitude);
      // A direction beyond the doubles in radians (-1e308 deg) has no cosine: off is NaN.
      if (!(off <= 1e-9 * env.amplitude))
        throw InputError(
            where + datasets::kStrain + ": probe " + std::to_string(i) +
            " is not the probe strain " +
            (directions ? "@amplitude (cos, sin) of its theta_deg" : "of norm @amplitude") +
            (std::isfinite(off)
                 ? " (off by " + decimal_g(off / env.amplitude, 3) + " of the amplitude)"
                 : " (theta_deg " + decimal_g(env.theta_deg[i]) + " has no finite cosine)"));
    }
  }
  return env;
}

}  // namespace rendulic
