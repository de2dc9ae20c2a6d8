// Faults met during and after real runs (docs/usage.md "Results are atomic"; docs/results.md):
// every subcommand that reads a results file walked over damaged copies of a real one (every
// group, dataset and attribute missing, wrongly typed or empty in turn, each with one command:
// damage_walk.hpp; the walk with every command is in faults_validate_test.cpp), a full disk under a
// run and under `calibrate`, a dataset declaring more values than the file holds, a late stage
// that fails, a signal in the middle of a run and in
// the middle of the figures, stale temporary files of killed runs, the stored scenario
// replayed. The real file comes from a tiny run (N = 250 at fast rates, about 3 s of CPU),
// made once per build and shared by the tests through a lock.
//
// The full-disk tests mount a small tmpfs when they can (root, as in CI); otherwise the
// kernel's file size limit (ulimit -f) makes the writes fail the same way (EFBIG instead of
// ENOSPC).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/mount.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <vector>

#include "cli_runner.hpp"
#include "damage_walk.hpp"
#include "rendulic/core/results.hpp"
#include "rendulic/core/scenario.hpp"
#include "tiny_run.hpp"

namespace {
namespace fs = std::filesystem;
using rendulic::testing::CliResult;
using rendulic::testing::read_file;
using rendulic::testing::temporaries;

const fs::path kRoot = fs::path(RENDULIC_TEST_TMP) / "app_faults_system";

fs::path fresh_dir(const std::string& name) {
  return rendulic::testing::fresh_dir("app_faults_system/" + name);
}

fs::path tiny_scenario() { return rendulic::testing::tiny_scenario(kRoot); }

// The real results file of the tiny run, made once per build (tiny_run.hpp).
fs::path base_results() { return rendulic::testing::tiny_results(); }

// --- the damaged-file walk -------------------------------------------------------------

TEST(FaultsSystem, EverySubcommandRefusesDamagedResultsFilesInOneLine) {
  // Each damage with one command (800 runs of the binary); every damage with every command is
  // FaultsValidate.EveryDamageWithEverySubcommand (label validate).
  rendulic::testing::walk_damaged_copies(base_results(), "app_faults_system/walk",
                                         kRoot / "walk-outcomes.txt",
                                         rendulic::testing::Coverage::one_command_each);
}

// --- full disks ----------------------------------------------------------------------------

// A small file system at `dir`: a tmpfs of `kib` KiB when mounting is allowed (root), else
// nothing (the caller limits the file size instead). Unmounted when destroyed.
class SmallDisk {
 public:
  SmallDisk(const fs::path& dir, int kib) : dir_(dir) {
    fs::create_directories(dir);
    const std::string opts = "size=" + std::to_string(kib) + "k";
    mounted_ = ::mount("tmpfs", dir.c_str(), "tmpfs", 0, opts.c_str()) == 0;
  }
  ~SmallDisk() {
    if (mounted_) ::umount2(dir_.c_str(), MNT_DETACH);
  }
  bool mounted() const { return mounted_; }
  // The command line that runs rendulic with ARGS on this disk: with the file size limit
  // when no tmpfs could be mounted.
  std::string command(const std::string& args, int fallback_kib) const {
    const std::string exe = std::string(RENDULIC_EXE) + " " + args;
    if (mounted_) return exe;
    return "sh -c \"trap '' XFSZ; ulimit -f " + std::to_string(fallback_kib) + "; exec " + exe +
           "\"";
  }
  const char* reason() const { return mounted_ ? "No space left on device" : "File too large"; }

