// Unit tests of model envelopes (docs/models.md sections 1-4,
// docs/physics.md section 5): the ellipses of the elastic laws against their closed forms, the
// pinned anisotropic tilt, the shifted hypoplastic ellipse and its linear scaling with the
// amplitude, and the elastic/elasto-plastic behaviour of elastoplastic_fabric. Envelope
// features come from tests/models/ellipse_of.hpp (affine fit + SVD), not from probes/.
#include "rendulic/models/envelope.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "ellipse_of.hpp"
#include "input_error.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/models/hypoplastic_wu.hpp"
#include "rendulic/models/paths.hpp"

namespace rendulic::models {
namespace {

using rendulic::testing::input_error;

using testing::ellipse_of;
using testing::rows_of;

// Linear laws give affine responses up to rounding: 1e-9 relative leaves six orders of margin
// over double rounding through a few hundred flops, and angles to 1e-7 deg.
constexpr double kExact = 1e-9;
constexpr double kAngleTol = 1e-7;

EnvelopeRecord run(const Law& law, const MaterialState& s, double amplitude,
                   EnvelopeMethod method = EnvelopeMethod::kIntegrated) {
  EnvelopeOptions o;
  o.amplitude = amplitude;
  o.method = method;
  return model_envelope(law, s, o);
}

TEST(Envelope, UsesTheDemProbeSet) {
  auto law = make_law("isotropic_elastic");
  const MaterialState s =
      law->make_state(Eigen::Matrix3d::Identity() * 1e9, Eigen::Matrix3d::Zero(), 0.82);
  const EnvelopeRecord env = run(*law, s, 5e-5);
  ASSERT_EQ(env.size(), 36u);
  const Eigen::VectorXd dirs = probe_directions_deg(36);
  for (int i = 0; i < 36; ++i) {
    EXPECT_EQ(env.theta_deg[i], dirs(i));
    EXPECT_NEAR(env.strain[i](0), 5e-5 * std::cos(deg_to_rad(dirs(i))), 1e-20);
    EXPECT_NEAR(env.strain[i](1), 5e-5 * std::sin(deg_to_rad(dirs(i))), 1e-20);
  }
}

// The record carries the tensors behind its pairs and the driver's report; a probe that cannot
// be followed is an InputError naming its cause, not a record with holes.
TEST(Envelope, IsARecordWithItsTensorsAndTheDriversReport) {
  auto law = make_law("isotropic_elastic");
  const MaterialState s =
      law->make_state(Eigen::Matrix3d::Identity() * 1e9, Eigen::Matrix3d::Zero(), 0.82);
  const EnvelopeRecord rate = run(*law, s, 5e-5, EnvelopeMethod::kRate);
  EXPECT_EQ(rate.method, "model");
  EXPECT_EQ(rate.amplitude, 5e-5);
  EXPECT_TRUE(rate.stress_star.empty());  // no k*: the pairs are in Pa in `stress`
  ASSERT_EQ(rate.d_stress.size(), rate.size());
  ASSERT_EQ(rate.d_fabric.size(), rate.size());
  for (std::size_t i = 0; i < rate.size(); ++i) {
    EXPECT_EQ(rate.stress[i], rendulic_pair(rate.d_stress[i]));
    EXPECT_EQ(rate.fabric[i], rendulic_pair(rate.d_fabric[i]));
    // The tensor of an axisymmetric probe follows from its pair (the calibration's probes).
    EXPECT_LE((rate.strain_tensor(i) - probe_strain(rate.theta_deg[i], 5e-5)).norm(), 1e-20);
  }
  EXPECT_EQ(rate.attributes.at("total_substeps"), 36.0);  // one rate evaluation per probe
  EXPECT_EQ(rate.attributes.at("within_tolerance"), 1.0);
  const EnvelopeRecord integrated = run(*law, s, 5e-5);
  EXPECT_GE(integrated.attributes.at("total_substeps"), 36.0);
  EXPECT_GE(integrated.attributes.at("max_error_estimate"), 0.0);

  auto hypo = make_law("hypoplastic_wu");
  const MaterialState t =
      hypo->make_state(Eigen::Matrix3d::Identity() * -1e5, Eigen::Matrix3d::Zero(), 0.6);
  const std::string what = input_error([&] { run(*hypo, t, 5e-5); });  // a start in tension
  EXPECT_NE(what.find("start state"), std::string::npos) << what;
  EnvelopeOptions bad;
  bad.directions = 2;
  EXPECT_THROW(model_envelope(*law, s, bad), InputError);
}

TEST(Envelope, IsotropicElasticIsTheClosedFormEllipse) {
  auto law = make_law("isotropic_elastic");
  const MaterialState s =
      law->make_state(Eigen::Matrix3d::Identity() * 1e9, Eigen::Matrix3d::Identity() * 2.0, 0.82);
  const double amp = 5e-5, k = law->parameter("K"), g = law->parameter("G");
  const EnvelopeRecord env = run(*law, s, amp);
  const auto e = ellipse_of(env.strain, env.stress);
  EXPECT_NEAR(e.a, 3 * k * amp, kExact * 3 * k * amp);
  EXPECT_NEAR(e.b, 2 * g * amp, kExact * 3 * k * amp);
  EXPECT_NEAR(e.inclination_deg, kIsoCompressionDeg, kAngleTol);
  EXPECT_LE(e.center.norm(), kExact * e.a);
  EXPECT_LE(e.rms, kExact * e.a);
  // The elastic fabric envelope is a line along the isotropic direction (no deviatoric change).
  const auto f = ellipse_of(env.strain, env.fabric);
  EXPECT_LE(f.b, kExact * f.a);
  EXPECT_NEAR(f.inclination_deg, kIsoCompressionDeg, kAngleTol);
  // d_F = c_F tr(d_eps) I / 3 for isotropic F: along the isotropic probe |d_eps| = amp gives
  // tr(d_eps) = sqrt(3) amp and |d_F| = c_F sqrt(3) amp / sqrt(3) = c_F amp.
  EXPECT_NEAR(f.a, law->parameter("c_F") * amp, kExact * f.a);
}

// Rendulic stiffness of the pinned form in the (iso, dev) frame, docs/models.md.
Eigen::Matrix2d pinned_d(double b, double g, double a) {
  Eigen::Matrix2d d;
  d << 3 * b, kSqrt3 * a, kSqrt3 * a, 2 * g;
  return d;
}

TEST(Envelope, AnisotropicTiltIsExactlyThePinnedAngle) {
  auto law = make_law("anisotropic_elastic");
  const double b = law->parameter("B"), g = law->parameter("G"), amp = 5e-5;
  const Eigen::Matrix3d stress = Eigen::Matrix3d::Identity() * 2e9;
  for (double f_xx : {1.6, 2.0, 2.4}) {  // extension fabric, isotropic, compression fabric
    const Eigen::Matrix3d fabric = Eigen::Vector3d(f_xx, 2.0, 2.0).asDiagonal();
    const double f_dev = signed_deviator(fabric);
    for (double beta : {0.0, 0.5, 2.0}) {
      std::string why;
      ASSERT_TRUE(law->set_parameter("beta_A", beta, &why));
      const MaterialState s = law->make_state(stress, fabric, 0.82);
      const auto e = ellipse_of(run(*law, s, amp).strain, run(*law, s, amp).stress);
      const double a = beta * f_dev * b;
      const double expect =
          kIsoCompressionDeg + 0.5 * rad_to_deg(std::atan2(2 * kSqrt3 * a, 3 * b - 2 * g));
      EXPECT_NEAR(e.inclination_deg, expect, kAngleTol) << "F_xx " << f_xx << " beta " << beta;
      if (beta == 0.0 || f_xx == 2.0) {
        EXPECT_NEAR(e.inclination_deg, kIsoCompressionDeg, kAngleTol);
      } else if (f_xx < 2.0) {  // extension fabric lowers the inclination
        EXPECT_LT(e.inclination_deg, kIsoCompressionDeg - 0.1);
      } else {
        EXPECT_GT(e.inclination_deg, kIsoCompressionDeg + 0.1);
      }
      // Semi-axes are |eigenvalues| of the symmetric D times |d_eps| (beta_A = 2 with the
      // compression fabric makes D indefinite: still an ellipse, traversed backwards).
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(pinned_d(b, g, a));
      EXPECT_NEAR(e.a, std::abs(eig.eigenvalues()(1)) * amp, kExact * e.a);
      EXPECT_NEAR(e.b, std::abs(eig.eigenvalues()(0)) * amp, kExact * e.a);
    }
  }
}

TEST(Envelope, RendulicTangentOfAnisotropicLawIsThePinnedStiffness) {
  auto law = make_law("anisotropic_elastic");
  const Eigen::Matrix3d fabric = Eigen::Vector3d(1.6, 2.2, 2.2).asDiagonal();
  const MaterialState s = law->make_state(Eigen::Matrix3d::Identity() * 2e9, fabric, 0.82);
  const double b = law->parameter("B"), g = law->parameter("G");
  const double a = law->parameter("beta_A") * signed_deviator(fabric) * b;
  const Eigen::Matrix2d r = rendulic_to_iso_dev();
  const Eigen::Matrix2d d_isodev = r * rendulic_tangent(*law, s, 0.0) * r.transpose();
  EXPECT_LE((d_isodev - pinned_d(b, g, a)).norm(), kExact * 3 * b);
  // And it maps each probe onto its rate-envelope point.
  const EnvelopeRecord env = run(*law, s, 1e-4, EnvelopeMethod::kRate);
  for (std::size_t i = 0; i < env.size(); ++i) {
    const Eigen::Vector2d pred = rendulic_tangent(*law, s, env.theta_deg[i]) * env.strain[i];
    EXPECT_LE((pred - env.stress[i]).norm(), kExact * 3 * b * 1e-4);
  }
}

TEST(Envelope, HypoplasticIsTheShiftedClosedFormEllipseScalingWithAmplitude) {
  auto law = make_law("hypoplastic_wu");
  const double p = 1e5;
  const double c1 = law->parameter("c1"), c2 = law->parameter("c2"), c3 = law->parameter("c3");
  const MaterialState s =
      law->make_state(Eigen::Matrix3d::Identity() * p, Eigen::Matrix3d::Zero(), 0.6);
  for (double amp : {1e-5, 3e-5}) {
    const EnvelopeRecord env = run(*law, s, amp, EnvelopeMethod::kRate);
    const auto e = ellipse_of(env.strain, env.stress);
    // Isotropic sigma = p I (compression positive form, hypoplastic_wu.hpp):
    // L = diag(-(3 c1 + c2) p, -3 c1 p) in the (iso, dev) frame; N = (c3 p / 3) I.
    EXPECT_NEAR(e.a, -(3 * c1 + c2) * p * amp, kExact * e.a);
    EXPECT_NEAR(e.b, -3 * c1 * p * amp, kExact * e.a);
    EXPECT_NEAR(e.inclination_deg, kIsoCompressionDeg, kAngleTol);
    const Eigen::Vector2d shift = rendulic_pair(Eigen::Matrix3d::Identity() * c3 * p / 3) * amp;
    EXPECT_LE((e.center - shift).norm(), kExact * e.a);
    EXPECT_LE(e.rms, kExact * e.a);
  }
  // An anisotropic stress: still exactly an affine image of the probe circle (an ellipse), its
  // centre shifted by N |d_eps|, and both scale linearly with the amplitude.
  const MaterialState t =
      law->make_state(Eigen::Vector3d(2 * p, p, p).asDiagonal(), Eigen::Matrix3d::Zero(), 0.6);
  const auto e1 = ellipse_of(run(*law, t, 1e-5, EnvelopeMethod::kRate).strain,
                             run(*law, t, 1e-5, EnvelopeMethod::kRate).stress);
  const auto e3 = ellipse_of(run(*law, t, 3e-5, EnvelopeMethod::kRate).strain,
                             run(*law, t, 3e-5, EnvelopeMethod::kRate).stress);
  EXPECT_LE(e1.rms, kExact * e1.a);
  const Eigen::Matrix3d n =
      HypoplasticWu::nonlinear_term(law->parameters().data(), Eigen::Matrix3d(t.stress));
  EXPECT_LE((e1.center - rendulic_pair(n) * 1e-5).norm(), kExact * e1.a);
  EXPECT_NEAR(e3.a, 3 * e1.a, kExact * e3.a);
  EXPECT_NEAR(e3.b, 3 * e1.b, kExact * e3.a);
  EXPECT_LE((e3.center - 3 * e1.center).norm(), kExact * e3.a);
  // Integrated probes converge to the rate envelope linearly in the amplitude (the stiffness
  // changes by O(c |d_eps|) along a probe): halving the amplitude halves the gap.
  auto gap = [&](double amp) {
    const EnvelopeRecord ri = run(*law, t, amp, EnvelopeMethod::kRate);
    const EnvelopeRecord in = run(*law, t, amp);
    return (rows_of(in.stress) - rows_of(ri.stress)).norm() / rows_of(ri.stress).norm();
  };
  const double g1 = gap(2e-6), g2 = gap(1e-6);
  EXPECT_LT(g1, 1e-2);
  EXPECT_NEAR(g1 / g2, 2.0, 0.05);
}

TEST(Envelope, ElastoplasticSmallProbesElasticLargeProbesShiftedAndThinner) {
  auto ep = make_law("elastoplastic_fabric");
  auto el = make_law("anisotropic_elastic");
  // Follow the undrained extension path of the law itself and probe its states, as the seed.
  const MaterialState start =
      ep->make_state(Eigen::Matrix3d::Identity() * 2e9, Eigen::Matrix3d::Identity() * 2.0, 0.82);
  PathOptions po;
  po.steps = 320;
  const PathSeries path = undrained_axisymmetric_path(*ep, start, -0.32, po);
  ASSERT_TRUE(path.success) << path.reason;
  double prev_ratio = 1e9, prev_shift = -1.0;
  for (int idx : {6, 21, 68, 320}) {  // -eps_dev = 0.006, 0.021, 0.068, 0.32
    const MaterialState s = ep->make_state(path.stress[idx], path.fabric[idx], 0.82);
    const EnvelopeRecord small = run(*ep, s, 5e-5);
    const EnvelopeRecord small_el = run(*el, s, 5e-5);
    // Elastic probes: exactly the anisotropic elastic envelope, no deviatoric fabric change.
    EXPECT_LE((rows_of(small.stress) - rows_of(small_el.stress)).norm(),
              kExact * rows_of(small.stress).norm())
        << idx;
    const EnvelopeRecord large = run(*ep, s, 2e-3);
    const auto es = ellipse_of(small.strain, small.stress);
    const auto el_ = ellipse_of(large.strain, large.stress);
    // Large probes: thinner than elastic, and a centre shift (incremental non-linearity,
    // measured against the minor axis) that grows with the anisotropy of the state.
    EXPECT_LT(el_.b / el_.a, es.b / es.a) << idx;
    const double shift = el_.center.norm() / el_.b;
    EXPECT_GT(shift, prev_shift) << idx;
    prev_shift = shift;
    if (idx == 320) {
      EXPECT_GT(shift, 0.3);
    }
    // The plastic envelope keeps thinning along the path, towards a line at the steady state.
    EXPECT_LT(el_.b / el_.a, prev_ratio) << idx;
    prev_ratio = el_.b / el_.a;
    // Plastic probes change the deviatoric fabric.
    const auto ef = ellipse_of(large.strain, large.fabric);
    EXPECT_GT(ef.b + ef.center.norm(), 0.0);
  }
}

// The smooth elastic-to-plastic transition of elastoplastic_fabric (w_yield, docs/models.md
// section 4) against the sharp switch (w_yield = 0): the elastic probes are the same to rounding
// (the relaxed state is the centre of the elastic domain, far below the transition), and the
// 2e-3 envelopes of the law's own path states move by far less than DEM noise (about 1e-3 of
// a stress envelope, 0.07 of a fabric one): the transition takes the last 2 % of the elastic
// range only.
TEST(Envelope, ElastoplasticSmoothTransitionChangesEnvelopesLittle) {
  auto smooth = make_law("elastoplastic_fabric");
  auto sharp = make_law("elastoplastic_fabric");
  std::string why;
  ASSERT_TRUE(sharp->set_parameter("w_yield", 0.0, &why)) << why;
  const MaterialState start = smooth->make_state(Eigen::Matrix3d::Identity() * 2e9,
                                                 Eigen::Matrix3d::Identity() * 2.0, 0.82);
  PathOptions po;
  po.steps = 68;
  const PathSeries path = undrained_axisymmetric_path(*smooth, start, -0.068, po);
  ASSERT_TRUE(path.success) << path.reason;
  for (int idx : {6, 21, 68}) {
    const MaterialState s = smooth->make_state(path.stress[idx], path.fabric[idx], 0.82);
    const EnvelopeRecord e1 = run(*smooth, s, 5e-5), e0 = run(*sharp, s, 5e-5);
    EXPECT_LE((rows_of(e1.stress) - rows_of(e0.stress)).norm(), kExact * rows_of(e0.stress).norm())
        << idx;
    const EnvelopeRecord p1 = run(*smooth, s, 2e-3), p0 = run(*sharp, s, 2e-3);
    const double ds = (rows_of(p1.stress) - rows_of(p0.stress)).norm() / rows_of(p0.stress).norm();
    const double df = (rows_of(p1.fabric) - rows_of(p0.fabric)).norm() / rows_of(p0.fabric).norm();
    EXPECT_GT(ds, 0.0) << idx;   // the transition is there
    EXPECT_LT(ds, 1e-4) << idx;  // measured 0.7-1.6e-5
    EXPECT_LT(df, 1e-3) << idx;  // measured 1.2-1.7e-4
  }
}

}  // namespace
}  // namespace rendulic::models
