// Unit tests of the sweep's bookkeeping (app/sweep.hpp): the Pareto front
// against a brute-force definition, the account of where methods break (refused steps, the
// relaxation's noise floor, the onset of rate effects, the cheapest setting that meets the
// target) on hand-made points whose answers are known, the option checks and the CSV.
#include "sweep.hpp"

#include <gtest/gtest.h>

#include <random>

namespace {
using rendulic::app::SweepOptions;
using rendulic::app::SweepPoint;
using rendulic::app::SweepSummary;

SweepPoint point(const std::string& factor, double value, double error, double cpu,
                 const std::string& status = "ok") {
  SweepPoint p;
  p.factor = factor;
  p.value = value;
  p.method = "dynamic";
  p.error = error;
  p.cpu_s = cpu;
  p.status = status;
  p.meets_target = status == "ok" && error <= 0.02;
  return p;
}

bool contains(const std::vector<std::string>& lines, const std::string& text) {
  for (const auto& l : lines)
    if (l.find(text) != std::string::npos) return true;
  return false;
}

TEST(SweepPareto, MatchesTheBruteForceDefinition) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<SweepPoint> pts;
  for (int i = 0; i < 60; ++i) pts.push_back(point("relax", i, u(rng), u(rng)));
  pts.push_back(point("dt_factor", 0.3, 0, 0, "refused"));  // never on the front
  pts[3].envelope = "plastic";                              // elastic points only
  pts.push_back(point("method", 0, 0.0, 0.0));              // the reference: left out
  pts.back().method = "linear_response";
  rendulic::app::mark_pareto(pts);
  auto eligible = [](const SweepPoint& p) {
    return p.status == "ok" && p.envelope == "elastic" && p.method != "linear_response";
  };
  for (const SweepPoint& p : pts) {
    bool dominated = false;
    for (const SweepPoint& q : pts)
      if (eligible(q) && &q != &p && q.cpu_s <= p.cpu_s && q.error <= p.error) dominated = true;
    EXPECT_EQ(p.pareto, eligible(p) && !dominated);
  }
  // The cheapest and the most accurate eligible points are always on it.
  int n_front = 0;
  for (const SweepPoint& p : pts) n_front += p.pareto;
  EXPECT_GE(n_front, 2);
}

TEST(SweepBreaks, NamesRefusedStepsNoiseFloorRateOnsetAndCheapestSetting) {
  SweepSummary s;
  s.options.target = 0.02;
  s.stability_limit_factor = 0.183;
  s.points = {point("dt_factor", 0.01, 0.015, 4.0), point("dt_factor", 0.05, 0.016, 1.0),
              point("dt_factor", 0.2, 0, 0, "refused"),
              // relaxation: falls until 1e-7, then a floor at ~0.01
              point("relax", 1e-4, 0.5, 0.1), point("relax", 1e-6, 0.1, 0.3),
              point("relax", 1e-7, 0.0105, 0.6), point("relax", 1e-8, 0.0100, 1.2),
              point("relax", 1e-9, 0.0102, 2.4),
              // rate: flat, then a rate effect from 1e-3
              point("inertial_number", 1e-5, 0.010, 3.0),
              point("inertial_number", 1e-4, 0.011, 1.0),
              point("inertial_number", 1e-3, 0.040, 0.9)};
  s.points[2].note = "refused: beyond stability (...)";
  rendulic::app::describe_breaks(s);
  EXPECT_TRUE(contains(s.breaks, "dt_factor = 0.2 (dynamic): refused: beyond stability"));
  EXPECT_TRUE(contains(s.breaks, "dt_factor: largest accepted 0.05"));
  EXPECT_TRUE(contains(s.breaks, "relax: noise floor error 0.01 reached at threshold 1e-07"));
  EXPECT_TRUE(contains(s.breaks, "inertial_number (elastic): rate effect from I = 0.001"));
  EXPECT_TRUE(contains(s.recommendations, "dt_factor: cheapest meeting error <= 0.02 is 0.05"));
  EXPECT_TRUE(contains(s.recommendations, "relax: cheapest meeting error <= 0.02 is 1e-07"));
  EXPECT_TRUE(contains(s.recommendations,
                       "inertial_number: cheapest meeting error <= 0.02 is "
                       "0.0001"));
  EXPECT_TRUE(contains(s.recommendations, "n_particles: no value meets"));
}

TEST(SweepBreaks, NoRateEffectIsSaidSo) {
  SweepSummary s;
  s.points = {point("inertial_number", 1e-5, 0.010, 3.0), point("inertial_number", 1e-3, 0.012, 1)};
  rendulic::app::describe_breaks(s);
  EXPECT_TRUE(contains(s.breaks, "no rate effect up to I = 0.001"));
}

TEST(SweepOptionsTest, PresetsAreValidAndBadValuesAreNamed) {
  std::string why;
  EXPECT_TRUE(SweepOptions::preset(true).IsValid(&why)) << why;
  EXPECT_TRUE(SweepOptions::preset(false).IsValid(&why)) << why;
  SweepOptions o = SweepOptions::preset(true);
  o.factors = {"relax", "speed"};
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("'speed'"), std::string::npos);
  EXPECT_NE(why.find("(dt_factor, n_particles, inertial_number, relax, dt_factor_tight, method, "
                     "path_rate)"),
            std::string::npos)
      << why;
  o.factors = {"relax", "dt_factor", "relax"};
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "sweep: factor 'relax' listed twice");
  o = SweepOptions::preset(true);
  o.path_rates = {400, 1000, 400};
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "sweep: path rate 400 listed twice");
  o = SweepOptions::preset(true);
  o.n_particles = {250.5};
  EXPECT_FALSE(o.IsValid(&why));
  o = SweepOptions::preset(true);
  o.inertial_numbers = {0.1};
  EXPECT_FALSE(o.IsValid(&why));
  o = SweepOptions::preset(true);
  o.target = 0;
  EXPECT_FALSE(o.IsValid(&why));
  o = SweepOptions::preset(true);
  o.methods = {"dynamic", "dynamc"};
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "sweep: method 'dynamc' is not one of dynamic, minimisation, linear_response");
}

TEST(SweepCsv, OneRowPerPointAndNoNumbersForPointsThatDidNotRun) {
  SweepSummary s;
  s.points = {point("relax", 1e-7, 0.01, 0.5), point("dt_factor", 0.3, 0, 0, "refused")};
  s.points[1].note = "refused: \"quoted\"";
  const std::string csv = rendulic::app::sweep_csv(s);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 3);
  const std::string refused = csv.substr(csv.find("dt_factor,0.3"));
  EXPECT_NE(refused.find(",refused,"), std::string::npos);
  EXPECT_EQ(refused.find("nan"), std::string::npos);
  EXPECT_NE(refused.find(",,,,"), std::string::npos);  // empty numeric cells
  EXPECT_EQ(refused.find("\"quoted\""), std::string::npos);
}

}  // namespace
