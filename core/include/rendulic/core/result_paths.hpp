// The names of the results file (docs/results.md): the one place where its groups, datasets
// and shared attributes are spelled. Every writer and reader in C++ builds its paths from
// here, so a name of the contract changes here or nowhere (the plotting script, app/plot.py,
// reads the same names from Python; docs/results.md is the contract both follow).
//
// Groups are absolute paths; dataset and child-group names carry their leading '/', so that
// `group + datasets::kStress` is a path. A pressure branch repeats the layout of the main run
// under its own root (pressure_branch()), hence the builders take a root.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <string>
#include <string_view>

#include "rendulic/core/comma_list.hpp"
#include "rendulic/core/decimal.hpp"

namespace rendulic {

// Whether `name` may be one component of a path in a results file: not empty, not "." or
// "..", no '/', no control characters (HDF5 names are C strings; "." is the group itself).
// Returns the reason it may not, or "". Here rather than with the writer, so that a scenario
// can check a label that will name a group without the HDF5 layer.
inline std::string invalid_object_name_reason(const std::string& name) {
  if (name.empty()) return "is empty";
  if (name == "." || name == "..") return "is reserved (HDF5 reads '.' and '..' as paths)";
  for (const char ch : name) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '/') return "contains '/'";
    if (c < 0x20 || c == 0x7f) return "contains a control character";
  }
  return "";
}

// The probe methods (docs/probes.md), the first word of an envelope's name and its `method`
// attribute: the one list against which the CLI, the probe campaign, the sweep and the Python
// reader check a method, so that a mistyped one is refused rather than read as no envelope.
inline constexpr std::array<std::string_view, 3> kProbeMethods = {"dynamic", "minimisation",
                                                                  "linear_response"};

}  // namespace rendulic

namespace rendulic::paths {

inline constexpr char kMaterial[] = "/material";
inline constexpr char kPreparation[] = "/preparation";
inline constexpr char kIsotropic[] = "/isotropic";
inline constexpr char kPath[] = "/path";
inline constexpr char kStates[] = "/states";
inline constexpr char kCalibration[] = "/calibration";
inline constexpr char kPressure[] = "/pressure";
inline constexpr char kTimings[] = "/timings";

// Below a state, a calibrated law or a pressure branch.
inline constexpr char kEnvelopes[] = "/envelopes";
inline constexpr char kElasticRange[] = "/elastic_range";
inline constexpr char kCheckpoint[] = "/checkpoint";
inline constexpr char kFitStress[] = "/fit_stress";
inline constexpr char kFitFabric[] = "/fit_fabric";

// "<root>/states" and "<root>/states/<label>" (root "" for the main run).
inline std::string states(const std::string& root = "") { return root + kStates; }
inline std::string state(const std::string& label, const std::string& root = "") {
  return states(root) + "/" + label;
}
// "<state>/envelopes" and "<state>/envelopes/<name>" for a state group from state().
inline std::string envelopes(const std::string& state_group) { return state_group + kEnvelopes; }
inline std::string envelope(const std::string& state_group, const std::string& name) {
  return envelopes(state_group) + "/" + name;
}
inline std::string elastic_range(const std::string& state_group) {
  return state_group + kElasticRange;
}
// A number as it appears in a group's name: %g, 6 significant digits. Lists whose entries name
// groups (probes.amplitudes, pressure.volume_fractions) must differ in this text (KeySpec's
// distinct).
inline std::string group_number(double x) { return decimal_g(x); }
// The name of an envelope: "<method>_<amplitude %g>", e.g. "dynamic_5e-05"; in a probe plane
// other than the Rendulic one (docs/probes.md "Probe planes") "<method>_<plane>_<amplitude>",
// e.g. "dynamic_deviatoric_5e-05".
inline std::string envelope_name(const std::string& method, double amplitude,
                                 const std::string& plane = "rendulic") {
  return method + (plane == "rendulic" ? "" : "_" + plane) + "_" + group_number(amplitude);
}
// "/calibration/<model>".
inline std::string calibration(const std::string& model) {
  return std::string(kCalibration) + "/" + model;
}
// "/pressure/nu<nu>", nu printed with %g (nu0.7, nu0.75).
inline std::string pressure_branch(double nu) {
  return std::string(kPressure) + "/nu" + group_number(nu);
}

}  // namespace rendulic::paths

