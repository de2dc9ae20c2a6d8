// `rendulic bench` (docs/performance.md "Commands", "The same steps for every figure"): every
// figure of a state times the same steps of the same trajectory, the settings in alternated
// rounds with each round's figure and the cores' round trip between rounds in the JSON, and
// --steps fixes the span. Nothing here is timed: the test reads what the bench says it did.
#include <gtest/gtest.h>

#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_runner.hpp"

namespace {
using rendulic::testing::run_rendulic;

nlohmann::json bench_json(const std::string& args) {
  const auto r = run_rendulic("bench --json --particles 200 " + args, false);
  EXPECT_EQ(r.code, 0) << r.err;
  return nlohmann::json::parse(r.out);
}

TEST(Bench, EveryFigureOfAStateTimesTheSameStepsInAlternatedRounds) {
  const nlohmann::json rows = bench_json("--repetitions 3 --seconds 0.02 --friction 0.5");
  std::map<double, std::int64_t> steps;  // per volume fraction
  int settings = 0, laws = 0;
  for (const auto& row : rows) {
    const double nu = row.at("volume_fraction");
    const std::int64_t s = row.at("steps");
    EXPECT_GT(s, 0);
    // The first figure of the state sets the span; every other one, frictional ones included,
    // times the same steps.
    if (steps.count(nu))
      EXPECT_EQ(s, steps[nu]) << row.dump();
    else
      steps[nu] = s;
    if (row.contains("friction")) {
      ++laws;
      continue;
    }
    ++settings;
    ASSERT_EQ(row.at("ns_per_particle_step_rounds").size(), 3u) << row.dump();
    double best = 1e300;
    for (const double x : row.at("ns_per_particle_step_rounds")) {
      EXPECT_GT(x, 0);
      best = std::min(best, x);
    }
    EXPECT_DOUBLE_EQ(row.at("ns_per_particle_step").get<double>(), best);
    // Where two CPUs are allowed, one round trip before each round and one after the last.
    if (row.contains("core_round_trip_ns_rounds")) {
      EXPECT_EQ(row.at("core_round_trip_ns_rounds").size(), 4u);
      EXPECT_EQ(row.at("core_round_trip_ns_before"), row.at("core_round_trip_ns_rounds").front());
      EXPECT_EQ(row.at("core_round_trip_ns_after"), row.at("core_round_trip_ns_rounds").back());
    }
  }
  EXPECT_EQ(steps.size(), 2u);
  EXPECT_EQ(settings, 6);  // 1 thread, 2 threads, the default; two states
  EXPECT_EQ(laws, 4);      // frictionless and frictional, one thread; two states
}

TEST(Bench, StepsFixesTheSpanOfEveryFigure) {
  for (const auto& row : bench_json("--repetitions 1 --steps 60 --threads 1"))
    EXPECT_EQ(row.at("steps").get<std::int64_t>(), 60) << row.dump();
  const auto r = run_rendulic("bench --particles 200 --steps 0");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--steps"), std::string::npos) << r.out;
}

}  // namespace