 private:
  fs::path dir_;
  bool mounted_ = false;
};

// A state's positions grown over chunks never written, declaring 2^40 rows (a damaged or
// unfinished file): `export` and `probe` ended in "internal error: std::bad_alloc", exit 1.
TEST(FaultsSystem, ADatasetDeclaringMoreValuesThanItHoldsIsOneLine) {
  const fs::path d = fresh_dir("declared");
  const fs::path f = d / "results.h5";
  fs::copy_file(base_results(), f);
  {
    H5::H5File h(f.string(), H5F_ACC_RDWR);
    const std::string p = "/states/a/positions";
    h.unlink(p);
    const hsize_t dims[2] = {hsize_t{1} << 40, 3}, max[2] = {H5S_UNLIMITED, 3}, chunk[2] = {64, 3};
    H5::DSetCreatPropList plist;
    plist.setChunk(2, chunk);
    h.createDataSet(p, H5::PredType::NATIVE_DOUBLE, H5::DataSpace(2, dims, max), plist);
  }
  const std::string before = read_file(f);
  for (const std::string& command :
       {"export " + f.string() + " --state a --lammps " + (d / "a.data").string(),
        "probe " + f.string() + ":/states/a --out " + (d / "probed").string()}) {
    const CliResult r = rendulic::testing::run_rendulic(command, false);
    EXPECT_EQ(r.code, 2) << command << "\n" << r.err;
    EXPECT_EQ(rendulic::testing::error_lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(f.string() + ": /states/a/positions: declares 3298534883328 values"),
              std::string::npos)
        << r.err;
  }
  EXPECT_FALSE(fs::exists(d / "a.data"));
  EXPECT_FALSE(fs::exists(d / "probed" / "results.h5"));
  EXPECT_EQ(read_file(f), before);
}

// A probe's strain pair set to nan (a file edited elsewhere, or damaged): the report fitted it
// for its claims and ended in "internal error: fit_rendulic_map: strain pairs are collinear",
// exit 1. Found by setting values of a real file to nan, inf and 1e308 at random.
TEST(FaultsSystem, APairThatIsNotFiniteIsOneLineNamingIt) {
  const fs::path d = fresh_dir("not_finite");
  const fs::path f = d / "results.h5";
  fs::copy_file(base_results(), f);
  const std::string g = "/states/b/envelopes/dynamic_0.002";
  {
    H5::H5File h(f.string(), H5F_ACC_RDWR);
    H5::DataSet strain = h.openDataSet(g + "/strain");
    std::vector<double> v(strain.getSpace().getSimpleExtentNpoints());
    strain.read(v.data(), H5::PredType::NATIVE_DOUBLE);
    v.at(10) = std::numeric_limits<double>::quiet_NaN();  // probe 5, x
    strain.write(v.data(), H5::PredType::NATIVE_DOUBLE);
  }
  const std::string before = read_file(f);
  for (const std::string& command :
       {"report --no-figures " + f.string(),
        "calibrate --model isotropic_elastic --max-iterations 5 --results " + f.string()}) {
    const CliResult r = rendulic::testing::run_rendulic(command, false);
    EXPECT_EQ(r.code, 2) << command << "\n" << r.err;
    EXPECT_EQ(rendulic::testing::error_lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(f.string() + ": envelope " + g + "/strain: probe 5 is not finite"),
              std::string::npos)
        << r.err;
  }
  EXPECT_FALSE(fs::exists(d / "report.md"));
  EXPECT_EQ(read_file(f), before);
}

// A probe direction of -1e308 deg (finite): its strain pair is not the probe strain of that
// direction, which has no finite cosine, so the file is refused at reading, naming the probe.
// It was read, and the calibration's objective was nan at the start (Ceres then blamed its own
// "gradient_tolerance = nan"; calibration Backends.AnObjectiveThatIsNotFiniteAtTheStartSaysSo
// keeps that guard's test).
TEST(FaultsSystem, AProbeDirectionBeyondTheDoublesIsRefusedAtReading) {
  const fs::path d = fresh_dir("nan_objective");
  const fs::path f = d / "results.h5";
  fs::copy_file(base_results(), f);
  {
    H5::H5File h(f.string(), H5F_ACC_RDWR);
    H5::DataSet theta = h.openDataSet("/states/a/envelopes/dynamic_5e-05/theta_deg");
    std::vector<double> v(theta.getSpace().getSimpleExtentNpoints());
    theta.read(v.data(), H5::PredType::NATIVE_DOUBLE);
    v.at(5) = -1e308;
    theta.write(v.data(), H5::PredType::NATIVE_DOUBLE);
  }
  for (const std::string command :
       {"calibrate --no-write --model isotropic_elastic --max-iterations 5 --results ",
        "report --no-figures "}) {
    const CliResult r = rendulic::testing::run_rendulic(command + f.string(), false);
    EXPECT_EQ(r.code, 2) << command << r.err;
    EXPECT_EQ(rendulic::testing::error_lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(": envelope /states/a/envelopes/dynamic_5e-05/strain: probe 5 is not the "
                         "probe strain @amplitude (cos, sin) of its theta_deg (theta_deg -1e+308 "
                         "has no finite cosine)"),
              std::string::npos)
        << r.err;
  }
}

TEST(FaultsSystem, ARunOnAFullDiskFailsInOneLineAndLeavesNoTemporary) {
  const fs::path d = fresh_dir("full_run");
  const SmallDisk disk(d / "disk", 160);
  const fs::path out = d / "disk" / "out";
  const CliResult r = rendulic::testing::run_command(
      disk.command(
          "run " + tiny_scenario().string() +
              " --quiet --threads 1 --set run.stages=prepare,isotropic,path,states --out " +
              out.string(),
          160),
      false);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(rendulic::testing::error_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find(disk.reason()), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out / "results.h5"));
  if (fs::exists(out)) {
    EXPECT_TRUE(temporaries(out).empty()) << temporaries(out).front();
    // What may be left is the completed stages' copy, whole, and the line says so.
    for (const auto& e : fs::directory_iterator(out)) {
      EXPECT_EQ(e.path().filename(), "results.h5.partial");
      EXPECT_NE(r.err.find("kept in " + e.path().string()), std::string::npos) << r.err;
      EXPECT_NO_THROW(rendulic::ResultsReader(e.path()).attr_double("/timings", "prepare"));
    }
  }
}

