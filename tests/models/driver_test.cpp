// Unit tests of the material-point driver (docs/models.md "Material-point driver"):
// exactness on a linear law, orders of convergence of the explicit and modified Euler schemes,
// error control holding its tolerance where the explicit scheme does not (and says so), mixed
// control against a closed form and meeting its stress target, and failures reported as reasons.
#include "rendulic/models/driver.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "wu_limit.hpp"

namespace rendulic::models {
namespace {

// Hypoplastic sand at 100 kPa: the law whose stiffness changes fastest along a step (its
// stiffness is ~1000 P, so 1% strain changes the stress by order 10x).
MaterialState sand_state(const Law& law) {
  return law.make_state(1e5 * Eigen::Matrix3d::Identity(), Eigen::Matrix3d::Zero(), 0.6);
}
// A large mixed increment: 1% axial compression with lateral extension (drained-like shear).
Eigen::Matrix3d large_increment() { return Eigen::Vector3d(1e-2, -3e-3, -3e-3).asDiagonal(); }

MaterialState reference(const Law& law, const MaterialState& s, const Eigen::Matrix3d& de) {
  StepOptions o;
  // Global error about 0.3 x the local tolerance for these laws (measured), so 1e-10 is far
  // below every tolerance and every discretisation error tested.
  o.tolerance = 1e-10;
  o.max_substeps = 10000000;
  const StepResult r = integrate(law, s, de, o);
  EXPECT_TRUE(r.success) << r.reason;
  return r.end;
}

double rel_error(const MaterialState& a, const MaterialState& ref) {
  return (a.stress - ref.stress).norm() / ref.stress.norm();
}

// Fixed substeps are held to the substep cap as adaptive ones are: `envelope --scheme explicit
// --substeps 2000000000` ran for ever (36 probes of 2e9 substeps each).
TEST(Driver, FixedSubstepsBeyondTheCapAreInvalid) {
  StepOptions o;
  o.scheme = Scheme::kExplicitEuler;
  o.fixed_substeps = o.max_substeps;
  std::string why;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  o.fixed_substeps = o.max_substeps + 1;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "fixed_substeps (100001) must not exceed max_substeps (100000)");
  o.scheme = Scheme::kModifiedEuler;
  o.adaptive = false;
  EXPECT_FALSE(o.IsValid(&why));
  o.adaptive = true;  // adaptive modified Euler ignores fixed_substeps
  EXPECT_TRUE(o.IsValid(&why)) << why;
}

TEST(Driver, LinearLawIsExactInOneExplicitStep) {
  auto law = make_law("isotropic_elastic");
  const MaterialState s = law->make_state(Eigen::Matrix3d::Zero(), Eigen::Matrix3d::Zero(), 0.64);
  const Eigen::Matrix3d de = probe_strain(60.0, 1e-3);
  StepOptions o;
  o.scheme = Scheme::kExplicitEuler;
  const StepResult r = integrate(*law, s, de, o);
  ASSERT_TRUE(r.success);
  const double k = law->parameter("K"), g = law->parameter("G");
  const Eigen::Matrix3d expect =
      k * de.trace() * Eigen::Matrix3d::Identity() + 2 * g * deviator(de);
  EXPECT_LE((r.end.stress - expect).norm(), 1e-12 * expect.norm());
  EXPECT_EQ(r.error_estimate, 0.0);
  EXPECT_TRUE(r.within_tolerance);
  // Volume fraction follows the log volumetric strain.
  EXPECT_NEAR(r.end.volume_fraction, 0.64 * std::exp(de.trace()), 1e-15);
}

// Observed order from errors at n and 2n substeps in the asymptotic range.
double observed_order(const Law& law, const MaterialState& s, const Eigen::Matrix3d& de,
                      Scheme scheme, int n, const MaterialState& ref) {
  StepOptions o;
  o.scheme = scheme;
  o.adaptive = false;
  o.fixed_substeps = n;
  const double e1 = rel_error(integrate(law, s, de, o).end, ref);
  o.fixed_substeps = 2 * n;
  const double e2 = rel_error(integrate(law, s, de, o).end, ref);
  return std::log2(e1 / e2);
}

TEST(Driver, OrdersOfConvergenceAreOneAndTwo) {
  auto law = make_law("hypoplastic_wu");
  const MaterialState s = sand_state(*law);
  const Eigen::Matrix3d de = large_increment();
  const MaterialState ref = reference(*law, s, de);
  // 0.1 around the theoretical orders: at 256..512 substeps the next error term is ~1/n
  // relative to the leading one, well under 10%.
  EXPECT_NEAR(observed_order(*law, s, de, Scheme::kExplicitEuler, 256, ref), 1.0, 0.1);
  EXPECT_NEAR(observed_order(*law, s, de, Scheme::kModifiedEuler, 256, ref), 2.0, 0.1);
}

TEST(Driver, ErrorControlHoldsToleranceWhereExplicitFailsAndSaysSo) {
  auto law = make_law("hypoplastic_wu");
  const MaterialState s = sand_state(*law);
  const Eigen::Matrix3d de = large_increment();
  const MaterialState ref = reference(*law, s, de);
  for (double tol : {1e-4, 1e-6}) {
    StepOptions o;
    o.tolerance = tol;
    const StepResult r = integrate(*law, s, de, o);
    ASSERT_TRUE(r.success) << r.reason;
    EXPECT_TRUE(r.within_tolerance);
    EXPECT_LE(r.error_estimate, tol);
    EXPECT_GT(r.substeps, 1);
    // The local control bounds the global error by a small multiple of the tolerance
    // (Sloan 1987); we require the global relative stress error to stay below the tolerance.
    EXPECT_LE(rel_error(r.end, ref), tol) << "substeps " << r.substeps;
  }
  StepOptions o;
  o.scheme = Scheme::kExplicitEuler;
  o.tolerance = 1e-4;
  o.fixed_substeps = 8;
  const StepResult e = integrate(*law, s, de, o);
  ASSERT_TRUE(e.success) << e.reason;  // it returns a state, but flags it
  EXPECT_FALSE(e.within_tolerance);
  EXPECT_GT(e.error_estimate, o.tolerance);
  EXPECT_NE(e.reason.find("exceeds tolerance"), std::string::npos) << e.reason;
  EXPECT_GT(rel_error(e.end, ref), 100 * o.tolerance);  // and it is indeed far off
  // In one explicit step the sand even goes into lateral tension and out of its domain.
  o.fixed_substeps = 1;
  const StepResult one = integrate(*law, s, de, o);
  EXPECT_FALSE(one.success);
  EXPECT_NE(one.reason.find("tr(sigma)"), std::string::npos) << one.reason;
}

// The error control has no constant in Pa: hypoplastic_wu has no stress scale (degree 1 in
// sigma), so the same increment from a stress 8 times larger is the same integration, substep
// for substep and to the bit. At a fraction of a pascal, where the former floor of 1 Pa stood
// in for |sigma|, the two took different substeps.
TEST(Driver, TheSubstepsDoNotDependOnTheStressUnit) {
  auto law = make_law("hypoplastic_wu");
  const Eigen::Matrix3d de = large_increment();
  for (const Scheme scheme : {Scheme::kModifiedEuler, Scheme::kBogackiShampine}) {
    StepOptions o;
    o.scheme = scheme;
    const auto from = [&](double p) {
      return integrate(
          *law, law->make_state(p * Eigen::Matrix3d::Identity(), Eigen::Matrix3d::Zero(), 0.6), de,
          o);
    };
    const StepResult a = from(0.25), b = from(2.0);
    ASSERT_TRUE(a.success) << a.reason;
    ASSERT_TRUE(b.success) << b.reason;
    EXPECT_GT(a.substeps, 1);
    EXPECT_EQ(a.substeps, b.substeps);
    EXPECT_EQ(a.rejected, b.rejected);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) EXPECT_EQ(8.0 * a.end.stress(i, j), b.end.stress(i, j));
  }
}

