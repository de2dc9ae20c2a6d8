// Calibration of a UMAT's PROPS (docs/umat.md "Calibration"): the hypoplastic UMAT of
// data/umat, calibrated against the same data as the built-in hypoplastic_wu, recovers the
// built-in law's fit (values to a small fraction of their standard errors, the standard errors
// and the yardstick score alike), with its Jacobian from central differences with the UMAT
// driver's increments frozen, checked here against the built-in law's exact (Jet) Jacobian.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <memory>

#include "rendulic/calibration/calibrate.hpp"
#include "rendulic/calibration/selection.hpp"
#include "rendulic/calibration/settings.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/models/umat.hpp"
#include "synthetic.hpp"

namespace rendulic::calibration {
namespace {

using testing::law_with;

std::shared_ptr<const models::UmatLaw> hypoplastic_umat() {
  return models::make_umat_law(
      std::string(RENDULIC_UMAT_DIR) + "/hypoplastic_wu.so",
      std::string(RENDULIC_SOURCE_DIR) + "/data/umat/hypoplastic_wu_params.toml");
}

// The soft packing of recovery_test.cpp (hypoplastic_wu ~100x softer than the published sand),
// envelopes at 2e-3 (integrated) and the undrained path, 1 % noise.
CalibrationData soft_packing_data() {
  const auto law =
      law_with("hypoplastic_wu", {{"c1", -0.9}, {"c2", -8.0}, {"c3", -7.0}, {"c4", 10.0}});
  testing::SyntheticSpec spec;
  spec.plastic_amplitude = 2e-3;
  spec.directions = 8;
  spec.path_end = -0.05;
  spec.path_samples = 10;
  spec.noise = {0.01, 5};
  return testing::synthetic_data(*law, spec);
}

TEST(UmatCalibration, JacobianOfFrozenIncrementsMatchesTheBuiltInJets) {
  models::set_session_umat(hypoplastic_umat());
  const CalibrationData d = soft_packing_data();
  const std::vector<double> p0 = {-1.0, -9.0, -6.0, 11.0};
  const auto builtin = models::make_law("hypoplastic_wu");
  const auto umat = models::make_law("umat");
  ASSERT_TRUE(umat);
  const std::vector<std::string> free = {"c1", "c2", "c3", "c4"};
  const std::vector<std::string> states = {"s0", "s1", "s2", "s3"};
  ObjectiveOptions oo;
  oo.step.tolerance = 1e-9;
  const Objective a("hypoplastic_wu", d, states, ParameterSpace(*builtin, p0, free), oo);
  const Objective b("umat", d, states, ParameterSpace(*umat, p0, free), oo);
  ASSERT_EQ(a.num_residuals(), b.num_residuals());
  EXPECT_FALSE(b.exact_derivatives());
  const std::vector<double> z = a.space().to_z(p0);
  ASSERT_EQ(z, b.space().to_z(p0));
  Eigen::VectorXd ra, rb;
  Eigen::MatrixXd ja, jb;
  ASSERT_TRUE(a.jacobian(z.data(), &ra, &ja));
  ASSERT_TRUE(b.jacobian(z.data(), &rb, &jb));
  EXPECT_LT((ra - rb).norm(), 1e-6 * ra.norm());
  for (int c = 0; c < ja.cols(); ++c)
    EXPECT_LT((ja.col(c) - jb.col(c)).norm(), 1e-5 * ja.col(c).norm()) << free[c];
}

TEST(UmatCalibration, HypoplasticUmatRecoversTheBuiltInFit) {
  models::set_session_umat(hypoplastic_umat());
  const CalibrationData d = soft_packing_data();
  CalibrationOptions o;
  o.model = "hypoplastic_wu";
  const CalibrationSummary builtin = calibrate(d, o);
  ASSERT_TRUE(builtin.fit.converged) << builtin.fit.report;
  o.model = "umat";
  const CalibrationSummary umat = calibrate(d, o);
  ASSERT_TRUE(umat.fit.converged) << umat.fit.report;
  std::cout << "built-in " << builtin.fit.seconds << " s, UMAT " << umat.fit.seconds << " s\n"
            << umat.BriefReport();
  EXPECT_EQ(umat.fit.jacobian, "numeric (central differences)");
  ASSERT_EQ(umat.fit.names, builtin.fit.names);  // c1..c4: the props with bounds
  for (std::size_t k = 0; k < umat.fit.names.size(); ++k) {
    const double se = builtin.fit.stderr_[k];
    ASSERT_TRUE(std::isfinite(se) && se > 0.0) << builtin.fit.names[k];
    EXPECT_LT(std::abs(umat.fit.values[k] - builtin.fit.values[k]), 0.01 * se) << umat.fit.names[k];
    EXPECT_NEAR(umat.fit.stderr_[k] / se, 1.0, 0.01) << umat.fit.names[k];
  }
  // The same yardstick: the same blocks, the same misfits.
  ASSERT_EQ(umat.score.blocks.size(), builtin.score.blocks.size());
  for (std::size_t b = 0; b < umat.score.blocks.size(); ++b) {
    EXPECT_EQ(umat.score.blocks[b].id, builtin.score.blocks[b].id);
    EXPECT_NEAR(umat.score.blocks[b].misfit / builtin.score.blocks[b].misfit, 1.0, 1e-3)
        << umat.score.blocks[b].id;
  }
  EXPECT_NEAR(umat.fitted_misfit / builtin.fitted_misfit, 1.0, 1e-3);
}

// A UMAT that returns NaN from its first increment (the example UMAT's PROPS(6), nan_beyond,
// at 1e-12) cannot be fitted: the calibration said "cost inf", exited 0 and wrote inf standard
// errors. It is an InputError that says where and what the UMAT returned.
TEST(UmatCalibration, AUmatThatCannotBeEvaluatedAtItsStartIsAnInputError) {
  models::UmatSpec spec = models::load_umat_parameters_toml(
      std::string(RENDULIC_SOURCE_DIR) + "/data/umat/hypoplastic_wu_params.toml");
  spec.props.insert(spec.props.end(), {0.0, 1e-12});  // no PNEWDT; NaN beyond |eps| 1e-12
  spec.prop_names.insert(spec.prop_names.end(), {"dstran_max", "nan_beyond"});
  const double inf = std::numeric_limits<double>::infinity();
  spec.lower.insert(spec.lower.end(), {-inf, -inf});
  spec.upper.insert(spec.upper.end(), {inf, inf});
  models::set_session_umat(std::make_shared<const models::UmatLaw>(
      std::string(RENDULIC_UMAT_DIR) + "/hypoplastic_wu.so", spec));
  CalibrationOptions o;
  o.model = "umat";
  std::string what;
  try {
    calibrate(soft_packing_data(), o);
  } catch (const InputError& e) {
    what = e.what();
  }
  models::set_session_umat(nullptr);
  EXPECT_EQ(what.rfind("calibration of umat: the model cannot be evaluated at its start "
                       "parameters: ",
                       0),
            0u)
      << what;
  EXPECT_NE(what.find("the UMAT returned NaN or inf in STRESS at increment KINC = 1"),
            std::string::npos)
      << what;
}

// The calibration stage's keys: model umat with calibration.umat and calibration.umat_params
// loads the UMAT and makes it the one make_law("umat") finds; without the library it is an
// InputError naming --umat, and "all" stays the built-in laws.
TEST(UmatCalibration, StageKeysLoadTheUmat) {
  models::set_session_umat(nullptr);
  CalibrationSettings s;
  s.model = "umat";
  EXPECT_THROW(calibration_plan(s), InputError);
  s.umat = std::string(RENDULIC_UMAT_DIR) + "/hypoplastic_wu.so";
  s.umat_params = std::string(RENDULIC_SOURCE_DIR) + "/data/umat/hypoplastic_wu_params.toml";
  const CalibrationPlan plan = calibration_plan(s);
  EXPECT_EQ(plan.models, std::vector<std::string>{"umat"});
  ASSERT_TRUE(models::session_umat());
  EXPECT_EQ(models::make_law("umat")->parameter_info()[3].name, "c4");
  s.model = "all";
  EXPECT_THROW(calibration_plan(s), InputError);  // --umat with another model
  s.umat.clear();
  EXPECT_EQ(calibration_plan(s).models, models::law_names());
}

}  // namespace
}  // namespace rendulic::calibration
