// Output of a calibration (docs/calibration.md; /calibration/<model> in docs/results.md): the
// JSON object (model, params, stderr, correlation, per_state.<label> with B, G, A and the
// plastic features, and diagnostics), and the HDF5 group written into a results file. Kept
// apart from the numerics (no I/O inside the calibration classes). Non-finite numbers (an
// undetermined parameter's +inf standard error) are JSON null, never a silent NaN; the
// warnings say why.
#pragma once

#include <string>
#include <vector>

#include "rendulic/calibration/calibrate.hpp"
#include "rendulic/core/results.hpp"

namespace rendulic::calibration {

std::string to_json(const CalibrationSummary& summary);

// Writes /calibration/<model>/ (attrs objective, converged, ...; datasets params, stderr,
// correlation; the yardstick scores; per-state numbers, predicted envelopes and path) into an
// open writer.
void write_calibration(ResultsWriter& out, const CalibrationSummary& summary);

// The yardstick scores of /calibration/<model> as written by write_calibration; false when the
// group has none (a failed law, or a file from before the yardstick).
bool read_model_score(const ResultsReader& in, const std::string& model, ModelScore* score);

// The parameters of /calibration/<model> as write_calibration stores them: names (param_names),
// values (params) and standard errors (stderr: 0 fixed, +inf undetermined; empty when the group
// has none), one per name. A damaged group (a name given twice, more or fewer values than
// names) is an InputError naming it: its readers paired them by position and dropped the rest.
struct StoredParameters {
  std::vector<std::string> names;
  std::vector<double> values;
  std::vector<double> stderr_;
};
StoredParameters read_parameters(const ResultsReader& in, const std::string& group);

// /calibration attributes selected_model, selected_model_stress, selection (the sentence),
// selection_rule; per law selection_note (why it is not a candidate, or empty).
void write_selection(ResultsWriter& out, const Selection& selection);

}  // namespace rendulic::calibration
