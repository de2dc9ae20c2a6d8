// Exact derivatives through the driver (docs/calibration.md "Predictions and derivatives"):
// the Jacobian of Jets pushed through the integrated probes and the path agrees with central
// differences of the same objective (an independent method), for the hypoplastic law (no yield
// surface) and for the elasto-plastic law (elastic start, yield-surface crossing inside most
// probes, plastic loading), at parameters away from the data's.
#include <gtest/gtest.h>

#include <iostream>

#include "rendulic/calibration/objective.hpp"
#include "synthetic.hpp"

namespace rendulic::calibration {
namespace {

using testing::law_with;

struct Jacobians {
  Eigen::MatrixXd exact, central;
  Eigen::VectorXd r_exact, r_central;
};

// The exact Jacobian (Jets through the driver's substeps at tolerance exact_tolerance: the
// derivative of the integrator's discrete map, which tends to the true sensitivity as the
// tolerance falls) and central differences of the residuals with step h in the working
// coordinates, on an objective integrated far more tightly (the difference quotient needs the
// objective smooth far below h; the driver's yield event is located to 1e-9 of the elastic
// range, so h = 1e-4 keeps that jitter at 1e-5).
Jacobians both(const std::string& law_name, const CalibrationData& d, const ParameterSpace& space,
               double h, double exact_tolerance) {
  ObjectiveOptions exact;
  exact.step.tolerance = exact_tolerance;
  exact.step.max_substeps = 100000;
  ObjectiveOptions tight = exact;
  tight.step.tolerance = 1e-12;
  tight.derivatives = Derivatives::kCentral;
  const Objective oe(law_name, d, d.labels(), space, exact);
  const Objective ot(law_name, d, d.labels(), space, tight);
  EXPECT_TRUE(oe.exact_derivatives());
  const std::vector<double> z = space.to_z(space.base());
  Jacobians j;
  EXPECT_TRUE(oe.jacobian(z.data(), &j.r_exact, &j.exact));
  const int n = ot.num_residuals();
  j.r_central.resize(n);
  EXPECT_TRUE(ot.residuals(z.data(), j.r_central.data()));
  j.central.resize(n, space.size());
  for (int k = 0; k < space.size(); ++k) {
    std::vector<double> zp = z, zm = z;
    zp[k] += h;
    zm[k] -= h;
    Eigen::VectorXd rp(n), rm(n);
    EXPECT_TRUE(ot.residuals(zp.data(), rp.data()));
    EXPECT_TRUE(ot.residuals(zm.data(), rm.data()));
    j.central.col(k) = (rp - rm) / (2.0 * h);
  }
  return j;
}

// Column by column: relative to the column's norm, so that every parameter counts.
double worst_column_error(const Jacobians& j, const std::vector<std::string>& names) {
  double worst = 0.0;
  for (Eigen::Index c = 0; c < j.exact.cols(); ++c) {
    const double e =
        (j.exact.col(c) - j.central.col(c)).norm() / std::max(j.central.col(c).norm(), 1e-300);
    std::cout << "  " << names[c] << ": |J_exact - J_central| / |J_central| = " << e << "\n";
    worst = std::max(worst, e);
  }
  return worst;
}

TEST(Derivatives, HypoplasticExactMatchesCentralDifferences) {
  const auto law =
      law_with("hypoplastic_wu", {{"c1", -1.8}, {"c2", -16.0}, {"c3", -14.0}, {"c4", 20.0}});
  testing::SyntheticSpec spec;
  spec.directions = 12;
  spec.plastic_amplitude = 2e-3;
  spec.path_end = -0.05;
  spec.path_samples = 10;
  const CalibrationData d = testing::synthetic_data(*law, spec);
  const auto l2 = models::make_law("hypoplastic_wu");
  std::vector<double> p0 = {-1.6, -18.0, -12.0, 24.0};
  const ParameterSpace space(*l2, p0, {"c1", "c2", "c3", "c4"});
  const Jacobians j = both("hypoplastic_wu", d, space, 1e-4, 1e-9);
  EXPECT_LT((j.r_exact - j.r_central).norm(), 1e-5 * j.r_central.norm());
  EXPECT_LT(worst_column_error(j, space.names()), 1e-4);
}

TEST(Derivatives, ElastoplasticExactMatchesCentralDifferences) {
  const auto law = law_with("elastoplastic_fabric", testing::kElastoplasticTruth);
  testing::SyntheticSpec spec;
  spec.states.erase(spec.states.begin(), spec.states.begin() + 2);  // two anisotropic states
  spec.directions = 6;
  spec.plastic_amplitude = 2e-3;
  spec.path_end = -0.08;
  spec.path_samples = 4;
  const CalibrationData d = testing::synthetic_data(*law, spec);
  const auto l2 = testing::law_with("elastoplastic_fabric", {{"B", 2.0e10},
                                                             {"G", 3.3e9},
                                                             {"beta_A", 0.6},
                                                             {"c_F", 5.0},
                                                             {"p_ref", 2e9},
                                                             {"n_p", 0.3},
                                                             {"a_G", 1.0},
                                                             {"m_e", 3e-3},
                                                             {"M_ss", 0.6},
                                                             {"beta_s", 25.0},
                                                             {"beta_F", 40.0},
                                                             {"F_dev_max", 0.4}});
  const ParameterSpace space(
      *l2, l2->parameters(),
      {"B", "G", "beta_A", "c_F", "n_p", "a_G", "m_e", "M_ss", "beta_s", "beta_F", "F_dev_max"});
  const Jacobians j = both("elastoplastic_fabric", d, space, 1e-4, 1e-9);
  EXPECT_LT((j.r_exact - j.r_central).norm(), 1e-6 * j.r_central.norm());
  EXPECT_LT(worst_column_error(j, space.names()), 1e-4);
  // At the calibration's default tolerance (1e-6) the derivative of the discrete map is still
  // within 1 % of the sensitivity: what Levenberg-Marquardt needs.
  Jacobians jd = j;
  ObjectiveOptions defaults;
  const Objective od("elastoplastic_fabric", d, d.labels(), space, defaults);
  const std::vector<double> z = space.to_z(space.base());
  ASSERT_TRUE(od.jacobian(z.data(), &jd.r_exact, &jd.exact));
  EXPECT_LT(worst_column_error(jd, space.names()), 1e-2);
}

}  // namespace
}  // namespace rendulic::calibration
