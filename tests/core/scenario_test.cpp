// Tests of core/scenario.hpp (docs/scenario-keys.md): strict parsing, one-line errors naming the
// key and file:line, --set overrides with the same validation, and the effective scenario
// round-tripping through its TOML text. Hostile input: a folder, a device or a FIFO as the
// scenario, a key nested 50,000 deep, control characters, integers at the edge of int64.
#include "rendulic/core/scenario.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>

#include "input_error.hpp"
#include "rendulic/core/errors.hpp"

namespace rendulic {
namespace {

ScenarioSchema make_schema() {
  ScenarioSchema s;
  s.add({.path = "run.seed",
         .type = KeyType::kInt,
         .default_value = std::int64_t{1},
         .unit = "-",
         .help = "seed",
         .min = 0});
  s.add({.path = "material.k",
         .type = KeyType::kDouble,
         .default_value = 1e8,
         .unit = "kg/s^2",
         .help = "normal stiffness",
         .min = 0,
         .min_open = true});
  s.add({.path = "material.w",
         .type = KeyType::kDouble,
         .default_value = 3.0,
         .unit = "-",
         .help = "polydispersity",
         .min = 1,
         .max = 10});
  s.add({.path = "states.eps_dev",
         .type = KeyType::kDoubleList,
         .default_value = std::vector<double>{0.006, 0.32},
         .unit = "-",
         .help = "states",
         .min = 0,
         .max = 1,
         .min_size = 1});
  s.add({.path = "probes.method",
         .type = KeyType::kString,
         .default_value = std::string("dynamic"),
         .unit = "-",
         .help = "method",
         .choices = {"dynamic", "minimisation"}});
  s.add({.path = "output.report",
         .type = KeyType::kBool,
         .default_value = true,
         .unit = "-",
         .help = "report"});
  s.add({.path = "run.big",
         .type = KeyType::kInt,
         .default_value = std::int64_t{1},
         .unit = "-",
         .help = "an integer bounded as the seed is",
         .min = 0,
         .max = 4.0e18});
  s.add({.path = "run.description",
         .type = KeyType::kString,
         .default_value = std::string{},
         .unit = "-",
         .help = "free text"});
  s.add({.path = "run.stages",
         .type = KeyType::kStringList,
         .default_value = std::vector<std::string>{"a"},
         .unit = "-",
         .help = "stages",
         .choices = {"a", "b", "c"}});
  s.add({.path = "probes.amplitudes",
         .type = KeyType::kDoubleList,
         .default_value = std::vector<double>{5e-5},
         .unit = "-",
         .help = "amplitudes, each naming a group",
         .min = 0,
         .min_open = true,
         .distinct = true});
  s.add({.path = "probes.planes",
         .type = KeyType::kStringList,
         .default_value = std::vector<std::string>{"rendulic"},
         .unit = "-",
         .help = "planes, each naming a group",
         .distinct = true});
  return s;
}

using rendulic::testing::input_error;

TEST(Scenario, DefaultsWithoutAFile) {
  const auto schema = make_schema();
  Scenario sc(schema);
  EXPECT_EQ(sc.get_int("run.seed"), 1);
  EXPECT_DOUBLE_EQ(sc.get_double("material.k"), 1e8);
  EXPECT_FALSE(sc.is_set("material.k"));
  EXPECT_EQ(sc.origin("material.k"), "default");
}

TEST(Scenario, ParsesTypedValuesAndRecordsTheirLines) {
  const auto schema = make_schema();
  const auto sc = Scenario::from_string(
      "[run]\nseed = 7\n\n[material]\nk = 2e8\nw = 2\n[states]\neps_dev = [0.1, 0.2]\n", "x.toml",
      schema);
  EXPECT_EQ(sc.get_int("run.seed"), 7);
  EXPECT_DOUBLE_EQ(sc.get_double("material.k"), 2e8);
  EXPECT_DOUBLE_EQ(sc.get_double("material.w"), 2.0);  // an integer where a number is due
  EXPECT_EQ(sc.get_doubles("states.eps_dev"), (std::vector<double>{0.1, 0.2}));
  EXPECT_EQ(sc.origin("material.k"), "x.toml:5");
  EXPECT_TRUE(sc.is_set("run.seed"));
}

TEST(Scenario, UnknownKeyIsNamedWithItsLineAndASuggestion) {
  const auto schema = make_schema();
  const auto msg = input_error([&] {
    Scenario::from_string("[material]\nk = 1e8\n[states]\nesp_dev = [0.1]\n", "s.toml", schema);
  });
  EXPECT_NE(msg.find("s.toml:4"), std::string::npos) << msg;
  EXPECT_NE(msg.find("unknown key 'states.esp_dev'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("did you mean 'states.eps_dev'"), std::string::npos) << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos) << "one line";
}

TEST(Scenario, UnknownSectionIsAnUnknownKey) {
  const auto schema = make_schema();
  const auto msg =
      input_error([&] { Scenario::from_string("[materal]\nk = 1e8\n", "s.toml", schema); });
  EXPECT_NE(msg.find("unknown key 'materal"), std::string::npos) << msg;
}

TEST(Scenario, WrongTypeIsNamed) {
  const auto schema = make_schema();
  auto msg =
      input_error([&] { Scenario::from_string("[material]\nk = \"stiff\"\n", "s.toml", schema); });
  EXPECT_NE(msg.find("s.toml:2: key 'material.k': expected a number, got a string"),
            std::string::npos)
      << msg;
  msg = input_error([&] { Scenario::from_string("[run]\nseed = 1.5\n", "s.toml", schema); });
  EXPECT_NE(msg.find("key 'run.seed': expected an integer"), std::string::npos) << msg;
  msg = input_error(
      [&] { Scenario::from_string("[states]\neps_dev = [0.1, \"x\"]\n", "s.toml", schema); });
  EXPECT_NE(msg.find("key 'states.eps_dev'"), std::string::npos) << msg;
}

TEST(Scenario, OutOfRangeIsNamed) {
  const auto schema = make_schema();
  auto msg = input_error([&] { Scenario::from_string("[material]\nk = 0\n", "s.toml", schema); });
  EXPECT_NE(msg.find("key 'material.k': value 0.0 is out of range (0.0, inf)"), std::string::npos)
      << msg;
  msg = input_error([&] { Scenario::from_string("[material]\nw = 11\n", "s.toml", schema); });
  EXPECT_NE(msg.find("material.w"), std::string::npos) << msg;
  msg = input_error([&] { Scenario::from_string("[material]\nw = nan\n", "s.toml", schema); });
  EXPECT_NE(msg.find("finite"), std::string::npos) << msg;
  msg = input_error([&] { Scenario::from_string("[states]\neps_dev = []\n", "s.toml", schema); });
  EXPECT_NE(msg.find("states.eps_dev"), std::string::npos) << msg;
  msg = input_error(
      [&] { Scenario::from_string("[probes]\nmethod = \"magic\"\n", "s.toml", schema); });
  EXPECT_NE(msg.find("'magic' is not one of dynamic, minimisation"), std::string::npos) << msg;
}

// A list whose entries name groups: an entry given twice, or two entries that print alike in a
// group's name (6 significant digits), would run the same work twice into one group.
TEST(Scenario, ADistinctListRefusesAnEntryGivenTwice) {
  const auto schema = make_schema();
  auto parse = [&](const std::string& text) { Scenario::from_string(text, "s.toml", schema); };
  EXPECT_NO_THROW(parse("[probes]\namplitudes = [1e-4, 2e-4]\nplanes = [\"a\", \"b\"]\n"));
  EXPECT_NO_THROW(parse("[probes]\namplitudes = [1e-4, 1.00001e-4]\n"));
  auto msg = input_error([&] { parse("[probes]\namplitudes = [1e-4, 2e-4, 1e-4]\n"); });
  EXPECT_NE(msg.find("key 'probes.amplitudes': value 0.0001 given twice"), std::string::npos)
      << msg;
  EXPECT_EQ(msg.find("significant"), std::string::npos) << msg;
  msg = input_error([&] { parse("[probes]\namplitudes = [1e-4, 1.000001e-4]\n"); });
  EXPECT_NE(msg.find("value 0.0001000001 given twice (as 0.0001: entries are told apart by 6 "
                     "significant digits"),
            std::string::npos)
      << msg;
  msg = input_error([&] { parse("[run]\nstages = [\"prepare\", 3]\n"); });
  EXPECT_NE(msg.find("expected a list of strings, found an integer"), std::string::npos) << msg;
  msg = input_error([&] { parse("[probes]\namplitudes = [1e-4, \"x\"]\n"); });
  EXPECT_NE(msg.find("expected a list of numbers, found a string"), std::string::npos) << msg;
  msg = input_error([&] { parse("[probes]\nplanes = [\"a\", \"b\", \"a\"]\n"); });
  EXPECT_NE(msg.find("key 'probes.planes': value 'a' given twice"), std::string::npos) << msg;
  // Lists without the flag keep repeats (two states at one strain are two states).
  EXPECT_NO_THROW(parse("[states]\neps_dev = [0.1, 0.1]\n"));
  const std::string md = schema.markdown();
  EXPECT_NE(md.find("(0.0, inf), distinct"), std::string::npos) << md;
}

TEST(Scenario, SyntaxErrorNamesTheLine) {
  const auto schema = make_schema();
  const auto msg =
      input_error([&] { Scenario::from_string("[run]\nseed = = 3\n", "s.toml", schema); });
  EXPECT_NE(msg.find("s.toml:2"), std::string::npos) << msg;
}

TEST(Scenario, MissingFileIsAnInputError) {
  const auto schema = make_schema();
  const auto msg = input_error([&] { Scenario::from_file("/nonexistent/x.toml", schema); });
  EXPECT_NE(msg.find("/nonexistent/x.toml"), std::string::npos);
}

TEST(Scenario, OverridesAreValidatedLikeTheFile) {
  const auto schema = make_schema();
  Scenario sc(schema);
  sc.apply_override("material.k=3e8");
  EXPECT_DOUBLE_EQ(sc.get_double("material.k"), 3e8);
  EXPECT_EQ(sc.origin("material.k"), "--set");
  sc.apply_override("probes.method=minimisation");  // bare string
  EXPECT_EQ(sc.get_string("probes.method"), "minimisation");
  sc.apply_override("states.eps_dev=[0.01, 0.02, 0.03]");
  EXPECT_EQ(sc.get_doubles("states.eps_dev").size(), 3u);
  sc.apply_override("run.stages=a,c");  // bare list
  EXPECT_EQ(sc.get_strings("run.stages"), (std::vector<std::string>{"a", "c"}));
  sc.apply_override("run.stages=[c, a]");  // bare list in brackets: the brackets are no part
  EXPECT_EQ(sc.get_strings("run.stages"), (std::vector<std::string>{"c", "a"}));
  sc.apply_override("output.report=false");
  EXPECT_FALSE(sc.get_bool("output.report"));

  auto msg = input_error([&] { sc.apply_override("material.kk=1"); });
  EXPECT_NE(msg.find("--set material.kk=1: unknown key 'material.kk'"), std::string::npos) << msg;
  msg = input_error([&] { sc.apply_override("material.k=-1"); });
  EXPECT_NE(msg.find("--set material.k=-1: key 'material.k'"), std::string::npos) << msg;
  msg = input_error([&] { sc.apply_override("material.k=abc"); });
  EXPECT_NE(msg.find("not a valid number"), std::string::npos) << msg;
  msg = input_error([&] { sc.apply_override("material.k"); });
  EXPECT_NE(msg.find("expected key=value"), std::string::npos) << msg;
  msg = input_error([&] { sc.apply_override("run.seed=2.5"); });
  EXPECT_NE(msg.find("run.seed"), std::string::npos) << msg;
}

TEST(Scenario, EffectiveScenarioRoundTripsThroughToml) {
  const auto schema = make_schema();
  auto sc = Scenario::from_string("[material]\nk = 123456789.123\n", "a.toml", schema);
  sc.apply_override("states.eps_dev=[0.006, 0.021, 0.32]");
  sc.apply_override("probes.method=minimisation");
  const auto back = Scenario::from_string(sc.to_toml(), "effective", schema);
  for (const auto& k : schema.keys()) {
    EXPECT_EQ(back.to_toml().find(k.path.substr(k.path.find('.') + 1)) != std::string::npos, true);
  }
  EXPECT_EQ(back.get_double("material.k"), 123456789.123);  // exact: shortest round-trip
  EXPECT_EQ(back.get_doubles("states.eps_dev"), sc.get_doubles("states.eps_dev"));
  EXPECT_EQ(back.get_string("probes.method"), "minimisation");
  EXPECT_EQ(back.to_toml().substr(back.to_toml().find('\n')),
            sc.to_toml().substr(sc.to_toml().find('\n')));
}

// `run --resume` compares the kept file's scenario with this run's setting by setting: the same
// settings from another file name are the same run, and a difference is named with both values.
TEST(Scenario, DifferencesFromAStoredScenarioAreItsSettingsNotItsFileName) {
  const auto schema = make_schema();
  const auto a = Scenario::from_string("[material]\nk = 2e8\n", "a.toml", schema);
  const auto b = Scenario::from_string("[material]\nk = 2e8\n", "/elsewhere/b.toml", schema);
  EXPECT_NE(a.to_toml(), b.to_toml());  // the header names the file
  EXPECT_TRUE(b.differences_from(a.to_toml()).empty());
  auto c = b;
  c.apply_override("material.k=3e8");
  c.apply_override("probes.method=minimisation");
  const auto d = c.differences_from(a.to_toml());
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0].key, "material.k");
  EXPECT_EQ(d[0].stored, "2e+08");
  EXPECT_EQ(d[0].now, "3e+08");
  EXPECT_EQ(d[1].key, "probes.method");
  EXPECT_EQ(d[1].now, "\"minimisation\"");
  // A setting the stored text lacks (a file of an older version) is a difference too.
  std::string older = a.to_toml();
  older.erase(older.find("k = 2e+08\n"), std::string("k = 2e+08\n").size());
  const auto e = a.differences_from(older);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].key, "material.k");
  EXPECT_EQ(e[0].stored, "(absent)");
}

