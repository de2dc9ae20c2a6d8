// The linear response of frictional packings (linear_response.hpp, docs/probes.md "Linear
// response of a frictional packing"):
//  - closed form: a simple cubic lattice of equal spheres with sticking, unsheared contacts
//    (affine by symmetry, no rotation), where eq. 1 gives C_xxxx = k / L, C_yyxx = f_n / L^2
//    and a shear modulus 2 G = (k_t L - 2 f_n) / L^2 (the tangential spring minus the
//    pre-stress terms);
//  - independent method: on a frictional packing of 250 particles with rolling resistance
//    (mu_r = 0.1) at rest, the stress increment of the engine's own dynamic probes (affine
//    loading, relaxation) in four directions equals the linear response's, with the rolling
//    springs and couples in the Jacobian, and the response without them is clearly another one;
//    the same with the dynamic probes at t_c / 10 (probes.dt_factor = 0.1, as frictional.toml's
//    probes);
//  - contacts at the Coulomb limit: the lattice in simple shear, its springs at, below and beyond
//    mu f_n, counted as such;
//  - the stage's path: the campaign gives a frictional envelope with its Coulomb attributes,
//    and the minimisation probes still refuse the packing with one line.
// The same comparison without rolling resistance, on a packing with contacts at the Coulomb
// limit, is linear_response_friction_validate_test.cpp: that packing takes 1.78 million steps
// to come to rest at the seed's damping. The frictionless path is pinned by
// linear_response_test.cpp and linear_response_system_test.cpp, which this code path does not
// touch.
#include <gtest/gtest.h>

#include <iostream>

#include "frictional_probes.hpp"
#include "input_error.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/dem/linear_response.hpp"
#include "rendulic/dem/probe_campaign.hpp"
#include "rendulic/dem/protocols.hpp"

