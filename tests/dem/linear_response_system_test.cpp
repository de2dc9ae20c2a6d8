// Finite-difference check of the linear response by an independent method:
// a jammed random packing (generated and minimised here, no DEM engine), six strain
// components applied affinely with both signs, each followed by FIRE energy minimisation at
// fixed cell; the central difference of the measured stress and fabric must equal C d_eps and
// G d_eps. This covers the Born term, the geometric term of the Hessian, the pre-stress terms
// and the non-affine relaxation at once, for normal and shear components.
#include <gtest/gtest.h>

#include "rendulic/dem/linear_response.hpp"
#include "rendulic/dem/probe_minimise.hpp"

namespace rendulic::dem {
namespace {

TEST(LinearResponseSystem, MatchesFiniteDifferencesOfMinimisedPackings) {
  GeneratedPackingOptions g;
  g.n = 250;
  g.volume_fraction = 0.70;
  g.seed = 11;
  // Minimisation error in the strain response is ~ tolerance * (mean overlap / r) / h relative
  // (a residual force f_res displaces particles by f_res / k): 1e-11 * 0.02 / 1e-6 ~ 2e-7.
  g.minimise.force_tolerance = 1e-11;
  MinimiseSummary s;
  const PackingData ref = generate_packing(g, &s);
  ASSERT_TRUE(s.converged) << s.message;
  const LinearResponse lr = linear_response(ref, LinearResponseOptions{});
  ASSERT_TRUE(lr.ok) << lr.message;
  ASSERT_GT(lr.n_rattlers, 0);  // the rattler path is exercised

  const double h = 1e-6;  // strain step; central differences make the O(h) error O(h^2)
  const StressFabric base = measure_stress_fabric(ref, g.minimise.k, &lr.backbone);
  Matrix6d c_fd, g_fd;
  for (int a = 0; a < 6; ++a) {
    Vector6d e = Vector6d::Zero();
    e(a) = h;
    StressFabric sf[2];
    for (int sign = 0; sign < 2; ++sign) {
      PackingData p = ref;
      apply_affine_strain(p, from_mandel(sign == 0 ? e : Vector6d(-e)));
      const MinimiseSummary m = minimise_energy(p, g.minimise);
      ASSERT_TRUE(m.converged) << m.message;
      sf[sign] = measure_stress_fabric(p, g.minimise.k, &lr.backbone);
      // The linear response assumes that no contact of the backbone opens or closes.
      ASSERT_EQ(sf[sign].contacts, base.contacts) << "component " << a;
    }
    c_fd.col(a) = to_mandel(sf[0].stress - sf[1].stress) / (2 * h);
    g_fd.col(a) = to_mandel(sf[0].fabric - sf[1].fabric) / (2 * h);
  }
  // Stated tolerance: 1e-6 of the largest modulus (the error budget above is ~2e-7; measured
  // 7e-8 for this packing on x86-64, Release).
  constexpr double kTol = 1e-6;
  const double c_scale = lr.stiffness.cwiseAbs().maxCoeff();
  const double g_scale = lr.fabric_stiffness.cwiseAbs().maxCoeff();
  EXPECT_LE((c_fd - lr.stiffness).cwiseAbs().maxCoeff(), kTol * c_scale)
      << "finite differences\n"
      << c_fd << "\nlinear response\n"
      << lr.stiffness;
  EXPECT_LE((g_fd - lr.fabric_stiffness).cwiseAbs().maxCoeff(), kTol * g_scale)
      << "finite differences\n"
      << g_fd << "\nlinear response\n"
      << lr.fabric_stiffness;
  // The affine stiffness alone is far off: the comparison resolves the relaxation.
  EXPECT_GT((c_fd - lr.affine_stiffness).cwiseAbs().maxCoeff(), 100 * kTol * c_scale);
  // And the reference stress is the same measure.
  EXPECT_LE((base.stress - lr.stress).cwiseAbs().maxCoeff(), 1e-12 * lr.stress.norm());
}

}  // namespace
}  // namespace rendulic::dem
