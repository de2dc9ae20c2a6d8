// Linear-response envelopes in other probe planes (docs/probes.md "Probe planes: true-triaxial
// probes"): in the deviatoric plane an isotropic stiffness gives a circle of radius 2G A (the
// FCC lattice's, radius (C11 - C12) A, is in probe_envelope_test.cpp); an anisotropic one gives
// the ellipse of the 6x6 stiffness restricted to the plane, computed here a second way (the 2x2
// Gram matrix B^T C B of the plane's Mandel basis B); the Rendulic plane stays bitwise today's
// envelope.
#include <gtest/gtest.h>

#include <cmath>

#include "rendulic/dem/probe_campaign.hpp"
#include "rendulic/dem/probe_envelope.hpp"

namespace rendulic::dem {
namespace {

// A linear response of a given stiffness (the envelope reads nothing else of it).
LinearResponse response_of(const Matrix6d& stiffness) {
  LinearResponse lr;
  lr.ok = true;
  lr.stiffness = stiffness;
  lr.fabric_stiffness = 1e-12 * stiffness;
  lr.fabric_volume_stiffness = Matrix6d::Zero();
  lr.fabric_rotation_stiffness = lr.fabric_stiffness;
  return lr;
}

// Isotropic elasticity in Mandel form: 3K on the isotropic projector, 2G on the deviatoric.
Matrix6d isotropic_stiffness(double bulk, double shear) {
  Vector6d i = Vector6d::Zero();
  i.head<3>().setConstant(1.0 / kSqrt3);
  const Matrix6d iso = i * i.transpose();
  return 3.0 * bulk * iso + 2.0 * shear * (Matrix6d::Identity() - iso);
}

TEST(ProbePlaneEnvelope, IsotropicStiffnessGivesACircleOfRadiusTwoGAInTheDeviatoricPlane) {
  const double bulk = 3e7, shear = 1.1e7, amp = 5e-5, k_star = 2e7;
  const ProbePlane plane = deviatoric_plane();
  const Envelope env = linear_response_envelope(response_of(isotropic_stiffness(bulk, shear)),
                                                probe_directions(36, plane), amp, k_star, plane);
  EXPECT_EQ(env.plane.name, "deviatoric");
  ASSERT_EQ(env.size(), 36u);
  const double radius = 2.0 * shear * amp;
  for (std::size_t i = 0; i < env.size(); ++i) {
    EXPECT_NEAR(env.d_stress[i].trace(), 0.0, 1e-9 * radius) << env.theta_deg[i];
    EXPECT_NEAR((env.stress[i] - 2.0 * shear * env.strain[i]).norm(), 0.0, 1e-9 * radius);
    EXPECT_NEAR(env.stress_star[i].norm() * k_star, radius, 1e-9 * radius);
    EXPECT_NEAR((env.strain_tensor(i) - plane_strain(plane, env.theta_deg[i], amp)).norm(), 0.0,
                1e-15 * amp);
  }
  const RendulicMap fit = fit_rendulic_map(env.strain, env.stress);
  EXPECT_NEAR(fit.semi_major, radius, 1e-9 * radius);
  EXPECT_NEAR(fit.semi_minor, radius, 1e-9 * radius);
  EXPECT_LT(fit.center.norm(), 1e-9 * radius);
  // The same stiffness in the Rendulic plane: semi-axes 3K A and 2G A (bulk and shear).
  const Envelope rendulic = linear_response_envelope(response_of(isotropic_stiffness(bulk, shear)),
                                                     probe_directions(36), amp, k_star);
  const RendulicMap r = fit_rendulic_map(rendulic.strain, rendulic.stress);
  EXPECT_NEAR(r.semi_major, 3.0 * bulk * amp, 1e-9 * radius);
  EXPECT_NEAR(r.semi_minor, radius, 1e-9 * radius);
}

TEST(ProbePlaneEnvelope, AnisotropicStiffnessGivesTheEllipseOfItsRestrictionToThePlane) {
  std::srand(3);
  Matrix6d a = Matrix6d::Random();
  const Matrix6d c = 1e7 * (a * a.transpose() + Matrix6d::Identity());  // SPD, anisotropic
  const double amp = 2e-5, k_star = 1e7;
  for (const char* name : {"rendulic", "deviatoric", "meridian_0", "meridian_40", "meridian_135"}) {
    const ProbePlane plane = *probe_plane_named(name);
    const Envelope env =
        linear_response_envelope(response_of(c), probe_directions(24, plane), amp, k_star, plane);
    // Second implementation: the plane's orthonormal Mandel basis B (6x2); a strain of pair
    // s is B s, its stress C B s, whose pair in the plane is B^T C B s.
    Eigen::Matrix<double, 6, 2> b = Eigen::Matrix<double, 6, 2>::Zero();
    b.col(0).head<3>() = plane.u;
    b.col(1).head<3>() = plane.v;
    const Eigen::Matrix2d map = b.transpose() * c * b;
    const Eigen::JacobiSVD<Eigen::Matrix2d> svd(map);
    const double major = amp * svd.singularValues()(0), minor = amp * svd.singularValues()(1);
    const RendulicMap fit = fit_rendulic_map(env.strain, env.stress);
    EXPECT_NEAR(fit.semi_major, major, 1e-9 * major) << name;
    EXPECT_NEAR(fit.semi_minor, minor, 1e-9 * major) << name;
    EXPECT_LE((plane_map_of(c, plane) - map).norm(), 1e-12 * map.norm()) << name;
    // The stress of every probe is C d_eps whole, its pair the projection on the plane.
    for (std::size_t i = 0; i < env.size(); ++i) {
      const Eigen::Matrix3d d_eps = plane_strain(plane, env.theta_deg[i], amp);
      EXPECT_LE((env.d_stress[i] - from_mandel(Vector6d(c * to_mandel(d_eps)))).norm(),
                1e-12 * major)
          << name;
      EXPECT_LE((env.stress[i] - map * env.strain[i]).norm(), 1e-9 * major) << name;
    }
  }
}

TEST(ProbePlaneEnvelope, RendulicPlaneEnvelopeIsBitwiseTheDefault) {
  std::srand(5);
  Matrix6d a = Matrix6d::Random();
  const LinearResponse lr = response_of(1e7 * (a * a.transpose() + Matrix6d::Identity()));
  const Envelope by_default = linear_response_envelope(lr, probe_directions(36), 5e-5, 1e7);
  const Envelope named = linear_response_envelope(
      lr, probe_directions(36, *probe_plane_named("rendulic")), 5e-5, 1e7, rendulic_plane());
  EXPECT_EQ(by_default.plane.name, "rendulic");
  ASSERT_EQ(by_default.size(), named.size());
  for (std::size_t i = 0; i < named.size(); ++i) {
    EXPECT_EQ(by_default.theta_deg[i], named.theta_deg[i]);
    EXPECT_EQ(by_default.strain[i], named.strain[i]);
    EXPECT_EQ(by_default.stress_star[i], named.stress_star[i]);
    // And the pairs are today's: Rendulic pairs of probe_strain and of the stress.
    EXPECT_EQ(named.strain[i], rendulic_pair(probe_strain(named.theta_deg[i], 5e-5)));
    EXPECT_EQ(named.stress[i], rendulic_pair(named.d_stress[i]));
    EXPECT_EQ(named.strain_tensor(i), from_rendulic_pair(named.strain[i]));
  }
  EXPECT_EQ(rendulic_map_of(lr.stiffness), plane_map_of(lr.stiffness, rendulic_plane()));
}

}  // namespace
}  // namespace rendulic::dem
