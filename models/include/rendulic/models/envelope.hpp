// Model response envelopes (docs/models.md "Material-point driver"; docs/physics.md section 5):
// from a given state, the DEM's probe set (core probe_directions_deg, probe_strain) is applied to a
// law and the stress and fabric increments are returned as Rendulic pairs, exactly as the DEM
// campaign reports them. Each probe starts from the same state (probes are independent).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "rendulic/core/envelope_record.hpp"
#include "rendulic/models/driver.hpp"

namespace rendulic::models {

enum class EnvelopeMethod {
  kIntegrated,  // each probe integrated by the driver (the finite-amplitude response)
  kRate,        // one evaluation of the rate law: the exact image of the probe under the
                // rate equation at the start state (the envelope of Gudehus 1979 / Wu 2000)
};
// The methods' names (`rendulic envelope --method`, Python's model_envelope), in the enum's
// order.
inline constexpr std::array<const char*, 2> kEnvelopeMethodNames = {"integrated", "rate"};

// The number of probe directions of an envelope: three make the smallest ellipse that can be
// fitted; the upper end keeps a mistyped count from running for hours.
inline constexpr int kEnvelopeDirectionsMin = 3;
inline constexpr int kEnvelopeDirectionsMax = 100000;

struct EnvelopeOptions {
  double amplitude = 5e-5;  // |d_eps| (Frobenius), docs/physics.md section 5 elastic default
  int directions = 36;
  EnvelopeMethod method = EnvelopeMethod::kIntegrated;
  StepOptions step;
  bool IsValid(std::string* why) const;
};

// The law's envelope as a record (core/envelope_record.hpp) with method "model": directions,
// strain pairs, `stress` pairs in Pa (no k*: stress_star is left empty), fabric pairs and the
// d_stress and d_fabric tensors, and the driver's error report as attributes:
// max_error_estimate, within_tolerance (1 or 0) and total_substeps. A probe the law cannot
// follow (inadmissible start state, a failed integration, a UMAT's refusal, a non-finite
// response) throws InputError naming the probe.
EnvelopeRecord model_envelope(const Law& law, const MaterialState& state,
                              const EnvelopeOptions& options = {});

// The 2x2 map from Rendulic strain pairs to Rendulic stress pairs given by the law's tangent at
// `state` for probes near the direction theta_deg (axisymmetric probes; the tangent of a
// rate-independent law depends on the direction only). For the elastic laws this is the
// Rendulic stiffness whose (iso, dev) form is [[3B, sqrt3 A], [sqrt3 A, 2G]] (docs/models.md
// "Coordinates" and section 2); rotate with core's rendulic_to_iso_dev() R as R D R^T.
Eigen::Matrix2d rendulic_tangent(const Law& law, const MaterialState& state, double theta_deg);

}  // namespace rendulic::models