TEST(Scenario, SchemaRejectsBadDeclarations) {
  ScenarioSchema s;
  s.add({.path = "a.b", .type = KeyType::kDouble, .default_value = 1.0});
  EXPECT_THROW(s.add({.path = "a.b", .type = KeyType::kDouble, .default_value = 1.0}),
               std::logic_error);
  EXPECT_THROW(s.add({.path = "a.c", .type = KeyType::kDouble, .default_value = 5.0, .max = 1}),
               std::logic_error);
  EXPECT_THROW(s.add({.path = "a.d", .type = KeyType::kInt, .default_value = 5.0}),
               std::logic_error);
}

TEST(Scenario, MarkdownReferenceListsEveryKey) {
  const auto schema = make_schema();
  const std::string md = schema.markdown();
  for (const auto& k : schema.keys()) EXPECT_NE(md.find("`" + k.path + "`"), std::string::npos);
  // One table per section, though run.big and run.description come after output.report.
  EXPECT_EQ(md.find("## [run]"), md.rfind("## [run]")) << md;
  EXPECT_LT(md.find("`run.description`"), md.find("## [output]")) << md;
  EXPECT_NE(md.find("kg/s^2"), std::string::npos);
  EXPECT_NE(md.find("(0.0, inf)"), std::string::npos);
}

