// OptionTable (core/option_table.hpp): the schema it registers carries the struct's own
// defaults, reading a scenario sets the members (nested ones too), and check() refuses what
// the scenario refuses, with the scenario's reason.
#include "rendulic/core/option_table.hpp"

#include <gtest/gtest.h>

#include <functional>

#include "input_error.hpp"
#include "rendulic/core/errors.hpp"

namespace rendulic {
namespace {

using rendulic::testing::input_error;

struct Inner {
  double tolerance = 1e-6;
};
struct Example {
  int count = 7;
  double rate = 2.5;
  std::vector<double> amplitudes = {1e-3, 2e-3};
  std::string mode = "fast";
  bool flag = true;
  Inner inner;
};

const OptionTable<Example>& table() {
  using Row = OptionRow<Example>;
  static const OptionTable<Example> t({
      Row{{.path = "ex.count", .unit = "-", .help = "h", .min = 1, .max = 10},
          [](Example& e) -> int& { return e.count; }},
      Row{{.path = "ex.rate", .unit = "1/s", .help = "h", .min = 0, .max = 5, .min_open = true},
          [](Example& e) -> double& { return e.rate; }},
      Row{{.path = "ex.amplitudes",
           .unit = "-",
           .help = "h",
           .min = 0,
           .max = 0.05,
           .min_open = true,
           .min_size = 1},
          [](Example& e) -> std::vector<double>& { return e.amplitudes; }},
      Row{{.path = "ex.mode", .unit = "-", .help = "h", .choices = {"fast", "slow"}},
          [](Example& e) -> std::string& { return e.mode; }},
      Row{{.path = "ex.flag", .unit = "-", .help = "h"},
          [](Example& e) -> bool& { return e.flag; }},
      Row{{.path = "ex.tolerance", .unit = "-", .help = "h", .min = 0, .max = 1, .min_open = true},
          [](Example& e) -> double& { return e.inner.tolerance; }},
  });
  return t;
}

TEST(OptionTable, SchemaDefaultsAreTheStructs) {
  ScenarioSchema schema;
  table().register_keys(schema);
  const Scenario sc(schema);
  Example e;
  e.count = 0;
  e.rate = 0;
  e.amplitudes.clear();
  e.mode.clear();
  e.flag = false;
  e.inner.tolerance = 0;
  table().read(sc, e);
  const Example d;
  EXPECT_EQ(sc.get_int("ex.count"), 7);
  EXPECT_EQ(e.count, d.count);
  EXPECT_EQ(e.rate, d.rate);
  EXPECT_EQ(e.amplitudes, d.amplitudes);
  EXPECT_EQ(e.mode, d.mode);
  EXPECT_EQ(e.flag, d.flag);
  EXPECT_EQ(e.inner.tolerance, d.inner.tolerance);
  EXPECT_EQ(schema.find("ex.tolerance")->type, KeyType::kDouble);
  EXPECT_EQ(schema.find("ex.count")->type, KeyType::kInt);
}

TEST(OptionTable, ReadSetsNestedMembers) {
  ScenarioSchema schema;
  table().register_keys(schema);
  Scenario sc(schema);
  sc.apply_override("ex.tolerance=1e-3");
  sc.apply_override("ex.mode=slow");
  Example e;
  table().read(sc, e);
  EXPECT_EQ(e.inner.tolerance, 1e-3);
  EXPECT_EQ(e.mode, "slow");
}

// The struct is held to the ranges a scenario is held to, with the same reason.
TEST(OptionTable, CheckRefusesWhatTheScenarioRefuses) {
  ScenarioSchema schema;
  table().register_keys(schema);
  const std::vector<std::pair<std::string, std::function<void(Example&)>>> bad = {
      {"ex.count=11", [](Example& e) { e.count = 11; }},
      {"ex.rate=0", [](Example& e) { e.rate = 0; }},
      {"ex.amplitudes=[0.1]", [](Example& e) { e.amplitudes = {0.1}; }},
      {"ex.amplitudes=[]", [](Example& e) { e.amplitudes = {}; }},
      {"ex.mode=medium", [](Example& e) { e.mode = "medium"; }},
      {"ex.tolerance=-1", [](Example& e) { e.inner.tolerance = -1; }},
  };
  Example good;
  std::string why;
  EXPECT_TRUE(table().check(good, &why)) << why;
  for (const auto& [assignment, spoil] : bad) {
    Scenario sc(schema);
    const std::string scenario_error = input_error([&] { sc.apply_override(assignment); });
    ASSERT_FALSE(scenario_error.empty()) << assignment;
    Example e;
    spoil(e);
    ASSERT_FALSE(table().check(e, &why)) << assignment;
    const std::string key = assignment.substr(0, assignment.find('='));
    ASSERT_EQ(why.rfind(key + ": ", 0), 0u) << why;
    // The reason after the key is the scenario's own.
    EXPECT_NE(scenario_error.find(why.substr(key.size() + 2)), std::string::npos)
        << scenario_error << " / " << why;
  }
}

}  // namespace
}  // namespace rendulic
