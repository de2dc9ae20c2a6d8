// Hostile input and faults that the real `rendulic` binary meets before or without any DEM
// (docs/usage.md: exit 2 and one line naming the culprit, nothing written, never a crash):
// state labels HDF5 cannot hold, a folder, device or FIFO as the scenario, a key nested 50,000
// deep, integers at the edge of int64, an unstable preparation damping, a step that strains the
// cell too far, a run that computes nothing, damaged results files (a wrongly typed attribute,
// /states as a dataset, a dangling link, an envelope without stress pairs, a hard-link cycle),
// `calibrate --out` to a path it cannot write, report and plot into a folder it cannot write,
// stale temporary files.
// Synthetic results files (synthetic_results.hpp) stand in for a run's; the damage is done with
// HDF5's own API.
#include <H5Cpp.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>
#include <vector>

#include "cli_runner.hpp"
#include "rendulic/core/results.hpp"
#include "synthetic_results.hpp"
#include "tiny_run.hpp"

namespace {
namespace fs = std::filesystem;
using rendulic::testing::CliResult;
using rendulic::testing::read_file;

fs::path fresh_dir(const std::string& name) {
  return rendulic::testing::fresh_dir("app_faults/" + name);
}

fs::path write_file(const fs::path& p, const std::string& text) {
  std::ofstream(p, std::ios::binary) << text;
  return p;
}

int lines(const std::string& s) { return static_cast<int>(std::count(s.begin(), s.end(), '\n')); }

// Runs `rendulic ARGS` with stderr apart from stdout.
CliResult rendulic(const std::string& args) { return rendulic::testing::run_rendulic(args, false); }

// The refusal every bad input gets: exit 2, one line on stderr that says `what`.
void expect_refusal(const CliResult& r, const std::string& what) {
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(lines(r.err), 1) << r.err;
  EXPECT_EQ(r.err.rfind("rendulic: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find(what), std::string::npos) << "expected '" << what << "' in: " << r.err;
}

// A seed-like results file that `calibrate` accepts (it needs /material k_star and each
// state's stress).
fs::path calibratable(const std::string& name) {
  const fs::path f = rendulic::app::testing::seed_like("faults_" + name, false);
  rendulic::ResultsWriter w = rendulic::ResultsWriter::update(f);
  w.attr("/material", "k_star", 1.0);
  for (int s = 1; s <= 5; ++s)
    w.write("/states/s" + std::to_string(s) + "/stress", Eigen::Matrix3d::Identity().eval());
  w.commit();
  return f;
}

// A thread count out of range is refused in counts, on a short line: CLI11's check of a
// non-negative number printed the largest double (309 digits) as its upper end.
TEST(Faults, AThreadCountOutOfRangeIsOneShortLine) {
  const fs::path d = fresh_dir("threads");
  const std::string scenario = write_file(d / "s.toml", "").string();
  for (const std::string& command :
       {"run " + scenario + " --out " + (d / "o").string(), "sweep " + scenario + " --quick",
        "probe " + scenario, std::string("calibrate --results x.h5 --model isotropic_elastic")})
    for (const char* value : {"-1", "5000", "two"}) {
      const CliResult r = rendulic(command + " --threads " + value);
      expect_refusal(r, "--threads");
      EXPECT_LT(r.err.size(), 120u) << r.err;
      EXPECT_FALSE(fs::exists(d / "o")) << command;
    }
}

// The same for the numbers that must be positive without a scenario key behind them.
TEST(Faults, ANonPositiveNumberIsOneShortLine) {
  const fs::path d = fresh_dir("positive");
  const std::string scenario = write_file(d / "s.toml", "").string();
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
      {"fit --in x.csv --loss-scale", {"-1", "nan"}},
      {"sweep " + scenario + " --quick --path-rates", {"0", "-5"}},
      {"probe " + scenario + " --directions", {"0", "-2"}}};
  for (const auto& [command, values] : cases)
    for (const std::string& value : values) {
      const CliResult r = rendulic(command + " " + value);
      expect_refusal(r, command.substr(command.rfind(' ') + 1));
      EXPECT_LT(r.err.size(), 120u) << r.err;
    }
}

// A material whose contact time makes the time step huge (density 1e300: dt ~ 1e140 s), so
// that one step strains the cell by more than DemSystem::kMaxStrainPerStep, is refused at the
// first step: it was an internal error of the neighbour list (exit 1) after infinite cell
// lengths.
TEST(Faults, AStepThatStrainsTheCellTooFarIsOneLine) {
  const fs::path d = fresh_dir("strain_step");
  const CliResult r = rendulic("run " + rendulic::testing::tiny_scenario(d).string() + " --out " +
                               (d / "o").string() + " --quiet --set material.density=1e300");
  expect_refusal(r, "per time step");
  EXPECT_NE(r.err.find("density"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(d / "o" / "results.h5"));
}

TEST(Faults, AnOutputPathOfTheWrongKindIsRefusedBeforeTheStagesRun) {
  // A folder named results.h5 or report.md, or a file named figures, failed only after the
  // last stage: the whole run's work then kept as results.h5.partial, or results.h5 written
  // and the report missing, exit 2.
  const fs::path d = fresh_dir("wrong_kind");
  const std::string run = "run " + rendulic::testing::tiny_scenario(d).string() +
                          " --quiet --threads 1 --set run.stages=prepare,isotropic,report --out ";
  fs::create_directories(d / "a" / "results.h5");
  expect_refusal(rendulic(run + (d / "a").string()),
                 (d / "a" / "results.h5").string() + ": is a folder (the results file is a file)");
  fs::create_directories(d / "b" / "report.md");
  expect_refusal(rendulic(run + (d / "b").string()),
                 (d / "b" / "report.md").string() + ": is a folder (the report is a file)");
  fs::create_directories(d / "c");
  write_file(d / "c" / "figures", "");
  expect_refusal(rendulic(run + (d / "c").string()),
                 (d / "c" / "figures").string() + ": is a file, not a folder (the figures folder)");
  for (const char* sub : {"a", "b", "c"})
    EXPECT_EQ(std::distance(fs::directory_iterator(d / sub), fs::directory_iterator{}), 1) << sub;
  // Without figures, a file named figures is no obstacle.
  const CliResult plain = rendulic(run + (d / "c").string() + " --set report.figures=false");
  EXPECT_EQ(plain.code, 0) << plain.err;
  EXPECT_TRUE(fs::is_regular_file(d / "c" / "report.md"));
}

TEST(Faults, StateLabelsHdf5CannotHoldAreRefusedBeforeAnythingIsWritten) {
  // "." named /states itself and aborted the run with an HDF5 exception (exit 134), leaving
  // its temporary file; a NUL cut the label short.
  const fs::path d = fresh_dir("labels");
  const fs::path out = d / "out";
  expect_refusal(
      rendulic("run " + (fs::path(RENDULIC_SOURCE_DIR) / "data/scenarios/quick.toml").string() +
               " --out " + out.string() + " --set states.labels=a,.,c,d,e"),
      "states.labels (--set): label '.' is reserved");
  const fs::path s =
      write_file(d / "nul.toml", "[states]\neps_dev = [0.01]\nlabels = [\"b\\u0000c\"]\n");
  expect_refusal(rendulic("run " + s.string() + " --out " + out.string()),
                 "nul.toml:3): label 'b\\x00c' contains a control character");
  EXPECT_FALSE(fs::exists(out));
}

TEST(Faults, AScenarioMustBeARegularTextFile) {
  // A folder ran the default scenario (N = 9261) and exited 0; /dev/zero read without end.
  const fs::path d = fresh_dir("scenario_files");
  const fs::path out = d / "out";
  expect_refusal(rendulic("run " + d.string() + " --out " + out.string()), "is a folder");
  expect_refusal(rendulic("run /dev/zero --out " + out.string()), "/dev/zero: not a regular file");
  ASSERT_EQ(::mkfifo((d / "fifo.toml").c_str(), 0600), 0);
  expect_refusal(rendulic("run " + (d / "fifo.toml").string() + " --out " + out.string()),
                 "fifo.toml: not a regular file");
  std::string deep = "run";
  for (int i = 0; i < 50000; ++i) deep += ".a";
  const fs::path s = write_file(d / "deep.toml", deep + " = 1\n");
  expect_refusal(rendulic("run " + s.string() + " --out " + out.string()),
                 "deep.toml:1: a dotted key nested deeper than 16 levels");
  EXPECT_FALSE(fs::exists(out));
}

TEST(Faults, ValidationGapsAreClosedBeforeAnythingIsWritten) {
  const fs::path d = fresh_dir("validation");
  const fs::path out = d / "out";
  const std::string quick = (fs::path(RENDULIC_SOURCE_DIR) / "data/scenarios/quick.toml").string();
  const std::string run = "run " + quick + " --out " + out.string() + " --set ";
  // Seeds compared in double: 4e18 + 1 passed, and 2^63 - 1 was printed as another number.
  expect_refusal(rendulic(run + "run.seed=4000000000000000001"),
                 "value 4000000000000000001 is out of range [0, 4000000000000000000]");
  expect_refusal(rendulic(run + "run.seed=9223372036854775807"),
                 "value 9223372036854775807 is out of range");
  // Checked only when the prepare stage started (an empty output folder was left), and the
  // message printed dem.dt_factor's value as preparation.gamma_b's.
  expect_refusal(rendulic(run + "preparation.gamma_b=5000"),
                 "preparation.gamma_b (--set): 5000 kg/s makes the preparation's time step");
  EXPECT_FALSE(fs::exists(out));
  // A run that computes nothing replaced an existing results.h5 with an empty one.
  {
    rendulic::ResultsWriter w(out / "results.h5");
    w.attr("/", "marker", std::string("earlier run"));
    w.commit();
  }
  const std::string before = read_file(out / "results.h5");
  expect_refusal(rendulic(run + "run.stages=[]"), "run.stages (--set): no stage that computes");
  expect_refusal(rendulic(run + "run.stages=report"), "run.stages (--set): no stage that computes");
  // A stage named twice ran once, without a word, where every other list of names refuses it.
  expect_refusal(rendulic(run + "run.stages=[prepare,isotropic,prepare]"),
                 "key 'run.stages': value 'prepare' given twice");
  EXPECT_EQ(read_file(out / "results.h5"), before);
}

TEST(Faults, DamagedResultsFilesAreOneLineNeverACrash) {
  const fs::path f = calibratable("damaged");
  const fs::path d = f.parent_path();
  auto damaged = [&](const std::string& name, auto&& damage) {
    const fs::path g = d / name / "results.h5";
    fs::create_directories(g.parent_path());
    fs::copy_file(f, g, fs::copy_options::overwrite_existing);
    H5::H5File h(g.string(), H5F_ACC_RDWR);
    damage(h);
    return g.string();
  };
  // A wrongly typed attribute: HDF5's exception escaped main (abort, exit 134).
  const std::string typed = damaged("typed", [](H5::H5File& h) {
    H5::Group m = h.openGroup("/material");
    m.removeAttr("k_star");
    m.createAttribute("k_star", H5::StrType(H5::PredType::C_S1, 3), H5::DataSpace(H5S_SCALAR));
  });
  expect_refusal(
      rendulic("calibrate --no-write --no-path --model isotropic_elastic --results " + typed),
      typed + ": /material @k_star: is not a number");
  // A state's volume fraction the laws' density terms read: NaN changed the fit, exit 0.
  const std::string nu = damaged("nu", [](H5::H5File& h) {
    H5::Group s = h.openGroup("/states/s1");
    if (s.attrExists("volume_fraction")) s.removeAttr("volume_fraction");
    const double nan = std::nan("");
    s.createAttribute("volume_fraction", H5::PredType::NATIVE_DOUBLE, H5::DataSpace(H5S_SCALAR))
        .write(H5::PredType::NATIVE_DOUBLE, &nan);
  });
  expect_refusal(rendulic("calibrate --no-write --model isotropic_elastic --results " + nu),
                 nu + ":/states/s1@volume_fraction is nan, outside [0, 1)");
  // An envelope's amplitude of 0 made the report call it elastic, with an infinite stiffness;
  // a particle count of -5 made C2's flip ratios negative: both exit 0, without a word.
  const std::string amplitude = damaged("amplitude", [](H5::H5File& h) {
    const double zero = 0.0;
    h.openGroup("/states/s1/envelopes/dynamic_5e-05")
        .openAttribute("amplitude")
        .write(H5::PredType::NATIVE_DOUBLE, &zero);
  });
  const std::string zero_amplitude =
      amplitude +
      ": envelope /states/s1/envelopes/dynamic_5e-05: @amplitude is 0, not a positive finite "
      "strain";
  expect_refusal(rendulic("report --no-figures " + amplitude), zero_amplitude);
  expect_refusal(
      rendulic("calibrate --no-write --no-path --model isotropic_elastic --results " + amplitude),
      zero_amplitude);
  const std::string count = damaged("count", [](H5::H5File& h) {
    const std::int64_t n = -5;
    h.openGroup("/material").openAttribute("n_particles").write(H5::PredType::NATIVE_INT64, &n);
  });
  expect_refusal(rendulic("report --no-figures " + count),
                 count + ":/material@n_particles is -5, not a positive count");
  // /states stored as a dataset.
  const std::string states = damaged("states", [](H5::H5File& h) {
    h.unlink("/states");
    const hsize_t n = 3;
    h.createDataSet("/states", H5::PredType::NATIVE_DOUBLE, H5::DataSpace(1, &n));
  });
  expect_refusal(rendulic("report --no-figures " + states), states + ": /states: is not a group");
  expect_refusal(rendulic("calibrate --no-write --model isotropic_elastic --results " + states),
                 states + ": /states: is not a group");
  EXPECT_EQ(rendulic("inspect " + states).code, 0);
  // A dangling link where an envelope's stress pairs should be.
  const std::string dangling = damaged("dangling", [](H5::H5File& h) {
    const std::string e = "/states/s1/envelopes/dynamic_5e-05/stress_star";
    h.unlink(e);
    H5Lcreate_soft("/nowhere", h.getId(), e.c_str(), H5P_DEFAULT, H5P_DEFAULT);
  });
  expect_refusal(
      rendulic("calibrate --no-write --no-path --model isotropic_elastic --results " + dangling),
      "neither stress_star nor d_stress");
  const CliResult ins = rendulic("inspect " + dangling);
  EXPECT_EQ(ins.code, 0) << ins.err;
  EXPECT_NE(ins.out.find("stress_star (dangling link)"), std::string::npos) << ins.out;
  // A hard-link cycle: inspect never returned and grew its memory.
  const std::string cycle = damaged("cycle", [](H5::H5File& h) {
    H5Lcreate_hard(h.getId(), "/states", h.getId(), "/states/s1/loop", H5P_DEFAULT, H5P_DEFAULT);
  });
  const CliResult cyc = rendulic("inspect " + cycle);
  EXPECT_EQ(cyc.code, 0) << cyc.err;
  EXPECT_NE(cyc.out.find("loop/ -> same group as /states"), std::string::npos) << cyc.out;
}

TEST(Faults, AnEnvelopeWithoutStressPairsIsNotMeasuredNotReadOutOfBounds) {
  // C3 indexed the stress pairs by the directions: absent or empty pairs were read out of
  // bounds (AddressSanitizer: heap-buffer-overflow in app/report.cpp).
  const fs::path f = calibratable("no_pairs");
  for (const bool empty : {false, true}) {
    {
      H5::H5File h(f.string(), H5F_ACC_RDWR);
      for (int s = 1; s <= 5; ++s) {
        const std::string e =
            "/states/s" + std::to_string(s) + "/envelopes/dynamic_5e-05/stress_star";
        if (H5Lexists(h.getId(), e.c_str(), H5P_DEFAULT) > 0) h.unlink(e);
        if (empty) {
          const hsize_t dims[2] = {0, 2};
          h.createDataSet(e, H5::PredType::NATIVE_DOUBLE, H5::DataSpace(2, dims));
        }
      }
    }
    const CliResult r = rendulic("report --no-figures " + f.string());
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string md = read_file(f.parent_path() / "report.md");
    EXPECT_NE(md.find("| C3 | Near isotropy the isotropic probe (35.26 deg) maps onto the major "
                      "axis (< 5 deg) | - | **not measured** |"),
              std::string::npos)
        << md;
  }
}

// Fits that could not be made (shape "none", an error) were read as fits with NaN axes: C1
// said "does not hold" with every value n/a. Nothing was measured, and the report says so
// (here every elastic envelope of every state: the claims fall back from one to the next).
TEST(Faults, ClaimsOnEnvelopesThatCouldNotBeFittedAreNotMeasured) {
  const fs::path f = calibratable("unfitted");
  {
    H5::H5File h(f.string(), H5F_ACC_RDWR);
    for (int s = 1; s <= 5; ++s)
      for (const char* e : {"dynamic_5e-05", "linear_response_5e-05"}) {
        const std::string g = "/states/s" + std::to_string(s) + "/envelopes/" + e + "/fit_stress";
        if (H5Lexists(h.getId(), g.c_str(), H5P_DEFAULT) > 0) h.unlink(g);
        H5::Group fit = h.createGroup(g);
        const H5::StrType text(H5::PredType::C_S1, H5T_VARIABLE);
        for (const auto& [name, value] :
             {std::pair<const char*, std::string>{"shape", "none"}, {"error", "degenerate"}})
          fit.createAttribute(name, text, H5::DataSpace(H5S_SCALAR)).write(text, value);
      }
  }
  const CliResult r = rendulic("report --no-figures " + f.string());
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string md = read_file(f.parent_path() / "report.md");
  EXPECT_NE(md.find("| C1 | Elastic stress envelope: an ellipse centred at the origin (|centre|/a "
                    "< 0.05) | - | **not measured** |"),
            std::string::npos)
      << md;
}

// calibrate --value: a parameter given twice kept the last value without a word, 0x10 was read
// as sixteen (std::stod takes hexadecimal), and nan was "outside its bounds". An unknown name
// given twice was refused as given twice, and an unknown name of --value or --free only after
// the results file was read.
TEST(Faults, CalibrateValuesGivenTwiceOrNotDecimalAreRefused) {
  const fs::path f = calibratable("values");
  const std::string calibrate =
      "calibrate --no-write --no-path --model isotropic_elastic --results " + f.string() +
      " --value ";
  expect_refusal(rendulic(calibrate + "K=1e10,K=2e10"), "--value: parameter 'K' given twice");
  const std::string unknown = "--value: unknown parameter 'Q' of isotropic_elastic (known: K, ";
  expect_refusal(rendulic(calibrate + "Q=1,Q=2"), unknown);
  expect_refusal(rendulic("calibrate --model isotropic_elastic --results " +
                          (f.parent_path() / "absent.h5").string() + " --value Q=1"),
                 unknown);
  expect_refusal(rendulic("calibrate --model isotropic_elastic --results " +
                          (f.parent_path() / "absent.h5").string() + " --free K,Q,Q"),
                 "--free: unknown parameter 'Q' of isotropic_elastic (known: K, ");
  for (const std::string v : {"K=0x10", "K=1e10x", "K=nan", "K=inf", "K=1e400", "K="})
    expect_refusal(rendulic(calibrate + v),
                   "--value '" + v + "': '" + v.substr(2) + "' is not a finite decimal number");
  // Out of bounds names the value and the bounds, as a parameters file does (it read "value of
  // 'K' outside its bounds").
  expect_refusal(rendulic(calibrate + "K=-5"),
                 "calibrate: --value parameter 'K' = -5 is outside its bounds [1, 1e+13] Pa");
}

TEST(Faults, CalibrateOutToAPathItCannotWriteTouchesNothing) {
  // It used to rewrite results.h5 first and then fail on --out with exit 2.
  const fs::path f = calibratable("out");
  const std::string before = read_file(f);
  const std::string calibrate =
      "calibrate --no-path --model isotropic_elastic --results " + f.string() + " --out ";
  expect_refusal(rendulic(calibrate + (f.parent_path() / "no/such/folder/x.json").string()),
                 "cannot write the JSON output");
  expect_refusal(rendulic(calibrate + f.parent_path().string()), "is a folder");
  EXPECT_EQ(read_file(f), before) << "results.h5 unchanged";
  const fs::path json = f.parent_path() / "fit.json";
  const CliResult ok = rendulic(calibrate + json.string());
  ASSERT_EQ(ok.code, 0) << ok.err;
  EXPECT_NE(read_file(json).find("\"model\""), std::string::npos);
  EXPECT_TRUE(rendulic::ResultsReader(f).exists("/calibration/isotropic_elastic"));
  for (const auto& e : fs::directory_iterator(f.parent_path()))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

TEST(Faults, ReportAndPlotIntoAFolderTheyCannotWriteExitTwo) {
  // A Python traceback and exit 1 before. Root writes anywhere but a read-only mount, so the
  // commands run as nobody when the test runs as root (setpriv, util-linux).
  const fs::path f = calibratable("readonly");
  const fs::path dir = f.parent_path();
  const auto read_only = fs::perms::owner_read | fs::perms::owner_exec | fs::perms::group_read |
                         fs::perms::group_exec | fs::perms::others_read | fs::perms::others_exec;
  fs::create_directories(dir / "figures");
  fs::permissions(f, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read |
                         fs::perms::others_read);
  fs::permissions(dir / "figures", read_only);
  fs::permissions(dir, read_only);
  const std::string as =
      geteuid() == 0 ? "setpriv --reuid=65534 --regid=65534 --clear-groups " : "";
  auto run = [&](const std::string& args) {
    return rendulic::testing::run_command(as + RENDULIC_EXE + " " + args, false);
  };
  expect_refusal(run("report " + f.string()), "figures: cannot write figures here");
  expect_refusal(run("plot " + f.string()), "figures: cannot write figures here");
  expect_refusal(run("report --no-figures " + f.string()), "cannot write the report");
  fs::permissions(dir, fs::perms::owner_all);
  fs::permissions(dir / "figures", fs::perms::owner_all);
}

TEST(Faults, AStaleTemporaryOfAKilledRunIsRemovedAndSaidSo) {
  const fs::path f = calibratable("stale");
  const pid_t dead = fork();
  if (dead == 0) _exit(0);
  waitpid(dead, nullptr, 0);
  const fs::path stale = f.parent_path() / (".results.h5.tmp-" + std::to_string(dead));
  write_file(stale, "the half-written file of a killed run");
  const CliResult r =
      rendulic("calibrate --no-path --model isotropic_elastic --results " + f.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find(stale.string() + ": removed, a temporary file of a run that was killed"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(stale));
}

}  // namespace