TEST(Driver, ErrorControlAcrossTheElastoplasticKink) {
  auto law = make_law("elastoplastic_fabric");
  const MaterialState s =
      law->make_state(Eigen::Matrix3d::Identity() * 2e9, Eigen::Matrix3d::Identity() * 2.0, 0.82);
  // Constant-volume extension of 2e-3: elastic for about 1e-3 * P / 2G = 4e-4, then plastic.
  const Eigen::Matrix3d de = probe_strain(kDevExtensionDeg, 2e-3);
  const MaterialState ref = reference(*law, s, de);
  StepOptions o;
  o.tolerance = 1e-5;
  const StepResult r = integrate(*law, s, de, o);
  ASSERT_TRUE(r.success) << r.reason;
  EXPECT_LE(rel_error(r.end, ref), o.tolerance);
  // The error is measured against |sigma|, dominated by P; the deviatoric increment (what an
  // envelope shows) must be accurate too: 1e-3 of it (measured ~1e-6 at this tolerance).
  const double dsd_ref = signed_deviator(ref.stress) - signed_deviator(s.stress);
  EXPECT_LE(std::abs(signed_deviator(r.end.stress) - signed_deviator(ref.stress)),
            1e-3 * std::abs(dsd_ref));
  // The explicit single step ignores the yield surface entirely and says so.
  o.scheme = Scheme::kExplicitEuler;
  const StepResult e = integrate(*law, s, de, o);
  EXPECT_FALSE(e.within_tolerance);
  EXPECT_GT(rel_error(e.end, ref), o.tolerance);
}

