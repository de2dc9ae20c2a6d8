// End-to-end tests of the `rendulic` executable's foundation behaviour: exit codes,
// one-line errors naming the culprit, nothing written on bad input, the effective scenario
// stored in the results file, `inspect` on good and bad files, standard streams that are full
// or closed. Runs the real binary.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "cli_runner.hpp"
#include "rendulic/core/results.hpp"
#include "tiny_run.hpp"

namespace {
namespace fs = std::filesystem;

using CmdResult = rendulic::testing::CliResult;
CmdResult rendulic(const std::string& args) { return rendulic::testing::run_rendulic(args); }
fs::path fresh_dir(const std::string& name) {
  return rendulic::testing::fresh_dir("app_cli/" + name);
}

fs::path write_file(const fs::path& p, const std::string& text) {
  std::ofstream(p) << text;
  return p;
}

int lines(const std::string& s) { return static_cast<int>(std::count(s.begin(), s.end(), '\n')); }

TEST(Cli, HelpAndVersionSucceed) {
  EXPECT_EQ(rendulic("--help").code, 0);
  EXPECT_EQ(rendulic("--version").code, 0);
  for (const char* sub : {"run", "fit", "envelope", "calibrate", "bench", "inspect", "plot", "keys",
                          "sweep", "report"})
    EXPECT_EQ(rendulic(std::string(sub) + " --help").code, 0) << sub;
}

TEST(Cli, UnknownSubcommandOrOptionExits2) {
  EXPECT_EQ(rendulic("frobnicate").code, 2);
  EXPECT_EQ(rendulic("inspect --bogus x").code, 2);
  EXPECT_EQ(rendulic("").code, 2);
}

// CLI11's own range check lets NaN through; before real_in_range, `bench --friction nan` timed
// the frictionless engine alone and exited 0, and `bench --seconds nan` printed 1e+300 ns.
TEST(Cli, ARealOptionThatIsNotFiniteIsRefusedNamingIt) {
  const fs::path d = fresh_dir("not_finite");
  const fs::path scenario = write_file(d / "s.toml", "[dem]\nn_particles = 250\n");
  for (const std::string& args : std::vector<std::string>{
           "bench --particles 100 --repetitions 1 --seconds nan",
           "bench --particles 100 --steps 1 --repetitions 1 --friction nan",
           "bench --particles 100 --steps 1 --repetitions 1 --friction 0.5 --rolling-friction nan",
           "bench --particles 100 --steps 1 --repetitions 1 --friction inf",
           "run " + scenario.string() + " --out " + (d / "out").string() + " --progress-every nan",
           "probe missing.data --out " + (d / "probe").string() + " --progress-every nan"}) {
    const CmdResult r = rendulic(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.out;
    EXPECT_EQ(lines(r.out), 1) << args << "\n" << r.out;
    EXPECT_NE(r.out.find("is not a finite number"), std::string::npos) << args << "\n" << r.out;
  }
  EXPECT_FALSE(fs::exists(d / "out"));
  EXPECT_FALSE(fs::exists(d / "probe"));
  // The folder of the LAMMPS files cannot be made where a file stands: one line, not an internal
  // error (exit 1), before any state is prepared.
  const fs::path file = write_file(d / "a_file", "x\n");
  const CmdResult r = rendulic("bench --particles 100 --steps 1 --repetitions 1 --lammps " +
                               (file / "sub").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_EQ(lines(r.out), 1) << r.out;
  EXPECT_NE(r.out.find(file.string() +
                       ": is a file, not a folder (it cannot hold the --lammps "
                       "folder " +
                       (file / "sub").string() + ")"),
            std::string::npos)
      << r.out;
}

// A count that is not a whole number was called out of range ("Value abc not in range 0 to
// 4096", CLI11's Range); a count out of range says the range as a real number's is said.
TEST(Cli, ACountThatIsNotAWholeNumberIsCalledSo) {
  for (const auto& [args, said] : std::vector<std::pair<std::string, std::string>>{
           {"run x.toml --threads abc", "--threads: Value abc is not a whole number (digits only)"},
           {"run x.toml --threads 2.5", "--threads: Value 2.5 is not a whole number (digits only)"},
           {"bench --repetitions x", "--repetitions: Value x is not a whole number (digits only)"},
           {"run x.toml --threads -1", "--threads: Value -1 is out of range [0, 4096]"},
           {"sweep --path-seeds 0", "--path-seeds: Value 0 is out of range [1, 64]"},
           // A real number's bounds as a scenario key's ("0.000000 to 10.000000" before), and a
           // word is not a number (it was "not in range").
           {"bench --friction -1", "--friction: Value -1 is out of range [0, 10]"},
           {"bench --friction abc", "--friction: Value abc is not a number"},
           {"bench --seconds nan", "--seconds: Value nan is not a finite number"},
           // Options backed by a scenario key too (CLI11 said "Could not convert").
           {"calibrate --function-tolerance abc",
            "--function-tolerance: Value abc is not a number"},
           {"calibrate --max-iterations 2.5",
            "--max-iterations: Value 2.5 is not a whole number (digits only)"},
           // And options without a check of their own.
           {"envelope --amplitude abc", "--amplitude: Value abc is not a number"},
           {"probe x.data --directions 2.5", "--directions: Value 2.5 is not a whole number"},
           {"probe x.data --amplitudes 1e-4,abc", "--amplitudes: Value abc is not a number"},
           // Both ways to say how long bench times (--steps won without a word).
           {"bench --seconds 1 --steps 5", "--seconds excludes --steps"}}) {
    const CmdResult r = rendulic(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.out;
    EXPECT_EQ(lines(r.out), 1) << args << "\n" << r.out;
    EXPECT_NE(r.out.find(said), std::string::npos) << args << "\n" << r.out;
  }
}

TEST(Cli, BadScenarioExits2NamingTheKeyAndWritesNothing) {
  const fs::path d = fresh_dir("bad_scenario");
  struct Case {
    std::string toml, expect, line;
  } cases[] = {
      {"[run]\nsede = 3\n", "unknown key 'run.sede' (did you mean 'run.seed'?)", "s.toml:2"},
      {"[run]\nseed = \"x\"\n", "key 'run.seed': expected an integer", "s.toml:2"},
      {"[run]\nseed = -4\n", "key 'run.seed': value -4 is out of range", "s.toml:2"},
      {"[run]\nstages = [\"prepare\", \"dance\"]\n", "'dance' is not one of", "s.toml:2"},
      {"[bogus_section]\nx = 1\n", "unknown key 'bogus_section'", "s.toml:1"},
  };
  for (const auto& c : cases) {
    const fs::path scen = write_file(d / "s.toml", c.toml);
    const fs::path out = d / "out";
    const CmdResult r = rendulic("run " + scen.string() + " --out " + out.string());
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_NE(r.out.find(c.expect), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(c.line), std::string::npos) << r.out;
    EXPECT_EQ(lines(r.out), 1) << r.out;
    EXPECT_FALSE(fs::exists(out)) << "nothing written";
  }
  const CmdResult missing = rendulic("run " + (d / "nope.toml").string());
  EXPECT_EQ(missing.code, 2);
  EXPECT_NE(missing.out.find("nope.toml"), std::string::npos);
}

TEST(Cli, BadOverrideExits2NamingTheKey) {
  const fs::path d = fresh_dir("bad_set");
  const fs::path scen = write_file(d / "s.toml", "[run]\nstages = []\n");
  const fs::path out = d / "out";
  for (const std::string set : {"run.sed=3", "run.seed=abc", "run.seed=-1", "run.seed"}) {
    const CmdResult r =
        rendulic("run " + scen.string() + " --out " + out.string() + " --set " + set);
    EXPECT_EQ(r.code, 2) << set << ": " << r.out;
    EXPECT_NE(r.out.find("--set " + set), std::string::npos) << r.out;
    EXPECT_EQ(lines(r.out), 1) << r.out;
    EXPECT_FALSE(fs::exists(out));
  }
}

TEST(Cli, StageFailingMidRunLeavesNoResultsFile) {
  // A pressure the volume-fraction bound cannot reach: after a small preparation the isotropic
  // stage fails with the results file open.
  const fs::path d = fresh_dir("mid_run");
  const fs::path scen = write_file(d / "s.toml",
                                   "[run]\nstages = [\"prepare\", \"isotropic\"]\n[dem]\n"
                                   "n_particles = 64\n[preparation]\nrate = 20000.0\n"
                                   "gamma_b = 5.0\n[relax]\ntime_cap = 1e-4\n[isotropic]\n"
                                   "pressure_star = 1.0\nnu_max = 0.66\n");
  const fs::path out = d / "out";
  const CmdResult r = rendulic("run " + scen.string() + " --out " + out.string());
  EXPECT_EQ(r.code, 2) << r.out;
  // The plan and the stages' starts (docs/usage.md "Progress and messages"), then one line.
  EXPECT_NE(r.out.find("stages prepare, isotropic"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("[isotropic] started"), std::string::npos) << r.out;
  const std::string last = r.out.substr(r.out.rfind('\n', r.out.size() - 2) + 1);
  EXPECT_EQ(last.rfind("rendulic: isotropic compression: P* = 1 not reached by the volume "
                       "fraction bound 0.66 (P* there ",
                       0),
            0u)
      << last;
  const std::string kept = "; raise the bound; completed stages (prepare) kept in " +
                           (out / "results.h5.partial").string() + "\n";
  EXPECT_EQ(last.substr(last.size() - std::min(last.size(), kept.size())), kept) << last;
  EXPECT_FALSE(fs::exists(out / "results.h5"));
  for (const auto& e : fs::directory_iterator(out))
    EXPECT_EQ(e.path().filename(), "results.h5.partial") << "no temporary left behind";
}

// An empty --out (a shell variable that is not set) wrote into the current folder without a word,
// and a file where the output folder must be was called "Not a directory".
TEST(Cli, AnOutputFolderThatIsEmptyOrAFileIsSaidSo) {
  const fs::path d = fresh_dir("out_folder");
  const fs::path scen =
      write_file(d / "s.toml", "[run]\nstages = [\"prepare\"]\n[dem]\nn_particles = 64\n");
  const fs::path file = write_file(d / "afile", "not a folder\n");
  for (const auto& [args, words] : std::vector<std::pair<std::string, std::string>>{
           {"run " + scen.string() + " --out ''",
            "--out: the output folder name is empty (. for the current folder)"},
           {"probe x.data --out ''",
            "--out: the output folder name is empty (. for the current folder)"},
           {"run " + scen.string() + " --out " + file.string(),
            file.string() + ": is a file, not a folder (the output folder)"},
           {"run " + scen.string() + " --out " + (file / "sub").string(),
            file.string() + ": is a file, not a folder (it cannot hold the output folder " +
                (file / "sub").string() + ")"}}) {
    const CmdResult r = rendulic(args);
    EXPECT_EQ(r.code, 2) << args;
    EXPECT_EQ(r.out, "rendulic: " + words + "\n") << args;
  }
  EXPECT_EQ(rendulic::testing::read_file(file), "not a folder\n");
  EXPECT_FALSE(fs::exists(fs::current_path() / "results.h5"));
}

// An empty file name (a shell variable that is not set) said ": no such file", a message that
// begins with nothing; where an option left out means a default, it took the default without a
// word: `envelope --params ''` the law's defaults, `sweep ''` the built-in scenario.
TEST(Cli, AnEmptyFileNameIsSaidSo) {
  const std::string state = std::string(RENDULIC_SOURCE_DIR) + "/data/models/isotropic_state.toml";
  for (const auto& [args, words] : std::vector<std::pair<std::string, std::string>>{
           {"inspect ''", "the name of the results file is empty"},
           {"plot ''", "the name of the results file is empty"},
           {"export '' --state a --lammps x.data", "the name of the results file is empty"},
           {"calibrate --model isotropic_elastic --results ''",
            "the name of the results file is empty"},
           {"probe '' --out x", "the name of the packing file is empty"},
           {"run '' --out x", "the name of the scenario file is empty"},
           {"envelope --model isotropic_elastic --amplitude 1e-4 --state ''",
            "the name of the state file is empty"},
           {"envelope --model isotropic_elastic --amplitude 1e-4 --state " + state + " --params ''",
            "--params: the file name is empty (see rendulic --help)"},
           // Small, so that without the check the default sweep this ran costs seconds.
           {"sweep '' --quick --factors method --base-n 50 --out x",
            "scenario: the file name is empty (see rendulic --help)"}}) {
    const CmdResult r = rendulic(args);
    EXPECT_EQ(r.code, 2) << args;
    EXPECT_EQ(r.out, "rendulic: " + words + "\n") << args;
  }
  EXPECT_FALSE(fs::exists(fs::current_path() / "x"));
}

// A stage whose input the run would not make (a label the run has no state of) is refused
// before any work: `run.stages = prepare, probes` prepared, then said "needs 'states'".
TEST(Cli, AStageWhoseInputTheRunWouldNotMakeIsRefusedBeforeAnyWork) {
  const fs::path d = fresh_dir("needs");
  const fs::path scen = write_file(d / "s.toml", "[dem]\nn_particles = 64\n");
  const fs::path out = d / "out";
  for (const auto& [set, words] : std::vector<std::pair<std::string, std::string>>{
           {"run.stages=prepare,probes",
            "run.stages (--set): stage 'probes' needs the stage 'states' in the same run; to "
            "probe a state of an existing file: `rendulic probe FILE.h5:LABEL`"},
           {"run.stages=prepare,isotropic,path,states,calibration",
            "run.stages (--set): stage 'calibration' needs the stage 'probes' or "
            "'linear_response' in the same run; to calibrate on an existing file: `rendulic "
            "calibrate --results FILE.h5`"},
           {"run.stages=prepare,pressure",
            "run.stages (--set): stage 'pressure' needs the stage 'isotropic' in the same run"},
           {"run.stages=isotropic,path",
            "run.stages (--set): stage 'isotropic' needs the stage 'prepare' in the same run"},
           {"run.stages=prepare,isotropic,path,states,linear_response,calibration --set "
            "calibration.states=[a,zz]",
            "calibration.states (--set): no state 'zz' in this run (states.labels: a, b, c, d, "
            "e)"}}) {
    const CmdResult r =
        rendulic("run " + scen.string() + " --out " + out.string() + " --set " + set);
    EXPECT_EQ(r.code, 2) << set << ": " << r.out;
    EXPECT_EQ(r.out, "rendulic: " + words + "\n") << set;
    EXPECT_FALSE(fs::exists(out)) << set;
  }
}

// fits or calibration without the stages they read: refused before anything is written, and
// an earlier results.h5 is kept (`--set run.stages=fits` replaced it by a file of nothing).
TEST(Cli, ARunOfOnlyFitsOrCalibrationIsRefusedAndKeepsTheFile) {
  const fs::path d = fresh_dir("only_fits");
  const fs::path scen = write_file(d / "s.toml", "[run]\nstages = [\"prepare\"]\n");
  const fs::path out = d / "out";
  fs::create_directories(out);
  const fs::path kept = write_file(out / "results.h5", "an earlier run's file\n");
  for (const std::string stages : {"fits", "calibration", "[fits,calibration,report]"}) {
    const CmdResult r =
        rendulic("run " + scen.string() + " --out " + out.string() + " --set run.stages=" + stages);
    EXPECT_EQ(r.code, 2) << stages << ": " << r.out;
    EXPECT_EQ(lines(r.out), 1) << r.out;
    EXPECT_NE(r.out.find("fits and calibration read what the DEM stages before them wrote; for "
                         "an existing file use `rendulic fit --results FILE.h5`"),
              std::string::npos)
        << r.out;
  }
  std::ifstream in(kept);
  EXPECT_EQ(std::string((std::istreambuf_iterator<char>(in)), {}), "an earlier run's file\n");
}

TEST(Cli, EffectiveScenarioIsStoredAndInspectable) {
  const fs::path d = fresh_dir("effective");
  // The cheapest run that computes something (a run of no stage is refused): a small
  // packing, prepared fast.
  const fs::path scen = write_file(d / "s.toml",
                                   "[run]\nstages = [\"prepare\"]\nseed = 5\ndescription = \"cli "
                                   "test\"\n[dem]\nn_particles = 64\n[preparation]\nrate = "
                                   "20000.0\ngamma_b = 5.0\n[relax]\ntime_cap = 1e-4\n");
  const fs::path out = d / "out";
  const CmdResult r =
      rendulic("run " + scen.string() + " --out " + out.string() + " --set run.seed=42");
  ASSERT_EQ(r.code, 0) << r.out;
  rendulic::ResultsReader reader(out / "results.h5");
  EXPECT_EQ(reader.attr_int("/", "seed"), 42);
  const std::string stored = reader.attr_string("/", "scenario");
  EXPECT_NE(stored.find("seed = 42"), std::string::npos) << stored;
  EXPECT_NE(stored.find("description = \"cli test\""), std::string::npos) << stored;

  const CmdResult ins = rendulic("inspect " + (out / "results.h5").string());
  EXPECT_EQ(ins.code, 0) << ins.out;
  EXPECT_NE(ins.out.find("@schema = \"rendulic/2\""), std::string::npos) << ins.out;
  EXPECT_NE(ins.out.find("@seed = 42"), std::string::npos) << ins.out;
}

// A path other than the seed's, from a packing loaded to a pressure (docs/dem.md "Paths",
// "Loading to a pressure"): the run stores the path's type and the servo's measured error, the
// isotropic state sits at its target pressure, the report shows the path's q/p and says the
// seed's path claim is not judged; a mistyped path is refused in one line naming the key.
TEST(Cli, ADrainedPathFromAPressureIsRunStoredAndReported) {
  const fs::path d = fresh_dir("drained");
  const fs::path scen = write_file(
      d / "s.toml",
      "[run]\nstages = [\"prepare\", \"isotropic\", \"path\"]\nseed = 3\n[dem]\nn_particles = "
      "128\n[preparation]\nrate = 20000.0\ngamma_b = 5.0\n[relax]\ntime_cap = 2e-4\n"
      "[isotropic]\npressure_star = 0.01\nrate_max = 2000.0\n"
      "[path]\ntype = \"drained_compression\"\nrate = 400.0\neps_dev_max = 0.02\nsamples = 20\n"
      "[states]\neps_dev = [0.01]\nlabels = [\"a\"]\n");
  const fs::path out = d / "out";
  CmdResult r = rendulic("run " + scen.string() + " --out " + out.string() + " --threads 1");
  ASSERT_EQ(r.code, 0) << r.out;
  {
    rendulic::ResultsReader reader(out / "results.h5");
    EXPECT_EQ(reader.attr_string("/path", "type"), "drained_compression");
    EXPECT_TRUE(reader.has_attr("/path", "servo_error"));
    EXPECT_NEAR(reader.attr_double("/isotropic", "relaxed_pressure_star"), 0.01, 1e-3 * 0.01);
  }
  r = rendulic("report --no-figures " + (out / "results.h5").string());
  ASSERT_EQ(r.code, 0) << r.out;
  std::ifstream in(out / "report.md");
  const std::string md((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(md.find("type: `drained_compression`"), std::string::npos) << md;
  EXPECT_NE(md.find("steady state"), std::string::npos) << md;
  EXPECT_NE(md.find("not the seed's undrained extension"), std::string::npos) << md;

  r = rendulic("run " + scen.string() + " --out " + (d / "bad").string() +
               " --set path.type=triaxial");
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(lines(r.out), 1) << r.out;
  EXPECT_NE(r.out.find("path.type"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("drained_compression"), std::string::npos) << r.out;
}

TEST(Cli, InspectRefusesFilesThatAreNotOurs) {
  const fs::path d = fresh_dir("inspect_bad");
  const fs::path txt = write_file(d / "notes.h5", "just text\n");
  CmdResult r = rendulic("inspect " + txt.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("not an HDF5 file"), std::string::npos) << r.out;
  EXPECT_EQ(lines(r.out), 1);
  r = rendulic("inspect " + (d / "missing.h5").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("no such file"), std::string::npos) << r.out;
  // `report` reads through the same reader: same one-line refusals, and nothing written.
  r = rendulic("report --no-figures " + txt.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("not an HDF5 file"), std::string::npos) << r.out;
  EXPECT_EQ(lines(r.out), 1);
  EXPECT_FALSE(fs::exists(d / "report.md"));
}

// Output that stdout could not take (a full disk under `rendulic keys > keys.md`; /dev/full
// here) was lost with exit 0. The reason is that of the first write that failed: by the end
// errno no longer said it for `keys`, `--version` and `inspect`; `envelope` writes with printf.
TEST(Cli, OutputThatStdoutCannotTakeIsOneLineAndExitTwo) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  const fs::path d = fresh_dir("stdout_full");
  for (const std::string& args : std::vector<std::string>{
           "keys", "--version", "run --help",
           "envelope --model isotropic_elastic --amplitude 1e-5 --state " +
               write_file(d / "state.toml", "stress = [[-1e5, 0, 0], [0, -1e5, 0], [0, 0, -1e5]]\n")
                   .string()}) {
    const CmdResult r = rendulic::testing::run_rendulic(args + " > /dev/full", false);
    EXPECT_EQ(r.code, 2) << args;
    EXPECT_EQ(r.err, "rendulic: standard output: cannot write: No space left on device\n") << args;
  }
}

// A run whose parent closed its stdout and stderr (`>&- 2>&-`): the results file took one of
// their numbers and the calibration's summary was written into it (HDF5 then read "bad object
// header version number"), exit 0. Closed standard streams are /dev/null now.
TEST(Cli, ARunWithItsStandardStreamsClosedKeepsItsResultsFileWhole) {
  const fs::path d = fresh_dir("closed_streams");
  const fs::path scen = rendulic::testing::tiny_scenario(d);
  const CmdResult r =
      rendulic::testing::run_command("(" + std::string(RENDULIC_EXE) + " run " + scen.string() +
                                     " --threads 1 --out " + (d / "out").string() + " >&- 2>&-)");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out, "");
  const CmdResult inspect = rendulic("inspect " + (d / "out" / "results.h5").string());
  EXPECT_EQ(inspect.code, 0) << inspect.out;
  const rendulic::ResultsReader results(d / "out" / "results.h5");
  EXPECT_TRUE(results.has_attr("/timings", "calibration"));
}

TEST(Cli, KeysReferenceMatchesTheDocs) {
  // docs/scenario-keys.md embeds `rendulic keys` verbatim between two markers: if a key is
  // added or changed without updating the docs, this fails and says how to regenerate.
  const CmdResult r = rendulic("keys");
  ASSERT_EQ(r.code, 0);
  std::ifstream in(fs::path(RENDULIC_SOURCE_DIR) / "docs" / "scenario-keys.md");
  ASSERT_TRUE(in) << "docs/scenario-keys.md missing";
  std::string doc((std::istreambuf_iterator<char>(in)), {});
  const std::string begin = "<!-- BEGIN rendulic keys -->\n", end = "<!-- END rendulic keys -->";
  const auto b = doc.find(begin), e = doc.find(end);
  ASSERT_NE(b, std::string::npos);
  ASSERT_NE(e, std::string::npos);
  EXPECT_EQ(doc.substr(b + begin.size(), e - b - begin.size()), r.out)
      << "docs/scenario-keys.md is stale: regenerate with docs/update-keys.sh";
}

}  // namespace