TEST(Scenario, OnlyARegularFileIsAScenario) {
  // A folder used to run the defaults, /dev/zero to read without end, a FIFO to hang.
  namespace fs = std::filesystem;
  const auto schema = make_schema();
  const fs::path d = fs::path(RENDULIC_TEST_TMP) / "core_scenario" / "not_files";
  fs::remove_all(d);
  fs::create_directories(d);
  auto msg = input_error([&] { Scenario::from_file(d.string(), schema); });
  EXPECT_NE(msg.find("is a folder"), std::string::npos) << msg;
  msg = input_error([&] { Scenario::from_file("/dev/zero", schema); });
  EXPECT_NE(msg.find("/dev/zero: not a regular file"), std::string::npos) << msg;
  const fs::path fifo = d / "fifo.toml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  msg = input_error([&] { Scenario::from_file(fifo.string(), schema); });
  EXPECT_NE(msg.find("not a regular file"), std::string::npos) << msg;
  {
    std::ofstream big(d / "big.toml");
    const std::string comment = "# " + std::string(1022, 'x') + "\n";
    for (int i = 0; i < 1100; ++i) big << comment;  // 1.1 MiB of valid TOML
  }
  msg = input_error([&] { Scenario::from_file((d / "big.toml").string(), schema); });
  EXPECT_NE(msg.find("larger than 1 MiB"), std::string::npos) << msg;
}

