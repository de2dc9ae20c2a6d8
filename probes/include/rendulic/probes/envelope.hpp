// Envelope data (docs/physics.md section 5): the response points of one probe campaign in the
// Rendulic plane, with the probe directions and strain points when they are known. The type
// says nothing about how the envelope was made (DEM, a constitutive model, a file from
// elsewhere): the fits of probes/ work on any of them (docs/architecture.md).
#pragma once

#include <Eigen/Dense>
#include <string>
#include <vector>

#include "rendulic/core/envelope_record.hpp"

namespace rendulic {

struct Envelope {
  // Response points (sqrt(2) * lateral, axial) of stress or fabric: required.
  std::vector<Eigen::Vector2d> response;
  // Probe directions in degrees, one per response point, or empty when unknown.
  std::vector<double> theta_deg;
  // Strain points (sqrt(2) d_eps_lat, d_eps_ax), one per response point, or empty.
  std::vector<Eigen::Vector2d> strain;
  // Frobenius norm of the probe strain; 0 when unknown.
  double amplitude = 0.0;

  std::size_t size() const { return response.size(); }
  bool has_theta() const { return !theta_deg.empty(); }
  bool has_strain() const { return !strain.empty(); }
  // Sizes agree, every number is finite, amplitude >= 0. `why` names the first culprit.
  bool IsValid(std::string* why) const;
  // Strain points of the probes: `strain` if given, else amplitude * (cos theta, sin theta)
  // (core's probe_strain convention). Empty if neither is known.
  std::vector<Eigen::Vector2d> strain_points() const;
};

// The view of a stored envelope (core/envelope_record.hpp) that the fits take: its stress
// pairs (sigma*) or its fabric pairs as the response, with its directions, strain points and
// amplitude (0 when the record has none).
enum class Response { kStress, kFabric };
Envelope envelope_of(const EnvelopeRecord& record, Response response);

}  // namespace rendulic
