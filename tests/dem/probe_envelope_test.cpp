// Probe directions and envelopes (docs/physics.md sections 5 and 6): unit-norm probe strains and
// the special directions, the linear-response envelope of a lattice with a closed-form
// stiffness, the Rendulic map fit and its ellipse (semi-axes = singular values).
#include "rendulic/dem/probe_envelope.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "rendulic/dem/probe_campaign.hpp"

namespace rendulic::dem {
namespace {

TEST(ProbeDirections, UnitNormAndSpecialDirections) {
  const std::vector<double> theta = probe_directions(36);
  ASSERT_EQ(theta.size(), 36u);
  EXPECT_DOUBLE_EQ(theta[1] - theta[0], 10.0);
  for (double t : theta) {
    const Eigen::Matrix3d e = probe_strain(t, 1.0);
    EXPECT_NEAR(e.norm(), 1.0, 1e-15);  // Frobenius norm = amplitude
    EXPECT_NEAR(rendulic_pair(e).norm(), 1.0, 1e-15);
    EXPECT_NEAR(probe_direction_deg(rendulic_pair(e)), t, 1e-12);
  }
  constexpr double kTol = 1e-14;  // a few ulps of the trigonometric functions
  // Isotropic compression / extension: equal principal strains, of the right sign.
  const Eigen::Matrix3d iso = probe_strain(kIsoCompressionDeg, 1.0);
  EXPECT_NEAR(iso(0, 0), iso(1, 1), kTol);
  EXPECT_NEAR(iso(0, 0), 1.0 / std::sqrt(3.0), kTol);
  EXPECT_NEAR(probe_strain(kIsoExtensionDeg, 1.0)(2, 2), -1.0 / std::sqrt(3.0), kTol);
  // Uniaxial: no lateral strain.
  EXPECT_NEAR(probe_strain(90.0, 1.0)(1, 1), 0.0, kTol);
  EXPECT_NEAR(probe_strain(270.0, 1.0)(0, 0), -1.0, kTol);
  // Deviatoric: constant volume; 125.26 is axial compression, 305.26 axial extension.
  const Eigen::Matrix3d dev = probe_strain(kDevCompressionDeg, 1.0);
  EXPECT_NEAR(dev.trace(), 0.0, kTol);
  EXPECT_GT(dev(0, 0), 0.0);
  EXPECT_NEAR(probe_strain(kDevExtensionDeg, 1.0).trace(), 0.0, kTol);
  EXPECT_LT(probe_strain(kDevExtensionDeg, 1.0)(0, 0), 0.0);
}

TEST(RendulicMap, FitRecoversAnAffineMapAndItsEllipse) {
  Eigen::Matrix2d map;
  map << 3.0, 1.0, 0.5, 2.0;
  const Eigen::Vector2d center(0.1, -0.2);
  std::vector<Eigen::Vector2d> s, r;
  for (double t : probe_directions(8)) {
    s.push_back(2e-3 * Eigen::Vector2d(std::cos(deg_to_rad(t)), std::sin(deg_to_rad(t))));
    r.push_back(map * s.back() + center);
  }
  const RendulicMap fit = fit_rendulic_map(s, r);
  EXPECT_LE((fit.map - map).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LE((fit.center - center).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT(fit.rms, 1e-12);
  const Eigen::JacobiSVD<Eigen::Matrix2d> svd(map);
  EXPECT_NEAR(fit.semi_major, 2e-3 * svd.singularValues()(0), 1e-12);
  EXPECT_NEAR(fit.semi_minor, 2e-3 * svd.singularValues()(1), 1e-12);
  // The ellipse's farthest point from the centre lies along the inclination.
  double best = 0.0, best_deg = 0.0;
  for (int i = 0; i < 3600; ++i) {
    const double t = deg_to_rad(0.1 * i);
    const Eigen::Vector2d p = map * Eigen::Vector2d(std::cos(t), std::sin(t));
    if (p.norm() > best) {
      best = p.norm();
      best_deg = std::fmod(rad_to_deg(std::atan2(p.y(), p.x())) + 360.0, 180.0);
    }
  }
  EXPECT_NEAR(fit.inclination_deg, best_deg, 0.2);
  EXPECT_THROW(fit_rendulic_map({s[0], s[4]}, {r[0], r[4]}), std::invalid_argument);
}

// The linear response of an FCC lattice (closed form in linear_response_test.cpp).
LinearResponse fcc_linear_response() {
  const double radius = 1e-3, r0 = 1.98e-3, a = r0 * std::numbers::sqrt2;
  const int cells = 3;
  const std::vector<Eigen::Vector3d> basis = {
      {0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  Eigen::MatrixX3d x(4 * cells * cells * cells, 3);
  int p = 0;
  for (int i = 0; i < cells; ++i)
    for (int j = 0; j < cells; ++j)
      for (int k = 0; k < cells; ++k)
        for (const auto& b : basis) x.row(p++) = (a * (Eigen::Vector3d(i, j, k) + b)).transpose();
  const PackingData fcc = PackingData::orthorhombic(x, Eigen::VectorXd::Constant(p, radius),
                                                    Eigen::Vector3d::Constant(cells * a));
  return linear_response(fcc, LinearResponseOptions{});
}

// FCC lattice: cubic symmetry maps isotropic strain onto isotropic stress, so the isotropic
// probe lies on an axis of the elastic ellipse, and the semi-axes are (C11 + 2 C12) |d_eps|
// (isotropic) and (C11 - C12) |d_eps| (deviatoric).
TEST(LinearResponseEnvelope, FccEllipseFromClosedForm) {
  const LinearResponse lr = fcc_linear_response();
  ASSERT_TRUE(lr.ok) << lr.message;
  const double k_star = 1e8 / 2e-3, amp = 5e-5;
  const Envelope env = linear_response_envelope(lr, probe_directions(36), amp, k_star);
  ASSERT_EQ(env.size(), 36u);
  EXPECT_EQ(env.method, "linear_response");
  for (std::size_t i = 0; i < env.size(); ++i) {
    EXPECT_LE((env.stress_star[i] - rendulic_pair(env.d_stress[i]) / k_star).norm(), 1e-15);
    // Same formula, possibly contracted differently into FMAs (-march=native): round-off.
    EXPECT_LE((env.strain[i] - rendulic_pair(probe_strain(env.theta_deg[i], amp))).norm(),
              1e-14 * amp);
  }
  const double c11 = lr.stiffness(0, 0), c12 = lr.stiffness(0, 1);
  const double bulk_axis = amp * (c11 + 2 * c12) / k_star, shear_axis = amp * (c11 - c12) / k_star;
  const RendulicMap fit = fit_rendulic_map(env.strain, env.stress_star);
  constexpr double kTol = 1e-9;  // round-off of a least-squares fit of exact data
  EXPECT_NEAR(fit.semi_major, bulk_axis, kTol * bulk_axis);
  EXPECT_NEAR(fit.semi_minor, shear_axis, kTol * bulk_axis);
  EXPECT_NEAR(fit.inclination_deg, kIsoCompressionDeg, 1e-6);
  EXPECT_LT(fit.center.norm(), kTol * bulk_axis);
  const RendulicMap exact = ellipse_of(rendulic_map_of(lr.stiffness) / k_star, amp);
  EXPECT_NEAR(exact.semi_major, fit.semi_major, kTol * bulk_axis);
}

// The same lattice in the deviatoric probe plane (docs/probes.md "Probe planes"): every
// diagonal constant-volume strain sees C11 - C12 alone, so the envelope is a circle of radius
// (C11 - C12) |d_eps|, the Rendulic envelope's deviatoric semi-axis.
TEST(LinearResponseEnvelope, FccDeviatoricPlaneEnvelopeIsACircle) {
  const LinearResponse lr = fcc_linear_response();
  ASSERT_TRUE(lr.ok) << lr.message;
  const double k_star = 1e8 / 2e-3, amp = 5e-5;
  const ProbePlane plane = deviatoric_plane();
  const Envelope env =
      linear_response_envelope(lr, probe_directions(36, plane), amp, k_star, plane);
  const double r = amp * (lr.stiffness(0, 0) - lr.stiffness(0, 1)) / k_star;
  ASSERT_GT(r, 0.0);
  for (std::size_t i = 0; i < env.size(); ++i)
    EXPECT_NEAR(env.stress_star[i].norm(), r, 1e-9 * r) << env.theta_deg[i];
}

}  // namespace
}  // namespace rendulic::dem
