// `rendulic bench` (docs/performance.md "Commands", "The same steps for every figure"): every
// figure of a state times the same steps of the same trajectory, the settings in alternated
// rounds with each round's figure and the cores' round trip between rounds in the JSON, and
// --steps fixes the span, and --phases says where a step goes per thread. Nothing here is timed:
// the test reads what the bench says it did.
#include <gtest/gtest.h>

#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <utility>
#include <vector>

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

// --phases: one more run per setting over the same steps, the time per step of each phase for
// each thread of the team; the phases and "other" add up to the run's wall time per step, which
// the bench does not report, so the test checks the parts: non-negative, one object per member
// of the team (N = 1000 allows a team of two), list builds and "other" on thread 0 only.
TEST(Bench, PhasesSayWhereAStepGoesPerThreadOfTheTeam) {
  const auto r = run_rendulic(
      "bench --json --particles 1000 --repetitions 1 --steps 40 --threads 1 2 --phases", false);
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json rows = nlohmann::json::parse(r.out);
  int teams_of_two = 0;
  for (const auto& row : rows) {
    ASSERT_TRUE(row.contains("phases_us_per_step")) << row.dump();
    const auto& threads = row.at("phases_us_per_step");
    const int t = row.at("threads");
    if (t > 0) {
      EXPECT_EQ(threads.size(), static_cast<std::size_t>(t)) << row.dump();
    }
    teams_of_two += t == 2;
    for (std::size_t k = 0; k < threads.size(); ++k) {
      const auto& p = threads[k];
      EXPECT_EQ(p.at("thread").get<std::size_t>(), k);
      for (const char* key : {"kick", "wait_kick", "forces", "wait_forces", "finish"})
        EXPECT_GE(p.at(key).get<double>(), 0.0) << key << " " << row.dump();
      EXPECT_EQ(p.contains("list"), k == 0);
      EXPECT_EQ(p.contains("other"), k == 0);
      if (k == 0) {
        EXPECT_GE(p.at("list").get<double>(), 0.0);
      }
    }
  }
  EXPECT_EQ(teams_of_two, 2);  // two states
  const auto text =
      run_rendulic("bench --particles 1000 --repetitions 1 --steps 20 --threads 1 --phases", false);
  ASSERT_EQ(text.code, 0) << text.err;
  EXPECT_NE(text.out.find("where a step goes"), std::string::npos) << text.out;
}

// --threads took "1 2" but refused "1,2", and timed a size given twice twice; --lammps "" wrote
// no file and said nothing.
TEST(Bench, TeamSizesAreDistinctTakeCommasAndTheLammpsFolderIsNamed) {
  std::map<double, std::set<int>> sizes;
  for (const auto& row : bench_json("--repetitions 1 --steps 5 --threads 2,1"))
    sizes[row.at("volume_fraction").get<double>()].insert(row.at("threads").get<int>());
  EXPECT_EQ(sizes.size(), 2u);
  for (const auto& [nu, s] : sizes) EXPECT_EQ(s, (std::set<int>{0, 1, 2})) << nu;
  for (const auto& [args, reason] : std::vector<std::pair<std::string, std::string>>{
           {"--threads 1 1", "bench --threads: 1 given twice"},
           {"--threads 2,1,2", "bench --threads: 2 given twice"},
           {"--lammps \"\"", "bench --lammps: the folder name is empty"}}) {
    const auto r = run_rendulic("bench --particles 200 --steps 1 --repetitions 1 " + args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.out;
    EXPECT_EQ(r.out, "rendulic: " + reason + "\n") << args;
  }
}

TEST(Bench, StepsFixesTheSpanOfEveryFigure) {
  for (const auto& row : bench_json("--repetitions 1 --steps 60 --threads 1"))
    EXPECT_EQ(row.at("steps").get<std::int64_t>(), 60) << row.dump();
  const auto r = run_rendulic("bench --particles 200 --steps 0");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--steps"), std::string::npos) << r.out;
}

}  // namespace