// The third-order pair under the same control: the substeps grow as tol^(-1/3) (modified
// Euler's as tol^(-1/2): 1808 -> 57156 over these three decades, 31.6x), the global error stays
// near the tolerance (measured 1.3x; the solution kept is the third-order one), and on this
// smooth law it takes an eleventh of modified Euler's rate evaluations (316 against 3623 at
// 1e-6; docs/models.md "Tolerance").
TEST(Driver, BogackiShampineIsThirdOrderUnderControl) {
  auto law = make_law("hypoplastic_wu");
  const MaterialState s = sand_state(*law);
  const Eigen::Matrix3d de = large_increment();
  const MaterialState ref = reference(*law, s, de);
  StepOptions o;
  o.scheme = Scheme::kBogackiShampine;
  o.max_substeps = 10000000;
  int substeps[2], evaluations = 0;
  for (int k = 0; k < 2; ++k) {
    o.tolerance = k == 0 ? 1e-6 : 1e-9;
    const StepResult r = integrate(*law, s, de, o);
    ASSERT_TRUE(r.success) << r.reason;
    EXPECT_LE(r.error_estimate, o.tolerance);
    EXPECT_LE(rel_error(r.end, ref), 2.0 * o.tolerance) << "substeps " << r.substeps;
    substeps[k] = r.substeps;
    if (k == 0) evaluations = r.rate_evaluations;
  }
  const double growth = static_cast<double>(substeps[1]) / substeps[0];
  EXPECT_GT(growth, 7.0);
  EXPECT_LT(growth, 14.0);
  StepOptions heun;
  heun.tolerance = 1e-6;
  const StepResult h = integrate(*law, s, de, heun);
  ASSERT_TRUE(h.success) << h.reason;
  EXPECT_LT(5 * evaluations, h.rate_evaluations);
  // Across the elasto-plastic kink it holds its tolerance too (event location as modified
  // Euler's), on a probe ten times longer than the kink test's.
  auto ep = make_law("elastoplastic_fabric");
  const MaterialState e =
      ep->make_state(Eigen::Matrix3d::Identity() * 2e9, Eigen::Matrix3d::Identity() * 2.0, 0.82);
  const Eigen::Matrix3d dp = probe_strain(kDevExtensionDeg, 2e-2);
  const MaterialState eref = reference(*ep, e, dp);
  o.tolerance = 1e-5;
  const StepResult b = integrate(*ep, e, dp, o);
  ASSERT_TRUE(b.success) << b.reason;
  EXPECT_LE(rel_error(b.end, eref), o.tolerance);
  // It is adaptive only: fixed substeps are refused with a reason, not run as another scheme.
  o.adaptive = false;
  const StepResult f = integrate(*law, s, de, o);
  EXPECT_FALSE(f.success);
  EXPECT_NE(f.reason.find("adaptive only"), std::string::npos) << f.reason;
}

