// Tests of the envelope features against closed forms: the stiffness of a
// linear law recovered by the affine fit and by the ellipse's axes (two independent routes
// to the singular values of D), centre shift, and the elastic/plastic comparison.
#include "rendulic/probes/features.hpp"

#include <gtest/gtest.h>

#include "rendulic/core/conventions.hpp"
#include "rendulic/core/errors.hpp"
#include "synthetic.hpp"

namespace rendulic {
namespace {

// Linear law plus shift: R = c + D e, e = amp (cos theta, sin theta).
Envelope linear_envelope(const Eigen::Matrix2d& D, const Eigen::Vector2d& c, double amp, int m,
                         double sigma = 0.0, std::uint64_t seed = 1) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Envelope env;
  env.amplitude = amp;
  for (int k = 0; k < m; ++k) {
    const double th = 360.0 * k / m;
    env.theta_deg.push_back(th);
    const Eigen::Vector2d e =
        amp * Eigen::Vector2d(std::cos(deg_to_rad(th)), std::sin(deg_to_rad(th)));
    env.response.push_back(c + D * e + sigma * Eigen::Vector2d(normal(rng), normal(rng)));
  }
  return env;
}

TEST(Features, RendulicStiffnessOfLinearLaw) {
  // A bulk-like major axis near the isotropic direction and a small shear stiffness: the
  // thin elastic ellipse of a frictionless packing.
  const Eigen::Matrix2d R = rendulic_to_iso_dev().transpose();
  const Eigen::Matrix2d D = R * Eigen::Vector2d(30.0, 0.6).asDiagonal() * R.transpose();
  const Eigen::Vector2d c(2e-6, -1e-6);
  const double amp = 5e-5;
  const Envelope env = linear_envelope(D, c, amp, 36);
  const RendulicStiffness k = fit_rendulic_stiffness(env);
  // Exact data: linear least squares to rounding of D's size.
  EXPECT_LT((k.D - D).norm(), 1e-9 * D.norm());
  EXPECT_LT((k.center - c).norm(), 1e-12);
  EXPECT_LT(k.asymmetry, 1e-9);
  EXPECT_LT(k.rms, 1e-12);

  // Independent route: the geometric ellipse fit of the same points, axes / amplitude.
  FitOptions o;
  o.shape = FitShape::kEllipse;
  const EnvelopeFit f = fit_envelope(env, o);
  const EnvelopeFeatures ft = envelope_features(f, amp);
  EXPECT_NEAR(ft.stiffness_major, 30.0, 1e-7 * 30.0);
  EXPECT_NEAR(ft.stiffness_minor, 0.6, 1e-7 * 30.0);
  EXPECT_NEAR(ft.aspect_ratio, 0.02, 1e-8);
  // The major axis lies along the isotropic direction, 35.26 deg.
  EXPECT_LT(test::angle_diff_deg(*ft.inclination_deg, kIsoCompressionDeg), 1e-6);
  EXPECT_NEAR(ft.center_shift, c.norm(), 1e-12);
  EXPECT_NEAR(ft.center_shift_relative, c.norm() / f.a, 1e-9);
}

TEST(Features, StiffnessErrorsAndAsymmetry) {
  Eigen::Matrix2d D;
  D << 10.0, 2.0, 2.0, 3.0;
  const Envelope env = linear_envelope(D, Eigen::Vector2d::Zero(), 1e-3, 36, 1e-5, 4);
  const RendulicStiffness k = fit_rendulic_stiffness(env);
  // Noise 1e-5 on responses with strains 1e-3: errors of D about 1e-2 / sqrt(18); within 4.
  EXPECT_LT(std::abs(k.D(0, 0) - 10.0), 4.0 * k.D_stderr(0));
  EXPECT_LT(std::abs(k.D(0, 1) - 2.0), 4.0 * k.D_stderr(1));
  EXPECT_LT(std::abs(k.D(1, 1) - 3.0), 4.0 * k.D_stderr(2));
  EXPECT_GT(k.D_stderr(0), 0.0);
  EXPECT_LT(k.asymmetry, 0.01);
  // A rotation-like (antisymmetric) part is measured, not hidden.
  Eigen::Matrix2d W;
  W << 10.0, 3.0, -3.0, 3.0;
  EXPECT_NEAR(
      fit_rendulic_stiffness(linear_envelope(W, Eigen::Vector2d::Zero(), 1e-3, 36)).asymmetry,
      (W - W.transpose()).norm() / (2.0 * W.norm()), 1e-9);
}

TEST(Features, StiffnessNeedsStrainPoints) {
  Envelope env = linear_envelope(Eigen::Matrix2d::Identity(), Eigen::Vector2d::Zero(), 1e-3, 8);
  env.amplitude = 0.0;  // theta without amplitude: no strain points
  EXPECT_THROW(fit_rendulic_stiffness(env), InputError);
  env.theta_deg.clear();
  env.amplitude = 1e-3;
  EXPECT_THROW(fit_rendulic_stiffness(env), InputError);
  EnvelopeFit f;
  f.a = 1.0;
  EXPECT_THROW(envelope_features(f, 0.0), InputError);
}

TEST(Features, ElasticPlasticComparisonClosedForm) {
  EnvelopeFit el, pl;
  el.center = {0.0, 0.0};
  el.a = 30.0 * 5e-5, el.b = 0.6 * 5e-5, el.inclination_deg = 35.0;
  pl.center = {-1e-3, 2e-3};
  pl.a = 20.0 * 2e-3, pl.b = 0.1 * 2e-3, pl.inclination_deg = 178.0;
  for (EnvelopeFit* f : {&el, &pl}) {
    f->has_stderr = true;
    f->a_stderr = 0.01 * f->a, f->b_stderr = 0.02 * f->b;
    f->inclination_stderr_deg = 0.5;
    f->covariance.diagonal() << 1e-12, 1e-12, f->a_stderr * f->a_stderr, f->b_stderr * f->b_stderr,
        deg_to_rad(0.5) * deg_to_rad(0.5);
  }
  const ElasticPlasticComparison c = compare_elastic_plastic(el, 5e-5, pl, 2e-3);
  EXPECT_NEAR(c.shift.x(), -0.5, 1e-12);
  EXPECT_NEAR(c.shift.y(), 1.0, 1e-12);
  EXPECT_NEAR(c.shift_norm, std::sqrt(1.25), 1e-12);
  EXPECT_NEAR(c.shift_relative, std::sqrt(1.25) / 20.0, 1e-12);
  EXPECT_NEAR(c.major_ratio, 20.0 / 30.0, 1e-12);
  ASSERT_TRUE(c.minor_ratio && c.thinning && c.rotation_deg);
  EXPECT_NEAR(*c.minor_ratio, 0.1 / 0.6, 1e-12);
  EXPECT_NEAR(*c.thinning, (0.1 / 20.0) / (0.6 / 30.0), 1e-12);
  // 178 deg and 35 deg are axes: the rotation is -37 deg, not +143.
  EXPECT_NEAR(*c.rotation_deg, -37.0, 1e-12);
  EXPECT_NEAR(*c.rotation_stderr_deg, std::hypot(0.5, 0.5), 1e-12);
  // Relative errors of independent ratios add in quadrature.
  EXPECT_NEAR(c.major_ratio_stderr, c.major_ratio * std::hypot(0.01, 0.01), 1e-12);
  // Against a line (the steady state) the thinning is defined and zero; against a circle
  // there is no rotation.
  EnvelopeFit line = pl;
  line.b = 0.0;
  EXPECT_NEAR(*compare_elastic_plastic(el, 5e-5, line, 2e-3).thinning, 0.0, 1e-15);
  EnvelopeFit circle = el;
  circle.inclination_deg.reset();
  EXPECT_FALSE(compare_elastic_plastic(circle, 5e-5, pl, 2e-3).rotation_deg.has_value());
}

}  // namespace
}  // namespace rendulic