TEST(FaultsSystem, CalibrateOnAFullDiskFailsInOneLine) {
  // The copy it updates did not fit: the results holder's destructor then closed a file it
  // never opened (a segfault).
  const fs::path base = base_results();
  const fs::path d = fresh_dir("full_calibrate");
  const auto size_kib = static_cast<int>(fs::file_size(base) / 1024);
  const SmallDisk disk(d / "disk", size_kib + 64);
  const fs::path f = d / "disk" / "results.h5";
  fs::copy_file(base, f);
  const CliResult r = rendulic::testing::run_command(
      disk.command("calibrate --model isotropic_elastic --max-iterations 5 --results " + f.string(),
                   size_kib + 8),
      false);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(rendulic::testing::error_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find(disk.reason()), std::string::npos) << r.err;
  EXPECT_TRUE(temporaries(f.parent_path()).empty()) << temporaries(f.parent_path()).front();
  EXPECT_EQ(read_file(f), read_file(base)) << "the file is as it was";
}

// --- failures and signals during a run ---------------------------------------------------

TEST(FaultsSystem, BadInputMetInsideAParallelLoopStaysBadInput) {
  // Each ended as an internal error (exit 1), its kind lost on leaving the loop: the states' (a
  // tolerance below the round-off floor, which also ran FIRE for 10^6 iterations per state)
  // and the probes' (a probe rate so slow that a probe needs more than 10^15 steps, which also
  // did not name its key).
  const struct {
    const char* folder;
    const char* sets;
    const char* words;
    const char* also;
  } cases[] = {
      {"round_off", "run.stages=prepare,isotropic,path,states --set states.force_tolerance=1e-16",
       ": states.force_tolerance = 1e-16 is below the round-off floor of this state's forces "
       "(FIRE stalled at ",
       " or more; completed stages (prepare, isotropic, path) kept in "},
      {"probe_rate",
       "run.stages=prepare,isotropic,path,states,probes --set probes.methods=dynamic --set "
       "probes.amplitudes=[0.02] --set probes.rate=1e-300",
       "rendulic: dynamic probe: strain increment at probes.rate = 1e-300 needs ",
       "; completed stages (prepare, isotropic, path, states) kept in "},
  };
  for (const auto& c : cases) {
    const CliResult r = rendulic::testing::run_rendulic(
        "run " + tiny_scenario().string() + " --quiet --threads 1 --set " + c.sets + " --out " +
            (fresh_dir(c.folder) / "out").string(),
        false);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(rendulic::testing::error_lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(c.words), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.also), std::string::npos) << r.err;
  }
}

