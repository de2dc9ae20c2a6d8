// Tests of the run report (issue 8 item 1): the claims C1-C8 evaluated on synthetic results
// files whose envelopes come from known linear maps (plus a shift for the plastic ones), so
// every verdict is known in advance: all hold on a seed-like file, the right ones fail on a
// file that contradicts them, and absent data is "not measured", never a guess.
#include "report.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "rendulic/core/conventions.hpp"
#include "synthetic_results.hpp"

namespace rendulic::app {
namespace {
namespace fs = std::filesystem;
using testing::seed_like;

std::map<std::string, Claim> by_id(const std::vector<Claim>& claims) {
  std::map<std::string, Claim> m;
  for (const auto& c : claims) m[c.id] = c;
  return m;
}

TEST(Report, EveryClaimHoldsOnASeedLikeFile) {
  const auto claims = by_id(evaluate_claims(ResultsReader(seed_like("holds", false))));
  ASSERT_EQ(claims.size(), 8u);
  for (const auto& [id, c] : claims) EXPECT_EQ(c.verdict, "holds") << id << ": " << c.measured;
}

TEST(Report, AShiftedElasticEnvelopeFailsC1Only) {
  const auto claims = by_id(evaluate_claims(ResultsReader(seed_like("shifted", true))));
  EXPECT_EQ(claims.at("C1").verdict, "does not hold") << claims.at("C1").measured;
  EXPECT_EQ(claims.at("C5").verdict, "holds");
  EXPECT_EQ(claims.at("C8").verdict, "holds");
}

TEST(Report, AbsentDataIsNotMeasured) {
  const fs::path dir = fs::path(RENDULIC_TEST_TMP) / "app_report" / "empty";
  fs::remove_all(dir);
  {
    ResultsWriter w(dir / "results.h5");
    w.commit();
  }
  for (const auto& c : evaluate_claims(ResultsReader(dir / "results.h5")))
    EXPECT_EQ(c.verdict, "not measured") << c.id;
}

// A linear response at 2e-3 is the elastic response scaled (the paper run without dynamic
// probes has only that): the plastic claims are then not measured, not judged on it.
TEST(Report, LinearResponseIsNeverTakenForPlasticData) {
  const auto claims =
      by_id(evaluate_claims(ResultsReader(seed_like("lr_plastic", false, "linear_response"))));
  EXPECT_EQ(claims.at("C6").verdict, "not measured") << claims.at("C6").measured;
  EXPECT_EQ(claims.at("C7").verdict, "not measured") << claims.at("C7").measured;
  EXPECT_EQ(claims.at("C1").verdict, "holds");
}

TEST(Report, ReportIsWrittenAtomicallyWithTheClaimTable) {
  const fs::path f = seed_like("written", false);
  const fs::path md = write_report(f, /*with_figures=*/false);
  std::ifstream in(md);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(text.find("| C1 |"), std::string::npos);
  EXPECT_NE(text.find("| C8 |"), std::string::npos);
  EXPECT_FALSE(fs::exists(f.parent_path() / ".report.md.tmp"));
}

// C6 also says why it fails when it does: the plastic envelope's axes per unit strain over the
// elastic ones. The seed-like file's plastic map keeps the bulk stiffness and halves the shear
// stiffness at the first state, and has none left at the steady state.
double first_number_after(const std::string& text, const std::string& key) {
  const auto at = text.find(key);
  return at == std::string::npos ? std::nan("") : std::stod(text.substr(at + key.size()));
}

TEST(Report, C6ReportsThePlasticOverElasticStiffness) {
  const auto claims = by_id(evaluate_claims(ResultsReader(seed_like("stiffness", false))));
  const std::string& m = claims.at("C6").measured;
  EXPECT_NEAR(first_number_after(m, "major axis: "), 1.0, 0.02) << m;
  EXPECT_NEAR(first_number_after(m, "minor axis: "), 0.5, 0.03) << m;
  const std::string minor = m.substr(m.find("minor axis: "));
  EXPECT_NEAR(std::stod(minor.substr(minor.rfind(", ") + 2)), 0.0, 0.01) << m;
}

}  // namespace
}  // namespace rendulic::app
