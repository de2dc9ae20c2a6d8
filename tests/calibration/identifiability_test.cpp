// Set-ups the data cannot determine are detected and reported: states all at
// one pressure cannot separate B from its pressure exponent n_p (rank-deficient Jacobian); an
// isotropic fabric makes beta_A invisible (zero Jacobian column); near-collinear columns give a
// correlation warning. The detector itself is checked on matrices with a known rank.
#include <gtest/gtest.h>

#include "rendulic/calibration/calibrate.hpp"
#include "rendulic/calibration/uncertainty.hpp"
#include "synthetic.hpp"

namespace rendulic::calibration {
namespace {

using testing::law_with;

bool any_warning_mentions(const std::vector<std::string>& w, const std::string& a,
                          const std::string& b = "") {
  for (const auto& s : w)
    if (s.find(a) != std::string::npos && (b.empty() || s.find(b) != std::string::npos))
      return true;
  return false;
}

TEST(Identifiability, DetectorOnKnownRank) {
  Eigen::MatrixXd J(5, 3);
  J << 1, 2, 3, 4, 5, 9, 7, 8, 15, 1, 0, 1, 0, 1, 1;  // column 3 = column 1 + column 2
  const Eigen::VectorXd r = Eigen::VectorXd::Constant(5, 0.1);
  const Uncertainty u = estimate_uncertainty(J, r, {"a", "b", "c"}, Eigen::Vector3d(1, 1, 1),
                                             Eigen::Vector3d(1, 1, 1));
  EXPECT_EQ(u.rank, 2);
  EXPECT_TRUE(std::isinf(u.condition_number));
  EXPECT_TRUE(any_warning_mentions(u.warnings, "rank-deficient"));
  EXPECT_FALSE(u.determined[0] && u.determined[1] && u.determined[2]);
  Eigen::MatrixXd Jfull = J;
  Jfull(0, 2) += 0.5;
  const Uncertainty v = estimate_uncertainty(Jfull, r, {"a", "b", "c"}, Eigen::Vector3d(1, 1, 1),
                                             Eigen::Vector3d(1, 1, 1));
  EXPECT_EQ(v.rank, 3);
  EXPECT_TRUE(std::isfinite(v.condition_number));
}

TEST(Identifiability, OnePressureCannotSeparateBFromNp) {
  const auto law = law_with("anisotropic_elastic", {{"B", 2e10}, {"n_p", 0.5}, {"p_ref", 1e9}});
  testing::SyntheticSpec spec;
  // Same pressure (2 GPa) at every state, different anisotropy.
  spec.states = {
      {"a", 2.0e9, 2.0e9, 1.8, 1.8}, {"b", 1.6e9, 2.2e9, 1.6, 1.9}, {"c", 1.4e9, 2.3e9, 1.4, 2.0}};
  spec.noise = {0.005, 2};
  const CalibrationData d = testing::synthetic_data(*law, spec);
  CalibrationOptions o;
  o.model = "anisotropic_elastic";
  o.values = {{"p_ref", 1e9}};
  o.free = {"B", "G", "beta_A", "n_p"};
  const CalibrationSummary s = calibrate(d, o);
  EXPECT_LT(s.fit.uncertainty.rank, 4);
  EXPECT_TRUE(any_warning_mentions(s.warnings, "rank-deficient", "n_p")) << s.BriefReport();
  EXPECT_TRUE(any_warning_mentions(s.warnings, "rank-deficient", "B")) << s.BriefReport();
  EXPECT_FALSE(s.fit.uncertainty.determined[3]);  // n_p
}

TEST(Identifiability, IsotropicFabricHidesBetaA) {
  const auto law = law_with("anisotropic_elastic", {{"beta_A", 0.7}});
  testing::SyntheticSpec spec;
  spec.states = {{"iso", 2.0e9, 2.0e9, 1.8, 1.8}};
  const CalibrationData d = testing::synthetic_data(*law, spec);
  CalibrationOptions o;
  o.model = "anisotropic_elastic";
  o.free = {"B", "G", "beta_A"};
  const CalibrationSummary s = calibrate(d, o);
  EXPECT_TRUE(any_warning_mentions(s.warnings, "'beta_A' does not affect")) << s.BriefReport();
  EXPECT_TRUE(std::isinf(s.fit.stderr_[2]));
  // B and G stay determined and exact.
  EXPECT_NEAR(s.fit.values[0] / 2e10, 1.0, 1e-6);
  EXPECT_TRUE(s.fit.uncertainty.determined[0]);
}

}  // namespace
}  // namespace rendulic::calibration
