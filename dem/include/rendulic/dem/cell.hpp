// Orthorhombic periodic cell and its driver (docs/physics.md section 2). The cell is a small value
// type (three lengths); changing it is the driver's job. The driver turns each axis's control
// (strain rate, or a stress target held by a servo) into the diagonal velocity gradient D of
// the step; the system then updates lengths with L_a <- L_a exp(D_aa dt), so that a trace-free
// D conserves the volume exactly (up to round-off), and remaps positions affinely.
#pragma once

#include <Eigen/Dense>
#include <array>
#include <string>

namespace rendulic::dem {

// The engine's cell: orthorhombic, so that its hot loop takes the periodic images from a table
// of 27 shifts (neighbor_list.hpp). The probe tools, which also deform a cell by any strain,
// hold it as a 3x3 matrix (PackingData, probe_geometry.hpp; lengths.asDiagonal() here) with the
// one minimum image for such cells (minimum_image() there).
struct PeriodicCell {
  Eigen::Vector3d lengths = Eigen::Vector3d::Ones();  // m
  double volume() const { return lengths.prod(); }
};

// How one axis of the cell moves.
struct AxisControl {
  enum class Mode { kStrainRate, kStress };
  Mode mode = Mode::kStrainRate;
  double rate = 0.0;         // kStrainRate: D_aa, 1/s (positive = extension)
  double target_stress = 0;  // kStress: sigma_aa to hold, Pa (compression positive)
};

// Servo settings. For a stress-controlled axis: D_aa = gain * (sigma_aa - target) / k*,
// clamped to |D_aa| <= max_rate (compressive stress above target makes the cell extend).
// With a tangent bulk-like stiffness K of the packing, the stress error decays at the rate
// gain * K / k*; K / k* is O(0.1 .. 1) on the states of this mission, so gain = 1e3 1/s gives
// time constants of ~1e-2 .. 1e-3 s: orders of magnitude slower than the sound crossing of
// the cell (~1e-5 s), hence stable and quasi-static. max_rate bounds the inertial number.
struct ServoOptions {
  double gain = 1e3;        // 1/s
  double max_rate = 500.0;  // 1/s
  bool IsValid(std::string* why) const;
};

struct CellControl {
  std::array<AxisControl, 3> axis{};
  ServoOptions servo{};

  static CellControl strain_rate(const Eigen::Vector3d& D);
  // Isotropic compression at a (positive) rate: D = -rate I.
  static CellControl isotropic_compression(double rate);
  // Constant-volume axisymmetric along x: D = rate diag(1, -1/2, -1/2) (rate > 0: extension).
  static CellControl undrained_axisymmetric(double rate);
  // Drained triaxial: axial (x) strain rate imposed, lateral stress held at `lateral_stress`.
  static CellControl drained_triaxial(double axial_rate, double lateral_stress);

  bool needs_stress() const;
  // D for the current measured stress (used only on stress-controlled axes).
  Eigen::Vector3d velocity_gradient(const Eigen::Vector3d& stress_diag, double k_star) const;
};

}  // namespace rendulic::dem
