// Tests of the line fit, the shape criterion (parametric-bootstrap test of line against
// ellipse, the guard against runaway ellipses), the circle flag and the robust losses.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "input_error.hpp"
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

// Too few points to choose: the hint to fit a line only where a line can be fitted.
TEST(ShapeSelection, TooFewPointsToChooseSayWhatCanBeFitted) {
  Envelope env;
  for (const int n : {0, 1, 2, 4}) {
    env.response.resize(static_cast<std::size_t>(n), Eigen::Vector2d(0.0, 0.0));
    for (int i = 0; i < n; ++i) env.response[static_cast<std::size_t>(i)] = {i, 2.0 * i};
    const std::string said = testing::input_error([&] { fit_envelope(env); });
    EXPECT_EQ(said, "fit: choosing between ellipse and line needs at least 5 points, got " +
                        std::to_string(n) + (n >= 2 ? " (use --shape line)" : ""));
    if (n >= 2) {
      FitOptions line;
      line.shape = FitShape::kLine;
      EXPECT_EQ(fit_envelope(env, line).shape, FitShape::kLine) << n;
    }
  }
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

// Collinear points without directions: every segment that covers them fits exactly, so no
// ellipse is determined, and no circle passes through them. The ellipse fit used to stall at
// its principal-axes start and report a segment shorter than the points (a = 2.66 for a
// half-length of 3, rms 0.14) as converged; the circle fit a circle of radius 1.6 about the
// segment's midpoint. Both are refused now, naming the way out; the automatic choice, and an
// ellipse with the directions, still give the segment.
TEST(ShapeSelection, CollinearPointsHaveNoEllipseWithoutDirectionsAndNoCircle) {
  Envelope even;  // evenly spaced along the segment, as no envelope of directions is
  for (int k = 0; k < 12; ++k) {
    const double s = -3.0 + 6.0 * k / 11.0;
    even.response.emplace_back(1.0 + s * std::cos(0.6), 2.0 + s * std::sin(0.6));
  }
  for (const FitLoss loss : {FitLoss::kNone, FitLoss::kHuber, FitLoss::kCauchy}) {
    SCOPED_TRACE(to_string(loss));
    FitOptions o;
    o.loss = loss;
    o.shape = FitShape::kEllipse;
    EXPECT_EQ(testing::input_error([&] { fit_envelope(even, o); }),
              "fit: the 12 points are collinear to rounding: without the probe directions "
              "(theta_deg) no ellipse through them is determined; fit a line (shape line or "
              "auto)");
    o.shape = FitShape::kCircle;
    EXPECT_EQ(testing::input_error([&] { fit_envelope(even, o); }),
              "fit: the 12 points are collinear to rounding: a circle through them would have "
              "an infinite radius; fit a line (shape line or auto)");
    o.shape = FitShape::kAuto;
    const EnvelopeFit line = fit_envelope(even, o);
    EXPECT_EQ(line.shape, FitShape::kLine);
    EXPECT_NEAR(line.a, 3.0, kExact);
  }
  // Directions given but ignored are no directions.
  FitOptions ignore;
  ignore.shape = FitShape::kEllipse;
  ignore.use_theta = false;
  EXPECT_THROW(fit_envelope(line_envelope({0.0, 0.5}, 1.0, 10.0, 36, 0.0, 1, true), ignore),
               InputError);
  // Points a size-relative 1e-8 off the line are no longer collinear to rounding: an ellipse
  // is fitted, a thin one through all of them (before, the same stall reported rms 0.14 at
  // 1e-9), and the latent-angle method finds the same distances.
  Envelope off = even;
  for (std::size_t i = 0; i < off.size(); ++i)
    off.response[i] += (i % 2 ? 1.0 : -1.0) * 1e-8 * Eigen::Vector2d(-std::sin(0.6), std::cos(0.6));
  FitOptions o;
  o.shape = FitShape::kEllipse;
  const EnvelopeFit f = fit_envelope(off, o);
  ASSERT_EQ(f.shape, FitShape::kEllipse);
  EXPECT_GE(f.a, 3.0 - 1e-7);
  EXPECT_LT(f.rms, 1.1e-8);
  o.method = FitMethod::kLatentAngles;
  EXPECT_LT(fit_envelope(off, o).rms, 1.1e-8);
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

// A nearly straight cloud whose residuals the F-test finds structured (p ~ 5e-4): the fabric
// of a dynamic probe campaign at |d eps| = 0.02 (quick.toml, state d). The orthogonal-distance
// ellipse (here a circle) runs away to a radius ~30 times the cloud's; the selection keeps
// the line, which is exactly the line fit's, and says why. The ellipses of the tests above
// (a / rms radius = sqrt(2)) are untouched by this guard.
TEST(ShapeSelection, RunawayEllipseOfANearlyStraightCloudIsALine) {
  const double pts[][3] = {{35.264389682754654, 0.32878491893728884, 0.24097234068051554},
                           {50.264389682754654, 0.31703256893885806, 0.23511725720677346},
                           {65.264389682754654, 0.29743640412130418, 0.22511250414783213},
                           {80.264389682754654, 0.24522097390171835, 0.17840615340066934},
                           {95.264389682754654, 0.1723074109514415, 0.12094163973717631},
                           {110.26438968275465, 0.098254822887818505, 0.063704413064214371},
                           {125.26438968275465, 0.014842224958288323, -0.00043630146798534497},
                           {140.26438968275465, -0.064030144838973568, -0.029088124462119058},
                           {155.26438968275465, -0.1324732189546044, -0.099611882947523434},
                           {170.26438968275465, -0.21047175776914373, -0.15135023991895702},
                           {185.26438968275465, -0.25452737163255262, -0.18031503155220818},
                           {200.26438968275465, -0.299623119334955, -0.22237652087080706},
                           {215.26438968275465, -0.30319401805492513, -0.22645836293033872},
                           {230.26438968275465, -0.30346319352814566, -0.24985261014021098},
                           {245.26438968275465, -0.2855207255829984, -0.21484971232812944},
                           {260.26438968275465, -0.20591994708337813, -0.16938675061928299},
                           {275.26438968275465, -0.14713563712308037, -0.1384882159009142},
                           {290.26438968275465, -0.070909209753807434, -0.080508798802468196},
                           {305.26438968275465, 0.035051920031211624, -0.024234348644282644},
                           {320.26438968275465, 0.072632246761729205, 0.026585667936943391},
                           {335.26438968275465, 0.14182139413694841, 0.089874064985250524},
                           {350.26438968275465, 0.2206042940354252, 0.15089257022769065},
                           {5.2643896827546541, 0.26435497998635982, 0.17672742477861769},
                           {20.264389682754654, 0.31345937637351384, 0.22427704113319802}};
  Envelope env;
  for (const auto& p : pts) {
    env.theta_deg.push_back(p[0]);
    env.response.emplace_back(p[1], p[2]);
  }
  env.amplitude = 0.02;
  FitOptions forced;
  forced.shape = FitShape::kEllipse;
  const EnvelopeFit ell = fit_envelope(env, forced);
  double rms = 0.0;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : env.response) mean += p / static_cast<double>(env.size());
  for (const auto& p : env.response)
    rms += (p - mean).squaredNorm() / static_cast<double>(env.size());
  rms = std::sqrt(rms);
  ASSERT_GT(ell.a, 4.0 * rms) << "the forced ellipse no longer runs away: " << ell.a / rms;
  const EnvelopeFit f = fit_envelope(env);
  EXPECT_EQ(f.shape, FitShape::kLine) << f.selection_note;
  ASSERT_TRUE(f.line_p_value.has_value());
  EXPECT_LT(*f.line_p_value, 0.01);
  EXPECT_NE(f.selection_note.find("runs away"), std::string::npos) << f.selection_note;
  FitOptions line;
  line.shape = FitShape::kLine;
  const EnvelopeFit l = fit_envelope(env, line);
  EXPECT_LT((f.center - l.center).norm(), kExact);
  EXPECT_NEAR(f.a, l.a, kExact);
  ASSERT_TRUE(f.inclination_deg && l.inclination_deg);
  EXPECT_NEAR(*f.inclination_deg, *l.inclination_deg, kExact);
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
