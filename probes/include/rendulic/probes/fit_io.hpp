// Envelope fits in results files (docs/results.md, groups
// /states/<label>/envelopes/<name>/fit_stress and fit_fabric): attributes shape, center[2],
// semi_axes[2], inclination_deg (absent for a circle: undefined), rms, and center_stderr,
// semi_axes_stderr, inclination_deg_stderr where defined; plus n_points, loss, loss_scale,
// converged, selection (why this shape) and line_p_value when a test was made. Written and
// read through core's ResultsWriter / ResultsReader.
#pragma once

#include <filesystem>
#include <string>

#include "rendulic/core/results.hpp"
#include "rendulic/probes/envelope.hpp"
#include "rendulic/probes/envelope_fit.hpp"

namespace rendulic {

void write_envelope_fit(ResultsWriter& out, const std::string& group, const EnvelopeFit& fit);
// InputError naming the group if it lacks shape, center or semi_axes. Residuals are not
// stored: the result has rms but empty residuals.
EnvelopeFit read_envelope_fit(const ResultsReader& in, const std::string& group);

// Fits the stress_star and fabric pairs of every /states/*/envelopes/* of a results file
// and writes fit_stress and fit_fabric (atomically, via ResultsWriter::update). An envelope
// that cannot be fitted (e.g. no fabric change at all) gets shape "none" and an attribute
// "error" with the reason instead of a fit. Returns the number of fits written.
struct FitAllSummary {
  int fitted = 0;
  int failed = 0;
};
// The same over a reader and a writer that are already open (the run's `fits` stage reads the
// writer's temporary file): every envelope's stress_star and fabric pairs, of /states and of
// the pressure branches' /pressure/<branch>/states, are fitted with their own options; pairs
// that were never measured are skipped.
FitAllSummary fit_envelopes(const ResultsReader& in, ResultsWriter& out,
                            const FitOptions& stress_options, const FitOptions& fabric_options);
// The same for the envelopes of one state group (e.g. a pressure branch's state).
FitAllSummary fit_state_envelopes(const ResultsReader& in, ResultsWriter& out,
                                  const std::string& state_group, const FitOptions& stress_options,
                                  const FitOptions& fabric_options);
FitAllSummary fit_all_envelopes(const std::filesystem::path& results_file,
                                const FitOptions& options = {});

}  // namespace rendulic