TEST(Driver, MixedControlUniaxialStressMatchesClosedForm) {
  auto law = make_law("isotropic_elastic");
  const MaterialState s =
      law->make_state(Eigen::Matrix3d::Identity() * 1e6, Eigen::Matrix3d::Zero(), 0.64);
  MixedControl c;
  c.stress_controlled = {false, true, true, true, true, true};
  c.strain_increment(0) = 1e-4;
  const MixedResult r = integrate_mixed(*law, s, c);
  ASSERT_TRUE(r.step.success) << r.step.reason;
  const double k = law->parameter("K"), g = law->parameter("G");
  const double young = 9 * k * g / (3 * k + g), poisson = (3 * k - 2 * g) / (2 * (3 * k + g));
  EXPECT_NEAR(r.strain_increment(1), -poisson * 1e-4, 1e-12 * 1e-4);
  EXPECT_NEAR(r.strain_increment(2), -poisson * 1e-4, 1e-12 * 1e-4);
  EXPECT_NEAR(r.step.end.stress(0, 0) - s.stress(0, 0), young * 1e-4, 1e-10 * young * 1e-4);
  EXPECT_NEAR(r.step.end.stress(1, 1), s.stress(1, 1), 1e-6);
}

TEST(Driver, MixedControlMeetsStressTargetOnHypoplasticDrainedTriaxial) {
  auto law = make_law("hypoplastic_wu");
  const MaterialState s = sand_state(*law);
  MixedControl c;
  c.stress_controlled = {false, true, true, true, true, true};
  c.strain_increment(0) = 2e-2;  // 2% axial compression at constant lateral stress
  MixedOptions o;
  o.load_steps = 20;
  const MixedResult r = integrate_mixed(*law, s, c, o);
  ASSERT_TRUE(r.step.success) << r.step.reason;
  // Target met to the Newton tolerance (1e-9 relative + 1e-6 Pa) of one load step: each aims
  // at the stress the increment has reached after it, so the 20 steps' residuals do not add up.
  const double tol = o.stress_tolerance_abs + o.stress_tolerance_rel * r.step.end.stress.norm();
  EXPECT_NEAR(r.step.end.stress(1, 1), 1e5, tol);
  EXPECT_NEAR(r.step.end.stress(2, 2), 1e5, tol);
  EXPECT_NEAR(r.step.end.stress(0, 1), 0.0, tol);
  EXPECT_GT(r.step.end.stress(0, 0), 2e5);  // sand strengthens in triaxial compression
  EXPECT_LE(r.stress_residual, o.stress_tolerance_abs + o.stress_tolerance_rel * 1e6);
  // Lateral expansion at the end (dilatancy of dense sand) or contraction: either way finite.
  EXPECT_TRUE(r.strain_increment.allFinite());
}

// Every stress component controlled: sigma_xx rises by `increment`, the others stay.
MixedControl axial_stress(double increment) {
  MixedControl c;
  c.stress_controlled = {true, true, true, true, true, true};
  c.stress_increment(0) = increment;
  return c;
}

// A stress-controlled load step too large for Newton is halved until it converges. The sand's
// drained triaxial to sigma_xx = 3e5 Pa (from 1e5) in one load step said "Newton did not
// converge in 50 iterations (residual 137 Pa)"; 20 load steps had to be asked for by hand.
TEST(Driver, MixedControlHalvesALoadStepThatNewtonCannotTake) {
  auto law = make_law("hypoplastic_wu");
  const MaterialState s = sand_state(*law);
  const MixedControl c = axial_stress(2e5);
  const MixedOptions o;  // one load step
  const MixedResult r = integrate_mixed(*law, s, c, o);
  ASSERT_TRUE(r.step.success) << r.step.reason;
  EXPECT_GT(r.load_step_cuts, 0);
  EXPECT_EQ(r.fraction_done, 1.0);
  // The last converged load step meets the running target to the Newton tolerance.
  const double tol = o.stress_tolerance_abs + o.stress_tolerance_rel * r.step.end.stress.norm();
  EXPECT_NEAR(r.step.end.stress(0, 0), 3e5, tol);
  EXPECT_NEAR(r.step.end.stress(1, 1), 1e5, tol);
  EXPECT_NEAR(r.step.end.stress(2, 2), 1e5, tol);
  EXPECT_GT(r.strain_increment(0), 0.0);  // compression positive
}

