// The calibration's threads (docs/calibration.md "Threads"): a fit on one thread and on two
// (the likelihood's starts side by side, the exact Jacobians' passes and parts shared with a
// helper thread) gives the same bits: parameters, cost, standard errors and report alike.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "rendulic/calibration/calibrate.hpp"
#include "synthetic.hpp"

namespace rendulic::calibration {
namespace {

TEST(Threads, AFitIsTheSameBitsOnOneThreadAndOnTwo) {
  // The elasto-plastic law through the driver (integrated envelopes and the path: Jets of
  // ~10 ms a Jacobian, long enough for the two threads to overlap), on noisy data.
  const auto law = testing::law_with("elastoplastic_fabric", testing::kElastoplasticTruth);
  testing::SyntheticSpec spec;
  spec.directions = 8;
  spec.plastic_amplitude = 2e-3;
  spec.path_end = -0.08;
  spec.path_samples = 6;
  spec.noise.relative = 0.02;
  const CalibrationData d = testing::synthetic_data(*law, spec);
  CalibrationOptions o;
  o.model = "elastoplastic_fabric";
  o.solver.threads = 1;
  const CalibrationSummary one = calibrate(d, o);
  o.solver.threads = 2;  // two, whatever the machine's count
  const CalibrationSummary two = calibrate(d, o);
  std::cout << one.fit.report << "\n1 thread " << one.fit.seconds << " s, 2 threads "
            << two.fit.seconds << " s\n";
  ASSERT_TRUE(std::isfinite(one.fit.cost)) << one.fit.report;
  ASSERT_EQ(one.fit.z.size(), two.fit.z.size());
  EXPECT_EQ(one.fit.cost, two.fit.cost);
  for (std::size_t k = 0; k < one.fit.z.size(); ++k) {
    EXPECT_EQ(one.fit.z[k], two.fit.z[k]) << one.fit.names[k];
    EXPECT_EQ(one.fit.stderr_[k], two.fit.stderr_[k]) << one.fit.names[k];
  }
  EXPECT_EQ(one.fit.report, two.fit.report);
}

}  // namespace
}  // namespace rendulic::calibration
