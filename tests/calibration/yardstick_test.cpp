// The common yardstick and the selection rule (docs/calibration.md "One yardstick", "Model
// selection"): the blocks and their normalisation do not depend on the law; a block's misfit is
// the relative rms of the predicted envelope against the data (recomputed here from the stored
// prediction); the block likelihood is the closed form of the docs; the noise estimate finds
// noise of a known size; the default held-out states; the rule on hand-made scores.
#include <gtest/gtest.h>

#include <cmath>

#include "rendulic/calibration/calibrate.hpp"
#include "rendulic/calibration/selection.hpp"
#include "synthetic.hpp"

namespace rendulic::calibration {
namespace {

using testing::law_with;

CalibrationSummary fit(const CalibrationData& d, const std::string& law) {
  CalibrationOptions o;
  o.model = law;
  return calibrate(d, o);
}

TEST(Yardstick, SameBlocksAndScalesForEveryLaw) {
  const auto law = law_with("anisotropic_elastic", {{"beta_A", 0.8}});
  testing::SyntheticSpec spec;
  spec.noise = {0.01, 3};
  const CalibrationData d = testing::synthetic_data(*law, spec);
  const CalibrationSummary a = fit(d, "isotropic_elastic");
  const CalibrationSummary b = fit(d, "anisotropic_elastic");
  ASSERT_EQ(a.score.blocks.size(), b.score.blocks.size());
  ASSERT_EQ(a.score.blocks.size(), 2 * d.states.size());  // stress and fabric per state
  for (std::size_t i = 0; i < a.score.blocks.size(); ++i) {
    EXPECT_EQ(a.score.blocks[i].id, b.score.blocks[i].id);
    EXPECT_EQ(a.score.blocks[i].scale, b.score.blocks[i].scale);
    EXPECT_EQ(a.score.blocks[i].noise, b.score.blocks[i].noise);
    EXPECT_EQ(a.score.blocks[i].components, 72);  // 36 directions, 2 components
  }
}

TEST(Yardstick, BlockMisfitIsTheRelativeRmsOfTheStoredPrediction) {
  const auto law = law_with("anisotropic_elastic", {{"beta_A", 0.8}});
  testing::SyntheticSpec spec;
  spec.noise = {0.01, 4};
  const CalibrationData d = testing::synthetic_data(*law, spec);
  const CalibrationSummary s = fit(d, "isotropic_elastic");
  int checked = 0;
  for (const auto& b : s.score.blocks) {
    const StateData& st = *d.find(b.state);
    const EnvelopeRecord& data = st.envelopes[0];
    const StateSummary* ss = nullptr;
    for (const auto& x : s.states)
      if (x.label == b.state) ss = &x;
    ASSERT_TRUE(ss && !ss->predicted.empty());
    const EnvelopeRecord& pred = ss->predicted[0];
    const bool stress = b.kind == "stress_elastic";
    double diff2 = 0.0, data2 = 0.0;
    for (std::size_t i = 0; i < data.size(); ++i) {
      const Eigen::Vector2d dv = stress ? data.stress[i] : data.fabric[i];
      const Eigen::Vector2d pv = stress ? pred.stress[i] : pred.fabric[i];
      diff2 += (pv - dv).squaredNorm();
      data2 += dv.squaredNorm();
    }
    EXPECT_NEAR(b.misfit, std::sqrt(diff2 / data2), 1e-9 * b.misfit) << b.id;
    EXPECT_NEAR(b.scale, std::sqrt(data2 / data.size()), 1e-9 * b.scale) << b.id;
    ++checked;
  }
  EXPECT_EQ(checked, 8);
}

TEST(Yardstick, BlockDevianceIsTheClosedForm) {
  BlockScore b;
  b.components = 48;
  b.noise = 0.01;
  b.misfit = 0.05;  // above the noise: sigma = misfit, N (ln(pi m^2) + 1)
  EXPECT_NEAR(block_deviance(b), 48 * (std::log(M_PI * 0.05 * 0.05) + 1.0), 1e-12);
  b.misfit = 0.004;  // below: sigma = noise, N (ln(pi nu^2) + m^2 / nu^2)
  EXPECT_NEAR(block_deviance(b), 48 * (std::log(M_PI * 1e-4) + 0.16), 1e-12);
  // Fitting below the noise earns at most N (the quadratic term), never the log's -infinity.
  b.misfit = 0.0;
  EXPECT_NEAR(block_deviance(b), 48 * std::log(M_PI * 1e-4), 1e-12);
}

TEST(Yardstick, NoiseEstimateFindsNoiseOfAKnownSize) {
  const auto law = law_with("anisotropic_elastic", {{"beta_A", 0.8}});
  testing::SyntheticSpec spec;
  spec.directions = 72;
  spec.noise = {0.01, 8};  // 1 % of the rms response per component: sqrt(2) % per pair
  const CalibrationData d = testing::synthetic_data(*law, spec);
  const CalibrationSummary s = fit(d, "anisotropic_elastic");
  for (const auto& b : s.score.blocks)
    EXPECT_NEAR(b.noise / (0.01 * std::sqrt(2.0)), 1.0, 0.25) << b.id;
  // Noiseless data: the floor, not zero.
  const CalibrationData clean = testing::synthetic_data(*law, {});
  for (const auto& b : fit(clean, "anisotropic_elastic").score.blocks) {
    EXPECT_GT(b.noise, 0.0);
    EXPECT_LT(b.noise, 1e-5);
  }
}

TEST(Yardstick, DefaultHoldoutIsEverySecondInnerState) {
  CalibrationData d;
  for (const auto& [label, eps] : std::vector<std::pair<std::string, double>>{
           {"e", -0.32}, {"a", -0.006}, {"c", -0.043}, {"b", -0.021}, {"d", -0.068}}) {
    StateData s;
    s.label = label;
    s.eps_dev = eps;
    d.states.push_back(s);
  }
  EXPECT_EQ(default_holdout(d), (std::vector<std::string>{"b", "d"}));
  d.states.pop_back();  // a, b, c, e
  EXPECT_EQ(default_holdout(d), (std::vector<std::string>{"b"}));
  d.states.resize(2);
  EXPECT_TRUE(default_holdout(d).empty());
}

ModelScore fake(const std::string& name, int k, double m_fit, double m_held, bool fabric = true) {
  ModelScore m;
  m.model = name;
  m.n_free = k;
  m.fitted_states = {"a"};
  m.held_out_states = {"b"};
  for (const char* kind : {"stress_elastic", "fabric_elastic"}) {
    if (!fabric && std::string(kind) == "fabric_elastic") continue;
    for (const char* st : {"a", "b"}) {
      BlockScore b;
      b.state = st;
      b.envelope = "e";
      b.kind = kind;
      b.id = std::string(st) + "/e/" + kind;
      b.held_out = std::string(st) == "b";
      b.components = 100;
      b.noise = 1e-3;
      b.misfit = b.held_out ? m_held : m_fit;
      m.blocks.push_back(b);
    }
  }
  return m;
}

TEST(Yardstick, SelectionRule) {
  // Two laws fit equally: the simpler one (its BIC is lower by the penalty).
  Selection s = select_model({fake("rich", 6, 0.02, 0.02), fake("simple", 3, 0.02, 0.02)});
  EXPECT_EQ(s.selected, "simple");
  // The richer law fits far better: it is needed.
  s = select_model({fake("rich", 6, 0.01, 0.01), fake("simple", 3, 0.02, 0.02)});
  EXPECT_EQ(s.selected, "rich");
  // ... unless it predicts the held-out state worse (over-fitting).
  s = select_model({fake("rich", 6, 0.01, 0.05), fake("simple", 3, 0.02, 0.02)});
  EXPECT_EQ(s.selected, "simple");
  EXPECT_NE(s.sentence.find("held-out"), std::string::npos) << s.sentence;
  // A law without fabric does not compete on every block, but does on the stress blocks.
  s = select_model({fake("rich", 6, 0.02, 0.02), fake("nofabric", 2, 0.01, 0.01, false)});
  EXPECT_EQ(s.selected, "rich");
  EXPECT_EQ(s.selected_stress, "nofabric");
  for (const auto& r : s.rows) {
    if (r.model == "nofabric") {
      EXPECT_FALSE(r.covers_all);
    }
  }
  // Laws fitted on other states are left out of the comparison.
  ModelScore other = fake("other", 1, 0.001, 0.001);
  other.fitted_states = {"b"};
  other.held_out_states = {"a"};
  s = select_model({fake("rich", 6, 0.02, 0.02), fake("simple", 3, 0.02, 0.02), other});
  EXPECT_EQ(s.selected, "simple");
  EXPECT_EQ(s.sentence.find("Read with care"), std::string::npos) << s.sentence;
}

// The sentence names the other laws by rising BIC, whatever order they were fitted in (a run
// fits the scenario's laws in one order, `rendulic calibrate --model` in the user's).
TEST(Yardstick, TheSentenceDoesNotDependOnTheOrderOfTheLaws) {
  const ModelScore a = fake("simple", 3, 0.02, 0.02), b = fake("middle", 5, 0.0199, 0.02),
                   c = fake("rich", 8, 0.0198, 0.02);
  const Selection one = select_model({a, b, c}), other = select_model({c, a, b});
  EXPECT_EQ(one.selected, "simple");
  EXPECT_EQ(other.selected, "simple");
  EXPECT_EQ(one.sentence, other.sentence);
  // The others by rising BIC: middle (fewer parameters, nearly the same fit) before rich.
  double bic_middle = 0, bic_rich = 0;
  for (const auto& r : one.rows) {
    if (r.model == "middle") bic_middle = r.all.bic;
    if (r.model == "rich") bic_rich = r.all.bic;
  }
  ASSERT_LT(bic_middle, bic_rich);
  const auto m = one.sentence.find("middle ("), r = one.sentence.find("rich (");
  ASSERT_NE(m, std::string::npos) << one.sentence;
  ASSERT_NE(r, std::string::npos) << one.sentence;
  EXPECT_LT(m, r) << one.sentence;
}

// A law selected by BIC although it misses a block (misfit >= 1: no better than predicting no
// change) is flagged, naming the block and the best other law there.
TEST(Yardstick, ASelectedLawThatMissesABlockIsFlagged) {
  ModelScore simple = fake("simple", 3, 0.02, 0.02), rich = fake("rich", 9, 0.02, 0.02);
  for (auto* m : {&simple, &rich}) {
    BlockScore b;
    b.state = "a";
    b.kind = "path_stress";
    b.id = "path/stress";
    b.components = 10;
    b.noise = 1e-3;
    b.misfit = m == &simple ? 1.9 : 0.77;
    m->blocks.push_back(b);
  }
  const Selection s = select_model({simple, rich});
  ASSERT_EQ(s.selected, "simple") << s.sentence;  // few components: BIC barely sees the path
  EXPECT_NE(s.sentence.find("Read with care: simple"), std::string::npos) << s.sentence;
  EXPECT_NE(s.sentence.find("path_stress 1.9 (rich: 0.77)"), std::string::npos) << s.sentence;
}

}  // namespace
}  // namespace rendulic::calibration