TEST(FaultsSystem, ALateStageFailureKeepsTheCompletedStagesAsPartial) {
  // Every earlier stage used to be thrown away with the temporary file.
  const fs::path d = fresh_dir("late_failure");
  const fs::path out = d / "out";
  {
    rendulic::ResultsWriter w(out / "results.h5");
    w.attr("/", "marker", std::string("an earlier, good run"));
    w.commit();
  }
  const std::string earlier = read_file(out / "results.h5");
  // A pressure beyond what the volume-fraction bound allows: the isotropic stage fails after
  // the preparation, which only the physics can tell (a stage whose input the run would not
  // make is refused before any work, pipeline.cpp).
  const CliResult r = rendulic::testing::run_rendulic(
      "run " + tiny_scenario().string() +
          " --quiet --threads 1 --set run.stages=prepare,isotropic --set "
          "isotropic.pressure_star=1 --set isotropic.nu_max=0.66 --out " +
          out.string(),
      false);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(rendulic::testing::error_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("P* = 1 not reached by the volume fraction bound 0.66"), std::string::npos)
      << r.err;
  EXPECT_NE(
      r.err.find("; completed stages (prepare) kept in " + (out / "results.h5.partial").string()),
      std::string::npos)
      << r.err;
  EXPECT_EQ(read_file(out / "results.h5"), earlier) << "never over a good results.h5";
  const rendulic::ResultsReader partial(out / "results.h5.partial");
  EXPECT_TRUE(partial.has_attr("/timings", "prepare"));
  EXPECT_FALSE(partial.has_attr("/timings", "isotropic"));
  EXPECT_TRUE(partial.exists("/preparation"));
  EXPECT_TRUE(temporaries(out).empty()) << temporaries(out).front();
}

// Starts `rendulic ARGS` with stderr into `err_file`; returns its pid.
pid_t start(const std::string& args, const fs::path& err_file) {
  const pid_t pid = fork();
  if (pid == 0) {
    std::freopen(err_file.c_str(), "w", stderr);
    std::freopen("/dev/null", "w", stdout);
    std::vector<std::string> words;
    std::istringstream in(args);
    for (std::string w; in >> w;) words.push_back(w);
    std::vector<char*> argv{const_cast<char*>(RENDULIC_EXE)};
    for (auto& w : words) argv.push_back(w.data());
    argv.push_back(nullptr);
    execv(RENDULIC_EXE, argv.data());
    _exit(127);
  }
  return pid;
}

