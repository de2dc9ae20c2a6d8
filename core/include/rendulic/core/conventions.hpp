// Sign conventions, tensor invariants, Rendulic coordinates and probe planes: the one place that
// defines them (docs/physics.md sections 2, 3 and 5; docs/models.md "Coordinates";
// docs/probes.md "Probe planes"). Everything else calls these functions instead of re-deriving
// a sign or a sqrt(2).
//
// - Strain epsilon = -E: compression positive. Stress: compression positive.
// - Q_dev = +-sqrt(2 J2), the sign of J3 (+ for axial compression, - for axial extension).
// - Rendulic pair of a tensor Q: (sqrt(2) * lateral, axial), lateral = (Q_yy + Q_zz) / 2,
//   axial = Q_xx. The (iso, dev) frame is that pair rotated by atan(1/sqrt(2)) = 35.26 deg.
// - Mandel 6-vectors: (xx, yy, zz, sqrt2 yz, sqrt2 xz, sqrt2 xy), so that the Euclidean
//   product of two Mandel vectors is the double contraction of the tensors.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>

#include "rendulic/core/decimal.hpp"

namespace rendulic {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

inline constexpr double kSqrt2 = std::numbers::sqrt2;
inline constexpr double kSqrt3 = std::numbers::sqrt3;
inline constexpr double kPi = std::numbers::pi;

inline constexpr double deg_to_rad(double deg) { return deg * kPi / 180.0; }
inline constexpr double rad_to_deg(double rad) { return rad * 180.0 / kPi; }

// Special directions of the strain Rendulic plane (docs/physics.md section 5), in degrees.
// atan(1/sqrt(2)) is the angle of the isotropic axis (1, 1, 1) in the (sqrt2 lat, ax) plane.
inline const double kIsoCompressionDeg = rad_to_deg(std::atan(1.0 / kSqrt2));  // 35.26
inline const double kIsoExtensionDeg = kIsoCompressionDeg + 180.0;             // 215.26
inline constexpr double kUniaxialCompressionDeg = 90.0;
inline constexpr double kUniaxialExtensionDeg = 270.0;
inline const double kDevCompressionDeg = kIsoCompressionDeg + 90.0;  // 125.26, constant volume
inline const double kDevExtensionDeg = kIsoCompressionDeg + 270.0;   // 305.26

// Strain (compression positive) from the kinematic strain E (extension positive).
inline Eigen::Matrix3d strain_from_kinematic(const Eigen::Matrix3d& E) { return -E; }

inline double isotropic_part(const Eigen::Matrix3d& Q) { return Q.trace() / 3.0; }
// P = tr(sigma)/3 (compression positive stress gives positive pressure).
inline double pressure(const Eigen::Matrix3d& sigma) { return isotropic_part(sigma); }
// eps_v = tr(epsilon) = -tr(E): positive on compression.
inline double volumetric_strain(const Eigen::Matrix3d& eps) { return eps.trace(); }

inline Eigen::Matrix3d deviator(const Eigen::Matrix3d& Q) {
  return Q - isotropic_part(Q) * Eigen::Matrix3d::Identity();
}
// J2 = (1/2) Q^D : Q^D, which equals half the sum of squared deviator eigenvalues.
inline double j2(const Eigen::Matrix3d& Q) {
  const Eigen::Matrix3d d = deviator(Q);
  return 0.5 * (d.array() * d.array()).sum();
}
inline double j3(const Eigen::Matrix3d& Q) { return deviator(Q).determinant(); }

// Q_dev = sign(J3) sqrt(2 J2). J3 = 0 (no deviator, or a non-axisymmetric deviator with a
// zero middle eigenvalue) takes the + sign: the magnitude is then the only defined part.
inline double signed_deviator(const Eigen::Matrix3d& Q) {
  const double mag = std::sqrt(2.0 * j2(Q));
  return j3(Q) < 0.0 ? -mag : mag;
}

// Rendulic pair (sqrt(2) * lateral, axial) with lateral the mean of yy and zz.
inline Eigen::Vector2d rendulic_pair(const Eigen::Matrix3d& Q) {
  return {kSqrt2 * 0.5 * (Q(1, 1) + Q(2, 2)), Q(0, 0)};
}
// The axisymmetric tensor whose Rendulic pair is r: diag(axial, lateral, lateral).
inline Eigen::Matrix3d from_rendulic_pair(const Eigen::Vector2d& r) {
  const double lat = r.x() / kSqrt2;
  return Eigen::Vector3d(r.y(), lat, lat).asDiagonal();
}

// Rotation from Rendulic (sqrt2 lat, ax) to the (iso, dev) frame of docs/models.md:
// iso = tr(Q)/sqrt(3), dev = sqrt(2/3) (ax - lat). Orthonormal, so it preserves norms.
inline Eigen::Matrix2d rendulic_to_iso_dev() {
  const double c = std::sqrt(2.0 / 3.0), s = 1.0 / kSqrt3;  // cos, sin of 35.26 deg
  Eigen::Matrix2d R;
  R << c, s, -s, c;
  return R;
}
inline Eigen::Vector2d iso_dev_from_rendulic(const Eigen::Vector2d& r) {
  return rendulic_to_iso_dev() * r;
}
inline Eigen::Vector2d rendulic_from_iso_dev(const Eigen::Vector2d& q) {
  return rendulic_to_iso_dev().transpose() * q;
}

// Probe strain (compression positive) for direction theta (docs/physics.md section 5):
// amplitude * diag(sin theta, cos theta / sqrt2, cos theta / sqrt2). Its Frobenius norm is
// the amplitude and its Rendulic pair is amplitude * (cos theta, sin theta).
inline Eigen::Matrix3d probe_strain(double theta_deg, double amplitude) {
  const double t = deg_to_rad(theta_deg);
  const double lat = amplitude * std::cos(t) / kSqrt2;
  return Eigen::Vector3d(amplitude * std::sin(t), lat, lat).asDiagonal();
}
// Probe planes (docs/probes.md "Probe planes: true-triaxial probes"): a probe of direction
// theta in a plane with orthonormal principal-strain directions u, v (components along x, y, z)
// has d_eps = amplitude diag(cos theta u + sin theta v), and a tensor's pair in the plane is
// its projection (Q : diag(u), Q : diag(v)). The Rendulic plane is today's axisymmetric one
// (u = (0, 1, 1)/sqrt2, v = (1, 0, 0)); its functions below are exactly probe_strain,
// rendulic_pair and from_rendulic_pair, so that Rendulic envelopes stay bitwise what they were.
// "deviatoric" is the pi-plane of constant volume, theta the Lode-type angle from axial (x)
// compression; "meridian_<deg>" holds the isotropic axis (theta = 0) and the deviatoric
// direction at that Lode angle (theta = 90), so that every principal direction is reachable.
struct ProbePlane {
  std::string name = "rendulic";
  Eigen::Vector3d u{0.0, 1.0 / kSqrt2, 1.0 / kSqrt2};
  Eigen::Vector3d v{1.0, 0.0, 0.0};
  double start_deg = kIsoCompressionDeg;  // the first of M equally spaced probe directions
  bool rendulic() const { return name == "rendulic"; }
};
inline constexpr char kProbePlaneNames[] =
    "rendulic, deviatoric, meridian_<Lode angle in [0, 180) deg>";
inline ProbePlane rendulic_plane() { return {}; }
// The deviatoric direction at Lode angle `lode_deg` from axial (x) compression.
inline Eigen::Vector3d deviatoric_direction(double lode_deg) {
  const double t = deg_to_rad(lode_deg);
  return std::cos(t) * Eigen::Vector3d(2.0, -1.0, -1.0) / std::sqrt(6.0) +
         std::sin(t) * Eigen::Vector3d(0.0, 1.0, -1.0) / kSqrt2;
}
// Axisymmetric compression and extension along x, y, z are probes whenever M is a multiple of 6.
inline ProbePlane deviatoric_plane() {
  return {"deviatoric", deviatoric_direction(0.0), deviatoric_direction(90.0), 0.0};
}
// Isotropic compression at 0 deg, the deviatoric direction at 90 deg (M a multiple of 4).
inline ProbePlane meridian_plane(double lode_deg) {
  return {"meridian_" + decimal_g(lode_deg), Eigen::Vector3d::Constant(1.0 / kSqrt3),
          deviatoric_direction(lode_deg), 0.0};
}
// The plane of a name of kProbePlaneNames (a meridian's angle as written, e.g. meridian_30);
// nullopt for any other name.
inline std::optional<ProbePlane> probe_plane_named(const std::string& name) {
  if (name == "rendulic") return rendulic_plane();
  if (name == "deviatoric") return deviatoric_plane();
  const std::string prefix = "meridian_";
  if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0)
    return std::nullopt;
  const std::optional<double> lode = decimal_number(name.substr(prefix.size()));
  if (!lode || !(*lode >= 0.0 && *lode < 180.0)) return std::nullopt;
  ProbePlane plane = meridian_plane(*lode);
  if (plane.name != name) return std::nullopt;  // one spelling per plane, so one envelope name
  return plane;
}
// Probe strain (compression positive) of direction theta in the plane, Frobenius norm amplitude.
inline Eigen::Matrix3d plane_strain(const ProbePlane& plane, double theta_deg, double amplitude) {
  if (plane.rendulic()) return probe_strain(theta_deg, amplitude);
  const double t = deg_to_rad(theta_deg);
  const Eigen::Vector3d d = amplitude * (std::cos(t) * plane.u + std::sin(t) * plane.v);
  return d.asDiagonal();
}
// The pair of a tensor in the plane (its projection on the plane's two directions).
inline Eigen::Vector2d plane_pair(const ProbePlane& plane, const Eigen::Matrix3d& Q) {
  if (plane.rendulic()) return rendulic_pair(Q);
  const Eigen::Vector3d d = Q.diagonal();
  return {d.dot(plane.u), d.dot(plane.v)};
}
// The diagonal tensor of the plane whose pair is r.
inline Eigen::Matrix3d from_plane_pair(const ProbePlane& plane, const Eigen::Vector2d& r) {
  if (plane.rendulic()) return from_rendulic_pair(r);
  const Eigen::Vector3d d = r.x() * plane.u + r.y() * plane.v;
  return d.asDiagonal();
}
// Elastic and elasto-plastic probes (docs/physics.md section 5): an envelope whose probes have
// |d_eps| below kElasticAmplitudeMax is elastic; one above kPlasticAmplitudeMin is
// elasto-plastic (between the two a probe is neither, and no claim or objective uses it).
inline constexpr double kElasticAmplitudeMax = 1e-4;
inline constexpr double kPlasticAmplitudeMin = 1e-3;
inline constexpr bool is_elastic_amplitude(double amplitude) {
  return amplitude < kElasticAmplitudeMax;
}
inline constexpr bool is_plastic_amplitude(double amplitude) {
  return amplitude > kPlasticAmplitudeMin;
}
// Direction of a strain Rendulic pair, in [0, 360) degrees.
inline double probe_direction_deg(const Eigen::Vector2d& strain_pair) {
  double deg = rad_to_deg(std::atan2(strain_pair.y(), strain_pair.x()));
  return deg < 0.0 ? deg + 360.0 : deg;
}
// M equally spaced directions starting at isotropic compression (35.26 deg), wrapped into
// [0, 360): whenever M is a multiple of 4 the set holds the isotropic and the deviatoric
// (constant-volume) directions of docs/physics.md section 5 exactly, so the seed's special points
// of Figs. 3-6 are probes, not interpolations.
inline Eigen::VectorXd probe_directions_deg(int m) {
  Eigen::VectorXd d(m);
  for (int i = 0; i < m; ++i) d(i) = std::fmod(kIsoCompressionDeg + 360.0 * i / m, 360.0);
  return d;
}

