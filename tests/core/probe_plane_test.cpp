// Tests of the probe planes of core/conventions.hpp (docs/probes.md "Probe planes: true-triaxial
// probes"): the Rendulic plane is bitwise the axisymmetric probe_strain / rendulic_pair /
// probe_directions_deg; the deviatoric plane holds constant-volume strains with theta the Lode
// angle from axial compression; a meridian plane holds the isotropic axis and one deviatoric
// direction, and every diagonal strain direction lies in the meridian at its own Lode angle;
// names parse to one spelling per plane.
#include <gtest/gtest.h>

#include <cmath>

#include "rendulic/core/conventions.hpp"

namespace rendulic {
namespace {

constexpr double kTight = 1e-12;

TEST(ProbePlane, RendulicPlaneIsBitwiseTheAxisymmetricProbes) {
  const ProbePlane plane = rendulic_plane();
  EXPECT_TRUE(plane.rendulic());
  EXPECT_TRUE(probe_plane_named("rendulic")->rendulic());
  const Eigen::VectorXd a = probe_directions_deg(36), b = plane_directions_deg(plane, 36);
  ASSERT_EQ(a.size(), b.size());
  for (int i = 0; i < a.size(); ++i) EXPECT_EQ(a(i), b(i)) << i;
  Eigen::Matrix3d q = Eigen::Matrix3d::Random();
  q = (q + q.transpose()).eval();
  for (double theta = 0.3; theta < 360; theta += 7.1) {
    // Bitwise: the Rendulic envelopes must not change by a single ulp.
    EXPECT_EQ(plane_strain(plane, theta, 5e-5), probe_strain(theta, 5e-5)) << theta;
    EXPECT_EQ(plane_pair(plane, q), rendulic_pair(q));
    const Eigen::Vector2d r(std::cos(theta), std::sin(theta));
    EXPECT_EQ(from_plane_pair(plane, r), from_rendulic_pair(r));
    // And its basis is what the generic formula would use: the pair is the projection.
    const Eigen::Matrix3d e = probe_strain(theta, 1.0);
    EXPECT_NEAR(e.diagonal().dot(plane.u), std::cos(deg_to_rad(theta)), kTight);
    EXPECT_NEAR(e.diagonal().dot(plane.v), std::sin(deg_to_rad(theta)), kTight);
  }
}

void expect_orthonormal(const ProbePlane& p) {
  EXPECT_NEAR(p.u.norm(), 1.0, kTight) << p.name;
  EXPECT_NEAR(p.v.norm(), 1.0, kTight) << p.name;
  EXPECT_NEAR(p.u.dot(p.v), 0.0, kTight) << p.name;
}

TEST(ProbePlane, DeviatoricPlaneIsConstantVolumeFromAxialCompression) {
  const ProbePlane plane = *probe_plane_named("deviatoric");
  EXPECT_FALSE(plane.rendulic());
  expect_orthonormal(plane);
  const double amp = 3e-5;
  for (double theta = 0; theta < 360; theta += 5) {
    const Eigen::Matrix3d e = plane_strain(plane, theta, amp);
    EXPECT_NEAR(e.trace(), 0.0, kTight * amp) << theta;
    EXPECT_NEAR(e.norm(), amp, kTight * amp) << theta;
    EXPECT_NEAR(std::sqrt(2.0 * j2(e)), amp, kTight * amp) << theta;
    const Eigen::Vector2d r = plane_pair(plane, e);
    EXPECT_NEAR(r.x(), amp * std::cos(deg_to_rad(theta)), kTight * amp);
    EXPECT_NEAR(r.y(), amp * std::sin(deg_to_rad(theta)), kTight * amp);
    EXPECT_NEAR((from_plane_pair(plane, r) - e).norm(), 0.0, kTight * amp);
  }
  // 0 deg: axial compression at constant volume, (2, -1, -1)/sqrt6 (the Rendulic plane's
  // kDevCompressionDeg); 180 deg its extension; every 60 deg an axisymmetric strain about the
  // next axis (x compression, z extension, y compression, ...).
  const Eigen::Matrix3d dev = probe_strain(kDevCompressionDeg, 1.0);
  EXPECT_NEAR((plane_strain(plane, 0.0, 1.0) - dev).norm(), 0.0, kTight);
  EXPECT_NEAR((plane_strain(plane, 180.0, 1.0) + dev).norm(), 0.0, kTight);
  const Eigen::Vector3d z_extension = Eigen::Vector3d(1, 1, -2) / std::sqrt(6.0);
  const Eigen::Vector3d y_compression = Eigen::Vector3d(-1, 2, -1) / std::sqrt(6.0);
  EXPECT_NEAR((plane_strain(plane, 60.0, 1.0).diagonal() - z_extension).norm(), 0.0, kTight);
  EXPECT_NEAR((plane_strain(plane, 120.0, 1.0).diagonal() - y_compression).norm(), 0.0, kTight);
  // Directions from 0 deg: 36 of them hold all six axisymmetric ones.
  const Eigen::VectorXd d = plane_directions_deg(plane, 36);
  EXPECT_EQ(d(0), 0.0);
  EXPECT_NEAR(d(6), 60.0, kTight);
}

TEST(ProbePlane, EveryPrincipalDirectionLiesInTheMeridianAtItsLodeAngle) {
  const ProbePlane m0 = *probe_plane_named("meridian_0");
  expect_orthonormal(m0);
  EXPECT_NEAR((plane_strain(m0, 0.0, 1.0) - probe_strain(kIsoCompressionDeg, 1.0)).norm(), 0.0,
              kTight);
  EXPECT_NEAR((plane_strain(m0, 90.0, 1.0) - probe_strain(kDevCompressionDeg, 1.0)).norm(), 0.0,
              kTight);
  std::srand(17);
  for (int k = 0; k < 50; ++k) {
    const Eigen::Vector3d d = Eigen::Vector3d::Random().normalized();
    // The Lode angle of d's deviator from the (2,-1,-1)/sqrt6, (0,1,-1)/sqrt2 axes, folded
    // into [0, 180): a meridian holds both signs of its deviatoric direction.
    const Eigen::Vector3d dev = d - Eigen::Vector3d::Constant(d.mean());
    double lode = rad_to_deg(std::atan2(dev.dot(Eigen::Vector3d(0, 1, -1) / kSqrt2),
                                        dev.dot(Eigen::Vector3d(2, -1, -1) / std::sqrt(6.0))));
    if (lode < 0) lode += 180.0;
    if (lode >= 180.0) lode -= 180.0;
    const ProbePlane m = meridian_plane(lode);
    expect_orthonormal(m);
    const Eigen::Vector3d in_plane = d.dot(m.u) * m.u + d.dot(m.v) * m.v;
    EXPECT_NEAR((in_plane - d).norm(), 0.0, 1e-12) << k << " lode " << lode;
    // The probe of the plane in d's direction is d.
    const double theta = rad_to_deg(std::atan2(d.dot(m.v), d.dot(m.u)));
    EXPECT_NEAR((plane_strain(m, theta, 1.0).diagonal() - d).norm(), 0.0, 1e-12) << k;
  }
}

TEST(ProbePlane, NamesParseToOneSpellingPerPlane) {
  EXPECT_EQ(probe_plane_named("deviatoric")->name, "deviatoric");
  EXPECT_EQ(probe_plane_named("meridian_30")->name, "meridian_30");
  EXPECT_EQ(probe_plane_named("meridian_22.5")->name, "meridian_22.5");
  EXPECT_NEAR((probe_plane_named("meridian_30")->v - deviatoric_direction(30.0)).norm(), 0.0,
              kTight);
  for (const char* bad :
       {"", "Rendulic", "pi", "meridian", "meridian_", "meridian_x", "meridian_180", "meridian_-10",
        "meridian_30.0", "meridian_30deg", "meridian_nan"})
    EXPECT_FALSE(probe_plane_named(bad).has_value()) << bad;
}

}  // namespace
}  // namespace rendulic
