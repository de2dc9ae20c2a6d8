// Envelope from a CSV file (docs/fitting.md "The fit command", `rendulic fit --in FILE.csv`): the
// header names the columns; x and y (the Rendulic response coordinates) are required, theta_deg is
// optional, other columns are ignored. Blank lines and lines starting with '#' are skipped.
// Anything else that is not a finite number where one is needed is an InputError naming file, line
// and column.
#pragma once

#include <filesystem>
#include <string>

#include "rendulic/probes/envelope.hpp"

namespace rendulic {

Envelope read_envelope_csv(const std::filesystem::path& path);
// Same, from text already in memory (`name` is used in messages).
Envelope parse_envelope_csv(const std::string& text, const std::string& name);

}  // namespace rendulic
