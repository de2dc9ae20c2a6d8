// Tests of the line fit, the shape criterion (parametric-bootstrap test of line against
// ellipse), the circle flag and the robust losses.
#include <gtest/gtest.h>

#include "rendulic/core/errors.hpp"
#include "rendulic/probes/envelope_fit.hpp"
#include "synthetic.hpp"

namespace rendulic {
namespace {

using test::angle_diff_deg;
using test::ellipse_envelope;
using test::line_envelope;
using test::TrueEllipse;

constexpr double kExact = 1e-8;  // noiseless fits converge to rounding

TEST(LineFit, ExactSegmentRecovered) {
  for (bool theta : {false, true}) {
    const Envelope env = line_envelope({0.4, -0.2}, 1.5, 35.26, 36, 0.0, 1, theta);
    const EnvelopeFit f = fit_line(env);
    ASSERT_EQ(f.shape, FitShape::kLine);
    EXPECT_NEAR(f.center.x(), 0.4, kExact);
    EXPECT_NEAR(f.center.y(), -0.2, kExact);
    // Without directions the half length comes from the extreme points, which for 36
    // directions with an offset of 0.1 rad do not sit exactly on the tips: cos(0.1 - ...)
    const double tol = theta ? kExact : 1.5 * (1.0 - std::cos(0.1));
    EXPECT_NEAR(f.a, 1.5, tol);
    EXPECT_EQ(f.b, 0.0);
    EXPECT_LT(angle_diff_deg(*f.inclination_deg, 35.26), 1e-9);
    EXPECT_LT(f.rms, kExact);
    EXPECT_EQ(f.used_theta, theta);
  }
}

TEST(ShapeSelection, ExactLineIsLine) {
  const EnvelopeFit f = fit_envelope(line_envelope({1.0, 1.0}, 2.0, 125.26, 36));
  EXPECT_EQ(f.shape, FitShape::kLine) << f.selection_note;
  EXPECT_LT(angle_diff_deg(*f.inclination_deg, 125.26), 1e-9);
}

TEST(ShapeSelection, ForcedEllipseOnLineDegeneratesToZeroMinorAxis) {
  FitOptions o;
  o.shape = FitShape::kEllipse;
  const EnvelopeFit f = fit_envelope(line_envelope({0.0, 0.5}, 1.0, 10.0, 36, 0.0, 1, true), o);
  EXPECT_EQ(f.shape, FitShape::kEllipse);
  EXPECT_NEAR(f.a, 1.0, kExact);
  EXPECT_NEAR(f.b, 0.0, kExact);
  EXPECT_LT(angle_diff_deg(*f.inclination_deg, 10.0), 1e-6);
}

TEST(ShapeSelection, NoisyLinesAreLines) {
  // The bootstrap test has size alpha = 1%: over 6 seeds x 2 (with / without directions) a
  // wrong "ellipse" would occur with probability ~ 11%; the seeds are fixed, so this is a
  // reproducible check that the naive F-test's failure (every noisy line an ellipse) is gone.
  int lines = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed)
    for (bool theta : {false, true}) {
      const EnvelopeFit f =
          fit_envelope(line_envelope({0.0, 0.0}, 1.0, 40.0, 36, 0.01, seed, theta));
      if (f.shape == FitShape::kLine) ++lines;
      EXPECT_TRUE(f.line_p_value.has_value());
    }
  EXPECT_GE(lines, 11);
}

TEST(ShapeSelection, ThinNoisyEllipseIsEllipse) {
  // b/a = 0.05 with noise sigma = b / 10: clearly an ellipse, with or without directions.
  TrueEllipse e{{0.0, 0.0}, 1.0, 0.05, 35.26};
  for (bool theta : {false, true}) {
    const EnvelopeFit f = fit_envelope(ellipse_envelope(e, 36, 0.005, 3, theta));
    EXPECT_EQ(f.shape, FitShape::kEllipse) << f.selection_note;
    EXPECT_NEAR(f.b, 0.05, 4.0 * f.b_stderr);
    ASSERT_TRUE(f.line_p_value.has_value());
    EXPECT_LT(*f.line_p_value, 0.01);
  }
}

TEST(ShapeSelection, ExactThinEllipseIsEllipse) {
  TrueEllipse e{{0.0, 0.0}, 1.0, 0.01, 20.0};
  const EnvelopeFit f = fit_envelope(ellipse_envelope(e, 36));
  EXPECT_EQ(f.shape, FitShape::kEllipse) << f.selection_note;
  EXPECT_NEAR(f.b, 0.01, kExact);
}

TEST(ShapeSelection, CircleHasNoInclination) {
  TrueEllipse e{{0.5, 0.5}, 1.0, 1.0, 0.0};
  // Exact circle: auto and forced ellipse both flag it.
  for (FitShape s : {FitShape::kAuto, FitShape::kEllipse}) {
    FitOptions o;
    o.shape = s;
    const EnvelopeFit f = fit_envelope(ellipse_envelope(e, 36), o);
    EXPECT_EQ(f.shape, FitShape::kCircle) << f.selection_note;
    EXPECT_FALSE(f.inclination_deg.has_value());
    EXPECT_FALSE(f.inclination_stderr_deg.has_value());
    EXPECT_NEAR(f.a, 1.0, kExact);
    EXPECT_NEAR(f.b, 1.0, kExact);
    EXPECT_LT((f.center - e.c).norm(), kExact);
  }
  // Noisy circle: axes differ by noise only, so it is still a circle, with errors. Without
  // directions the line is rejected by the bootstrap; 39 draws at alpha = 5% keep this unit
  // test fast (the default 199 draws at 1% are exercised in ThinNoisyEllipseIsEllipse).
  FitOptions quick;
  quick.bootstrap_samples = 39;
  quick.selection_alpha = 0.05;
  const EnvelopeFit f = fit_envelope(ellipse_envelope(e, 36, 0.01, 5), quick);
  EXPECT_EQ(f.shape, FitShape::kCircle) << f.selection_note;
  EXPECT_FALSE(f.inclination_deg.has_value());
  ASSERT_TRUE(f.has_stderr);
  EXPECT_NEAR(f.a, 1.0, 4.0 * f.a_stderr);
  // A clearly elongated noisy ellipse is not flagged.
  TrueEllipse el{{0.0, 0.0}, 1.0, 0.8, 50.0};
  EXPECT_EQ(fit_envelope(ellipse_envelope(el, 36, 0.01, 5), quick).shape, FitShape::kEllipse);
}

Envelope with_outliers(const TrueEllipse& e, bool theta) {
  Envelope env = ellipse_envelope(e, 36, 0.003, 17, theta);
  // Four gross outliers (100 sigma), all pushed outwards on one side: they bias a
  // least-squares fit in one direction instead of averaging out.
  for (int i : {2, 3, 4, 5}) env.response[static_cast<std::size_t>(i)] += Eigen::Vector2d(0.3, 0.3);
  return env;
}

TEST(RobustLoss, RobustBeatsLeastSquaresWithOutliers) {
  TrueEllipse e{{0.0, 0.0}, 1.0, 0.4, 30.0};
  for (bool theta : {false, true}) {
    FitOptions o;
    o.shape = FitShape::kEllipse;
    auto err = [&](const EnvelopeFit& f) {
      return std::max({(f.center - e.c).norm(), std::abs(f.a - e.a), std::abs(f.b - e.b)});
    };
    const EnvelopeFit plain = fit_envelope(with_outliers(e, theta), o);
    o.loss = FitLoss::kHuber;
    const EnvelopeFit huber = fit_envelope(with_outliers(e, theta), o);
    o.loss = FitLoss::kCauchy;
    const EnvelopeFit cauchy = fit_envelope(with_outliers(e, theta), o);
    SCOPED_TRACE(::testing::Message() << "theta " << theta);
    EXPECT_GT(err(plain), 0.02);    // least squares is pulled by the outliers
    EXPECT_LT(err(huber), 0.02);    // Huber's linear tails limit their pull
    EXPECT_LT(err(cauchy), 0.006);  // Cauchy ignores them: error of the order of the noise
    EXPECT_LT(err(cauchy), err(plain) / 5.0);
    EXPECT_GT(huber.loss_scale, 0.0);
    // The automatic scale follows the inliers' noise (0.003), not the outliers.
    EXPECT_LT(cauchy.loss_scale, 10.0 * 0.003);
  }
}

TEST(RobustLoss, RobustLineIgnoresOutliers) {
  Envelope env = line_envelope({0.0, 0.0}, 1.0, 20.0, 36, 0.002, 9, true);
  env.response[7] += Eigen::Vector2d(0.0, 1.0);
  env.response[8] += Eigen::Vector2d(0.0, 1.0);
  FitOptions o;
  o.shape = FitShape::kLine;
  const EnvelopeFit plain = fit_envelope(env, o);
  o.loss = FitLoss::kCauchy;
  const EnvelopeFit robust = fit_envelope(env, o);
  EXPECT_GT(angle_diff_deg(*plain.inclination_deg, 20.0), 1.0);
  EXPECT_LT(angle_diff_deg(*robust.inclination_deg, 20.0), 0.5);
  EXPECT_LT(robust.center.norm(), 0.01);
}

TEST(RobustLoss, NamesRoundTrip) {
  for (const char* s : {"none", "huber", "cauchy"})
    EXPECT_EQ(to_string(fit_loss_from_string(s)), s);
  for (const char* s : {"ellipse", "line", "circle", "auto"})
    EXPECT_EQ(to_string(fit_shape_from_string(s)), s);
  EXPECT_THROW(fit_loss_from_string("l2"), InputError);
  EXPECT_THROW(fit_shape_from_string("hyperbola"), InputError);
}

}  // namespace
}  // namespace rendulic
