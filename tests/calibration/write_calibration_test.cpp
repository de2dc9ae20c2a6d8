// The /calibration/<model> group (docs/results.md; calibration/report.hpp): every parameter's
// standard error lands beside that parameter. The free parameters come out of the solver in
// their own order (B, G, beta_A, c_F, n_p, a_G), not the law's (..., n_p, p_ref, a_G, c_F), so
// a positional copy would pair values with the wrong errors; this reads the file back.
#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>

#include "rendulic/calibration/calibrate.hpp"
#include "rendulic/calibration/report.hpp"
#include "rendulic/core/results.hpp"
#include "synthetic.hpp"

namespace rendulic::calibration {
namespace {

TEST(WriteCalibration, StandardErrorsSitBesideTheirParameters) {
  const auto law = testing::law_with("anisotropic_elastic", {{"B", 2.2e10},
                                                             {"G", 3.0e9},
                                                             {"beta_A", 0.8},
                                                             {"n_p", 0.5},
                                                             {"p_ref", 1.8e9},
                                                             {"a_G", 2.0},
                                                             {"c_F", 4.0}});
  testing::SyntheticSpec spec;
  spec.noise.relative = 2e-3;  // finite, distinct standard errors
  const CalibrationData d = testing::synthetic_data(*law, spec);
  CalibrationOptions o;
  o.model = "anisotropic_elastic";
  o.values = {{"p_ref", 1.8e9}};
  const CalibrationSummary s = calibrate(d, o);
  ASSERT_TRUE(s.fit.converged) << s.fit.report;

  const auto dir = std::filesystem::path(RENDULIC_TEST_TMP) / "write_calibration";
  std::filesystem::create_directories(dir);
  const auto file = dir / "c.h5";
  {
    ResultsWriter w(file);
    write_calibration(w, s);
    w.commit();
  }
  const ResultsReader r(file);
  const std::string g = "/calibration/anisotropic_elastic";
  const std::vector<double> p = r.read_vector(g + "/params");
  const std::vector<double> se = r.read_vector(g + "/stderr");
  const std::vector<std::string> names = r.attr_strings(g, "param_names");
  ASSERT_EQ(names.size(), p.size());
  ASSERT_EQ(se.size(), p.size());
  std::size_t matched = 0;
  for (std::size_t k = 0; k < s.fit.names.size(); ++k)
    for (std::size_t i = 0; i < names.size(); ++i)
      if (names[i] == s.fit.names[k]) {
        EXPECT_EQ(se[i], s.fit.stderr_[k]) << names[i];
        EXPECT_EQ(p[i], s.fit.values[k]) << names[i];
        ++matched;
      }
  EXPECT_EQ(matched, s.fit.names.size());
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == "p_ref") {
      EXPECT_EQ(se[i], 0.0);  // fixed: not estimated
    }
  }
}

}  // namespace
}  // namespace rendulic::calibration
