// Tests of core/conventions.hpp: sign rules and invariants of docs/physics.md section 3, the
// Rendulic pair and (iso, dev) frame of docs/models.md, probe strains and special directions of
// docs/physics.md section 5. Closed forms and round trips; tolerances are a few ulps of O(1)
// numbers (kTight) because every function is a handful of exact-ish floating operations.
#include "rendulic/core/conventions.hpp"

#include <gtest/gtest.h>

namespace rendulic {
namespace {

constexpr double kTight = 1e-12;

Eigen::Matrix3d random_symmetric(int seed) {
  std::srand(seed);
  Eigen::Matrix3d a = Eigen::Matrix3d::Random();
  return 0.5 * (a + a.transpose());
}

TEST(Conventions, SpecialDirectionsHaveTheirClosedFormAngles) {
  EXPECT_NEAR(kIsoCompressionDeg, 35.26438968, 1e-8);
  EXPECT_NEAR(kDevCompressionDeg, 125.26438968, 1e-8);
  EXPECT_NEAR(kIsoExtensionDeg, 215.26438968, 1e-8);
  EXPECT_NEAR(kDevExtensionDeg, 305.26438968, 1e-8);
}

TEST(Conventions, ProbeStrainHasUnitNormAndItsDirectionAsRendulicPair) {
  for (double theta = 0; theta < 360; theta += 7.5) {
    const Eigen::Matrix3d e = probe_strain(theta, 1.0);
    EXPECT_NEAR(e.norm(), 1.0, kTight) << theta;
    const Eigen::Vector2d r = rendulic_pair(e);
    EXPECT_NEAR(r.x(), std::cos(deg_to_rad(theta)), kTight);
    EXPECT_NEAR(r.y(), std::sin(deg_to_rad(theta)), kTight);
    EXPECT_NEAR(probe_direction_deg(r), theta, 1e-9);
    EXPECT_NEAR(probe_strain(theta, 3e-5).norm(), 3e-5, 1e-18);
  }
}

TEST(Conventions, IsotropicCompressionDirectionIsIsotropicCompression) {
  const Eigen::Matrix3d e = probe_strain(kIsoCompressionDeg, 1.0);
  EXPECT_NEAR(j2(e), 0.0, kTight);
  EXPECT_GT(volumetric_strain(e), 0.0);  // compression positive
  EXPECT_NEAR(volumetric_strain(e), kSqrt3, kTight);
  EXPECT_NEAR(e(0, 0), e(1, 1), kTight);
  const Eigen::Matrix3d x = probe_strain(kIsoExtensionDeg, 1.0);
  EXPECT_NEAR(volumetric_strain(x), -kSqrt3, kTight);
}

TEST(Conventions, DeviatoricCompressionDirectionConservesVolumeAndCompressesAxially) {
  const Eigen::Matrix3d e = probe_strain(kDevCompressionDeg, 1.0);
  EXPECT_NEAR(volumetric_strain(e), 0.0, kTight);
  EXPECT_GT(e(0, 0), 0.0);
  EXPECT_NEAR(signed_deviator(e), 1.0, kTight);  // unit norm, all deviatoric, + for compression
  EXPECT_NEAR(signed_deviator(probe_strain(kDevExtensionDeg, 1.0)), -1.0, kTight);
}

TEST(Conventions, UniaxialDirections) {
  const Eigen::Matrix3d e = probe_strain(kUniaxialCompressionDeg, 2.0);
  EXPECT_NEAR(e(0, 0), 2.0, kTight);
  EXPECT_NEAR(e(1, 1), 0.0, kTight);
  EXPECT_NEAR(probe_strain(kUniaxialExtensionDeg, 2.0)(0, 0), -2.0, kTight);
}

TEST(Conventions, StrainIsMinusKinematicStrain) {
  const Eigen::Matrix3d E = Eigen::Vector3d(1.0, -0.5, -0.5).asDiagonal();  // axial extension
  const Eigen::Matrix3d eps = strain_from_kinematic(E);
  EXPECT_NEAR(volumetric_strain(eps), 0.0, kTight);
  EXPECT_LT(signed_deviator(eps), 0.0);  // extension: negative eps_dev
}

TEST(Conventions, InvariantsClosedForms) {
  // Axisymmetric compression: Q = diag(a, b, b), a > b. Q_dev = sqrt(2/3) (a - b).
  const double a = 5.0, b = 2.0;
  const Eigen::Matrix3d q = Eigen::Vector3d(a, b, b).asDiagonal();
  EXPECT_NEAR(pressure(q), 3.0, kTight);
  EXPECT_NEAR(j2(q), (a - b) * (a - b) / 3.0, kTight);
  EXPECT_NEAR(j3(q), 2.0 * std::pow(a - b, 3) / 27.0, kTight);
  EXPECT_NEAR(signed_deviator(q), std::sqrt(2.0 / 3.0) * (a - b), kTight);
  const Eigen::Matrix3d qe = Eigen::Vector3d(b, a, a).asDiagonal();  // axial extension
  EXPECT_NEAR(signed_deviator(qe), -std::sqrt(2.0 / 3.0) * (a - b), kTight);
  EXPECT_NEAR(signed_deviator(Eigen::Matrix3d::Identity() * 4.0), 0.0, kTight);
}

TEST(Conventions, J2IsHalfTheSumOfSquaredDeviatorEigenvalues) {
  for (int s = 1; s < 20; ++s) {
    const Eigen::Matrix3d q = random_symmetric(s);
    const Eigen::Vector3d ev =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(deviator(q)).eigenvalues();
    EXPECT_NEAR(j2(q), 0.5 * ev.squaredNorm(), kTight);
    EXPECT_NEAR(j3(q), ev.prod(), kTight);
    EXPECT_NEAR(deviator(q).trace(), 0.0, kTight);
  }
}

TEST(Conventions, IsoDevFrameMatchesModelsSpec) {
  // docs/models.md: eps_iso = eps_v / sqrt(3), eps_d = sqrt(2/3) (eps_xx - eps_yy).
  const Eigen::Matrix3d e = Eigen::Vector3d(0.3, -0.1, -0.1).asDiagonal();
  const Eigen::Vector2d q = iso_dev_from_rendulic(rendulic_pair(e));
  EXPECT_NEAR(q.x(), volumetric_strain(e) / kSqrt3, kTight);
  EXPECT_NEAR(q.y(), std::sqrt(2.0 / 3.0) * 0.4, kTight);
  EXPECT_NEAR(q.y(), signed_deviator(e), kTight);
  // Stress: sigma_iso = sqrt(3) P.
  const Eigen::Matrix3d s = Eigen::Vector3d(2.0, 5.0, 5.0).asDiagonal();
  EXPECT_NEAR(iso_dev_from_rendulic(rendulic_pair(s)).x(), kSqrt3 * pressure(s), kTight);
  // The rotation is orthonormal and the isotropic direction maps to (1, 0).
  const Eigen::Matrix2d R = rendulic_to_iso_dev();
  EXPECT_NEAR((R * R.transpose() - Eigen::Matrix2d::Identity()).norm(), 0.0, kTight);
  const Eigen::Vector2d iso = rendulic_pair(probe_strain(kIsoCompressionDeg, 1.0));
  EXPECT_NEAR((iso_dev_from_rendulic(iso) - Eigen::Vector2d(1, 0)).norm(), 0.0, kTight);
  EXPECT_NEAR((rendulic_from_iso_dev(iso_dev_from_rendulic(iso)) - iso).norm(), 0.0, kTight);
}

TEST(Conventions, IsotropicLinearLawEnvelopeIsTheWorkedCheckOfModelsSpec) {
  // D = diag(3K, 2G) in the (iso, dev) frame: semi-axes 3K, 2G, major axis at 35.26 deg.
  const double K = 7.0, G = 2.0;
  const Eigen::Matrix2d R = rendulic_to_iso_dev();
  const Eigen::Matrix2d D = R.transpose() * Eigen::Vector2d(3 * K, 2 * G).asDiagonal() * R;
  Eigen::JacobiSVD<Eigen::Matrix2d> svd(D, Eigen::ComputeFullU);
  EXPECT_NEAR(svd.singularValues()(0), 3 * K, kTight);
  EXPECT_NEAR(svd.singularValues()(1), 2 * G, kTight);
  const Eigen::Vector2d major = svd.matrixU().col(0);
  double incl = rad_to_deg(std::atan2(major.y(), major.x()));
  if (incl < 0) incl += 180;
  EXPECT_NEAR(incl, kIsoCompressionDeg, 1e-9);
}

TEST(Conventions, RendulicAndMandelRoundTrips) {
  const Eigen::Vector2d r(1.7, -0.4);
  EXPECT_NEAR((rendulic_pair(from_rendulic_pair(r)) - r).norm(), 0.0, kTight);
  for (int s = 1; s < 10; ++s) {
    const Eigen::Matrix3d q = random_symmetric(s), p = random_symmetric(s + 100);
    EXPECT_NEAR((from_mandel(to_mandel(q)) - q).norm(), 0.0, kTight);
    // Mandel vectors preserve the double contraction.
    EXPECT_NEAR(to_mandel(q).dot(to_mandel(p)), (q.array() * p.array()).sum(), kTight);
  }
}

TEST(Conventions, ProbeDirectionsAreEquallySpacedAndHoldTheSpecialDirections) {
  const Eigen::VectorXd d = probe_directions_deg(36);
  ASSERT_EQ(d.size(), 36);
  EXPECT_DOUBLE_EQ(d(0), kIsoCompressionDeg);
  EXPECT_NEAR(d(1) - d(0), 10.0, kTight);
  for (int i = 0; i < 36; ++i) {
    EXPECT_GE(d(i), 0.0);
    EXPECT_LT(d(i), 360.0);
  }
  for (int m : {4, 8, 24, 36}) {
    const Eigen::VectorXd dm = probe_directions_deg(m);
    for (double special :
         {kIsoCompressionDeg, kDevCompressionDeg, kIsoExtensionDeg, kDevExtensionDeg}) {
      double best = 360;
      for (int i = 0; i < m; ++i) best = std::min(best, std::abs(dm(i) - special));
      EXPECT_LT(best, 1e-9) << "M = " << m << " misses " << special;
    }
  }
}

}  // namespace
}  // namespace rendulic
