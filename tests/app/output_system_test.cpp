// The output a researcher reads (docs/usage.md "Progress and messages", docs/results.md
// "Units"): a run whose stderr goes to a file (not a terminal) logs every stage's start, end and
// progress in plain lines, --quiet silences them; every float dataset of a real results file
// carries its unit, lists are string arrays, counters integers, and the model envelopes are
// starred like the DEM's. Runs the real binary (the tiny run of tiny_run.hpp).
#include <H5Cpp.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "cli_runner.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/core/results.hpp"
#include "tiny_run.hpp"

namespace {
namespace fs = std::filesystem;
using rendulic::testing::CliResult;

const fs::path kRoot = fs::path(RENDULIC_TEST_TMP) / "app_output_system";

TEST(Progress, ALogGetsPlainLinesForEveryDemStage) {
  const fs::path out = rendulic::testing::fresh_dir("app_output_system/log");
  // stderr is a pipe here, as in a batch job's log.
  const CliResult r = rendulic::testing::run_rendulic(
      "run " + rendulic::testing::tiny_scenario(kRoot).string() +
      " --threads 1 --progress-every 0.1 --set run.stages=prepare,isotropic,path,states --out " +
      out.string());
  ASSERT_EQ(r.code, 0) << r.out;
  for (const char* stage : {"prepare", "isotropic", "path", "states"}) {
    const std::string tag = std::string("[") + stage + "]";
    EXPECT_NE(r.out.find("rendulic: " + tag + " started\n"), std::string::npos) << stage;
    EXPECT_TRUE(std::regex_search(r.out, std::regex("rendulic: \\" + tag.substr(0, tag.size() - 1) +
                                                    "\\] done in [0-9]+ s\n")))
        << stage << "\n"
        << r.out;
  }
  // Progress with an estimate, as lines: a percentage and the time left.
  EXPECT_TRUE(std::regex_search(
      r.out, std::regex("rendulic: \\[[a-z_]+\\] .* [0-9.]+%, .* in stage, about .* left\n")))
      << r.out;
  // No terminal control in a log: no carriage return, no erase-line sequence.
  EXPECT_EQ(r.out.find('\r'), std::string::npos);
  EXPECT_EQ(r.out.find("\033["), std::string::npos);

  const CliResult q = rendulic::testing::run_rendulic(
      "run " + rendulic::testing::tiny_scenario(kRoot).string() +
      " --quiet --threads 1 --progress-every 0.1 --set run.stages=prepare --out " +
      (out / "quiet").string());
  ASSERT_EQ(q.code, 0) << q.out;
  EXPECT_EQ(q.out.find("[prepare]"), std::string::npos) << q.out;
}

// Every object of a file, with HDF5's own visitor (independent of our reader).
struct Seen {
  std::vector<std::string> float_datasets, integer_datasets;
};
herr_t visit(hid_t obj, const char* name, const H5O_info_t* info, void* data) {
  if (info->type != H5O_TYPE_DATASET) return 0;
  auto* seen = static_cast<Seen*>(data);
  const hid_t ds = H5Dopen2(obj, name, H5P_DEFAULT);
  const hid_t type = H5Dget_type(ds);
  const H5T_class_t cls = H5Tget_class(type);
  const std::string path = std::string("/") + name;
  if (cls == H5T_FLOAT) seen->float_datasets.push_back(path);
  if (cls == H5T_INTEGER) seen->integer_datasets.push_back(path);
  H5Tclose(type);
  H5Dclose(ds);
  return 0;
}

std::string unit_of(const H5::H5File& f, const std::string& path) {
  const H5::DataSet ds = f.openDataSet(path);
  if (!ds.attrExists("units")) return "";
  const H5::Attribute a = ds.openAttribute("units");
  if (a.getSpace().getSimpleExtentNdims() == 1) {  // one unit per entry (a law's params)
    const auto n = static_cast<std::size_t>(a.getSpace().getSimpleExtentNpoints());
    std::vector<char*> units(n, nullptr);
    a.read(a.getStrType(), units.data());
    std::string joined;
    for (char* u : units) joined += std::string(joined.empty() ? "" : ",") + (u ? u : "?");
    H5Dvlen_reclaim(a.getStrType().getId(), a.getSpace().getId(), H5P_DEFAULT, units.data());
    return joined;
  }
  std::string unit;
  a.read(a.getStrType(), unit);
  return unit;
}

TEST(Units, EveryFloatDatasetOfARunCarriesItsUnit) {
  const fs::path file = rendulic::testing::tiny_results();
  ASSERT_TRUE(fs::exists(file));
  const H5::H5File f(file.string(), H5F_ACC_RDONLY);
  Seen seen;
  H5Ovisit(f.getId(), H5_INDEX_NAME, H5_ITER_NATIVE, visit, &seen);
  ASSERT_GT(seen.float_datasets.size(), 50u);
  for (const std::string& p : seen.float_datasets) {
    const std::string unit = unit_of(f, p);
    EXPECT_FALSE(unit.empty()) << p << " has no units attribute";
    EXPECT_FALSE(rendulic::units::is_counter(p)) << p << " counts: it should be an integer";
  }
  // Spot checks against the conventions: SI stress in Pa, starred stress and strain 1.
  EXPECT_EQ(unit_of(f, "/path/stress"), "Pa");
  EXPECT_EQ(unit_of(f, "/path/stress_star"), "1");
  EXPECT_EQ(unit_of(f, "/path/time"), "s");
  EXPECT_EQ(unit_of(f, "/states/a/positions"), "m");
  EXPECT_EQ(unit_of(f, "/states/a/envelopes/dynamic_5e-05/theta_deg"), "deg");
  // A law's parameters, one unit each (isotropic_elastic: K, G in Pa, n_p dimensionless, ...).
  EXPECT_EQ(unit_of(f, "/calibration/isotropic_elastic/params").substr(0, 10), "Pa,Pa,1,Pa");
  // Counters are integers: every per-probe counter of the envelopes.
  std::set<std::string> counters;
  for (const std::string& p : seen.integer_datasets)
    if (rendulic::units::is_counter(p)) counters.insert(p.substr(p.rfind('/') + 1));
  EXPECT_TRUE(counters.count("contacts_opened")) << "counters stored as integers";
  EXPECT_TRUE(counters.count("relax_steps"));
}

TEST(Units, FloatAttributesWithAUnitSayIt) {
  const rendulic::ResultsReader r(rendulic::testing::tiny_results());
  EXPECT_EQ(r.attr_string("/material", "k_units"), "N/m");
  EXPECT_EQ(r.attr_string("/material", "k_star_units"), "Pa");
  EXPECT_EQ(r.attr_string("/material", "dt_units"), "s");
  EXPECT_EQ(r.attr_string("/states/a", "minimise_max_displacement_units"), "m");
  EXPECT_FALSE(r.has_attr("/material", "w_units"));  // dimensionless: no companion
}

TEST(Lists, AreStringArraysAndModelEnvelopesAreStarred) {
  const fs::path file = rendulic::testing::tiny_results();
  const H5::H5File f(file.string(), H5F_ACC_RDONLY);
  const std::string g = "/calibration/isotropic_elastic";
  for (const char* name : {"param_names", "free", "fitted_states", "yardstick_blocks"}) {
    const H5::Attribute a = f.openGroup(g).openAttribute(name);
    EXPECT_EQ(a.getTypeClass(), H5T_STRING) << name;
    EXPECT_EQ(a.getSpace().getSimpleExtentNdims(), 1) << name << " is one joined text";
  }
  const rendulic::ResultsReader r(file);
  const std::vector<std::string> states = r.attr_strings(g, "fitted_states");
  EXPECT_FALSE(states.empty());
  for (const std::string& s : states) EXPECT_EQ(s.find(','), std::string::npos) << s;
  EXPECT_EQ(r.attr_strings(g, "param_names").size(), r.read_vector(g + "/params").size());
  // The law's envelope beside the DEM's: the same name and unit, starred.
  const std::string dem = "/states/a/envelopes/dynamic_5e-05";
  const std::string law = g + "/states/a/envelopes/dynamic_5e-05";
  ASSERT_TRUE(r.exists(law + "/stress_star")) << "model envelope not starred";
  EXPECT_FALSE(r.exists(law + "/stress"));
  EXPECT_EQ(unit_of(f, law + "/stress_star"), unit_of(f, dem + "/stress_star"));
  // And the same order of magnitude as the DEM's points (a law fitted to them).
  const auto dem_points = r.read_pairs(dem + "/stress_star");
  const auto law_points = r.read_pairs(law + "/stress_star");
  ASSERT_EQ(dem_points.size(), law_points.size());
  double dem_size = 0, law_size = 0;
  for (std::size_t i = 0; i < dem_points.size(); ++i)
    dem_size += dem_points[i].norm(), law_size += law_points[i].norm();
  EXPECT_GT(law_size, 0.1 * dem_size);
  EXPECT_LT(law_size, 10 * dem_size);
}

// `rendulic fit --results` fits a stored run again in place: forced to lines, every stored stress
// fit becomes a line with b = 0 while the envelopes themselves keep every bit; a missing file
// and --in with --results are one-line errors (exit 2) that leave the file as it was.
TEST(Refit, AResultsFileIsFittedAgainInPlace) {
  const fs::path dir = rendulic::testing::fresh_dir("app_output_system/refit");
  const fs::path file = dir / "results.h5";
  fs::copy_file(rendulic::testing::tiny_results(), file);
  const std::string env = "/states/a/envelopes/dynamic_5e-05";  // elastic: an ellipse
  Eigen::MatrixXd pairs_before;
  {
    const rendulic::ResultsReader r(file);
    pairs_before = r.read_matrix(env + "/stress_star");
    ASSERT_EQ(r.attr_string(env + "/fit_stress", "shape"), "ellipse");
  }
  // A pressure branch's states (here a copy of the main ones, as a run's pressure stage stores
  // them): refitted too; they kept their old fits.
  const std::string branch_env = "/pressure/nu0.7" + env;
  {
    H5::H5File h(file.string(), H5F_ACC_RDWR);
    h.createGroup("/pressure").close();
    h.createGroup("/pressure/nu0.7").close();
    ASSERT_GE(H5Ocopy(h.getId(), "/states", h.getId(), "/pressure/nu0.7/states", H5P_DEFAULT,
                      H5P_DEFAULT),
              0);
  }
  const CliResult ok =
      rendulic::testing::run_rendulic("fit --results " + file.string() + " --shape line --json");
  ASSERT_EQ(ok.code, 0) << ok.out;
  EXPECT_NE(ok.out.find("\"fitted\""), std::string::npos) << ok.out;
  const rendulic::ResultsReader r(file);
  EXPECT_EQ(r.attr_string(env + "/fit_stress", "shape"), "line");
  EXPECT_EQ(r.attr_string(branch_env + "/fit_stress", "shape"), "line");
  EXPECT_EQ(r.attr_doubles(env + "/fit_stress", "semi_axes")[1], 0.0);
  EXPECT_TRUE(r.read_matrix(env + "/stress_star") == pairs_before);

  const auto stamp = fs::last_write_time(file);
  for (const std::string& bad : {"fit --results " + (dir / "absent.h5").string(),
                                 "fit --results " + file.string() + " --in x.csv"}) {
    const CliResult e = rendulic::testing::run_rendulic(bad, /*merge_stderr=*/true);
    EXPECT_EQ(e.code, 2) << bad;
    EXPECT_EQ(rendulic::testing::error_lines(e.out), 1) << e.out;
  }
  EXPECT_EQ(fs::last_write_time(file), stamp);
  // A file without envelopes (a run of prepare alone): nothing to fit is said, not "0 fitted,
  // stored in FILE" with exit 0.
  const fs::path bare = dir / "bare.h5";
  {
    rendulic::ResultsWriter w(bare);
    w.create_group("/states/a");
    w.commit();
  }
  const auto bare_stamp = fs::last_write_time(bare);
  const CliResult none = rendulic::testing::run_rendulic("fit --results " + bare.string(), false);
  EXPECT_EQ(none.code, 2) << none.err;
  EXPECT_EQ(none.err, "rendulic: " + bare.string() +
                          ": no envelope to fit (the probes and linear_response stages of a run, "
                          "or `rendulic probe FILE.h5:LABEL`, make them)\n");
  EXPECT_EQ(fs::last_write_time(bare), bare_stamp);
}

// What a calibration writes does not depend on its threads ("results do not depend on it",
// docs/calibration.md "Threads"), its tally of evaluations that failed on the substep cap
// included. The tiny run's elasto-plastic fit has trial points where one part fails on the
// cap and another fails otherwise: with a helper thread, which of the two failed first in time
// used to decide the count (136, 132 or 133 of 206 failed evaluations on two threads, 136 on
// one) and with it the warning's words.
TEST(Calibrate, WritesTheSameOnOneThreadAndOnTwo) {
  const fs::path dir = rendulic::testing::fresh_dir("app_output_system/calibrate_threads");
  fs::copy_file(rendulic::testing::tiny_results(), dir / "results.h5");
  const auto json = [&](int threads) {
    const CliResult r = rendulic::testing::run_rendulic(
        "calibrate --results " + (dir / "results.h5").string() +
            " --model elastoplastic_fabric --no-write --threads " + std::to_string(threads),
        /*merge_stderr=*/false);
    EXPECT_EQ(r.code, 0) << r.err;
    // Every line but the wall time's.
    std::vector<std::string> lines;
    std::istringstream in(r.out);
    for (std::string line; std::getline(in, line);)
      if (line.find("\"seconds\":") == std::string::npos) lines.push_back(line);
    return lines;
  };
  const std::vector<std::string> one = json(1);
  ASSERT_GT(one.size(), 100u);
  for (int round = 0; round < 3; ++round) {
    const std::vector<std::string> two = json(2);
    ASSERT_EQ(two.size(), one.size()) << "round " << round;
    for (std::size_t k = 0; k < one.size(); ++k)
      ASSERT_EQ(two[k], one[k]) << "round " << round << ", line " << k + 1;
  }
}

}  // namespace
