// The response envelope as the results file stores it (docs/results.md,
// /states/<label>/envelopes/<name>; docs/probes.md): the one record of an envelope whatever
// made it (dynamic probes, minimisation probes, the linear response, another DEM code's data
// converted to the schema). Plain data: the engine fills it without knowing the results file;
// its one writer and one reader live in envelope_io.hpp. The DEM writes it, the fits, the
// calibration and the report read it; each takes the view it needs from this record
// (docs/architecture.md "Where each concept lives").
//
// Stored: attributes amplitude, method, directions, k_star, plane and plane_basis (the probe
// plane, core/conventions.hpp; a file without them reads as the Rendulic plane) and the
// envelope's own scalar attributes; datasets theta_deg[m], strain[m,2], stress_star[m,2],
// fabric[m,2], d_stress[m,3,3] (Pa), d_fabric[m,3,3], the fabric split d_fabric_volume,
// d_fabric_rotation, d_fabric_contacts [m,3,3] when made, and one [m] dataset per probe
// diagnostic. The names of the diagnostics and extra attributes are listed in the string
// attributes `diagnostics` and `attributes` (comma-separated) so that a reader finds them
// without guessing.
#pragma once

#include <Eigen/Dense>
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "rendulic/core/conventions.hpp"

namespace rendulic {

struct EnvelopeRecord {
  // The envelope's name, the last part of its group (e.g. dynamic_5e-05): read_envelope fills
  // it from the group, write_envelope writes to the group it is given (the file has no other
  // place for it).
  std::string name;
  std::string method;      // "dynamic" | "minimisation" | "linear_response" | ...
  double amplitude = 0.0;  // |d_eps| (Frobenius)
  double k_star = 0.0;     // Pa, the stress scale of stress_star
  // The plane of the probes (docs/probes.md "Probe planes"): the pairs below are coordinates
  // in it, which for the Rendulic plane (the default) are the Rendulic pairs. Set it before
  // add(). Whoever reads the pairs as Rendulic pairs (a model's Rendulic envelope, the claims)
  // checks plane.rendulic() first.
  ProbePlane plane;
  std::vector<double> theta_deg;
  std::vector<Eigen::Vector2d> strain;       // pairs of d_eps in the plane
  std::vector<Eigen::Vector2d> stress_star;  // pairs of d_sigma / k*
  std::vector<Eigen::Vector2d> fabric;       // pairs of d_F
  // Pairs of d_sigma in Pa, for those who work in Pa (a model's envelope, the
  // calibration's residuals). Held in memory, not stored (stress_star is): add() and
  // model_envelope() fill it; the calibration's loader fills a record read from a file with
  // stress_star times the file's k* (docs/calibration.md), once, so that its residuals subtract
  // stored numbers and not a product the compiler might fuse into them.
  std::vector<Eigen::Vector2d> stress;
  std::vector<Eigen::Matrix3d> d_stress;  // Pa, compression positive
  std::vector<Eigen::Matrix3d> d_fabric;
  // d_fabric split with the contact set of the starting state held fixed (docs/probes.md
  // "Fabric split"): volume change, rotation of the normals, contacts made and lost. Empty
  // for envelopes made without it; otherwise one entry per probe each.
  std::vector<Eigen::Matrix3d> d_fabric_volume, d_fabric_rotation, d_fabric_contacts;
  // Per-probe diagnostics ([m] each), e.g. contacts_opened, contacts_closed, relax_time,
  // relax_steps, kinetic_to_elastic, converged; written as datasets next to the envelope.
  std::map<std::string, std::vector<double>> diagnostics;
  // Per-envelope scalars (attributes), e.g. rate, inertial_number, n_rattlers.
  std::map<std::string, double> attributes;

  std::size_t size() const { return theta_deg.size(); }
  // Elastic probes by the one threshold (core/conventions.hpp).
  bool elastic() const { return is_elastic_amplitude(amplitude); }
  bool has_fabric() const { return !fabric.empty() && fabric.size() == size(); }
  // The strain tensor of probe i: the probe is diagonal and in the plane (docs/physics.md
  // section 5, docs/probes.md "Probe planes"), so its pair fixes it.
  Eigen::Matrix3d strain_tensor(std::size_t i) const { return from_plane_pair(plane, strain[i]); }
  // Appends one probe; the pairs follow from the tensors (core/conventions.hpp).
  void add(double theta, const Eigen::Matrix3d& d_eps, const Eigen::Matrix3d& d_sigma,
           const Eigen::Matrix3d& d_f);
  // The same with the probe's fabric split (volume + rotation + contacts = d_f).
  void add(double theta, const Eigen::Matrix3d& d_eps, const Eigen::Matrix3d& d_sigma,
           const Eigen::Matrix3d& d_f, const Eigen::Matrix3d& d_f_volume,
           const Eigen::Matrix3d& d_f_rotation, const Eigen::Matrix3d& d_f_contacts);
};

// The largest ratio of a pair's size (its larger coordinate) to the median pair's that one
// envelope's response may span. The envelope fit works in units of the data's size, set by its
// largest pairs: beyond about 1e154 the others' residuals square to below the smallest double,
// and a pair of 1e300 among pairs of 0.14 fitted as a line through it with rms 0 and standard
// errors 0. Real envelopes span a few decades: beyond this, a pair is damage (docs/fitting.md).
inline constexpr double kMaxEnvelopeSpan = 1e100;

// A pair beyond kMaxEnvelopeSpan times the median pair's size: which, its size and the median.
struct SpanExcess {
  std::size_t index = 0;
  double size = 0.0, median = 0.0;
};
// The largest pair of `pairs` if it exceeds the span (3 pairs or more, median above 0).
std::optional<SpanExcess> span_excess(const std::vector<Eigen::Vector2d>& pairs);

}  // namespace rendulic
