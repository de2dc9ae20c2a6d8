// Cost and scale of the envelope fits (docs/fitting.md "Accuracy and cost"): the work of a
// fit, counted in point operations (EnvelopeFit::point_operations), grows linearly with the
// number of points, and a fit of data near 1e300, or up to the largest double, is the fit of the
// same data near 1 scaled; a fit whose numbers would exceed the largest double is refused, and
// so are points whose sizes span more than the fit can resolve.
// The distinctness check of the ellipse fit once compared every point with every other:
// 200,000 points took 51 s against 0.6 s for 20,000.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "input_error.hpp"
#include "rendulic/probes/envelope_fit.hpp"
#include "synthetic.hpp"

namespace rendulic {
namespace {

TEST(FitScaling, WorkGrowsLinearlyWithThePoints) {
  test::TrueEllipse e;
  e.c = {3.0, 1.0}, e.a = 2.0, e.b = 1.0, e.phi_deg = 17.0;
  FitOptions opts;  // auto: the F-test on the directions, then one ellipse fit
  const EnvelopeFit small = fit_envelope(test::ellipse_envelope(e, 20000, 0.01, 1, true), opts);
  const EnvelopeFit large = fit_envelope(test::ellipse_envelope(e, 200000, 0.01, 1, true), opts);
  ASSERT_EQ(large.shape, FitShape::kEllipse);
  EXPECT_NEAR(large.a, 2.0, 1e-3);
  const double per_point_small = static_cast<double>(small.point_operations) / 20000;
  const double per_point_large = static_cast<double>(large.point_operations) / 200000;
  // Quadratic work would make the ratio 10; a few more solver iterations is all that varies.
  EXPECT_LT(per_point_large, 1.5 * per_point_small)
      << small.point_operations << " operations for 20000 points, " << large.point_operations
      << " for 200000";
  EXPECT_LT(per_point_large, 1000.0);
  // Every shape counts its work, the line too.
  FitOptions line = opts;
  line.shape = FitShape::kLine;
  const EnvelopeFit l = fit_envelope(test::ellipse_envelope(e, 200000, 0.01, 1, true), line);
  EXPECT_GT(l.point_operations, 200000);
  EXPECT_LT(l.point_operations, 10 * 200000);
}

TEST(FitScaling, DataNear1e300FitAsTheSameDataNear1) {
  // Sums of squares overflowed: every point normalised to 0, "fewer than 2 distinct points".
  test::TrueEllipse e;
  e.c = {3.0, 1.0}, e.a = 2.0, e.b = 1.0, e.phi_deg = 17.0;
  for (const bool theta : {true, false}) {
    for (const FitShape shape : {FitShape::kAuto, FitShape::kEllipse, FitShape::kLine}) {
      const Envelope unit = test::ellipse_envelope(e, 36, 0.01, 3, theta);
      Envelope huge = unit;
      for (auto& p : huge.response) p *= 1e300;
      FitOptions opts;
      opts.shape = shape;
      const EnvelopeFit a = fit_envelope(unit, opts), b = fit_envelope(huge, opts);
      ASSERT_EQ(a.shape, b.shape);
      EXPECT_NEAR(b.center.x() / 1e300, a.center.x(), 1e-9);
      EXPECT_NEAR(b.center.y() / 1e300, a.center.y(), 1e-9);
      EXPECT_NEAR(b.a / 1e300, a.a, 1e-9);
      EXPECT_NEAR(b.rms / 1e300, a.rms, 1e-9);
      ASSERT_EQ(a.has_stderr, b.has_stderr);
      if (a.has_stderr) {
        EXPECT_NEAR(b.a_stderr / 1e300, a.a_stderr, 1e-9);
        EXPECT_TRUE(std::isfinite(b.center_stderr.x()));
      }
      if (a.inclination_deg) {
        EXPECT_NEAR(*b.inclination_deg, *a.inclination_deg, 1e-7);
      }
      EXPECT_EQ(b.selection_note, a.selection_note);
    }
  }
  // And near the smallest normal numbers.
  Envelope tiny = test::ellipse_envelope(e, 36, 0.01, 3, true);
  for (auto& p : tiny.response) p *= 1e-300;
  EXPECT_NEAR(fit_envelope(tiny).a / 1e-300, 2.0, 0.05);
}

TEST(FitScaling, DataUpToTheLargestDoubleFitAsTheSameDataNear1) {
  // Above 2^1023 (about 9e307) the normalisation's scale was 2^1024, infinite: every number of
  // the fit inf or nan, printed with exit 0. Scaled by a power of two, the fit is the same fit.
  test::TrueEllipse e;
  e.c = {3.0, 1.0}, e.a = 2.0, e.b = 1.0, e.phi_deg = 17.0;
  for (const FitShape shape : {FitShape::kAuto, FitShape::kEllipse, FitShape::kLine}) {
    const Envelope unit = test::ellipse_envelope(e, 36, 0.01, 3, true);
    Envelope huge = unit;
    double largest = 0.0;
    for (auto& p : huge.response) {
      p = {std::ldexp(p.x(), 1021), std::ldexp(p.y(), 1021)};
      largest = std::max(largest, p.cwiseAbs().maxCoeff());
    }
    ASSERT_GT(largest, std::ldexp(1.0, 1023));
    FitOptions opts;
    opts.shape = shape;
    const EnvelopeFit a = fit_envelope(unit, opts), b = fit_envelope(huge, opts);
    ASSERT_EQ(a.shape, b.shape);
    const auto down = [](double x) { return std::ldexp(x, -1021); };
    EXPECT_NEAR(down(b.center.x()), a.center.x(), 1e-12 * a.a);
    EXPECT_NEAR(down(b.center.y()), a.center.y(), 1e-12 * a.a);
    EXPECT_NEAR(down(b.a), a.a, 1e-12 * a.a);
    EXPECT_NEAR(down(b.b), a.b, 1e-12 * a.a);
    EXPECT_NEAR(down(b.rms), a.rms, 1e-9 * a.rms);
    ASSERT_EQ(a.has_stderr, b.has_stderr);
    if (a.has_stderr) {
      EXPECT_NEAR(down(b.a_stderr), a.a_stderr, 1e-9 * a.a_stderr);
    }
  }
}

TEST(FitScaling, AFitBeyondTheLargestDoubleIsRefused) {
  // Points along the diagonal out to +-1.7e308: the line's half-length, 2.4e308, is no double.
  // It was printed as inf (null in JSON) with exit 0.
  Envelope diagonal;
  for (const double t : {-1.7e308, -1e308, 0.0, 5e307, 1e308, 1.7e308})
    diagonal.response.push_back({t, t});
  FitOptions opts;
  opts.shape = FitShape::kLine;
  EXPECT_EQ(testing::input_error([&] { fit_envelope(diagonal, opts); }),
            "fit: the fit's numbers exceed the largest double (the points reach 1.7e+308); "
            "rescale the points");
}

// One point 1e300 among points of about 0.1 (a damaged point): the fit in units of the data's
// size made the others' residuals square to zero, and `rendulic fit` printed a line through it
// with rms 0 and standard errors 0, exit 0. Beyond 1e100 times the median point's size it is
// refused naming the point; within it the fit keeps the others' residuals (rms as computed
// here, from the residuals).
TEST(FitScaling, APointBeyondTheFitsSpanIsRefusedNamingIt) {
  const auto with_point = [](double big) {
    Envelope env;
    for (int i = 0; i < 17; ++i) {
      const double t = 2.0 * M_PI * i / 17.0;
      env.response.push_back({0.14 * std::cos(t), 0.042 * std::sin(t)});
    }
    env.response[2].y() = big;
    return env;
  };
  const std::string why =
      testing::input_error([&] { fit_envelope(with_point(1e300), FitOptions{}); });
  EXPECT_NE(why.find("fit: response point 2 reaches 1e+300, more than 1e+100 times the median "
                     "point's 0.1"),
            std::string::npos)
      << why;
  EXPECT_NE(testing::input_error([&] { fit_envelope(with_point(1e200), FitOptions{}); }), "");
  const EnvelopeFit f = fit_envelope(with_point(1e90), FitOptions{});
  double ssr = 0.0;
  for (double r : f.residuals) ssr += r * r;
  ASSERT_GT(ssr, 0.0);
  EXPECT_NEAR(f.rms, std::sqrt(ssr / static_cast<double>(f.residuals.size())), 1e-9 * f.rms);
}

}  // namespace
}  // namespace rendulic