// Beyond the law's strength no strain gives the stress asked for. The result is the last state
// that met its target, with the strain and the fraction of the increment that led there;
// before, `end` was Newton's last unconverged iterate (3.73e5 Pa), with no fraction to say how
// far the path got. Where it stops is the law's limit surface, found by a second method.
TEST(Driver, MixedControlBeyondTheStrengthEndsAtTheLastConvergedState) {
  auto law = make_law("hypoplastic_wu");
  const MaterialState s = sand_state(*law);
  const MixedControl c = axial_stress(3e5);
  MixedOptions o;
  o.load_steps = 20;
  const MixedResult r = integrate_mixed(*law, s, c, o);
  ASSERT_FALSE(r.step.success);
  EXPECT_NE(r.step.reason.find("mixed control: a load step of"), std::string::npos)
      << r.step.reason;
  EXPECT_NE(r.step.reason.find("beyond the law's strength"), std::string::npos) << r.step.reason;
  EXPECT_GT(r.fraction_done, 0.8);
  EXPECT_LT(r.fraction_done, 1.0);
  const double tol = o.stress_tolerance_abs + o.stress_tolerance_rel * r.step.end.stress.norm();
  EXPECT_NEAR(r.step.end.stress(0, 0), 1e5 + r.fraction_done * 3e5, tol);
  EXPECT_NEAR(r.step.end.stress(1, 1), 1e5, tol);
  EXPECT_TRUE(r.strain_increment.allFinite());
  EXPECT_GT(r.strain_increment(0), 0.02);  // the peak lies at about 5 % axial strain
  // The drained triaxial peak is on the limit surface, sigma_xx = 366498.58 Pa (34.8 deg): the
  // path ends 0.46 Pa below it, one smallest load step (1.5e-6 of 3e5 Pa).
  const double peak = 1e5 * wu_limit_ratio(*law, 1e5);
  EXPECT_NEAR(r.step.end.stress(0, 0), peak, 1e-5 * peak);
}

TEST(Driver, FailuresAreReasonsNotExceptions) {
  auto law = make_law("hypoplastic_wu");
  MaterialState s = sand_state(*law);
  s.stress *= -1.0;  // tension: the law is undefined
  const StepResult r = integrate(*law, s, probe_strain(0.0, 1e-3));
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.reason.find("tr(sigma)"), std::string::npos) << r.reason;
  MaterialState nan_state = sand_state(*law);
  nan_state.fabric(0, 0) = std::nan("");
  const StepResult n = integrate(*law, nan_state, probe_strain(0.0, 1e-3));
  EXPECT_FALSE(n.success);
  EXPECT_NE(n.reason.find("non-finite"), std::string::npos) << n.reason;
  StepOptions bad;
  bad.tolerance = -1.0;
  const StepResult b = integrate(*law, sand_state(*law), probe_strain(0.0, 1e-3), bad);
  EXPECT_FALSE(b.success);
  EXPECT_NE(b.reason.find("tolerance"), std::string::npos);
  // Strong isotropic extension: the exact solution decays towards zero pressure (the law is
  // homogeneous in sigma), which error control follows; one explicit step overshoots into
  // tension, where the law is undefined: reported as a failure with its reason, not NaN.
  const Eigen::Matrix3d ext = probe_strain(kIsoExtensionDeg, 0.05);
  const StepResult t = integrate(*law, sand_state(*law), ext);
  ASSERT_TRUE(t.success) << t.reason;
  EXPECT_GT(t.end.stress.trace(), 0.0);
  StepOptions ex;
  ex.scheme = Scheme::kExplicitEuler;
  const StepResult e = integrate(*law, sand_state(*law), ext, ex);
  EXPECT_FALSE(e.success);
  EXPECT_NE(e.reason.find("left the law's domain"), std::string::npos) << e.reason;
}