// M equally spaced directions of a plane from its start: probe_directions_deg for the Rendulic
// plane, so that its directions are bitwise what they were.
inline Eigen::VectorXd plane_directions_deg(const ProbePlane& plane, int m) {
  if (plane.rendulic()) return probe_directions_deg(m);
  Eigen::VectorXd d(m);
  for (int i = 0; i < m; ++i) d(i) = std::fmod(plane.start_deg + 360.0 * i / m, 360.0);
  return d;
}

// Mandel form of a symmetric tensor (xx, yy, zz, sqrt2 yz, sqrt2 xz, sqrt2 xy) and back: the
// dot product of two Mandel vectors is the double contraction of the tensors. Templates on the
// scalar so that the constitutive laws push automatic-differentiation types through the same
// code; the double overloads also take Eigen expressions.
template <typename T>
Eigen::Matrix<T, 6, 1> to_mandel(const Eigen::Matrix<T, 3, 3>& Q) {
  const T r2 = T(kSqrt2);
  Eigen::Matrix<T, 6, 1> v;
  v << Q(0, 0), Q(1, 1), Q(2, 2), r2 * Q(1, 2), r2 * Q(0, 2), r2 * Q(0, 1);
  return v;
}
template <typename T>
Eigen::Matrix<T, 3, 3> from_mandel(const Eigen::Matrix<T, 6, 1>& v) {
  const T r2 = T(kSqrt2);
  const T yz = v(3) / r2, xz = v(4) / r2, xy = v(5) / r2;
  Eigen::Matrix<T, 3, 3> Q;
  Q << v(0), xy, xz, xy, v(1), yz, xz, yz, v(2);
  return Q;
}
inline Vector6d to_mandel(const Eigen::Matrix3d& Q) { return to_mandel<double>(Q); }
inline Eigen::Matrix3d from_mandel(const Vector6d& v) { return from_mandel<double>(v); }

}  // namespace rendulic
