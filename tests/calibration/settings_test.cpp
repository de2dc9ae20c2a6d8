// CalibrationSettings (calibration/settings.hpp): the calibration.* keys carry its defaults,
// and calibration_plan() is the one translation of the settings that the run stage and
// `rendulic calibrate` share.
#include "rendulic/calibration/settings.hpp"

#include <gtest/gtest.h>

#include "input_error.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/models/law.hpp"

namespace rendulic::calibration {
namespace {

using rendulic::testing::input_error;

TEST(CalibrationSettings, KeysCarryTheStructsDefaults) {
  ScenarioSchema schema;
  register_calibration_keys(schema);
  const CalibrationSettings d;
  const CalibrationSettings s = calibration_settings_from(Scenario(schema));
  EXPECT_EQ(s.model, d.model);
  EXPECT_EQ(s.holdout, d.holdout);
  EXPECT_EQ(s.max_iterations, d.max_iterations);
  EXPECT_EQ(s.function_tolerance, kDemFunctionTolerance);
  EXPECT_EQ(s.driver_tolerance, 1e-6);  // the driver's own default (docs/models.md "Tolerance")
  EXPECT_EQ(s.max_substeps, ObjectiveOptions{}.step.max_substeps);
  // The third-order pair where a law has no yield surface (docs/calibration.md).
  EXPECT_EQ(s.driver_scheme, "auto");
  EXPECT_EQ(calibration_plan(s).options.objective.step.scheme, models::Scheme::kAuto);
  EXPECT_EQ(std::get<double>(schema.find("calibration.function_tolerance")->default_value),
            kDemFunctionTolerance);
}

TEST(CalibrationSettings, PlanTranslatesOnce) {
  CalibrationSettings s;
  s.model = "all";
  s.holdout = {"none"};
  s.path = false;
  s.features = true;
  s.max_iterations = 17;
  s.driver_tolerance = 1e-4;
  s.max_substeps = 5000;
  CalibrationPlan p = calibration_plan(s);
  EXPECT_EQ(p.options.objective.step.tolerance, 1e-4);
  EXPECT_EQ(p.options.objective.step.max_substeps, 5000);
  s.driver_scheme = "bogacki-shampine";
  EXPECT_EQ(calibration_plan(s).options.objective.step.scheme, models::Scheme::kBogackiShampine);
  s.driver_scheme = "auto";
  EXPECT_EQ(p.models, models::law_names());
  EXPECT_TRUE(p.options.holdout.empty());
  EXPECT_FALSE(p.options.objective.path);
  EXPECT_FALSE(p.load.load_path);
  EXPECT_TRUE(p.options.objective.envelope_features);
  EXPECT_EQ(p.options.solver.max_iterations, 17);
  EXPECT_EQ(p.options.solver.gradient_tolerance, kDemGradientTolerance);
  // A held-out state is loaded with an explicit list of states, once.
  s.model = "isotropic_elastic";
  s.states = {"a", "c"};
  s.holdout = {"b", "c"};
  p = calibration_plan(s);
  EXPECT_EQ(p.models, std::vector<std::string>{"isotropic_elastic"});
  EXPECT_EQ(p.load.states, (std::vector<std::string>{"a", "c", "b"}));
  // Every state (an empty list) stays every state.
  s.states.clear();
  EXPECT_TRUE(calibration_plan(s).load.states.empty());
}

TEST(CalibrationSettings, OutOfRangeIsRefusedNamingTheKey) {
  CalibrationSettings s;
  s.function_tolerance = 0.5;
  const std::string what = input_error([&] { calibration_plan(s); });
  EXPECT_NE(what.find("calibration.function_tolerance"), std::string::npos) << what;
  s = {};
  s.max_iterations = 0;
  EXPECT_THROW(calibration_plan(s), InputError);
  s = {};
  s.max_substeps = 1;
  EXPECT_THROW(calibration_plan(s), InputError);
  // Only the adaptive schemes: explicit Euler's one fixed substep would fit nothing well.
  for (const char* bad : {"explicit", "rk4"}) {
    s = {};
    s.driver_scheme = bad;
    const std::string m = input_error([&] { calibration_plan(s); });
    EXPECT_NE(m.find("calibration.driver_scheme"), std::string::npos) << bad << ": " << m;
  }
  // A state listed twice to fit or to hold out (`calibrate --states a,a`) is refused, not fitted
  // once or counted twice.
  s = {};
  s.states = {"a", "b", "a"};
  EXPECT_EQ(input_error([&] { calibration_plan(s); }), "calibration.states: value 'a' given twice");
  s = {};
  s.holdout = {"b", "b"};
  EXPECT_EQ(input_error([&] { calibration_plan(s); }),
            "calibration.holdout: value 'b' given twice");
}

}  // namespace
}  // namespace rendulic::calibration
