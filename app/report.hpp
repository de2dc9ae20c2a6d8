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
std::string report_markdown(const ResultsReader& results, const std::vector<Claim>& claims,
                            const std::vector<std::string>& figures);

// The folder of a results file's figures: figures/ beside it.
std::filesystem::path figures_folder(const std::filesystem::path& results_file);

// Writes DIR/report.md atomically and the figures into DIR/figures (if plotting is
// available; otherwise the report says so). Returns the report path. With `early` started
// (a run whose calibration drew the other figures meanwhile), only the figures of the
// calibrated laws are drawn here, and then the early ones are waited for.
class EarlyFigures;
std::filesystem::path write_report(const std::filesystem::path& results_file, bool with_figures,
                                   EarlyFigures* early = nullptr);

}  // namespace rendulic::app
