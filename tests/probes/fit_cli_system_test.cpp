// End-to-end tests of `rendulic fit` (docs/fitting.md "The fit command"): JSON keys and values on
// a known ellipse and line, the circle's undefined inclination, the readable summary, and
// bad input (missing file, empty file, missing column, NaN, too few points, degenerate data)
// -> exit 2 with a one-line reason. Runs the real binary.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli_runner.hpp"
#include "synthetic.hpp"

namespace rendulic {
namespace {
namespace fs = std::filesystem;

using CmdResult = rendulic::testing::CliResult;
CmdResult run_fit(const std::string& args) {
  return rendulic::testing::run_rendulic("fit " + args, /*merge_stderr=*/false);
}

fs::path dir() {
  const fs::path d = fs::path(RENDULIC_TEST_TMP) / "probes_cli";
  fs::create_directories(d);
  return d;
}

fs::path write_csv(const std::string& name, const std::string& text) {
  const fs::path p = dir() / name;
  std::ofstream(p) << text;
  return p;
}

fs::path envelope_csv(const std::string& name, const Envelope& env) {
  std::ostringstream o;
  o.precision(17);
  o << (env.has_theta() ? "theta_deg,x,y,comment\n" : "x,y\n");
  for (std::size_t i = 0; i < env.size(); ++i) {
    if (env.has_theta()) o << env.theta_deg[i] << ",";
    o << env.response[i].x() << "," << env.response[i].y();
    if (env.has_theta()) o << ",probe" << i;
    o << "\n";
  }
  return write_csv(name, o.str());
}

// The number at `key` (the index-th element if it holds an array), read by a JSON parser
// independent of the writer: output that is not valid JSON fails here.
double json_number(const std::string& json, const std::string& key, int index = 0) {
  const nlohmann::json j = nlohmann::json::parse(json);
  EXPECT_TRUE(j.contains(key)) << key << " in " << json;
  if (!j.contains(key)) return std::nan("");
  return j[key].is_array() ? j[key][index].get<double>() : j[key].get<double>();
}
nlohmann::json parsed(const std::string& json) { return nlohmann::json::parse(json); }

TEST(FitCli, EllipseJson) {
  test::TrueEllipse e{{0.01, -0.02}, 0.5, 0.05, 30.0};
  const fs::path csv = envelope_csv("ellipse.csv", test::ellipse_envelope(e, 36, 0.0, 1, true));
  const CmdResult r = run_fit("--in " + csv.string() + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << "one JSON object, one line";
  EXPECT_EQ(parsed(r.out)["shape"], "ellipse") << r.out;
  // Noiseless: exact to the solver's tolerance (the JSON carries 17 digits).
  EXPECT_NEAR(json_number(r.out, "center", 0), 0.01, 1e-9);
  EXPECT_NEAR(json_number(r.out, "center", 1), -0.02, 1e-9);
  EXPECT_NEAR(json_number(r.out, "semi_axes", 0), 0.5, 1e-9);
  EXPECT_NEAR(json_number(r.out, "semi_axes", 1), 0.05, 1e-9);
  EXPECT_NEAR(json_number(r.out, "inclination_deg"), 30.0, 1e-6);
  EXPECT_EQ(parsed(r.out)["stderr"]["center"].size(), 2u) << r.out;
  EXPECT_EQ(parsed(r.out)["used_theta"], true);
}

TEST(FitCli, LineAndCircleAndText) {
  const fs::path line = envelope_csv("line.csv", test::line_envelope({1.0, 2.0}, 3.0, 35.26, 24));
  const CmdResult rl = run_fit("--in " + line.string() + " --json --shape auto");
  ASSERT_EQ(rl.code, 0) << rl.err;
  EXPECT_EQ(parsed(rl.out)["shape"], "line") << rl.out;
  EXPECT_NEAR(json_number(rl.out, "semi_axes", 1), 0.0, 0.0);
  EXPECT_NEAR(json_number(rl.out, "inclination_deg"), 35.26, 1e-9);

  test::TrueEllipse c{{0.0, 0.0}, 1.0, 1.0, 0.0};
  const fs::path circle = envelope_csv("circle.csv", test::ellipse_envelope(c, 20));
  const CmdResult rc = run_fit("--in " + circle.string() + " --json --loss huber");
  ASSERT_EQ(rc.code, 0) << rc.err;
  EXPECT_EQ(parsed(rc.out)["shape"], "circle") << rc.out;
  EXPECT_TRUE(parsed(rc.out)["inclination_deg"].is_null()) << rc.out;
  EXPECT_EQ(rc.out.find("nan"), std::string::npos);

  const CmdResult rt = run_fit("--in " + circle.string());
  ASSERT_EQ(rt.code, 0);
  EXPECT_NE(rt.out.find("undefined (circle)"), std::string::npos) << rt.out;
}

// A value below the smallest normal double is a number (strtod's ERANGE for it is not an
// error): it used to be refused as "not finite". A leading + is a number too.
TEST(FitCli, ASubnormalValueIsReadAsTheNumberItIs) {
  const CmdResult ref =
      run_fit("--in " + write_csv("zero.csv", "x,y\n1,0\n0,1\n-1,0\n0,-1\n0.7,0.7\n").string() +
              " --json --ignore-theta");
  const CmdResult sub = run_fit(
      "--in " +
      write_csv("subnormal.csv", "x,y\n1,1e-320\n0,1\n-1,-4.9e-324\n0,-1\n+0.7,0.7\n").string() +
      " --json --ignore-theta");
  ASSERT_EQ(ref.code, 0) << ref.err;
  ASSERT_EQ(sub.code, 0) << sub.err;
  for (const char* key : {"center", "semi_axes"})
    for (int i = 0; i < 2; ++i)
      EXPECT_NEAR(json_number(sub.out, key, i), json_number(ref.out, key, i), 1e-12) << key;
}

void expect_input_error(const std::string& args, const std::string& reason) {
  const CmdResult r = run_fit(args);
  EXPECT_EQ(r.code, 2) << args << "\n" << r.out << r.err;
  EXPECT_NE(r.err.find(reason), std::string::npos) << args << ": " << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line: " << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

// A spreadsheet's "CSV UTF-8" (a byte-order mark, CRLF line ends) is read as the plain file:
// the mark made the first column's name differ from the one it shows. A column that looks
// meant for the directions but is not theta_deg is said to be ignored.
TEST(FitCli, ASpreadsheetsCsvIsReadAndADirectionsColumnMisnamedIsSaid) {
  const std::string rows = "0,1,0\n90,0,1\n180,-1,0\n270,0,-1\n45,0.7,0.7\n";
  const CmdResult plain =
      run_fit("--in " + write_csv("plain.csv", "theta_deg,x,y\n" + rows).string());
  ASSERT_EQ(plain.code, 0) << plain.err;
  std::string crlf = "\xEF\xBB\xBF";
  for (const char c : "theta_deg,x,y\n" + rows)
    crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  const CmdResult sheet = run_fit("--in " + write_csv("sheet.csv", crlf).string());
  EXPECT_EQ(sheet.code, 0) << sheet.err;
  EXPECT_EQ(sheet.out, plain.out);
  EXPECT_EQ(sheet.err, "");
  const CmdResult misnamed =
      run_fit("--in " + write_csv("theta.csv", "Theta,x,y\n" + rows).string());
  EXPECT_EQ(misnamed.code, 0) << misnamed.err;
  EXPECT_EQ(misnamed.err, "rendulic: warning: " + (dir() / "theta.csv").string() +
                              ":1: column 'Theta' is not read; the probe directions' column is "
                              "theta_deg (degrees)\n");
  EXPECT_EQ(misnamed.out.find("directions used"), std::string::npos) << misnamed.out;
  // A decimal-comma locale's spreadsheet writes ';' between cells, and some tools a tab: the
  // header's separator is the file's (they were refused, "must name columns 'x' and 'y'").
  for (const char sep : {';', '\t'}) {
    std::string text = "theta_deg,x,y\n" + rows;
    std::replace(text.begin(), text.end(), ',', sep);
    const CmdResult other = run_fit("--in " + write_csv("separated.csv", text).string());
    EXPECT_EQ(other.code, 0) << other.err;
    EXPECT_EQ(other.out, plain.out);
  }
  // Its numbers with a decimal comma are refused with the point they need.
  expect_input_error("--in " + write_csv("comma.csv", "x;y\n1;0\n0,5;1\n").string(),
                     "comma.csv:3: column 'x': '0,5' is not a finite decimal number (a decimal "
                     "comma: write numbers with a point, 0.5)");
}

TEST(FitCli, BadInputExits2WithAReason) {
  expect_input_error("--in " + (dir() / "missing.csv").string(),
                     "missing.csv: cannot read CSV file: No such file or directory");
  expect_input_error("--in " + write_csv("empty.csv", "").string(), "empty file");
  expect_input_error("--in " + write_csv("header_only.csv", "x,y\n").string(), "no data rows");
  expect_input_error("--in " + write_csv("no_y.csv", "x,z\n1,2\n").string(), "'x' and 'y'");
  // Rows without a header said "column '0' appears twice".
  expect_input_error("--in " + write_csv("rows.csv", "0,1,0\n90,0,1\n").string(),
                     "rows.csv:1: the first line is a row of numbers, not a header naming the "
                     "columns (x,y or theta_deg,x,y)");
  expect_input_error("--in " + write_csv("nan.csv", "x,y\n1,2\n3,nan\n4,5\n").string(),
                     "nan.csv:3: column 'y'");
  for (const char* bad : {"abc", "0x10", "1e400", "-inf", "1e5e"})
    expect_input_error(
        "--in " + write_csv("text.csv", std::string("x,y\n1,2\n3,") + bad + "\n").string(),
        std::string("text.csv:3: column 'y': '") + bad + "' is not a finite decimal number");
  expect_input_error("--in " + dir().string(), "is a folder, not a CSV file");
  expect_input_error("--in " + write_csv("short.csv", "x,y\n1,2\n3\n").string(),
                     "expected 2 fields");
  const fs::path four = write_csv("four.csv", "x,y\n1,0\n0,1\n-1,0\n0,-0.5\n");
  expect_input_error("--in " + four.string() + " --shape ellipse", "at least 5 points");
  expect_input_error("--in " + four.string(), "at least 5 points");
  expect_input_error(
      "--in " + write_csv("same.csv", "x,y\n1,1\n1,1\n1,1\n1,1\n1,1\n1,1\n").string(),
      "all points coincide");
  // Evenly spaced on a segment, no directions: no ellipse is determined (it was a wrong one).
  const fs::path segment = write_csv("segment.csv", "x,y\n0,0\n1,2\n2,4\n3,6\n4,8\n5,10\n");
  expect_input_error("--in " + segment.string() + " --shape ellipse",
                     "the 6 points are collinear to rounding");
  const fs::path ok = write_csv("ok.csv", "x,y\n1,0\n0,1\n-1,0\n0,-1\n0.7,0.7\n");
  // In data units (this file's size is 1): 1e308 went into the fit as inf, 1e-320 failed it
  // and the message blamed the data.
  for (const char* scale : {"1e308", "1e-320", "1e9", "1e-9"})
    expect_input_error("--in " + ok.string() + " --loss huber --loss-scale " + scale,
                       "times the data's size 0.978162; give one within 1e-08 to 1e+08");
  for (const char* scale : {"1e7", "1e-7"})
    EXPECT_EQ(run_fit("--in " + ok.string() + " --loss cauchy --loss-scale " + scale).code, 0)
        << scale;
  EXPECT_EQ(run_fit("--in " + ok.string() + " --shape hyperbola").code, 2);
  EXPECT_EQ(run_fit("--in " + ok.string() + " --loss l1").code, 2);
  EXPECT_EQ(run_fit("").code, 2);
}

}  // namespace
}  // namespace rendulic