// Datasets, with their leading '/'. One name, one meaning: the same quantity has the same
// name in a series (/isotropic, /path), a state, an envelope and a calibrated law.
namespace rendulic::datasets {

inline constexpr char kTime[] = "/time";
inline constexpr char kStrain[] = "/strain";  // strain tensors (series) or Rendulic pairs
inline constexpr char kEpsV[] = "/eps_v";
inline constexpr char kEpsDev[] = "/eps_dev";
inline constexpr char kStress[] = "/stress";  // Pa
inline constexpr char kStressStar[] = "/stress_star";
inline constexpr char kFabric[] = "/fabric";
inline constexpr char kVolumeFraction[] = "/volume_fraction";
// A state.
inline constexpr char kPositions[] = "/positions";
inline constexpr char kRadii[] = "/radii";
inline constexpr char kCellLengths[] = "/cell_lengths";
// A state's checkpoint (DemSystem::restore()).
inline constexpr char kVelocities[] = "/velocities";
inline constexpr char kForces[] = "/forces";
inline constexpr char kReferencePositions[] = "/reference_positions";
inline constexpr char kReferenceCellLengths[] = "/reference_cell_lengths";
inline constexpr char kReferenceHalfSkins[] = "/reference_half_skins";
inline constexpr char kStrainE[] = "/strain_E";
inline constexpr char kLastD[] = "/last_D";
// ... when the state's last force evaluation summed its stress (a servo step, a refresh):
// DemSystem::step(CellControl) reads it.
inline constexpr char kLastStressDiag[] = "/last_stress_diag";  // Pa
// ... of a frictional state only: angular velocities and torques [N,3], the tangential spring
// of each entry of the neighbour list [entries,3] in the list's order (the list is rebuilt
// identically from the reference state) and the sliding dissipation so far (attribute); with
// rolling resistance, the rolling spring of each entry likewise.
inline constexpr char kAngularVelocities[] = "/angular_velocities";
inline constexpr char kTorques[] = "/torques";
inline constexpr char kTangentialSprings[] = "/tangential_springs";
inline constexpr char kRollingSprings[] = "/rolling_springs";
// The remaining series of /isotropic and /path, one row per sample.
inline constexpr char kPressure[] = "/pressure";  // Pa
inline constexpr char kPressureStar[] = "/pressure_star";
inline constexpr char kCoordination[] = "/coordination";
inline constexpr char kCoordinationNonrattler[] = "/coordination_nonrattler";
inline constexpr char kRattlerFraction[] = "/rattler_fraction";
inline constexpr char kKineticEnergy[] = "/kinetic_energy";
inline constexpr char kElasticEnergy[] = "/elastic_energy";
inline constexpr char kInertialNumber[] = "/inertial_number";
// ... with friction only: the rotations' kinetic energy, the work dissipated by sliding since
// the system was made, and the fraction of contacts at the Coulomb limit.
inline constexpr char kRotationalEnergy[] = "/rotational_energy";
inline constexpr char kSlidingDissipation[] = "/sliding_dissipation";
inline constexpr char kSlidingFraction[] = "/sliding_fraction";
// An envelope (per probe) and the elastic-range ladder.
inline constexpr char kThetaDeg[] = "/theta_deg";
inline constexpr char kDStress[] = "/d_stress";
inline constexpr char kDFabric[] = "/d_fabric";
inline constexpr char kDFabricVolume[] = "/d_fabric_volume";
inline constexpr char kDFabricRotation[] = "/d_fabric_rotation";
inline constexpr char kDFabricContacts[] = "/d_fabric_contacts";
inline constexpr char kContactsOpened[] = "/contacts_opened";
inline constexpr char kContactsClosed[] = "/contacts_closed";
// A linear-response envelope: the 6x6 Mandel stiffness [Pa] and fabric stiffness.
inline constexpr char kStiffness[] = "/stiffness";
inline constexpr char kFabricStiffness[] = "/fabric_stiffness";
// The elastic-range ladder, one row per amplitude.
inline constexpr char kAmplitude[] = "/amplitude";
inline constexpr char kMinorOverElastic[] = "/minor_over_elastic";
inline constexpr char kMajorOverElastic[] = "/major_over_elastic";
inline constexpr char kCenterOverA[] = "/center_over_a";
inline constexpr char kKContinue[] = "/k_continue";
inline constexpr char kKReverse[] = "/k_reverse";
inline constexpr char kDeparture[] = "/departure";
inline constexpr char kSeconds[] = "/seconds";
// A calibrated law.
inline constexpr char kParams[] = "/params";
inline constexpr char kStderr[] = "/stderr";
inline constexpr char kCorrelation[] = "/correlation";

}  // namespace rendulic::datasets

