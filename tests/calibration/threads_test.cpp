// The calibration's threads (docs/calibration.md "Threads"): a fit on one thread and on two
// (the likelihood's starts side by side, the exact Jacobians' passes and parts and the trial
// points' parts shared with a helper thread) gives the same bits: parameters, cost, standard
// errors and report alike.
#include <ceres/cost_function.h>
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <memory>
#include <vector>

#include "rendulic/calibration/objective.hpp"
#include "rendulic/calibration/solver.hpp"
#include "synthetic.hpp"

namespace rendulic::calibration {
namespace {

TEST(Threads, AFitIsTheSameBitsOnOneThreadAndOnTwo) {
  // The elasto-plastic law through the driver (integrated envelopes and the path), on noisy
  // data.
  const auto law = testing::law_with("elastoplastic_fabric", testing::kElastoplasticTruth);
  testing::SyntheticSpec spec;
  spec.states.erase(spec.states.begin(), spec.states.begin() + 2);  // two anisotropic states
  spec.directions = 6;
  spec.plastic_amplitude = 2e-3;
  spec.path_end = -0.08;
  spec.path_samples = 4;
  spec.noise.relative = 0.02;
  const CalibrationData d = testing::synthetic_data(*law, spec);
  // Five free parameters: two passes of Jets, each in its parts (the path, the envelopes). A
  // few iterations are enough to compare the bits, and keep the test short under the
  // sanitizers.
  const ParameterSpace space(*law, law->parameters(),
                             {"m_e", "M_ss", "beta_s", "beta_F", "F_dev_max"});
  const Objective objective("elastoplastic_fabric", d, d.labels(), space, {});
  std::vector<double> z0 = space.to_z(space.base());
  for (double& z : z0) z *= 1.1;  // away from the truth
  SolverOptions o;
  o.likelihood = true;
  o.max_iterations = 6;
  o.threads = 1;
  const FitResult one = solve(objective, z0, o);
  o.threads = 2;  // two, whatever the machine's count
  const FitResult two = solve(objective, z0, o);
  std::cout << one.report << "\n1 thread " << one.seconds << " s, 2 threads " << two.seconds
            << " s\n";
  ASSERT_TRUE(std::isfinite(one.cost)) << one.report;
  ASSERT_GT(one.evaluations, 2) << one.report;
  ASSERT_EQ(one.z.size(), two.z.size());
  EXPECT_EQ(one.cost, two.cost);
  for (std::size_t k = 0; k < one.z.size(); ++k) {
    EXPECT_EQ(one.z[k], two.z[k]) << one.names[k];
    EXPECT_EQ(one.stderr_[k], two.stderr_[k]) << one.names[k];
  }
  EXPECT_EQ(one.report, two.report);

  // The values alone, as Ceres asks for them at a trial point: after a fit on two threads a
  // core is free, so the parts go to a helper; the residuals are those of one pass on this
  // thread, bit for bit, and points where the law cannot be evaluated (some corners of the
  // box) fail in both; the test counts that there are some.
  const std::unique_ptr<ceres::CostFunction> cost(objective.make_cost_function());
  const int n = objective.num_residuals();
  std::vector<std::vector<double>> points = {z0, {two.z.begin(), two.z.end()}};
  for (int k = 0; k < space.size(); ++k)
    for (const double bound : {space.z_lower(k), space.z_upper(k)}) {
      points.emplace_back(two.z.begin(), two.z.end());
      points.back()[k] = bound;
    }
  int failed = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    std::vector<double> shared(n, 0.0), alone(n, 0.0);
    const double* params[1] = {points[i].data()};
    const bool ok_shared = cost->Evaluate(params, shared.data(), nullptr);
    const bool ok_alone = objective.residuals(points[i].data(), alone.data());
    EXPECT_EQ(ok_shared, ok_alone) << "point " << i;
    failed += ok_alone ? 0 : 1;
    if (!ok_shared || !ok_alone) continue;
    for (int k = 0; k < n; ++k)
      EXPECT_EQ(shared[k], alone[k]) << "point " << i << ", residual " << k;
  }
  std::cout << failed << " of " << points.size() << " points cannot be evaluated\n";
  EXPECT_GT(failed, 0);
}

}  // namespace
}  // namespace rendulic::calibration