TEST(Scenario, DeepDottedKeyIsRefusedBeforeTheParserRecurses) {
  // toml++ recurses once per segment: 50,000 segments overflowed the stack.
  const auto schema = make_schema();
  std::string key = "run";
  for (int i = 0; i < 50000; ++i) key += ".a";
  for (const std::string& text :
       {"\n" + key + " = 1\n", "\n[" + key + "]\n", "\nx = {" + key + " = 1}\n"}) {
    const auto msg = input_error([&] { Scenario::from_string(text, "deep.toml", schema); });
    EXPECT_NE(msg.find("deep.toml:2: a dotted key nested deeper than 16 levels"), std::string::npos)
        << msg.substr(0, 200);
  }
  // What a scenario holds is untouched by the check: numbers, times, dotted strings.
  const auto sc = Scenario::from_string(
      "# a.b.c.d.e.f.g.h.i.j.k.l.m.n.o.p.q.r.s\n[material]\nk = 1.5e8\n[run]\n"
      "description = \"a.b.c.d.e.f.g.h.i.j.k.l.m.n.o.p.q.r.s\"\n",
      "ok.toml", schema);
  EXPECT_EQ(sc.get_double("material.k"), 1.5e8);
}

TEST(Scenario, EveryCharacterOfAStringRoundTripsThroughTheStoredToml) {
  // \u0000 used to cut the stored text short (HDF5 strings end at a NUL) and \u0001 was
  // written raw, which TOML does not allow.
  const auto schema = make_schema();
  std::string all;
  for (int c = 0; c < 0x80; ++c) all += static_cast<char>(c);
  all += "\xc3\xa9\xe2\x82\xac";  // é, €
  Scenario sc(schema);
  sc.set("run.description", all);
  const std::string text = sc.to_toml();
  EXPECT_EQ(text.find('\0'), std::string::npos);
  for (char c = 1; c < 0x20; ++c) {
    if (c != '\n') {
      EXPECT_EQ(text.find(c), std::string::npos) << int(c);
    }
  }
  const auto back = Scenario::from_string(text, "stored", schema);
  EXPECT_EQ(back.get_string("run.description"), all);
}

