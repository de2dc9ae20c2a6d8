// Output of a calibration (interfaces.md `rendulic calibrate` and /calibration/<model>): the
// JSON object (model, params, stderr, correlation, per_state.<label> with B, G, A and the
// plastic features, and diagnostics), and the HDF5 group written into a results file. Kept
// apart from the numerics (no I/O inside the calibration classes). Non-finite numbers (an
// undetermined parameter's +inf standard error) are JSON null, never a silent NaN; the
// warnings say why.
#pragma once

#include <string>

#include "rendulic/calibration/calibrate.hpp"
#include "rendulic/core/results.hpp"

namespace rendulic::calibration {

std::string to_json(const CalibrationSummary& summary);

// Writes /calibration/<model>/ (attrs objective, converged, ...; datasets params, stderr,
// correlation; per-state numbers and predicted envelopes) into an open writer.
void write_calibration(ResultsWriter& out, const CalibrationSummary& summary);

}  // namespace rendulic::calibration
