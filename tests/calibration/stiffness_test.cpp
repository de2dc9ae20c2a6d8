// Level-one calibration (stiffness.hpp) against closed forms: the isotropic law's ellipse of
// docs/models.md "Coordinates" (D = diag(3K, 2G), semi-axes 3K|de| and 2G|de|, major axis at
// 35.26 deg), the anisotropic law's A = beta_A F_dev B and tilt (1/2) atan2(2 sqrt3 A, 3B - 2G),
// an independent estimator (core's affine map fit), the hypoplastic centre shift N |d_eps|, and
// the reported standard errors against the scatter of repeated noisy fits.
#include "rendulic/calibration/stiffness.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "rendulic/core/affine_map.hpp"
#include "rendulic/models/hypoplastic_wu.hpp"
#include "rendulic/probes/envelope_fit.hpp"
#include "rendulic/probes/features.hpp"
#include "synthetic.hpp"

namespace rendulic::calibration {
namespace {

using testing::law_with;

// Rate envelopes are exact images of a linear map: B, G, A to round-off (1e-9 relative leaves
// ~6 orders of margin over double precision in the 36 x 5 least-squares problem).
constexpr double kExact = 1e-9;

models::MaterialState state_of(const models::Law& law, double p_ax, double p_lat, double f_ax,
                               double f_lat) {
  return law.make_state(Eigen::Vector3d(p_ax, p_lat, p_lat).asDiagonal(),
                        Eigen::Vector3d(f_ax, f_lat, f_lat).asDiagonal(), 0.8);
}

TEST(Stiffness, IsotropicLawGivesTheClosedFormEllipse) {
  const auto law = law_with("isotropic_elastic", {{"K", 2e10}, {"G", 3e9}});
  std::mt19937 rng(1);
  const EnvelopeRecord e = testing::envelope_of(*law, state_of(*law, 1e9, 1e9, 1.8, 1.8), "el",
                                                5e-5, 36, models::EnvelopeMethod::kRate, {}, &rng);
  const RendulicStiffness s = fit_rendulic_stiffness(e);
  ASSERT_TRUE(s.ok) << s.note;
  EXPECT_NEAR(s.B / 2e10, 1.0, kExact);
  EXPECT_NEAR(s.G / 3e9, 1.0, kExact);
  EXPECT_NEAR(s.A / 2e10, 0.0, kExact);
  EXPECT_NEAR(s.a, 3 * 2e10 * 5e-5, kExact * s.a);
  EXPECT_NEAR(s.b, 2 * 3e9 * 5e-5, kExact * s.a);
  EXPECT_NEAR(s.inclination_deg, kIsoCompressionDeg, 1e-7);
  EXPECT_LT(s.center.norm(), kExact * s.a);
  EXPECT_LT(s.B_stderr, kExact * s.B);  // exact data: no scatter
}

TEST(Stiffness, AnisotropicLawGivesAAndTheTilt) {
  const double B = 2.2e10, G = 3e9, beta_a = 0.8;
  const auto law = law_with("anisotropic_elastic", {{"B", B}, {"G", G}, {"beta_A", beta_a}});
  const models::MaterialState st = state_of(*law, 1.3e9, 1.9e9, 1.4, 2.0);
  std::mt19937 rng(1);
  const EnvelopeRecord e =
      testing::envelope_of(*law, st, "el", 5e-5, 36, models::EnvelopeMethod::kRate, {}, &rng);
  const RendulicStiffness s = fit_rendulic_stiffness(e);
  ASSERT_TRUE(s.ok);
  const double f_dev = signed_deviator(st.fabric);
  ASSERT_LT(f_dev, 0.0);  // axial extension
  EXPECT_NEAR(s.B / B, 1.0, kExact);
  EXPECT_NEAR(s.G / G, 1.0, kExact);
  EXPECT_NEAR(s.A / (beta_a * f_dev * B), 1.0, kExact);
  const double tilt = 0.5 * rad_to_deg(std::atan2(2 * kSqrt3 * s.A, 3 * s.B - 2 * s.G));
  EXPECT_NEAR(s.inclination_deg, kIsoCompressionDeg + tilt, 1e-7);
  EXPECT_LT(s.inclination_deg, kIsoCompressionDeg);  // extension lowers the inclination

  // Independent estimator: the affine map fit of core gives M = D_rendulic * amplitude.
  const AffineMapFit af = fit_affine_map(direction_vectors(e.theta_deg), e.stress);
  ASSERT_TRUE(af.ok);
  EXPECT_LT((af.map / e.amplitude - s.rendulic_matrix()).norm(),
            kExact * s.rendulic_matrix().norm());
  // And the symmetric fit of probes/ features.hpp (c + D e, D symmetric).
  Envelope pe;
  pe.response = e.stress;
  pe.strain = e.strain;
  pe.theta_deg = e.theta_deg;
  pe.amplitude = e.amplitude;
  const rendulic::RendulicStiffness ps = rendulic::fit_rendulic_stiffness(pe);
  EXPECT_LT((ps.D - s.rendulic_matrix()).norm(), kExact * s.rendulic_matrix().norm());
  // And the law's own tangent (models/ rendulic_tangent), no envelope involved.
  const Eigen::Matrix2d t = models::rendulic_tangent(*law, st, 0.0);
  EXPECT_LT((t - s.rendulic_matrix()).norm(), kExact * s.rendulic_matrix().norm());
}

TEST(Stiffness, StandardErrorsMatchTheScatterOfNoisyFits) {
  const auto law = law_with("anisotropic_elastic", {{"B", 2.2e10}, {"G", 3e9}, {"beta_A", 0.8}});
  const models::MaterialState st = state_of(*law, 1.3e9, 1.9e9, 1.4, 2.0);
  std::mt19937 rng(11);
  const int trials = 200;
  double sum = 0, sum2 = 0, reported = 0;
  for (int t = 0; t < trials; ++t) {
    const EnvelopeRecord e = testing::envelope_of(*law, st, "el", 5e-5, 36,
                                                  models::EnvelopeMethod::kRate, {0.02, 0}, &rng);
    const RendulicStiffness s = fit_rendulic_stiffness(e);
    sum += s.G;
    sum2 += s.G * s.G;
    reported += s.G_stderr;
  }
  const double sd = std::sqrt(sum2 / trials - std::pow(sum / trials, 2));
  // 200 trials estimate a standard deviation to ~5% (1/sqrt(2 n)); 25% is a loose, safe band.
  EXPECT_NEAR(reported / trials / sd, 1.0, 0.25);
}

TEST(Stiffness, HypoplasticCentreShiftIsNTimesTheAmplitude) {
  const auto law = models::make_law("hypoplastic_wu");
  const models::MaterialState st = state_of(*law, 1.2e6, 2e6, 0, 0);
  std::mt19937 rng(1);
  const double amp = 2e-3;
  const EnvelopeRecord e =
      testing::envelope_of(*law, st, "pl", amp, 36, models::EnvelopeMethod::kRate, {}, &rng);
  const PlasticFeatures f = plastic_features(e);
  ASSERT_TRUE(f.ok) << f.note;
  // The rate envelope is L : d_eps + N |d_eps|: an ellipse centred at N |d_eps| exactly.
  const Eigen::Vector2d expected = rendulic_pair(models::HypoplasticWu::nonlinear_term(
                                       law->parameters().data(), Eigen::Matrix3d(st.stress))) *
                                   amp;
  EXPECT_LT((f.shift - expected).norm(), 1e-9 * f.a);
  EXPECT_GT(f.shift_ratio, 0.0);
  EXPECT_LE(f.thinning, 1.0);
}

TEST(Stiffness, TooFewDirectionsIsReportedNotGuessed) {
  EnvelopeRecord e = probe_set("two", 5e-5, 2);
  e.stress = {Eigen::Vector2d(1, 2), Eigen::Vector2d(3, 4)};
  const RendulicStiffness s = fit_rendulic_stiffness(e);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.note.find("fewer than 3"), std::string::npos);
}

}  // namespace
}  // namespace rendulic::calibration
