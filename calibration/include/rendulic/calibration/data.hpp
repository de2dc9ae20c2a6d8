// What calibration fits against (docs/calibration.md "Two levels", docs/results.md): per
// state the relaxed stress and fabric and its probe envelopes (Rendulic pairs of d_sigma in Pa
// and of d_F, one per probe direction), and the main undrained path (stress and fabric versus
// eps_dev). The loader reads any results file with /material and /states/<label>/envelopes, so
// envelopes from another DEM code converted to our schema calibrate the same way as ours.
// Stress pairs are converted to Pa with /material k_star (docs/results.md: *_star datasets are
// divided by k*). No physics here, only data and its provenance.
#pragma once

#include <Eigen/Dense>
#include <filesystem>
#include <string>
#include <vector>

#include "rendulic/core/conventions.hpp"
#include "rendulic/core/envelope_record.hpp"
#include "rendulic/core/results.hpp"

namespace rendulic::calibration {

// The calibration's envelopes are stored records (core/envelope_record.hpp) with `name`, the
// directions, the strain pairs, `stress` (Rendulic pairs of d_sigma in Pa) and, when known,
// the fabric pairs filled in. Sizes agree, everything finite, at least 3 directions and a
// positive amplitude; `why` names the envelope and the culprit.
bool is_valid_envelope(const EnvelopeRecord& e, std::string* why);

struct StateData {
  std::string label;
  Eigen::Matrix3d stress = Eigen::Matrix3d::Zero();  // Pa, compression positive
  Eigen::Matrix3d fabric = Eigen::Matrix3d::Zero();
  double volume_fraction = 0.0;
  double eps_dev = 0.0;
  std::vector<EnvelopeRecord> envelopes;

  // The elastic envelope with the smallest amplitude, or nullptr.
  const EnvelopeRecord* elastic_envelope() const;
  // The non-elastic envelope with the largest amplitude, or nullptr.
  const EnvelopeRecord* plastic_envelope() const;
};

// The main path, subsampled; row 0 is the start state of the model path.
struct PathData {
  // Signed (docs/physics.md section 3), relative to row 0 after loading.
  std::vector<double> eps_dev;
  std::vector<Eigen::Matrix3d> stress;  // Pa
  std::vector<Eigen::Matrix3d> fabric;
  // The DEM's strain epsilon (compression positive) relative to row 0, for paths other than
  // the undrained ones (docs/dem.md "Paths"); empty for an undrained path, whose strain is
  // the undrained axisymmetric one of eps_dev.
  std::vector<Eigen::Matrix3d> strain;
  double volume_fraction = 0.0;  // at row 0
  bool empty() const { return eps_dev.size() < 2; }
  // The strain from row k - 1 to row k that the laws are driven by: the DEM's own on any path
  // (on the drained and constant-p paths the law then follows the DEM's measured volume
  // change, a strain-driven replay of the mixed test).
  Eigen::Matrix3d increment(std::size_t k) const;
};

struct CalibrationData {
  std::string source;   // file name or "synthetic"
  double k_star = 0.0;  // Pa; 0 when not from a file
  std::vector<StateData> states;
  PathData path;

  const StateData* find(const std::string& label) const;
  std::vector<std::string> labels() const;
};

struct LoadOptions {
  std::vector<std::string> states;  // empty: every state with at least one envelope
  bool load_path = true;
  int max_path_samples = 40;  // the path is subsampled evenly in eps_dev to at most this
  bool IsValid(std::string* why) const;
};

// Throws InputError naming the file (as the reader names it: a run reads its temporary file
// under the final name, ResultsWriter::read_back) and the culprit: no /states, a requested
// label that does not exist (the message lists the ones that do), a requested state without
// envelopes, no envelope at all, malformed envelope datasets.
CalibrationData load_calibration_data(const ResultsReader& results,
                                      const LoadOptions& options = {});
CalibrationData load_calibration_data(const std::filesystem::path& file,
                                      const LoadOptions& options = {});

// Envelope from probe directions and amplitude with the strain pairs filled in (core's
// probe_strain); stress and fabric left empty for the caller.
EnvelopeRecord probe_set(const std::string& name, double amplitude, int directions);

}  // namespace rendulic::calibration