// Polls `ready` every 10 ms for up to `seconds`.
bool wait_for(const std::function<bool()>& ready, double seconds) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end) {
    if (ready()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

TEST(FaultsSystem, ASignalDuringARunKeepsTheCompletedStagesAndNoTemporary) {
  const fs::path d = fresh_dir("signal_run");
  const fs::path out = d / "out";
  const pid_t pid =
      start("run " + tiny_scenario().string() + " --quiet --threads 1 --out " + out.string(),
            d / "stderr.txt");
  const fs::path saved = out / (".results.h5.tmp-" + std::to_string(pid) + ".partial");
  ASSERT_TRUE(wait_for([&] { return fs::exists(saved); }, 120)) << "prepare never completed";
  kill(pid, SIGTERM);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the run ended before the signal";
  EXPECT_EQ(WTERMSIG(status), SIGTERM);
  const std::string err = read_file(d / "stderr.txt");
  EXPECT_NE(err.find("rendulic: stopped by a signal; completed stages (prepare"), std::string::npos)
      << err;
  EXPECT_FALSE(fs::exists(out / "results.h5"));
  EXPECT_TRUE(temporaries(out).empty()) << temporaries(out).front();
  EXPECT_TRUE(rendulic::ResultsReader(out / "results.h5.partial").has_attr("/timings", "prepare"));
}

// A file of /proc/PID, empty once the process is gone. Read with read(2): a process that ends
// between the open and the read makes the read fail (ESRCH), which std::ifstream turns into an
// exception (CI, 2026-12-01: matplotlib's short-lived fc-list, read as a child of the script).
std::string proc_file(pid_t pid, const std::string& name) {
  const std::string path = "/proc/" + std::to_string(pid) + "/" + name;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return {};
  std::string out;
  char buf[4096];
  for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;)
    out.append(buf, static_cast<std::size_t>(n));
  ::close(fd);
  return out;
}

// The children of `pid`.
std::vector<pid_t> children_of(pid_t pid) {
  std::vector<pid_t> out;
  std::istringstream in(proc_file(pid, "task/" + std::to_string(pid) + "/children"));
  for (pid_t c; in >> c;) out.push_back(c);
  return out;
}

// Its command line: the arguments, each ended by a NUL.
std::string cmdline_of(pid_t pid) { return proc_file(pid, "cmdline"); }

bool running(pid_t pid) {
  const std::string stat = proc_file(pid, "stat");
  const auto close = stat.rfind(')');
  return close != std::string::npos && close + 2 < stat.size() && stat[close + 2] != 'Z';
}

// `rendulic plot` stopped by `sig` while the script draws: the script and its workers end, and
// no figure's temporary is left.
void expect_a_stopped_plot_leaves_nothing_running(int sig, const std::string& dir) {
  const fs::path base = base_results();
  const fs::path d = fresh_dir(dir);
  fs::copy_file(base, d / "results.h5");
  // Two drawing processes whatever the cores: with one, the script could finish its figures
  // while the workers are waited for, and the stop would come after the end.
  setenv("RENDULIC_PLOT_JOBS", "2", 1);
  const pid_t pid = start("plot " + (d / "results.h5").string(), d / "stderr.txt");
  unsetenv("RENDULIC_PLOT_JOBS");
  pid_t script = 0;
  auto script_started = [&] {
    for (pid_t c : children_of(pid)) {
      // Between fork and exec the child still shows rendulic's own command line: wait for
      // the interpreter's.
      const std::string cmd = cmdline_of(c);
      // The name of the program, not its path: the build may sit under a folder whose name
      // says python.
      const std::string argv0 = fs::path(cmd.substr(0, cmd.find('\0'))).filename().string();
      if (argv0.find("python") != std::string::npos &&
          cmd.find((d / "results.h5").string()) != std::string::npos)
        script = c;
    }
    return script != 0;
  };
  ASSERT_TRUE(wait_for(script_started, 60)) << "the figure script never started";
  // argv: python, "-c", the script's text, the file, the folder: no script file.
  const std::string cmdline = cmdline_of(script);
  const auto arg1 = cmdline.find('\0') + 1;
  EXPECT_EQ(cmdline.substr(arg1, 3), std::string("-c\0", 3));
  // The script draws in a worker process besides its own: stop it while they draw (if the
  // worker is seen in time), and none may draw on after it. The first interpreter may be
  // one without the modules (PATH's pyenv or conda build), which exits at once and leaves the
  // drawing to /usr/bin/python3: the script is looked for again while waiting. A worker is a
  // child that names itself rendulic-draw; other children are not: matplotlib's first import
  // on a machine runs fc-list to build its font cache, which ends on its own, and between its
  // fork and exec it shows the script's command line (CI's fresh machine, 2026-12-01: that
  // fc-list was taken for a worker that ran on).
  std::vector<pid_t> workers;
  wait_for(
      [&] {
        script_started();
        workers.clear();
        for (pid_t c : children_of(script))
          if (proc_file(c, "comm") == "rendulic-draw\n") workers.push_back(c);
        return !workers.empty();
      },
      10);
  kill(pid, sig);
  const auto stopped = fs::file_time_type::clock::now();
  int status = 0;
  waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFSIGNALED(status));
  EXPECT_TRUE(wait_for([&] { return !running(script); }, 30)) << "the figure script runs on";
  // No figure put in place after the stop: a second leaves the save under way, if any, to end
  // (the script stops at its next step; its figures take 0.3-1.2 s each to draw).
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(d / "figures", ec))
    EXPECT_LT(e.last_write_time(), stopped + std::chrono::seconds(1))
        << e.path() << " was written after the stop";
  // The script ends only after its workers (terminated and joined on its way out).
  for (pid_t w : workers) EXPECT_FALSE(running(w)) << "a figure worker runs on";
  // Nor a figure's temporary: each is saved beside its name and renamed (plot.py save()).
  EXPECT_TRUE(temporaries(d / "figures").empty()) << temporaries(d / "figures").front();
}

