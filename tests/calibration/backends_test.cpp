// Every back end and the feature objective reach the same optimum on a problem with a known
// answer (noiseless anisotropic-elastic envelopes), from a start far from it: the multi-start
// and BOBYQA (+ Ceres polish) paths of solver.cpp, and the envelope-feature objective (the
// affine (c, M) of each envelope instead of its points).
#include <gtest/gtest.h>

#include "rendulic/calibration/calibrate.hpp"
#include "rendulic/core/errors.hpp"
#include "synthetic.hpp"

namespace rendulic::calibration {
namespace {

using testing::law_with;

// Noiseless and exact: 1e-6 relative.
constexpr double kNoiseless = 1e-6;

class Backends : public ::testing::Test {
 protected:
  void SetUp() override {
    law_ = law_with("anisotropic_elastic",
                    {{"B", 2.2e10}, {"G", 3e9}, {"beta_A", 0.8}, {"c_F", 4.0}, {"p_ref", 1.8e9}});
    data_ = testing::synthetic_data(*law_, {});
    options_.model = "anisotropic_elastic";
    options_.free = {"B", "G", "beta_A", "c_F"};
    // A poor start: moduli a decade off, coupling of the wrong sign.
    options_.values = {{"p_ref", 1.8e9}, {"B", 2e9}, {"G", 3e10}, {"beta_A", -2.0}, {"c_F", 1.0}};
    options_.level_one_start = false;
  }
  void expect_recovered(const CalibrationSummary& s) {
    ASSERT_TRUE(s.fit.converged) << s.fit.report;
    for (std::size_t k = 0; k < s.fit.names.size(); ++k)
      EXPECT_NEAR(s.fit.values[k] / law_->parameter(s.fit.names[k]), 1.0, kNoiseless)
          << s.fit.names[k] << " " << s.fit.report;
  }
  std::unique_ptr<models::Law> law_;
  CalibrationData data_;
  CalibrationOptions options_;
};

TEST_F(Backends, MultiStart) {
  options_.solver.backend = Backend::kMultiStart;
  options_.solver.starts = 3;
  const CalibrationSummary s = calibrate(data_, options_);
  expect_recovered(s);
  EXPECT_NE(s.fit.report.find("ceres start 2"), std::string::npos);
}

TEST_F(Backends, BobyqaThenCeresPolish) {
  options_.solver.backend = Backend::kLocalNlopt;
  options_.solver.local_evaluations = 400;
  const CalibrationSummary s = calibrate(data_, options_);
  expect_recovered(s);
  EXPECT_NE(s.fit.report.find("BOBYQA"), std::string::npos) << s.fit.report;
}

TEST_F(Backends, FeatureObjective) {
  options_.objective.envelope_points = false;
  options_.objective.envelope_features = true;
  const CalibrationSummary s = calibrate(data_, options_);
  expect_recovered(s);
  for (const auto& b : s.blocks) EXPECT_NE(b.kind.find("features"), std::string::npos);
}

// A probe direction of -1e308 deg (the readers refuse it in a file: envelope_io) has no finite
// radians, so the predictions and the cost at the start are nan: the fit stops there and says
// why. Ceres's gradient tolerance, relative to that cost, was nan, and Ceres blamed its own
// configuration ("Solver::Options::gradient_tolerance = nan").
TEST_F(Backends, AnObjectiveThatIsNotFiniteAtTheStartSaysSo) {
  data_.states[0].envelopes[0].theta_deg[5] = -1e308;
  const CalibrationSummary s = calibrate(data_, options_);
  EXPECT_FALSE(s.fit.converged) << s.fit.report;
  EXPECT_NE(s.fit.report.find("the objective at the start point is nan (a datum or a prediction "
                              "is not finite there)"),
            std::string::npos)
      << s.fit.report;
  EXPECT_EQ(s.fit.report.find("gradient_tolerance"), std::string::npos) << s.fit.report;
}

TEST_F(Backends, BadOptionsAreInputErrors) {
  options_.free = {"B", "nope"};
  EXPECT_THROW(calibrate(data_, options_), InputError);
  options_.free = {"B"};
  options_.bounds = {{"B", {1e12, 1e11}}};
  EXPECT_THROW(calibrate(data_, options_), InputError);
  options_.bounds.clear();
  options_.holdout = {"s0", "s1", "s2", "s3"};
  EXPECT_THROW(calibrate(data_, options_), InputError);
  options_.holdout.clear();
  options_.model = "no_such_law";
  EXPECT_THROW(calibrate(data_, options_), InputError);
}

}  // namespace
}  // namespace rendulic::calibration
