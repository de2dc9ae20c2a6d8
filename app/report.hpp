// The run report: report.md beside results.h5, with the table of the seed's
// claims C1-C8 (docs/claims.md, seed paper section 4) evaluated on the file's own
// numbers, and the figures. Reads a committed results file only (ResultsReader), so it works
// on any conforming file and never on half-written data.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "rendulic/core/results.hpp"

namespace rendulic::app {

struct Claim {
  std::string id;        // "C1".."C8"
  std::string claim;     // the seed's statement
  std::string measured;  // the numbers behind the verdict
  std::string verdict;   // "holds", "does not hold", "not measured"
};

// Evaluates C1-C8 on a results file; a claim whose data is absent is "not measured".
std::vector<Claim> evaluate_claims(const ResultsReader& results);

// Markdown report: run summary, claim table, figure links, timings if present.
// `plotted`: the figures were asked for and drawn (`figures` may then still be empty: the file
// holds none of their data).
std::string report_markdown(const ResultsReader& results, const std::vector<Claim>& claims,
                            const std::vector<std::string>& figures, bool plotted);

// Writes DIR/report.md atomically and the figures into DIR/figures (if plotting is
// available; otherwise the report says so). Returns the report path.
std::filesystem::path write_report(const std::filesystem::path& results_file, bool with_figures);
// Refuses, before a run's stages, a DIR where write_report would fail at their end: a folder
// named report.md, or a file named figures (InputError naming it).
void check_report_destination(const std::filesystem::path& dir, bool with_figures);

}  // namespace rendulic::app
