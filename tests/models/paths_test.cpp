// Unit tests of the main paths driven through the laws: isotropic compression, undrained
// axisymmetric extension and drained triaxial paths, against closed forms for the linear law,
// the hypoplastic sand's limit state found by a second method, and the steady state that
// elastoplastic_fabric is built to reach.
#include "rendulic/models/paths.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "wu_limit.hpp"

namespace rendulic::models {
namespace {

TEST(Paths, IsotropicElasticClosedForms) {
  auto law = make_law("isotropic_elastic");
  const double k = law->parameter("K"), g = law->parameter("G");
  const MaterialState s =
      law->make_state(Eigen::Matrix3d::Identity() * 1e8, Eigen::Matrix3d::Identity() * 2.0, 0.7);
  const PathSeries iso = isotropic_compression_path(*law, s, 0.02);
  ASSERT_TRUE(iso.success) << iso.reason;
  ASSERT_EQ(iso.stress.size(), 201u);
  for (size_t i = 0; i < iso.stress.size(); ++i) {
    EXPECT_NEAR(pressure(iso.stress[i]), 1e8 + k * iso.eps_v[i], 1e-9 * k * 0.02);
    EXPECT_NEAR(std::sqrt(2 * j2(iso.stress[i])), 0.0, 1e-6);
  }
  EXPECT_NEAR(iso.eps_v.back(), 0.02, 1e-15);
  EXPECT_NEAR(iso.volume_fraction.back(), 0.7 * std::exp(0.02), 1e-12);
  // d tr(F) = c_F d eps_v with F kept isotropic: tr(F) grows linearly.
  EXPECT_NEAR(iso.fabric.back().trace(), 6.0 + law->parameter("c_F") * 0.02, 1e-12);

  const PathSeries und = undrained_axisymmetric_path(*law, s, -0.05);
  ASSERT_TRUE(und.success) << und.reason;
  EXPECT_NEAR(und.eps_dev.back(), -0.05, 1e-15);
  for (size_t i = 0; i < und.stress.size(); ++i) {
    EXPECT_NEAR(und.eps_v[i], 0.0, 1e-15);
    EXPECT_NEAR(pressure(und.stress[i]), 1e8, 1e-6 * 1e8);
    EXPECT_NEAR(signed_deviator(und.stress[i]), 2 * g * und.eps_dev[i], 1e-9 * 2 * g * 0.05);
  }
  EXPECT_LT(und.strain.back()(0, 0), 0.0);  // axial extension along x
}

// A path that compresses a packing beyond solid stops there (material_point_path(kind=
// "isotropic", end=50) returned a volume fraction of 3e21), and 2^31 steps (~700 GB of series)
// are refused before any is run. A state without a volume fraction (0) runs as before.
TEST(Paths, APathBeyondSolidOrWithoutBoundOnItsStepsIsRefused) {
  auto law = make_law("isotropic_elastic");
  PathOptions o;
  o.steps = 200;
  const MaterialState dense =
      law->make_state(Eigen::Matrix3d::Identity() * 1e8, Eigen::Matrix3d::Identity() * 2.0, 0.6);
  const PathSeries beyond = isotropic_compression_path(*law, dense, 50.0, o);
  EXPECT_FALSE(beyond.success);
  EXPECT_NE(beyond.reason.find("step 3 of 200: the volume fraction reached 1.2702, outside [0, 1)"),
            std::string::npos)
      << beyond.reason;
  EXPECT_TRUE(isotropic_compression_path(*law, dense, 0.5, o).success);  // nu 0.6 e^0.5 < 1
  const MaterialState unknown =
      law->make_state(Eigen::Matrix3d::Identity() * 1e8, Eigen::Matrix3d::Identity() * 2.0, 0.0);
  EXPECT_TRUE(undrained_axisymmetric_path(*law, unknown, -0.05, o).success);
  // A NaN end (material_point_path(end=nan)) is refused before the first step; it read "step 1
  // of 200: non-finite strain increment".
  const PathSeries nan_end = undrained_axisymmetric_path(*law, dense, std::nan(""), o);
  EXPECT_EQ(nan_end.reason, "the path's end strain is not finite");
  EXPECT_TRUE(nan_end.stress.empty());
  o.steps = PathOptions::kMaxSteps + 1;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "steps must be in [1, 1000000]");
}

TEST(Paths, EveryLawRunsBothPaths) {
  for (const std::string& name : law_names()) {
    auto law = make_law(name);
    const double p0 = name == "hypoplastic_wu" ? 1e5 : 2e9;  // sand in kPa, DEM scale in GPa
    const MaterialState s =
        law->make_state(Eigen::Matrix3d::Identity() * p0, Eigen::Matrix3d::Identity() * 2.0, 0.82);
    PathOptions o;
    o.steps = 64;
    const PathSeries iso = isotropic_compression_path(*law, s, 0.01, o);
    ASSERT_TRUE(iso.success) << name << ": " << iso.reason;
    EXPECT_GT(pressure(iso.stress.back()), p0) << name;
    const PathSeries und = undrained_axisymmetric_path(*law, s, -0.32, o);
    ASSERT_TRUE(und.success) << name << ": " << und.reason;
    EXPECT_EQ(und.stress.size(), 65u);
    for (const auto& st : und.stress) EXPECT_TRUE(st.allFinite()) << name;
    // Extension along x: the axial stress falls below the lateral ones.
    EXPECT_LT(und.stress.back()(0, 0), und.stress.back()(1, 1)) << name;
    EXPECT_NEAR(und.stress.back()(1, 1), und.stress.back()(2, 2), 1e-9 * p0) << name;
  }
}

TEST(Paths, ElastoplasticReachesItsSteadyState) {
  auto law = make_law("elastoplastic_fabric");
  const MaterialState s =
      law->make_state(Eigen::Matrix3d::Identity() * 2e9, Eigen::Matrix3d::Identity() * 2.0, 0.82);
  PathOptions o;
  o.steps = 100;
  const PathSeries und = undrained_axisymmetric_path(*law, s, -0.32, o);
  ASSERT_TRUE(und.success) << und.reason;
  const Eigen::Matrix3d& end = und.stress.back();
  // Stress ratio and fabric deviator approach M_ss and -F_dev_max exponentially with plastic
  // deviatoric strain; beta_F = 30 over ~0.3 leaves exp(-9) ~ 1e-4, beta_s = 10 leaves ~5%.
  const double ratio = signed_deviator(end) / pressure(end);
  EXPECT_LT(ratio, 0.0);
  EXPECT_NEAR(-ratio, law->parameter("M_ss") + law->parameter("m_e"), 0.1 * law->parameter("M_ss"));
  EXPECT_NEAR(signed_deviator(und.fabric.back()), -law->parameter("F_dev_max"),
              1e-3 * law->parameter("F_dev_max"));
  // The seed's Fig. 1: sigma_xx falls, sigma_yy = sigma_zz rise; F_xx falls, F_yy rises.
  EXPECT_LT(end(0, 0), 2e9);
  EXPECT_GT(end(1, 1), 2e9);
  EXPECT_LT(und.fabric.back()(0, 0), 2.0);
  EXPECT_GT(und.fabric.back()(1, 1), 2.0);
  // The ratio grows monotonically towards the steady state along the path.
  for (size_t i = 1; i < und.stress.size(); ++i)
    EXPECT_LE(signed_deviator(und.stress[i]) / pressure(und.stress[i]),
              signed_deviator(und.stress[i - 1]) / pressure(und.stress[i - 1]) + 1e-12);
}

// Drained triaxial: sigma_yy = sigma_zz held at the start's, no shear strain. The linear law's
// closed form is Young's modulus and Poisson's ratio: d sigma_xx = E d eps_xx, d eps_yy = -nu
// d eps_xx.
TEST(Paths, DrainedTriaxialOfTheLinearLawIsYoungAndPoisson) {
  auto law = make_law("isotropic_elastic");
  const double k = law->parameter("K"), g = law->parameter("G");
  const double young = 9 * k * g / (3 * k + g), poisson = (3 * k - 2 * g) / (2 * (3 * k + g));
  const MaterialState s =
      law->make_state(Eigen::Matrix3d::Identity() * 1e8, Eigen::Matrix3d::Identity() * 2.0, 0.7);
  PathOptions o;
  o.steps = 40;
  for (const double end : {0.01, -0.004}) {
    const PathSeries d = drained_triaxial_path(*law, s, end, o);
    ASSERT_TRUE(d.success) << d.reason;
    ASSERT_EQ(d.stress.size(), 41u);
    EXPECT_NEAR(d.strain.back()(0, 0), end, 1e-15);
    for (size_t i = 0; i < d.stress.size(); ++i) {
      const double ea = d.strain[i](0, 0);
      EXPECT_NEAR(d.stress[i](0, 0) - 1e8, young * ea, 1e-9 * young * std::abs(end));
      EXPECT_NEAR(d.stress[i](1, 1), 1e8, 1e-9 * 1e8);
      EXPECT_NEAR(d.stress[i](2, 2), 1e8, 1e-9 * 1e8);
      EXPECT_NEAR(d.strain[i](1, 1), -poisson * ea, 1e-9 * std::abs(end));
      EXPECT_NEAR(d.strain[i](2, 2), -poisson * ea, 1e-9 * std::abs(end));
      EXPECT_NEAR(d.eps_v[i], (1 - 2 * poisson) * ea, 1e-9 * std::abs(end));
      EXPECT_EQ(d.strain[i](0, 1), 0.0);
    }
  }
}

// The hypoplastic sand, sheared drained far enough, ends at its limit state: there the stress
// rate vanishes for the path's strain rate, so sigma_xx / sigma_yy is the limit surface's ratio,
// found from the law's equation by bisection (wu_limit.hpp), in compression and in extension.
TEST(Paths, DrainedTriaxialOfTheSandEndsOnItsLimitSurface) {
  auto law = make_law("hypoplastic_wu");
  const MaterialState s =
      law->make_state(1e5 * Eigen::Matrix3d::Identity(), Eigen::Matrix3d::Zero(), 0.6);
  PathOptions o;
  o.steps = 100;
  const struct {
    double end, limit;
  } cases[] = {{0.3, wu_limit_ratio(*law, 1e5)}, {-0.1, wu_limit_ratio(*law, 1e5, 1.0, 0.01)}};
  for (const auto& c : cases) {
    const PathSeries d = drained_triaxial_path(*law, s, c.end, o);
    ASSERT_TRUE(d.success) << d.reason;
    const Eigen::Matrix3d& end = d.stress.back();
    EXPECT_NEAR(end(1, 1), 1e5, 1e-8 * 1e5);
    EXPECT_NEAR(end(2, 2), 1e5, 1e-8 * 1e5);
    EXPECT_NEAR(end(0, 0) / end(1, 1), c.limit, 1e-6 * c.limit) << c.end;
  }
  // The bisections found the two sides of the surface: axial stress above the lateral in
  // compression, below it in extension.
  EXPECT_GT(cases[0].limit, 1.0);
  EXPECT_LT(cases[1].limit, 1.0);
}

TEST(Paths, ADrainedPathOfElastoplasticFabricReachesItsSteadyStateRatio) {
  auto law = make_law("elastoplastic_fabric");
  const MaterialState s =
      law->make_state(Eigen::Matrix3d::Identity() * 2e9, Eigen::Matrix3d::Identity() * 2.0, 0.82);
  PathOptions o;
  o.steps = 64;
  for (const double end : {0.3, -0.3}) {
    const PathSeries d = drained_triaxial_path(*law, s, end, o);
    ASSERT_TRUE(d.success) << d.reason;
    for (const auto& st : d.stress) {
      EXPECT_NEAR(st(1, 1), 2e9, 1e-8 * 2e9);
      EXPECT_NEAR(st(2, 2), 2e9, 1e-8 * 2e9);
    }
    const double ratio = signed_deviator(d.stress.back()) / pressure(d.stress.back());
    EXPECT_NEAR(std::abs(ratio), law->parameter("M_ss") + law->parameter("m_e"),
                0.1 * law->parameter("M_ss"))
        << end;
    EXPECT_EQ(ratio > 0.0, end > 0.0);
  }
}

TEST(Paths, ADrainedPathRefusesANonFiniteEndAndBadOptions) {
  auto law = make_law("isotropic_elastic");
  const MaterialState s =
      law->make_state(Eigen::Matrix3d::Identity() * 1e8, Eigen::Matrix3d::Identity() * 2.0, 0.7);
  EXPECT_EQ(drained_triaxial_path(*law, s, std::nan("")).reason,
            "the path's end strain is not finite");
  PathOptions o;
  o.steps = 0;
  EXPECT_EQ(drained_triaxial_path(*law, s, 0.01, o).reason,
            "invalid path options: steps must be in [1, 1000000]");
}

}  // namespace
}  // namespace rendulic::models
