// Envelope fits in results files (docs/results.md fit_stress / fit_fabric): attributes written
// through core's ResultsWriter read back equal through ResultsReader; a circle stores no
// inclination; fit_all_envelopes fits every envelope of a file and marks the unfittable.
#include "rendulic/probes/fit_io.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#include "rendulic/core/errors.hpp"
#include "rendulic/core/results.hpp"
#include "synthetic.hpp"

namespace rendulic {
namespace {
namespace fs = std::filesystem;

fs::path fresh(const std::string& name) {
  const fs::path d = fs::path(RENDULIC_TEST_TMP) / "probes_io";
  fs::create_directories(d);
  fs::remove(d / name);
  return d / name;
}

TEST(FitIo, RoundTrip) {
  test::TrueEllipse e{{0.1, 0.2}, 1.0, 0.3, 40.0};
  const EnvelopeFit f = fit_envelope(test::ellipse_envelope(e, 36, 0.01, 3));
  test::TrueEllipse c{{0.0, 0.0}, 1.0, 1.0, 0.0};
  const EnvelopeFit fc = fit_envelope(test::ellipse_envelope(c, 36));
  ASSERT_EQ(fc.shape, FitShape::kCircle);
  const fs::path path = fresh("roundtrip.h5");
  {
    ResultsWriter w(path);
    write_envelope_fit(w, "/states/a/envelopes/e/fit_stress", f);
    write_envelope_fit(w, "/states/a/envelopes/e/fit_fabric", fc);
    w.commit();
  }
  ResultsReader r(path);
  const std::string g = "/states/a/envelopes/e/fit_stress";
  for (const char* key : {"shape", "center", "semi_axes", "inclination_deg", "rms", "center_stderr",
                          "semi_axes_stderr", "inclination_deg_stderr"})
    EXPECT_TRUE(r.has_attr(g, key)) << key;
  const EnvelopeFit b = read_envelope_fit(r, g);
  EXPECT_EQ(b.shape, f.shape);
  EXPECT_EQ(b.center, f.center);  // doubles stored as doubles: bit-exact
  EXPECT_EQ(b.a, f.a);
  EXPECT_EQ(b.b, f.b);
  EXPECT_EQ(*b.inclination_deg, *f.inclination_deg);
  EXPECT_EQ(b.rms, f.rms);
  EXPECT_EQ(b.a_stderr, f.a_stderr);
  EXPECT_EQ(*b.inclination_stderr_deg, *f.inclination_stderr_deg);
  EXPECT_EQ(b.selection_note, f.selection_note);
  EXPECT_EQ(b.line_p_value, f.line_p_value);

  const std::string gc = "/states/a/envelopes/e/fit_fabric";
  EXPECT_EQ(r.attr_string(gc, "shape"), "circle");
  EXPECT_FALSE(r.has_attr(gc, "inclination_deg"));
  EXPECT_FALSE(r.has_attr(gc, "inclination_deg_stderr"));
  EXPECT_FALSE(read_envelope_fit(r, gc).inclination_deg.has_value());
  EXPECT_THROW(read_envelope_fit(r, "/states/a/envelopes/e"), InputError);
}

TEST(FitIo, FitAllEnvelopesOfAFile) {
  const fs::path path = fresh("all.h5");
  test::TrueEllipse e{{0.0, 0.0}, 1e-3, 2e-5, 35.26};
  const Envelope stress = test::ellipse_envelope(e, 36, 0.0, 1, true);
  const Envelope fabric = test::line_envelope({0.0, 0.0}, 1e-4, 35.26, 36, 0.0, 1, true);
  {
    ResultsWriter w(path);
    for (const char* label : {"s1", "s2"}) {
      const std::string g = std::string("/states/") + label + "/envelopes/elastic";
      w.attr(g, "amplitude", 5e-5);
      w.write(g + "/theta_deg", stress.theta_deg);
      w.write(g + "/stress_star", stress.response);
      // s2's fabric does not change at all: nothing to fit, and it must say so.
      w.write(g + "/fabric", std::string(label) == "s1"
                                 ? fabric.response
                                 : std::vector<Eigen::Vector2d>(36, Eigen::Vector2d::Zero()));
    }
    w.commit();
  }
  const FitAllSummary s = fit_all_envelopes(path);
  EXPECT_EQ(s.fitted, 3);
  EXPECT_EQ(s.failed, 1);
  ResultsReader r(path);
  const EnvelopeFit fs1 = read_envelope_fit(r, "/states/s1/envelopes/elastic/fit_stress");
  EXPECT_EQ(fs1.shape, FitShape::kEllipse);
  EXPECT_NEAR(fs1.a, 1e-3, 1e-11);
  EXPECT_NEAR(fs1.b, 2e-5, 1e-11);
  EXPECT_EQ(read_envelope_fit(r, "/states/s1/envelopes/elastic/fit_fabric").shape, FitShape::kLine);
  EXPECT_EQ(r.attr_string("/states/s2/envelopes/elastic/fit_fabric", "shape"), "none");
  EXPECT_NE(r.attr_string("/states/s2/envelopes/elastic/fit_fabric", "error").find("coincide"),
            std::string::npos);
  // The envelope data are untouched by the update.
  EXPECT_EQ(r.read_pairs("/states/s1/envelopes/elastic/stress_star").size(), 36u);
}

// A refit replaces each fit group whole: an earlier failed fit's `error` stayed beside a new
// ellipse, and an earlier auto fit's line_p_value beside a refit of a given shape.
TEST(FitIo, ARefitKeepsNothingOfTheEarlierFit) {
  const fs::path path = fresh("refit.h5");
  test::TrueEllipse e{{0.0, 0.0}, 1e-3, 2e-5, 35.26};
  const Envelope stress = test::ellipse_envelope(e, 36, 0.0, 1, true);
  const std::string g = "/states/s1/envelopes/elastic";
  {
    ResultsWriter w(path);
    w.attr(g, "amplitude", 5e-5);
    w.write(g + "/theta_deg", stress.theta_deg);
    w.write(g + "/stress_star", stress.response);
    w.attr(g + "/fit_stress", "shape", "none");
    w.attr(g + "/fit_stress", "error", "an earlier failure");
    w.attr(g + "/fit_stress", "line_p_value", 0.5);
    w.commit();
  }
  FitOptions o;
  o.shape = FitShape::kEllipse;
  EXPECT_EQ(fit_all_envelopes(path, o).fitted, 1);
  ResultsReader r(path);
  EXPECT_EQ(r.attr_string(g + "/fit_stress", "shape"), "ellipse");
  for (const char* stale : {"error", "line_p_value"})
    EXPECT_FALSE(r.has_attr(g + "/fit_stress", stale)) << stale;
}

}  // namespace
}  // namespace rendulic