TEST(Scenario, IntegersAreComparedAsIntegers) {
  // Compared in double, 4e18 + 1 rounded to 4e18 and passed; 2^63 - 1 printed as -2^63.
  const auto schema = make_schema();
  auto sc = Scenario::from_string("[run]\nbig = 4000000000000000000\n", "s.toml", schema);
  EXPECT_EQ(sc.get_int("run.big"), 4000000000000000000);
  auto msg = input_error(
      [&] { Scenario::from_string("[run]\nbig = 4000000000000000001\n", "s.toml", schema); });
  EXPECT_NE(msg.find("value 4000000000000000001 is out of range [0, 4000000000000000000]"),
            std::string::npos)
      << msg;
  msg = input_error([&] { sc.apply_override("run.big=9223372036854775807"); });
  EXPECT_NE(msg.find("value 9223372036854775807 is out of range"), std::string::npos) << msg;
  msg = input_error([&] { sc.apply_override("run.seed=-9223372036854775808"); });
  EXPECT_NE(msg.find("value -9223372036854775808 is out of range [0, inf)"), std::string::npos)
      << msg;
}

TEST(Scenario, TextMustBeUtf8AndMessagesStayOnOneLine) {
  const auto schema = make_schema();
  Scenario sc(schema);
  auto msg = input_error([&] { sc.apply_override("run.description=caf\xe9"); });
  EXPECT_NE(msg.find("not valid UTF-8"), std::string::npos) << msg;
  msg = input_error([&] { sc.apply_override("probes.method=\"dyn\\namic\""); });
  EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  EXPECT_NE(msg.find("'dyn\\x0aamic' is not one of"), std::string::npos) << msg;
}

}  // namespace
}  // namespace rendulic
