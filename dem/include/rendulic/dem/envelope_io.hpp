// Envelopes in the results file (docs/results.md, /states/<label>/envelopes/<name>): attrs
// amplitude, method, directions (and k_star plus the envelope's own scalar attributes);
// datasets theta_deg[m], strain[m,2], stress_star[m,2], fabric[m,2], d_stress[m,3,3] (Pa),
// d_fabric[m,3,3], and one [m] dataset per probe diagnostic. The names of the diagnostics and
// extra attributes are listed in the string attributes `diagnostics` and `attributes`
// (comma-separated) so that a reader finds them without guessing.
#pragma once

#include <string>

#include "rendulic/core/result_paths.hpp"
#include "rendulic/core/results.hpp"
#include "rendulic/dem/probe_envelope.hpp"

namespace rendulic::dem {

void write_envelope(ResultsWriter& out, const std::string& group, const Envelope& envelope);
// InputError (naming the file and group) if the group is missing or malformed.
Envelope read_envelope(const ResultsReader& in, const std::string& group);

}  // namespace rendulic::dem
