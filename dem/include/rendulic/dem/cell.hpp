// Orthorhombic periodic cell and its driver (docs/physics.md section 2). The cell is a small value
// type (three lengths); changing it is the driver's job. The driver turns each axis's control
// (strain rate, or a stress target held by a servo) into the diagonal velocity gradient D of
// the step; the system then updates lengths with L_a <- L_a exp(D_aa dt), so that a trace-free
// D conserves the volume exactly (up to round-off), and remaps positions affinely.
#pragma once

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <cstddef>
#include <string>

namespace rendulic::dem {

// The periodic cell of every packing: its matrix h, whose columns are the cell vectors. The
// engine's cells are orthorhombic (h = diag(L); DemSystem refuses others), so that its hot loop
// takes the periodic images from a table of 27 shifts (neighbor_list.hpp); the probe tools,
// which also deform a cell by any strain (PackingData, probe_geometry.hpp), use the general h
// with the one minimum image below.
struct PeriodicCell {
  Eigen::Matrix3d h = Eigen::Matrix3d::Identity();  // columns: cell vectors, m

  static PeriodicCell orthorhombic(const Eigen::Vector3d& lengths) {
    PeriodicCell c;
    c.h = lengths.asDiagonal();
    return c;
  }
  bool is_orthorhombic() const { return h.isDiagonal(0.0); }
  // The edge lengths of an orthorhombic cell (h's diagonal).
  Eigen::Vector3d lengths() const { return h.diagonal(); }
  // det h. (The engine, whose cells are orthorhombic, takes the product of the lengths in its
  // own order of operations: DemSystem::volume().)
  double volume() const { return h.determinant(); }
  // The homogeneous deformation x -> F x of the cell (F the deformation gradient).
  void deform(const Eigen::Matrix3d& F) { h = F * h; }
};

// A coordinate wrapped into [0, L) along an orthorhombic cell's axis, as the engine keeps its
// particles (a coordinate a rounding below a multiple of L lands on 0).
inline double wrap_coordinate(double x, double L) {
  double q = x - L * std::floor(x / L);
  if (q >= L) q -= L;  // floor rounding can leave q == L
  return q < 0 ? 0.0 : q;
}

// Minimum-image vector of a separation in a (nearly orthorhombic) cell; h_inverse = cell.h^-1,
// passed in because callers take it once for many pairs.
inline Eigen::Vector3d minimum_image(const PeriodicCell& cell, const Eigen::Matrix3d& h_inverse,
                                     const Eigen::Vector3d& separation) {
  Eigen::Vector3d s = h_inverse * separation;
  for (int a = 0; a < 3; ++a) s(a) -= std::nearbyint(s(a));
  return cell.h * s;
}

// minimum_image() in an orthorhombic cell (h and h_inverse diagonal, passed as their
// diagonals): the same numbers (the off-diagonal products are exact zeros), a third of the
// arithmetic. The probe tools' hot loops (find_pairs, the FIRE forces) take it when
// PeriodicCell::is_orthorhombic(): every probe strain is principal.
inline Eigen::Vector3d minimum_image_orthorhombic(const Eigen::Vector3d& h_diagonal,
                                                  const Eigen::Vector3d& h_inverse_diagonal,
                                                  const Eigen::Vector3d& separation) {
  Eigen::Vector3d s = h_inverse_diagonal.cwiseProduct(separation);
  s -= s.unaryExpr([](double v) { return std::nearbyint(v); }).eval();
  return h_diagonal.cwiseProduct(s);
}

// Bins of a cell list along each axis of a cell whose perpendicular widths are `widths`, for
// `n` particles: as many bins as fit bins no narrower than min_width (at least one per axis),
// but no more than kMaxBinsPerParticle per particle (and at least 2^16 in all) in a dilute cell.
// Without that bound a few particles in a wide box (a gas of preparation.nu_gas = 1e-6, a
// packing file from another engine) asked for billions of bins, gigabytes and an int overflow.
// Bins wider than min_width only add candidates, so every list stays complete; dense packings
// hold one or two particles per bin and never meet the bound. The engine's neighbour list, the
// random gas and the probe tools' pair search all take their bins here (docs/dem.md).
inline constexpr double kMaxBinsPerParticle = 64.0;
std::array<int, 3> cell_list_bins(const Eigen::Vector3d& widths, double min_width, std::size_t n);

// The minimum-image convention holds only where every perpendicular width of the cell exceeds
// twice the interaction range (2 r_max + skin): InputError naming the axis otherwise ("periodic
// cell too small: ..."), for the engine's list and the probe tools' pair search alike.
void require_minimum_image(const Eigen::Vector3d& widths, double range);

// How one axis of the cell moves.
struct AxisControl {
  enum class Mode { kStrainRate, kStress };
  Mode mode = Mode::kStrainRate;
  double rate = 0.0;         // kStrainRate: D_aa, 1/s (positive = extension)
  double target_stress = 0;  // kStress: sigma_aa to hold, Pa (compression positive)
};

// Servo settings. For a stress-controlled axis, with the error e = (sigma_aa - target) / k*
// (compressive stress above target makes the cell extend):
//   proportional (integral_gain = 0): D_aa = gain e;
//   proportional-integral: D_aa = I_a + gain e, dI_a/dt = integral_gain e;
// clamped to |D_aa| <= max_rate. With a tangent stiffness K of the packing along the axis, the
// error obeys e'' + gain K* e' + integral_gain K* e = 0 (K* = K / k*, O(0.1 .. 1) on the states
// of this mission). The proportional servo holds a target only when the cell does not move
// otherwise (as in a hold at fixed stress: time constant 1 / (gain K*), ~1e-2 .. 1e-3 s for
// gain = 1e3 1/s, orders of magnitude slower than the sound crossing of the cell, ~1e-5 s).
// Under a path the lateral axes must follow a rate D_lat that the material sets (dilatancy):
// a proportional servo then lags by e = D_lat / gain, which at the path's rates is per cent of
// the stress, while the integral term learns D_lat and the lag decays (docs/dem.md "Paths").
// max_rate bounds the inertial number.
struct ServoOptions {
  double gain = 1e3;           // 1/s
  double integral_gain = 0.0;  // 1/s^2; 0: proportional only
  double max_rate = 500.0;     // 1/s
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
  // D for the current measured stress (used only on stress-controlled axes): the proportional
  // servo, and with `integral` (the servo's integral term I, one per axis, carried from step to
  // step and advanced here by dt) the proportional-integral one of ServoOptions.
  Eigen::Vector3d velocity_gradient(const Eigen::Vector3d& stress_diag, double k_star) const;
  Eigen::Vector3d velocity_gradient(const Eigen::Vector3d& stress_diag, double k_star, double dt,
                                    Eigen::Vector3d& integral) const;
};

}  // namespace rendulic::dem