namespace rendulic::dem {
namespace {

using rendulic::testing::input_error;
using testing::check_at_a_tenth_of_the_contact_time;
using testing::frictional_packing;
using testing::probe_both;
using testing::Probed;

TEST(LinearResponseFriction, SimpleCubicLatticeClosedForm) {
  const int m = 3;  // 27 particles: the cell is wide enough for a unique minimum image
  const double r = 1e-3, delta = 1e-5, L = 2 * r - delta, k = 1e8, k_t = 2.0 / 7.0 * k;
  Eigen::MatrixX3d x(m * m * m, 3);
  int p = 0;
  for (int a = 0; a < m; ++a)
    for (int b = 0; b < m; ++b)
      for (int c = 0; c < m; ++c) x.row(p++) << a * L, b * L, c * L;
  const PackingData packing = PackingData::orthorhombic(x, Eigen::VectorXd::Constant(p, r),
                                                        Eigen::Vector3d::Constant(m * L));
  LinearResponseOptions lo;
  lo.k = k;
  lo.min_contacts = rattler_min_contacts(true);
  LinearFriction fr;
  fr.k_t = k_t;
  fr.mu = 0.5;
  const LinearResponse lr = linear_response(packing, lo, fr);
  ASSERT_TRUE(lr.ok) << lr.message;
  EXPECT_EQ(lr.n_rattlers, 0);
  EXPECT_EQ(lr.n_backbone_contacts, 3 * p);
  EXPECT_EQ(lr.n_coulomb_limit, 0);
  EXPECT_FALSE(lr.direction_dependent());
  const double f_n = k * delta;
  auto response = [&](int i, int j) {
    Eigen::Matrix3d e = Eigen::Matrix3d::Zero();
    e(i, j) = e(j, i) = 1.0;
    return lr.stress_increment(e);
  };
  const double tol = 1e-9 * k / L;
  const Eigen::Matrix3d normal = response(0, 0);
  EXPECT_NEAR(normal(0, 0), k / L, tol);
  EXPECT_NEAR(normal(1, 1), f_n / (L * L), tol);
  EXPECT_NEAR(normal(2, 2), f_n / (L * L), tol);
  EXPECT_NEAR(normal(0, 1), 0.0, tol);
  const Eigen::Matrix3d shear = response(0, 1);
  EXPECT_NEAR(shear(0, 1), (k_t * L - 2 * f_n) / (L * L), tol);
  EXPECT_NEAR(shear(0, 0), 0.0, tol);
  // No relaxation: the lattice deforms affinely.
  EXPECT_LE((lr.stiffness - lr.affine_stiffness).cwiseAbs().maxCoeff(), tol);
}

// Contacts at the Coulomb limit, which the default suite otherwise meets in no packing (the
// validation's has three): the lattice above in simple shear, every x contact's spring along y
// and every y contact's along x, which keeps each sphere's forces and torques balanced. At
// |k_t xi| = mu f_n those 2/3 of the contacts are counted at the limit and the response says it
// depends on the direction; at 0.99 mu f_n (outside the tolerance of 1e-3) none is; a spring
// beyond the limit is held at it, as the engine holds it (the reference stress, in closed form,
// says so).
TEST(LinearResponseFriction, ASimpleShearedLatticeAtTheCoulombLimitSaysSo) {
  const int m = 3;
  const double r = 1e-3, delta = 1e-5, L = 2 * r - delta, k = 1e8, k_t = 2.0 / 7.0 * k;
  const double mu = 0.5, f_n = k * delta;
  Eigen::MatrixX3d x(m * m * m, 3);
  auto index = [&](int a, int b, int c) { return (a * m + b) * m + c; };
  for (int a = 0; a < m; ++a)
    for (int b = 0; b < m; ++b)
      for (int c = 0; c < m; ++c) x.row(index(a, b, c)) << a * L, b * L, c * L;
  const int p = m * m * m;
  const PackingData packing = PackingData::orthorhombic(x, Eigen::VectorXd::Constant(p, r),
                                                        Eigen::Vector3d::Constant(m * L));
  LinearResponseOptions lo;
  lo.k = k;
  lo.min_contacts = rattler_min_contacts(true);
  for (const double of_limit : {1.0, 0.99, 1.5}) {
    LinearFriction fr;
    fr.k_t = k_t;
    fr.mu = mu;
    const double s = of_limit * mu * f_n / k_t;
    for (int a = 0; a < m; ++a)
      for (int b = 0; b < m; ++b)
        for (int c = 0; c < m; ++c) {
          const int i = index(a, b, c);
          // The +x and +y neighbours; the pair is stored from its lower index, which flips
          // the contact's direction and so the spring's sign.
          for (const auto& [j, along] :
               {std::pair{index((a + 1) % m, b, c), Eigen::Vector3d::UnitY().eval()},
                std::pair{index(a, (b + 1) % m, c), Eigen::Vector3d::UnitX().eval()}}) {
            const double sign = i < j ? 1.0 : -1.0;
            fr.springs.push_back({std::min(i, j), std::max(i, j), sign * s * along});
          }
        }
    const LinearResponse lr = linear_response(packing, lo, fr);
    ASSERT_TRUE(lr.ok) << of_limit << ": " << lr.message;
    EXPECT_EQ(lr.n_backbone_contacts, 3 * p);
    const int at_limit = of_limit >= 1.0 ? 2 * p : 0;
    EXPECT_EQ(lr.n_coulomb_limit, at_limit) << of_limit;
    EXPECT_NEAR(lr.coulomb_limit_fraction, at_limit / (3.0 * p), 1e-12) << of_limit;
    EXPECT_EQ(lr.direction_dependent(), at_limit > 0) << of_limit;
    EXPECT_TRUE(lr.stiffness.allFinite());
    // Closed form of the reference stress, eq. 1 over the cell's 3 p contacts of branch L:
    // f_n / L^2 on the diagonal, the held tangential force over L^2 in xy, symmetric.
    const double tol = 1e-9 * f_n / (L * L);
    EXPECT_NEAR(lr.stress(0, 0), f_n / (L * L), tol);
    EXPECT_NEAR(std::abs(lr.stress(0, 1)), std::min(of_limit, 1.0) * mu * f_n / (L * L), tol)
        << of_limit;
    EXPECT_NEAR(lr.stress(0, 1), lr.stress(1, 0), tol);
    EXPECT_NEAR(lr.stress(0, 2), 0.0, tol);
    EXPECT_LE(lr.residual_force_ratio, 1e-9);
  }
}

// With rolling resistance (docs/physics.md): the linear response against the engine's dynamic
// probes on a packing prepared and relaxed with mu_r = 0.1 (156 thousand steps to rest: the
// rolling springs damp the slow modes that keep the packing without them moving for 1.78
// million), and the response without the rolling springs is clearly another one; then the
// dynamic probes at t_c / 10 against the same linear response (measured 0.14 % and 0.50 %).
TEST(LinearResponseFriction, WithRollingResistanceMatchesTheEnginesDynamicProbesAtBothSteps) {
  const DemSystem state = frictional_packing(0.1);
  ASSERT_TRUE(state.material().rolling());
  int rolling_springs = 0;
  for (const Contact& c : state.contacts()) rolling_springs += c.rolling_spring.norm() > 0;
  ASSERT_GT(rolling_springs, 0);
  // 3e-6: the dynamic probes' own residue (the reference's creep and relaxation, not odd in
  // the direction) is a fixed stress, so the relative difference falls as the amplitude grows
  // while the response stays linear: measured 2.8 %, 1.6 %, 0.61 % at 3e-7, 1e-6, 3e-6 in the
  // direction 125.26 (0.67 %, 0.28 %, 0.26 % at 35.26); a missing linear term would not fall.
  const double amplitude = 3e-6;
  const Probed probed = probe_both(state, amplitude);
  const LinearResponse& lr = probed.lr;
  const std::vector<double>& theta = probed.theta;
  ASSERT_TRUE(lr.ok) << lr.message;
  EXPECT_EQ(probed.lin.attributes.at("n_rolling_limit"), lr.n_rolling_limit);
  // The rolling couples are in the reference's torque balance.
  EXPECT_LT(lr.residual_force_ratio, 1e-3);
  const Envelope& dyn = probed.dyn;
  ASSERT_EQ(dyn.d_stress.size(), theta.size());

  // The same packing's response without rolling springs (the tangential ones kept).
  LinearResponseOptions lo = probed.options.linear;
  lo.k = state.material().k;
  lo.min_contacts = rattler_min_contacts(true);
  LinearFriction sliding_only;
  sliding_only.k_t = state.material().tangential().k_t;
  sliding_only.mu = state.material().mu;
  for (const Contact& c : state.contacts())
    if (c.spring != Eigen::Vector3d::Zero()) sliding_only.springs.push_back({c.i, c.j, c.spring});
  const LinearResponse without = linear_response(geometry_of(state), lo, sliding_only);

  // Odd part of the dynamic response against the linear one, as in the test above; the same
  // stated tolerance.
  constexpr double kTol = 0.015;
  const std::size_t half = theta.size() / 2;
  double largest_rolling_effect = 0;
  for (std::size_t p = 0; p < half; ++p) {
    const Eigen::Matrix3d d_eps = probe_strain(theta[p], amplitude);
    const Eigen::Matrix3d expected = lr.stress_increment(d_eps);
    const double size = expected.norm();
    const double misfit = probed.misfit(p, amplitude, kTol);
    double effect = -1;
    if (without.ok) {
      effect = (without.stress_increment(d_eps) - expected).norm() / size;
      largest_rolling_effect = std::max(largest_rolling_effect, effect);
    }
    std::cout << "theta " << theta[p] << ": |dynamic - linear| / |linear| = " << misfit
              << "; without rolling springs " << effect << "\n";
  }
  // Without its rolling springs the linear response misses the dynamic one by more than the
  // tolerance in some direction (or has no elastic response at all).
  if (without.ok) {
    EXPECT_GT(largest_rolling_effect, 2 * kTol);
  }
  std::cout << lr.message << "; without rolling springs: " << without.message << "\n";
  SCOPED_TRACE("at t_c / 10");
  check_at_a_tenth_of_the_contact_time(state);
}

TEST(LinearResponseFriction, MinimisationStillRefusesAFrictionalPacking) {
  SystemOptions o;
  o.material.mu = 0.5;
  GasOptions g;
  g.n_particles = 250;
  g.volume_fraction = 0.3;
  const DemSystem s = make_gas(o, g, 3);
  // A frictional packing must not reach the energy minimisation.
  const std::string what = input_error([&] { (void)packing_of(s); });
  EXPECT_NE(what.find("dem.friction"), std::string::npos) << what;
  EXPECT_EQ(what.find("linear response"), std::string::npos) << what;
  EXPECT_EQ(what.find('\n'), std::string::npos) << what;
}

}  // namespace
}  // namespace rendulic::dem
