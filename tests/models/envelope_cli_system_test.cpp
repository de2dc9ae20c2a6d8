// Tests of `rendulic envelope` (docs/models.md "Model envelopes and `rendulic envelope`") run as a
// user would, through the built executable: the JSON contract (keys, Pa, Rendulic pairs equal to
// the library's envelope) and exit code 2 with a one-line reason naming the culprit on bad input.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "rendulic/models/envelope.hpp"
#include "rendulic/models/material_io.hpp"

namespace rendulic::models {
namespace {

namespace fs = std::filesystem;

struct CliRun {
  int code;
  std::string out, err;
};

// One directory per test: ctest runs the tests of this file side by side (-j 2), and a shared
// `out` file let one test read another's output.
fs::path scratch() {
  const fs::path d = fs::path(RENDULIC_TEST_TMP) / "models_envelope_cli" /
                     ::testing::UnitTest::GetInstance()->current_test_info()->name();
  fs::create_directories(d);
  return d;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

CliRun rendulic(const std::string& args) {
  const fs::path d = scratch();
  const std::string cmd = std::string(RENDULIC_EXE) + " " + args + " >" + (d / "out").string() +
                          " 2>" + (d / "err").string();
  const int status = std::system(cmd.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(d / "out"), slurp(d / "err")};
}

std::string data(const std::string& name) {
  return std::string(RENDULIC_SOURCE_DIR) + "/data/models/" + name;
}

fs::path write(const std::string& name, const std::string& text) {
  const fs::path p = scratch() / name;
  std::ofstream(p) << text;
  return p;
}

// The numbers of the JSON array at `key`, flattened, read by a JSON parser independent of the
// writer (output that is not valid JSON fails here).
void flatten(const nlohmann::json& j, std::vector<double>& v) {
  if (j.is_array())
    for (const auto& x : j) flatten(x, v);
  else
    v.push_back(j.get<double>());
}
std::vector<double> numbers_of(const std::string& json, const std::string& key) {
  const nlohmann::json j = nlohmann::json::parse(json);
  EXPECT_TRUE(j.contains(key)) << key;
  std::vector<double> v;
  if (j.contains(key)) flatten(j[key], v);
  return v;
}

TEST(EnvelopeCli, JsonMatchesTheLibraryEnvelope) {
  const CliRun r = rendulic(
      "envelope --model elastoplastic_fabric --params " + data("elastoplastic_fabric_params.toml") +
      " --state " + data("anisotropic_state.toml") + " --amplitude 2e-3 --directions 12 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* key : {"theta_deg", "strain", "stress", "fabric"})
    EXPECT_NE(r.out.find(std::string("\"") + key + "\": ["), std::string::npos) << key;
  auto law = make_law("elastoplastic_fabric");
  load_parameters_toml(data("elastoplastic_fabric_params.toml"), law.get());
  const MaterialState s = load_state_toml(data("anisotropic_state.toml"), *law);
  EnvelopeOptions o;
  o.amplitude = 2e-3;
  o.directions = 12;
  const EnvelopeRecord env = model_envelope(*law, s, o);
  const std::vector<double> theta = numbers_of(r.out, "theta_deg");
  const std::vector<double> strain = numbers_of(r.out, "strain");
  const std::vector<double> stress = numbers_of(r.out, "stress");
  const std::vector<double> fabric = numbers_of(r.out, "fabric");
  ASSERT_EQ(theta.size(), 12u);
  ASSERT_EQ(stress.size(), 24u);
  ASSERT_EQ(fabric.size(), 24u);
  for (int i = 0; i < 12; ++i) {
    EXPECT_EQ(theta[i], env.theta_deg[i]);
    for (int c = 0; c < 2; ++c) {
      // %.17g round-trips doubles exactly.
      EXPECT_EQ(strain[2 * i + c], env.strain[i](c));
      EXPECT_EQ(stress[2 * i + c], env.stress[i](c));  // Pa
      EXPECT_EQ(fabric[2 * i + c], env.fabric[i](c));
    }
  }
}

TEST(EnvelopeCli, TableOutputAndDefaults) {
  const CliRun r = rendulic("envelope --model isotropic_elastic --state " +
                            data("isotropic_state.toml") + " --amplitude 5e-5");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("theta_deg"), std::string::npos);
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 3 + 36);
}

TEST(EnvelopeCli, ExplicitSchemeSaysWhenItExceedsTheTolerance) {
  const CliRun r =
      rendulic("envelope --model elastoplastic_fabric --state " + data("anisotropic_state.toml") +
               " --amplitude 2e-3 --scheme explicit --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("exceeded the tolerance"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("\"within_tolerance\": false"), std::string::npos);
}

// The third-order scheme through the CLI: on the sand (no yield surface) its 2e-3 envelope agrees
// with modified Euler's to the tolerance's order (each within ~1e-6 of the exact response), and
// auto picks it there (the same numbers).
TEST(EnvelopeCli, BogackiShampineAgreesWithModifiedEulerAndAutoPicksIt) {
  const std::string base = "envelope --model hypoplastic_wu --params " +
                           data("hypoplastic_wu_params.toml") + " --state " +
                           data("sand_state.toml") + " --amplitude 2e-3 --directions 12 --json";
  std::vector<std::vector<double>> stress;
  for (const char* scheme : {"modified-euler", "bogacki-shampine", "auto"}) {
    const CliRun r = rendulic(base + " --scheme " + scheme);
    ASSERT_EQ(r.code, 0) << scheme << ": " << r.err;
    stress.push_back(numbers_of(r.out, "stress"));
    ASSERT_EQ(stress.back().size(), 24u) << scheme;
  }
  double scale = 0;
  for (double x : stress[0]) scale = std::max(scale, std::abs(x));
  for (std::size_t k = 0; k < 24; ++k) {
    EXPECT_NEAR(stress[1][k], stress[0][k], 1e-5 * scale) << k;
    EXPECT_EQ(stress[2][k], stress[1][k]) << k;
  }
  // A scheme that does not exist is refused by name (exit 2, one line).
  const CliRun bad = rendulic(base + " --scheme rk4");
  EXPECT_EQ(bad.code, 2) << bad.err;
  EXPECT_NE(bad.err.find("rk4"), std::string::npos) << bad.err;
  // Substeps only the explicit scheme takes did nothing without a word to an error-controlled
  // one; the envelope is the one without them, and the warning says so.
  const CliRun ignored = rendulic(base + " --scheme modified-euler --substeps 7");
  EXPECT_EQ(ignored.code, 0) << ignored.err;
  EXPECT_NE(ignored.err.find("warning: --substeps 7 has no effect: the modified-euler scheme"),
            std::string::npos)
      << ignored.err;
  EXPECT_EQ(ignored.out, rendulic(base + " --scheme modified-euler").out);
  EXPECT_EQ(rendulic(base + " --scheme explicit --substeps 7").err.find("has no effect"),
            std::string::npos);
  // The rate method integrates nothing: the driver's options given with it did nothing without
  // a word, and its header named a scheme and tolerance that made nothing.
  const std::string rate = base + " --method rate";
  const CliRun rate_ignored = rendulic(rate + " --scheme explicit --tolerance 0.001 --substeps 7");
  EXPECT_EQ(rate_ignored.code, 0) << rate_ignored.err;
  EXPECT_NE(rate_ignored.err.find("warning: --scheme explicit, --tolerance 0.001, --substeps 7 "
                                  "have no effect: the rate method evaluates the rate law once"),
            std::string::npos)
      << rate_ignored.err;
  EXPECT_EQ(numbers_of(rate_ignored.out, "stress"), numbers_of(rendulic(rate).out, "stress"));
  EXPECT_EQ(rendulic(rate).err.find("no effect"), std::string::npos);
  const std::string table = rate.substr(0, rate.find(" --json")) + " --method rate";
  const CliRun text = rendulic(table);
  ASSERT_EQ(text.code, 0) << text.err;
  EXPECT_EQ(text.out.rfind("# hypoplastic_wu envelope, |d_eps| = 0.002, 12 directions, rate\n", 0),
            0u)
      << text.out;
}

void expect_input_error(const std::string& args, const std::vector<std::string>& mentions) {
  const CliRun r = rendulic(args);
  EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;  // one line
  for (const auto& m : mentions) EXPECT_NE(r.err.find(m), std::string::npos) << r.err;
}

// An integrated probe's response is a difference of stresses: at amplitudes whose increments
// are near the stress's rounding it was noise (1e-18: a lopsided envelope; 1e-300: zero), both
// exit 0 "within tolerance". The rate method takes no difference and stays exact. (1e-300 gives
// increments of exactly zero: the law's rate then says whether zero is its answer.)
TEST(EnvelopeCli, AnIntegratedEnvelopeBelowTheStressRoundingIsRefused) {
  const std::string state = " --state " + data("isotropic_state.toml");
  for (const char* amplitude : {"1e-18", "1e-300"}) {
    const CliRun r =
        rendulic("envelope --model hypoplastic_wu --amplitude " + std::string(amplitude) + state);
    EXPECT_EQ(r.code, 2) << amplitude << ": " << r.out << r.err;
    EXPECT_NE(r.err.find(std::string("amplitude ") + amplitude + ": the largest stress increment"),
              std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("would be rounding noise; use a larger amplitude or the rate method"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
    const CliRun rate =
        rendulic("envelope --model hypoplastic_wu --method rate --json --amplitude " +
                 std::string(amplitude) + state);
    ASSERT_EQ(rate.code, 0) << rate.err;
    double largest = 0.0;
    for (double x : numbers_of(rate.out, "stress")) largest = std::max(largest, std::abs(x));
    EXPECT_GT(largest, 0.0) << amplitude;
  }
  EXPECT_EQ(rendulic("envelope --model hypoplastic_wu --amplitude 1e-9" + state).code, 0);
}

TEST(EnvelopeCli, BadInputExitsTwoNamingTheCulprit) {
  const std::string state = " --state " + data("isotropic_state.toml") + " --amplitude 5e-5";
  const fs::path unknown = write("unknown.toml", "B = 1e10\nkappa = 3\n");
  expect_input_error("envelope --model anisotropic_elastic --params " + unknown.string() + state,
                     {"kappa", unknown.string()});
  const fs::path bounds = write("bounds.toml", "G = -1.0\n");
  expect_input_error("envelope --model anisotropic_elastic --params " + bounds.string() + state,
                     {"'G'", "bounds", bounds.string()});
  const fs::path text = write("text.toml", "B = \"big\"\n");
  expect_input_error("envelope --model anisotropic_elastic --params " + text.string() + state,
                     {"'B'", text.string()});
  const fs::path broken = write("broken.toml", "B = = 3\n");
  expect_input_error("envelope --model anisotropic_elastic --params " + broken.string() + state,
                     {broken.string()});
  const fs::path no_stress = write("no_stress.toml", "volume_fraction = 0.8\n");
  expect_input_error(
      "envelope --model isotropic_elastic --amplitude 5e-5 --state " + no_stress.string(),
      {"stress", no_stress.string()});
  const fs::path shape = write("shape.toml", "stress = [[1.0, 0.0], [0.0, 1.0]]\n");
  expect_input_error(
      "envelope --model isotropic_elastic --amplitude 5e-5 --state " + shape.string(),
      {"3x3", shape.string()});
  const fs::path asym =
      write("asym.toml", "stress = [[1.0, 2.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]\n");
  expect_input_error("envelope --model isotropic_elastic --amplitude 5e-5 --state " + asym.string(),
                     {"symmetric", asym.string()});
  const fs::path extra = write("extra.toml",
                               "stress = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], "
                               "[0.0, 0.0, 1.0]]\ntemperature = 3\n");
  expect_input_error(
      "envelope --model isotropic_elastic --amplitude 5e-5 --state " + extra.string(),
      {"temperature", extra.string()});
  expect_input_error("envelope --model cam_clay" + state, {"cam_clay"});
  expect_input_error("envelope --model isotropic_elastic --state " + data("isotropic_state.toml") +
                         " --amplitude -1",
                     {"amplitude"});
  // Counts named as the options are: --substeps 0 said "fixed_substeps must be >= 1", and a
  // count beyond an int "Could not convert".
  for (const auto& [option, words] : std::vector<std::pair<std::string, std::string>>{
           {" --substeps 0", "--substeps: Value 0 is out of range [1, 100000]"},
           {" --substeps 3000000000", "--substeps: Value 3000000000 is out of range [1, 100000]"},
           {" --directions 2", "--directions: Value 2 is out of range [3, 100000]"},
           // A word among choices, in a scenario key's words (CLI11: "foo not in {...}").
           {" --method foo", "--method: 'foo' is not one of integrated, rate"},
           // "envelope options: tolerance must be in (0, 1)": the driver's words.
           {" --tolerance 2", "--tolerance: Value 2 is out of range (0, 1)"}})
    expect_input_error("envelope --model isotropic_elastic" + state + option, {words});
  expect_input_error(
      "envelope --model isotropic_elastic --state /nonexistent/s.toml --amplitude 1e-4",
      {"/nonexistent/s.toml"});
  // Read as empty files before ("missing key 'stress'"); a FIFO hung the command.
  expect_input_error("envelope --model isotropic_elastic --amplitude 1e-4 --state " +
                         fs::path(data("isotropic_state.toml")).parent_path().string(),
                     {"is a folder, not a state file"});
  expect_input_error("envelope --model anisotropic_elastic --params /dev/zero" + state,
                     {"/dev/zero: not a regular file (a parameter file is a text file)"});
  // A state where the law is undefined (hypoplasticity in tension).
  const fs::path tension = write("tension.toml",
                                 "stress = [[-1.0e5, 0.0, 0.0], [0.0, -1.0e5, "
                                 "0.0], [0.0, 0.0, -1.0e5]]\n");
  expect_input_error("envelope --model hypoplastic_wu --amplitude 1e-4 --state " + tension.string(),
                     {"tr(sigma)", tension.string()});
}

}  // namespace
}  // namespace rendulic::models