TEST(FaultsSystem, AnInterruptedPlotLeavesNoFigureScriptRunningNorItsFile) {
  // The figure script was a temporary file under /tmp, and its process went on writing
  // figures after rendulic was stopped.
  expect_a_stopped_plot_leaves_nothing_running(SIGTERM, "signal_plot");
}

TEST(FaultsSystem, AKilledPlotLeavesNoFigureScriptRunning) {
  // SIGKILL runs no handler of rendulic's: the script drew on for seconds, renaming figures
  // into the folder after the command had ended (where a later report could already have
  // written newer ones). It now gets SIGTERM when rendulic dies (PR_SET_PDEATHSIG), and ends
  // its workers and its temporaries as when rendulic stops it.
  expect_a_stopped_plot_leaves_nothing_running(SIGKILL, "kill_plot");
}

TEST(FaultsSystem, TheNextRunTidiesStaleTemporariesAndTheStoredScenarioReplays) {
  const fs::path d = fresh_dir("next_run");
  const fs::path out = d / "out";
  fs::create_directories(out);
  const pid_t dead = fork();
  if (dead == 0) _exit(0);
  waitpid(dead, nullptr, 0);
  const std::string tag = std::to_string(dead);
  std::ofstream(out / (".results.h5.tmp-" + tag)) << "half a file";
  {
    rendulic::ResultsWriter w(d / "saved.h5");
    w.attr("/timings", "prepare", 1.0);
    w.commit();
  }
  fs::rename(d / "saved.h5", out / (".results.h5.tmp-" + tag + ".partial"));
  // A description that used to cut the stored scenario short (\u0000) or make it unreadable
  // (\u0001).
  const fs::path s = d / "s.toml";
  std::string text = rendulic::testing::kTinyScenario;
  text.replace(text.find("[run]\n"), 6, "[run]\ndescription = \"x\\u0000y\\u0001z\"\n");
  std::ofstream(s, std::ios::trunc) << text;
  const CliResult r = rendulic::testing::run_rendulic(
      "run " + s.string() + " --threads 1 --set run.stages=prepare --out " + out.string(), false);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find(".results.h5.tmp-" + tag +
                       ": removed, a temporary file of a run that "
                       "was killed (process " +
                       tag + ")"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("are kept in " + (out / "results.h5.partial").string()), std::string::npos)
      << r.err;
  EXPECT_TRUE(temporaries(out).empty()) << temporaries(out).front();
  // The stored scenario is a scenario: run it again and it stores the same text.
  const std::string stored =
      rendulic::ResultsReader(out / "results.h5").attr_string("/", "scenario");
  EXPECT_NE(stored.find("description = \"x\\u0000y\\u0001z\""), std::string::npos) << stored;
  std::ofstream(d / "replay.toml") << stored;
  const CliResult again = rendulic::testing::run_rendulic(
      "run " + (d / "replay.toml").string() + " --quiet --threads 1 --out " + (d / "out2").string(),
      false);
  ASSERT_EQ(again.code, 0) << again.err;
  const std::string replayed =
      rendulic::ResultsReader(d / "out2" / "results.h5").attr_string("/", "scenario");
  EXPECT_EQ(replayed.substr(replayed.find('\n')), stored.substr(stored.find('\n')));
}

}  // namespace