// The fabric law ends at P = 0 and its elastic part keeps its stiffness there (3.7e10 Pa at the
// defaults), so isotropic extension by 1e-3 from 1e5 Pa unloads it to zero pressure after 3e-6.
// The substeps shrink towards that point as the stress vanishes; the failure says so and names
// the law's domain, where it said "law too stiff or undefined". The stiff but well-scaled failure
// keeps that wording.
TEST(Driver, AnIncrementThatUnloadsTheLawToZeroStressNamesItsDomain) {
  auto law = make_law("elastoplastic_fabric");
  const MaterialState s =
      law->make_state(1e5 * Eigen::Matrix3d::Identity(), Eigen::Matrix3d::Identity() / 3.0, 0.64);
  for (const Scheme scheme : {Scheme::kModifiedEuler, Scheme::kBogackiShampine}) {
    StepOptions o;
    o.scheme = scheme;
    const StepResult r = integrate(*law, s, probe_strain(kIsoExtensionDeg, 1e-3), o);
    EXPECT_FALSE(r.success);
    EXPECT_FALSE(r.on_substep_limit);
    EXPECT_NE(r.reason.find("substep below 1e-10 of the increment at fraction 0.00"),
              std::string::npos)
        << r.reason;
    EXPECT_NE(r.reason.find(", where the stress has fallen to "), std::string::npos) << r.reason;
    EXPECT_NE(r.reason.find("leaves the law's domain: elastoplastic_fabric needs P > 0"),
              std::string::npos)
        << r.reason;
    EXPECT_GT(r.end.stress.trace(), 0.0);
    EXPECT_LT(r.end.stress.norm(), 1e-3 * s.stress.norm());
  }
  StepOptions stiff;
  stiff.min_fraction = 0.5;  // the first rejection drops below it, far from zero stress
  auto sand = make_law("hypoplastic_wu");
  const StepResult w = integrate(*sand, sand_state(*sand), large_increment(), stiff);
  EXPECT_FALSE(w.success);
  EXPECT_NE(w.reason.find("(law too stiff or undefined)"), std::string::npos) << w.reason;
}

// The cap on substeps is the one failure a larger cap cures, so it carries its own flag (the
// calibration counts it apart); a substep below min_fraction or a state outside the law's
// domain does not set it. The reason names the scheme that ran.
TEST(Driver, TheSubstepCapIsFlaggedApartFromOtherFailures) {
  auto law = make_law("hypoplastic_wu");
  StepOptions o;
  o.tolerance = 1e-10;
  o.max_substeps = 5;
  for (const Scheme scheme : {Scheme::kModifiedEuler, Scheme::kBogackiShampine}) {
    o.scheme = scheme;
    const StepResult r = integrate(*law, sand_state(*law), large_increment(), o);
    EXPECT_FALSE(r.success);
    EXPECT_TRUE(r.on_substep_limit) << r.reason;
    EXPECT_EQ(r.attempted(), 5);
    const char* name = scheme == Scheme::kModifiedEuler ? "modified Euler" : "Bogacki-Shampine";
    EXPECT_EQ(r.reason.rfind(std::string(name) + ": more than 5 substeps", 0), 0u) << r.reason;
  }
  o.max_substeps = 10000000;
  o.min_fraction = 0.5;  // the first rejection drops below it
  o.scheme = Scheme::kModifiedEuler;
  const StepResult m = integrate(*law, sand_state(*law), large_increment(), o);
  EXPECT_FALSE(m.success);
  EXPECT_FALSE(m.on_substep_limit);
  EXPECT_NE(m.reason.find("substep below"), std::string::npos) << m.reason;
  MaterialState s = sand_state(*law);
  s.stress *= -1.0;
  const StepResult t = integrate(*law, s, probe_strain(0.0, 1e-3));
  EXPECT_FALSE(t.success);
  EXPECT_FALSE(t.on_substep_limit);
  o = StepOptions{};
  const StepResult ok = integrate(*law, sand_state(*law), large_increment(), o);
  ASSERT_TRUE(ok.success) << ok.reason;
  EXPECT_FALSE(ok.on_substep_limit);
  EXPECT_LT(ok.attempted(), o.max_substeps);
}

}  // namespace
}  // namespace rendulic::models
