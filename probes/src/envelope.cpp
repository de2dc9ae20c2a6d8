// Envelope validation and strain points (docs/physics.md section 5; see envelope.hpp).
#include "rendulic/probes/envelope.hpp"

#include <cmath>

#include "rendulic/core/conventions.hpp"

namespace rendulic {

bool Envelope::IsValid(std::string* why) const {
  auto fail = [why](const std::string& msg) {
    if (why) *why = msg;
    return false;
  };
  if (!theta_deg.empty() && theta_deg.size() != response.size())
    return fail("envelope: " + std::to_string(theta_deg.size()) + " directions for " +
                std::to_string(response.size()) + " response points");
  if (!strain.empty() && strain.size() != response.size())
    return fail("envelope: " + std::to_string(strain.size()) + " strain points for " +
                std::to_string(response.size()) + " response points");
  for (std::size_t i = 0; i < response.size(); ++i)
    if (!response[i].allFinite())
      return fail("envelope: response point " + std::to_string(i) + " is not finite");
  for (std::size_t i = 0; i < theta_deg.size(); ++i)
    if (!std::isfinite(theta_deg[i]))
      return fail("envelope: direction " + std::to_string(i) + " is not finite");
  for (std::size_t i = 0; i < strain.size(); ++i)
    if (!strain[i].allFinite())
      return fail("envelope: strain point " + std::to_string(i) + " is not finite");
  if (!std::isfinite(amplitude) || amplitude < 0.0)
    return fail("envelope: amplitude must be finite and >= 0");
  return true;
}

Envelope envelope_of(const EnvelopeRecord& record, Response response) {
  Envelope env;
  env.response = response == Response::kStress ? record.stress_star : record.fabric;
  env.theta_deg = record.theta_deg;
  env.strain = record.strain;
  if (std::isfinite(record.amplitude)) env.amplitude = record.amplitude;
  return env;
}

std::vector<Eigen::Vector2d> Envelope::strain_points() const {
  if (!strain.empty()) return strain;
  std::vector<Eigen::Vector2d> out;
  if (theta_deg.empty() || amplitude <= 0.0) return out;
  out.reserve(theta_deg.size());
  for (double t : theta_deg) {
    const double r = deg_to_rad(t);
    out.emplace_back(amplitude * std::cos(r), amplitude * std::sin(r));
  }
  return out;
}

}  // namespace rendulic
