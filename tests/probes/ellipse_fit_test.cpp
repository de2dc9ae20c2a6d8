// Tests of the geometric ellipse fit (docs/physics.md section 6): exact recovery,
// thin ellipses down to b/a = 0.001, half arcs, few points, noise, the two initial guesses,
// and the closed form "axes of the envelope of a linear law = singular values of D".
#include <gtest/gtest.h>

#include "rendulic/core/errors.hpp"
#include "rendulic/probes/envelope_fit.hpp"
#include "synthetic.hpp"

namespace rendulic {
namespace {

using test::angle_diff_deg;
using test::ellipse_envelope;
using test::TrueEllipse;

// A noiseless fit converges to rounding: 1e-8 relative leaves room for the conditioning of
// thin ellipses (b/a = 1e-3 squares to 1e-6 in the normal equations' spread).
constexpr double kExact = 1e-8;

FitOptions ellipse_only() {
  FitOptions o;
  o.shape = FitShape::kEllipse;
  return o;
}

void expect_matches(const EnvelopeFit& f, const TrueEllipse& e, double tol) {
  ASSERT_EQ(f.shape, FitShape::kEllipse) << f.selection_note;
  EXPECT_NEAR(f.center.x(), e.c.x(), tol * e.a);
  EXPECT_NEAR(f.center.y(), e.c.y(), tol * e.a);
  EXPECT_NEAR(f.a, e.a, tol * e.a);
  EXPECT_NEAR(f.b, e.b, tol * e.a);
  ASSERT_TRUE(f.inclination_deg.has_value());
  EXPECT_GE(*f.inclination_deg, 0.0);
  EXPECT_LT(*f.inclination_deg, 180.0);
  EXPECT_LT(angle_diff_deg(*f.inclination_deg, e.phi_deg), rad_to_deg(tol) * 10.0);
}

TEST(EllipseFit, ExactRecoveryWithoutDirections) {
  TrueEllipse e{{0.3, -0.5}, 2.0, 0.7, 30.0};
  const EnvelopeFit f = fit_ellipse(ellipse_envelope(e, 36), ellipse_only());
  expect_matches(f, e, kExact);
  EXPECT_FALSE(f.used_theta);
  EXPECT_LT(f.rms, kExact * e.a);
  EXPECT_TRUE(f.converged);
}

TEST(EllipseFit, ExactRecoveryWithDirections) {
  TrueEllipse e{{-1.0, 4.0}, 3.0, 1.2, 125.0};
  const EnvelopeFit f = fit_ellipse(ellipse_envelope(e, 36, 0.0, 1, true), ellipse_only());
  expect_matches(f, e, kExact);
  EXPECT_TRUE(f.used_theta);
}

TEST(EllipseFit, InclinationFoldedIntoHalfTurn) {
  for (double phi : {0.0, 1.0, 89.0, 91.0, 179.0, 200.0, -30.0}) {
    TrueEllipse e{{0.0, 0.0}, 1.0, 0.4, phi};
    const EnvelopeFit f = fit_ellipse(ellipse_envelope(e, 24), ellipse_only());
    ASSERT_TRUE(f.inclination_deg.has_value());
    EXPECT_GE(*f.inclination_deg, 0.0);
    EXPECT_LT(*f.inclination_deg, 180.0);
    EXPECT_LT(angle_diff_deg(*f.inclination_deg, phi), 1e-6) << phi;
  }
}

TEST(EllipseFit, ThinEllipsesDownToOnePerMille) {
  for (double ratio : {0.05, 0.01, 0.001}) {
    for (bool theta : {false, true}) {
      TrueEllipse e{{0.02, 0.01}, 1.0, ratio, 35.26};
      const EnvelopeFit f = fit_ellipse(ellipse_envelope(e, 36, 0.0, 1, theta), ellipse_only());
      SCOPED_TRACE(::testing::Message() << "b/a " << ratio << " theta " << theta);
      expect_matches(f, e, kExact);
      EXPECT_NEAR(f.b / f.a, ratio, kExact);
    }
  }
}

TEST(EllipseFit, ScaleInvariance) {
  // Stresses in Pa (1e6) and fabric changes (1e-6) must fit alike: the fit works in
  // normalized coordinates.
  for (double s : {1e-6, 1.0, 1e6}) {
    TrueEllipse e{{0.5 * s, 0.2 * s}, 2.0 * s, 0.02 * s, 60.0};
    const EnvelopeFit f = fit_ellipse(ellipse_envelope(e, 36, 0.0, 3, true), ellipse_only());
    expect_matches(f, e, kExact);
  }
}

TEST(EllipseFit, HalfArcAndFewPoints) {
  TrueEllipse e{{0.1, 0.2}, 1.5, 0.6, 20.0};
  // Half of the ellipse, 12 points, noiseless: still exact.
  expect_matches(fit_ellipse(ellipse_envelope(e, 12, 0.0, 1, false, kPi), ellipse_only()), e,
                 kExact);
  // Five points determine the ellipse: exact, but nothing left for the errors.
  const EnvelopeFit f5 = fit_ellipse(ellipse_envelope(e, 5), ellipse_only());
  expect_matches(f5, e, 1e-6);
  // Six points around the whole ellipse, with directions.
  expect_matches(fit_ellipse(ellipse_envelope(e, 6, 0.0, 2, true), ellipse_only()), e, kExact);
}

TEST(EllipseFit, NoisyFitWithinReportedErrors) {
  TrueEllipse e{{0.0, 0.0}, 1.0, 0.3, 40.0};
  const double sigma = 0.01;
  for (bool theta : {false, true}) {
    const EnvelopeFit f = fit_ellipse(ellipse_envelope(e, 36, sigma, 7, theta), ellipse_only());
    ASSERT_TRUE(f.has_stderr);
    // The rms orthogonal residual estimates sigma; with 31 degrees of freedom it lies within
    // 30% of it with overwhelming probability.
    EXPECT_NEAR(f.rms, sigma, 0.3 * sigma);
    // Within 4 standard errors (a 4-sigma miss has probability 6e-5 per parameter).
    EXPECT_LT(std::abs(f.a - e.a), 4.0 * f.a_stderr);
    EXPECT_LT(std::abs(f.b - e.b), 4.0 * f.b_stderr);
    EXPECT_LT(std::abs(f.center.x() - e.c.x()), 4.0 * f.center_stderr.x());
    EXPECT_LT(std::abs(f.center.y() - e.c.y()), 4.0 * f.center_stderr.y());
    EXPECT_LT(angle_diff_deg(*f.inclination_deg, e.phi_deg), 4.0 * *f.inclination_stderr_deg);
    // The errors are of the size sigma / sqrt(n) suggests, not inflated.
    EXPECT_LT(f.a_stderr, 3.0 * sigma);
  }
}

// fits.shape = "circle" (`rendulic fit --shape circle`): Kasa's linear start refined in the
// orthogonal distances. Exact on a noiseless circle, within its reported errors on a noisy one,
// and the same circle as the ellipse fit of the same points (a second method).
TEST(CircleFit, RequestedCircleIsTheGeneratingOneAndTheEllipseFitsToo) {
  FitOptions circle;
  circle.shape = FitShape::kCircle;
  const TrueEllipse c{{0.3, -0.2}, 1.7, 1.7, 0.0};
  for (bool theta : {false, true}) {
    SCOPED_TRACE(theta ? "with directions" : "without directions");
    const EnvelopeFit f = fit_envelope(ellipse_envelope(c, 24, 0.0, 1, theta), circle);
    ASSERT_EQ(f.shape, FitShape::kCircle) << f.selection_note;
    EXPECT_NEAR(f.center.x(), 0.3, kExact);
    EXPECT_NEAR(f.center.y(), -0.2, kExact);
    EXPECT_NEAR(f.a, 1.7, kExact);
    EXPECT_EQ(f.b, f.a);
    EXPECT_FALSE(f.inclination_deg.has_value());
    EXPECT_LT(f.rms, kExact);

    const double sigma = 0.01;
    const Envelope noisy = ellipse_envelope(c, 36, sigma, 7, theta);
    const EnvelopeFit n = fit_envelope(noisy, circle);
    ASSERT_TRUE(n.has_stderr);
    EXPECT_NEAR(n.rms, sigma, 0.3 * sigma);
    EXPECT_LT(std::abs(n.a - 1.7), 4.0 * n.a_stderr);
    EXPECT_LT(std::abs(n.center.x() - 0.3), 4.0 * n.center_stderr.x());
    EXPECT_LT(std::abs(n.center.y() + 0.2), 4.0 * n.center_stderr.y());
    EXPECT_LT(n.a_stderr, 3.0 * sigma);
    const EnvelopeFit e = fit_envelope(noisy, ellipse_only());
    EXPECT_NEAR(n.a, 0.5 * (e.a + e.b), 2.0 * n.a_stderr);
    EXPECT_LT((n.center - e.center).norm(), 2.0 * n.center_stderr.norm());
  }
  // An ellipse asked to be a circle is fitted as one, and its rms says how badly.
  const EnvelopeFit bad = fit_envelope(ellipse_envelope({{0, 0}, 1.0, 0.5, 30.0}, 24), circle);
  ASSERT_EQ(bad.shape, FitShape::kCircle);
  EXPECT_GT(bad.a, 0.5);
  EXPECT_LT(bad.a, 1.0);
  EXPECT_GT(bad.rms, 0.1);
}

TEST(EllipseFit, NoisyHalfArcWithDirections) {
  // Half arcs are where the directions matter: the points alone leave the far side free.
  TrueEllipse e{{0.0, 0.0}, 1.0, 0.2, 35.0};
  const EnvelopeFit f =
      fit_ellipse(ellipse_envelope(e, 18, 0.005, 11, true, kPi, 0.3), ellipse_only());
  ASSERT_TRUE(f.has_stderr);
  EXPECT_LT(std::abs(f.a - e.a), 4.0 * f.a_stderr);
  EXPECT_LT(std::abs(f.b - e.b), 4.0 * f.b_stderr);
  EXPECT_NEAR(f.a, e.a, 0.05);
}

TEST(EllipseFit, LinearLawEnvelopeAxesAreSingularValues) {
  // docs/physics.md section 6: response = c + D * strain, strain = A (cos theta, sin theta) gives
  // an ellipse with semi-axes A * singular values of D. D symmetric, like a Rendulic
  // stiffness of a hyperelastic law, but far from diagonal.
  Eigen::Matrix2d D;
  D << 3.0, 1.1, 1.1, 0.5;
  const double amp = 2e-3;
  const Eigen::Vector2d c(1e-4, -3e-4);
  Envelope env;
  for (int k = 0; k < 36; ++k) {
    const double th = 10.0 * k;
    const Eigen::Vector2d u(std::cos(deg_to_rad(th)), std::sin(deg_to_rad(th)));
    env.response.push_back(c + D * u * amp);
    env.theta_deg.push_back(th);
  }
  Eigen::JacobiSVD<Eigen::Matrix2d> svd(D, Eigen::ComputeFullU);
  const EnvelopeFit f = fit_ellipse(env, ellipse_only());
  EXPECT_NEAR(f.a, amp * svd.singularValues()(0), kExact * f.a);
  EXPECT_NEAR(f.b, amp * svd.singularValues()(1), kExact * f.a);
  const double incl = rad_to_deg(std::atan2(svd.matrixU()(1, 0), svd.matrixU()(0, 0)));
  EXPECT_LT(angle_diff_deg(*f.inclination_deg, incl), 1e-6);
  EXPECT_NEAR((f.center - c).norm(), 0.0, kExact * f.a);
}

TEST(InitialGuess, AffineFitIsExactForLinearLaw) {
  Eigen::Matrix2d M;
  M << 1.0, 0.4, -0.3, 0.2;  // not symmetric, not positive: any linear map
  std::vector<Eigen::Vector2d> pts;
  std::vector<double> th;
  for (int k = 0; k < 7; ++k) {
    th.push_back(17.0 + 51.0 * k);
    const double r = deg_to_rad(th.back());
    pts.push_back(Eigen::Vector2d(0.5, 0.25) + M * Eigen::Vector2d(std::cos(r), std::sin(r)));
  }
  const AffineMapFit af = fit_affine_map(direction_vectors(th), pts);
  ASSERT_TRUE(af.ok);
  EXPECT_LT((af.map - M).norm(), 1e-12);
  EXPECT_LT((af.center - Eigen::Vector2d(0.5, 0.25)).norm(), 1e-12);
  // The guess built from it reproduces every point with its latent angle.
  const EllipseGuess g = ellipse_guess_from_affine(af, th);
  ASSERT_TRUE(g.ok);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const double p = g.phi;
    const Eigen::Vector2d local(g.a * std::cos(g.t[i]), g.b * std::sin(g.t[i]));
    Eigen::Matrix2d R;
    R << std::cos(p), -std::sin(p), std::sin(p), std::cos(p);
    EXPECT_LT((g.center + R * local - pts[i]).norm(), 1e-12);
  }
}

TEST(InitialGuess, HalirFlusserExactAndRefusesCollinear) {
  TrueEllipse e{{2.0, -1.0}, 1.0, 0.25, 70.0};
  const Envelope env = ellipse_envelope(e, 20);
  const EllipseGuess g = ellipse_guess_algebraic(env.response);
  ASSERT_TRUE(g.ok);
  EXPECT_NEAR(g.a, 1.0, 1e-9);
  EXPECT_NEAR(g.b, 0.25, 1e-9);
  EXPECT_LT((g.center - e.c).norm(), 1e-9);
  std::vector<Eigen::Vector2d> line;
  for (int k = 0; k < 10; ++k) line.emplace_back(0.1 * k, 0.2 * k + 1.0);
  EXPECT_FALSE(ellipse_guess_algebraic(line).ok);
}

TEST(EllipseFit, RefusesBadInput) {
  TrueEllipse e;
  Envelope four = ellipse_envelope(e, 4);
  EXPECT_THROW(fit_ellipse(four, ellipse_only()), InputError);
  Envelope nan = ellipse_envelope(e, 10);
  nan.response[3].x() = std::nan("");
  EXPECT_THROW(fit_ellipse(nan, ellipse_only()), InputError);
  EXPECT_THROW(fit_envelope(nan), InputError);
  Envelope same;
  for (int k = 0; k < 8; ++k) same.response.emplace_back(1.0, 2.0);
  EXPECT_THROW(fit_ellipse(same, ellipse_only()), InputError);
  EXPECT_THROW(fit_line(same), InputError);
  EXPECT_THROW(fit_envelope(same), InputError);
  Envelope dup = ellipse_envelope(e, 4);
  dup.response.push_back(dup.response[0]);
  dup.response.push_back(dup.response[1]);
  EXPECT_THROW(fit_ellipse(dup, ellipse_only()), InputError);
  Envelope mismatch = ellipse_envelope(e, 10, 0.0, 1, true);
  mismatch.theta_deg.pop_back();
  EXPECT_THROW(fit_envelope(mismatch), InputError);
  FitOptions bad;
  bad.selection_alpha = 2.0;
  std::string why;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_FALSE(why.empty());
  EXPECT_THROW(fit_envelope(ellipse_envelope(e, 10), bad), InputError);
}

}  // namespace
}  // namespace rendulic
