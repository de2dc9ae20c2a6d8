// Envelopes to and from the results file (docs/results.md /states/<label>/envelopes/<name>).
// See envelope_io.hpp.
#include "rendulic/dem/envelope_io.hpp"

#include <sstream>

#include "rendulic/core/errors.hpp"
#include "rendulic/core/result_paths.hpp"

namespace rendulic::dem {

namespace {

std::string join(const std::vector<std::string>& names) {
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "" : ",") + n;
  return s;
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, ',');) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

}  // namespace

void write_envelope(ResultsWriter& out, const std::string& group, const Envelope& envelope) {
  const std::size_t m = envelope.size();
  if (envelope.strain.size() != m || envelope.stress_star.size() != m ||
      envelope.fabric.size() != m || envelope.d_stress.size() != m ||
      envelope.d_fabric.size() != m) {
    throw std::logic_error("write_envelope: inconsistent envelope sizes");
  }
  out.create_group(group);
  out.attr(group, "amplitude", envelope.amplitude);
  out.attr(group, "method", envelope.method);
  out.attr(group, "directions", static_cast<std::int64_t>(m));
  out.attr(group, "k_star", envelope.k_star);
  out.write(group + datasets::kThetaDeg, envelope.theta_deg);
  out.write(group + datasets::kStrain, envelope.strain);
  out.write(group + datasets::kStressStar, envelope.stress_star);
  out.write(group + datasets::kFabric, envelope.fabric);
  out.write(group + datasets::kDStress, envelope.d_stress);
  out.write(group + datasets::kDFabric, envelope.d_fabric);
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
  out.attr(group, "diagnostics", join(names));
  names.clear();
  for (const auto& [name, value] : envelope.attributes) {
    out.attr(group, name, value);
    names.push_back(name);
  }
  out.attr(group, "attributes", join(names));
}

Envelope read_envelope(const ResultsReader& in, const std::string& group) {
  if (!in.exists(group)) {
    throw InputError(in.path().string() + ": no envelope at " + group);
  }
  Envelope env;
  env.amplitude = in.attr_double(group, "amplitude");
  env.method = in.attr_string(group, "method");
  if (in.has_attr(group, "k_star")) env.k_star = in.attr_double(group, "k_star");
  env.theta_deg = in.read_vector(group + datasets::kThetaDeg);
  env.strain = in.read_pairs(group + datasets::kStrain);
  env.stress_star = in.read_pairs(group + datasets::kStressStar);
  env.fabric = in.read_pairs(group + datasets::kFabric);
  env.d_stress = in.read_tensors(group + datasets::kDStress);
  env.d_fabric = in.read_tensors(group + datasets::kDFabric);
  if (in.exists(group + datasets::kDFabricVolume)) {
    env.d_fabric_volume = in.read_tensors(group + datasets::kDFabricVolume);
    env.d_fabric_rotation = in.read_tensors(group + datasets::kDFabricRotation);
    env.d_fabric_contacts = in.read_tensors(group + datasets::kDFabricContacts);
  }
  const std::size_t m = env.theta_deg.size();
  if (env.strain.size() != m || env.stress_star.size() != m || env.fabric.size() != m ||
      env.d_stress.size() != m || env.d_fabric.size() != m ||
      in.attr_int(group, "directions") != static_cast<std::int64_t>(m)) {
    throw InputError(in.path().string() + ": envelope " + group +
                     " has datasets of different lengths");
  }
  if (in.has_attr(group, "diagnostics")) {
    for (const std::string& name : split(in.attr_string(group, "diagnostics"))) {
      env.diagnostics[name] = in.read_vector(group + "/" + name);
    }
  }
  if (in.has_attr(group, "attributes")) {
    for (const std::string& name : split(in.attr_string(group, "attributes"))) {
      env.attributes[name] = in.attr_double(group, name);
    }
  }
  return env;
}

}  // namespace rendulic::dem