// Units of the results file (docs/results.md "Units"): the `units` attribute every float
// dataset carries, and the `<name>_units` attribute beside every float attribute with a
// physical unit. "1" is a dimensionless or starred quantity (stress / k*). One table, by the
// last component of the name: one name, one meaning, one unit.
namespace rendulic::units {

struct Entry {
  const char* name;
  const char* unit;
};

// Datasets (without their leading '/').
inline constexpr Entry kDatasets[] = {
    {"time", "s"},
    {"seconds", "s"},
    {"relax_time", "s"},
    {"strain", "1"},
    {"eps_v", "1"},
    {"eps_dev", "1"},
    {"stress", "Pa"},
    {"d_stress", "Pa"},
    {"pressure", "Pa"},
    {"stress_star", "1"},
    {"pressure_star", "1"},
    {"fabric", "1"},
    {"d_fabric", "1"},
    {"d_fabric_volume", "1"},
    {"d_fabric_rotation", "1"},
    {"d_fabric_contacts", "1"},
    {"volume_fraction", "1"},
    {"coordination", "1"},
    {"coordination_nonrattler", "1"},
    {"rattler_fraction", "1"},
    {"kinetic_energy", "J"},
    {"elastic_energy", "J"},
    {"inertial_number", "1"},
    {"kinetic_to_elastic", "1"},
    {"positions", "m"},
    {"radii", "m"},
    {"cell_lengths", "m"},
    {"reference_positions", "m"},
    {"reference_cell_lengths", "m"},
    {"reference_half_skins", "m"},
    {"velocities", "m/s"},
    {"forces", "N"},
    {"max_force", "N"},
    {"strain_E", "1"},
    {"last_D", "1/s"},
    {"last_stress_diag", "Pa"},
    {"angular_velocities", "1/s"},
    {"torques", "N m"},
    {"tangential_springs", "m"},
    {"rotational_energy", "J"},
    {"sliding_dissipation", "J"},
    {"sliding_fraction", "1"},
    {"theta_deg", "deg"},
    {"stiffness", "Pa"},
    {"fabric_stiffness", "1"},
    {"fabric_volume_stiffness", "1"},
    {"fabric_rotation_stiffness", "1"},
    {"amplitude", "1"},
    {"minor_over_elastic", "1"},
    {"major_over_elastic", "1"},
    {"center_over_a", "1"},
    {"k_continue", "Pa"},
    {"k_reverse", "Pa"},
    {"departure", "1"},
    {"correlation", "1"},
};

// Float attributes with a physical unit (every other float attribute is dimensionless).
inline constexpr Entry kAttributes[] = {
    {"k", "N/m"},
    {"gamma", "kg/s"},
    {"gamma_b", "kg/s"},
    {"density", "kg/m^3"},
    {"r_mean", "m"},
    {"k_star", "Pa"},
    {"dt", "s"},
    {"time", "s"},
    {"seconds", "s"},
    {"relax_time", "s"},
    {"relax_time_cap", "s"},
    {"compression_time", "s"},
    {"wall_time_s", "s"},
    {"wall_s", "s"},
    {"cpu_s", "s"},
    {"rate", "1/s"},
    {"elastic_k", "Pa"},
    {"elastic_major", "Pa"},
    {"elastic_minor", "Pa"},
    {"minimise_max_displacement", "m"},
    {"min_overlap", "m"},
    {"sliding_dissipation", "J"},
    {"B", "Pa"},
    {"G", "Pa"},
    {"A", "Pa"},
    {"B_stderr", "Pa"},
    {"G_stderr", "Pa"},
    {"A_stderr", "Pa"},
    {"inclination_deg", "deg"},
    {"inclination_deg_stderr", "deg"},
    {"plastic_inclination_deg", "deg"},
    {"plastic_shift", "Pa"},
};

// Per-probe and per-state counters: stored as integers, without a unit.
inline constexpr const char* kCounters[] = {
    "contacts_opened",
    "contacts_closed",
    "backbone_contacts_opened",
    "backbone_contacts_closed",
    "load_steps",
    "relax_steps",
    "relax_iterations",
    "relax_converged",
    "iterations",
    "converged",
    "steps",
    "minimise_iterations",
    "n_particles",
    "n_rattlers",
    "n_backbone_contacts",
    "reference_relax_steps",
    "reference_relax_iterations",
};

namespace detail {
inline std::string_view last_component(std::string_view path) {
  const auto slash = path.rfind('/');
  return slash == std::string_view::npos ? path : path.substr(slash + 1);
}
template <std::size_t N>
const char* find(const Entry (&table)[N], std::string_view name) {
  for (const Entry& e : table)
    if (name == e.name) return e.unit;
  return nullptr;
}
}  // namespace detail

// The unit of a dataset by its path (nullptr: not in the table).
inline const char* of_dataset(std::string_view path) {
  return detail::find(kDatasets, detail::last_component(path));
}
// The unit of a float attribute (nullptr: dimensionless).
inline const char* of_attribute(std::string_view name) { return detail::find(kAttributes, name); }
// Whether a dataset or attribute of this name counts something (stored as an integer).
inline bool is_counter(std::string_view path) {
  const std::string_view name = detail::last_component(path);
  for (const char* c : kCounters)
    if (name == c) return true;
  return false;
}

}  // namespace rendulic::units
