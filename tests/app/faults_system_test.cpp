// Faults met during and after real runs (docs/usage.md "Results are atomic"; docs/results.md):
// every subcommand that reads a results file walked over damaged copies of a real one (every
// group, dataset and attribute missing, wrongly typed or empty in turn), a full disk under a
// run and under `calibrate`, a late stage that fails, a signal in the middle of a run and in
// the middle of the figures, stale temporary files of killed runs, the stored scenario
// replayed. The real file comes from a tiny run (N = 250 at fast rates, about 3 s of CPU),
// made once per build and shared by the tests through a lock.
//
// The full-disk tests mount a small tmpfs when they can (root, as in CI); otherwise the
// kernel's file size limit (ulimit -f) makes the writes fail the same way (EFBIG instead of
// ENOSPC).
#include <H5Cpp.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/mount.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include "cli_runner.hpp"
#include "rendulic/core/results.hpp"
#include "rendulic/core/scenario.hpp"
#include "tiny_run.hpp"

namespace {
namespace fs = std::filesystem;
using rendulic::testing::CliResult;

const fs::path kRoot = fs::path(RENDULIC_TEST_TMP) / "app_faults_system";

int lines(const std::string& s) { return static_cast<int>(std::count(s.begin(), s.end(), '\n')); }
std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

fs::path fresh_dir(const std::string& name) {
  return rendulic::testing::fresh_dir("app_faults_system/" + name);
}

fs::path tiny_scenario() { return rendulic::testing::tiny_scenario(kRoot); }

// Temporary files in a folder: anything a writer leaves while it works.
std::vector<std::string> temporaries(const fs::path& dir) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string n = e.path().filename().string();
    if (n.find(".tmp") != std::string::npos) out.push_back(n);
  }
  return out;
}

// The real results file of the tiny run, made once per build (tiny_run.hpp).
fs::path base_results() { return rendulic::testing::tiny_results(kRoot); }

// --- the damaged-file walk -------------------------------------------------------------

struct Damage {
  std::string what;  // "missing /path/time", "wrongly typed /material @k_star", ...
  std::string object;
  std::function<void(H5::H5File&)> apply;
};

struct Attribute {
  std::string name;
  bool text, array;
};

struct Object {
  std::string path;
  bool group;
  std::vector<Attribute> attributes;
};

// The path with every state label and envelope name replaced by "*": the states (and their
// envelopes) of a file repeat one structure, read by the same code.
std::string structure_of(const std::string& path) {
  std::string out;
  std::istringstream in(path);
  std::string previous;
  for (std::string part; std::getline(in, part, '/');) {
    if (part.empty()) continue;
    out += "/" + (previous == "states" || previous == "envelopes" ? std::string("*") : part);
    previous = part;
  }
  return out.empty() ? "/" : out;
}

struct Visit {
  std::vector<Object> objects;
  std::set<std::string> structures;
};

herr_t visit(hid_t, const char* name, const H5O_info_t* info, void* data) {
  auto* v = static_cast<Visit*>(data);
  const std::string path = std::string(name) == "." ? "/" : "/" + std::string(name);
  // The first state and the first envelope stand for all.
  if (v->structures.insert(structure_of(path)).second)
    v->objects.push_back({path, info->type == H5O_TYPE_GROUP, {}});
  return 0;
}

std::vector<Object> objects_of(const fs::path& file) {
  Visit v;
  H5::H5File h(file.string(), H5F_ACC_RDONLY);
  H5Ovisit2(h.getId(), H5_INDEX_NAME, H5_ITER_INC, visit, &v, H5O_INFO_BASIC);
  std::vector<Object>& objects = v.objects;
  for (auto& o : objects) {
    const hid_t id = H5Oopen(h.getId(), o.path.c_str(), H5P_DEFAULT);
    H5O_info_t info;
    H5Oget_info2(id, &info, H5O_INFO_NUM_ATTRS);
    for (hsize_t i = 0; i < info.num_attrs; ++i) {
      const hid_t a =
          H5Aopen_by_idx(id, ".", H5_INDEX_NAME, H5_ITER_NATIVE, i, H5P_DEFAULT, H5P_DEFAULT);
      char name[256] = {0};
      H5Aget_name(a, sizeof name, name);
      const hid_t t = H5Aget_type(a);
      const hid_t sp = H5Aget_space(a);
      o.attributes.push_back(
          {name, H5Tget_class(t) == H5T_STRING, H5Sget_simple_extent_ndims(sp) > 0});
      H5Sclose(sp);
      H5Tclose(t);
      H5Aclose(a);
    }
    H5Oclose(id);
  }
  return objects;
}

void delete_children(H5::H5File& h, const std::string& group) {
  H5::Group g = h.openGroup(group);
  std::vector<std::string> names;
  for (hsize_t i = 0; i < g.getNumObjs(); ++i) names.push_back(g.getObjnameByIdx(i));
  for (const auto& n : names) g.unlink(n);
}

// Every group and dataset missing, wrongly typed (a group as numbers, numbers as text) and
// empty (no members, no rows); every attribute missing and wrongly typed (text for a number, a
// number for text), and every numeric array attribute empty. Of the states and envelopes, the
// first stands for all (structure_of).
std::vector<Damage> damages_of(const fs::path& file) {
  std::vector<Damage> out;
  static const hsize_t two = 2;
  for (const Object& o : objects_of(file)) {
    const std::string p = o.path;
    if (p != "/") {
      out.push_back({"missing " + p, p, [p](H5::H5File& h) { h.unlink(p); }});
      out.push_back({"wrongly typed " + p, p, [p, g = o.group](H5::H5File& h) {
                       h.unlink(p);
                       if (g)
                         h.createDataSet(p, H5::PredType::NATIVE_DOUBLE, H5::DataSpace(1, &two));
                       else
                         h.createDataSet(p, H5::StrType(H5::PredType::C_S1, 4),
                                         H5::DataSpace(1, &two));
                     }});
      const bool childless =
          o.group && H5::H5File(file.string(), H5F_ACC_RDONLY).openGroup(p).getNumObjs() == 0;
      if (!childless)  // else nothing to empty
        out.push_back({"empty " + p, p, [p, g = o.group](H5::H5File& h) {
                         if (g) return delete_children(h, p);
                         H5::DataSet ds = h.openDataSet(p);
                         std::vector<hsize_t> dims(ds.getSpace().getSimpleExtentNdims());
                         ds.getSpace().getSimpleExtentDims(dims.data());
                         ds.close();
                         h.unlink(p);
                         if (dims.empty()) dims.push_back(0);
                         dims[0] = 0;
                         h.createDataSet(p, H5::PredType::NATIVE_DOUBLE,
                                         H5::DataSpace(static_cast<int>(dims.size()), dims.data()));
                       }});
    }
    for (const auto& [name, text, array] : o.attributes) {
      const std::string where = p + " @" + name;
      auto with_object = [p, g = o.group](H5::H5File& h,
                                          const std::function<void(H5::H5Object&)>& fn) {
        if (g) {
          H5::Group obj = h.openGroup(p);
          fn(obj);
        } else {
          H5::DataSet obj = h.openDataSet(p);
          fn(obj);
        }
      };
      const std::string n = name;
      out.push_back({"missing " + where, p, [with_object, n](H5::H5File& h) {
                       with_object(h, [&](H5::H5Object& obj) { obj.removeAttr(n); });
                     }});
      out.push_back({"wrongly typed " + where, p, [with_object, n, text = text](H5::H5File& h) {
                       with_object(h, [&](H5::H5Object& obj) {
                         obj.removeAttr(n);
                         if (text) {
                           const double one = 1.0;
                           obj.createAttribute(n, H5::PredType::NATIVE_DOUBLE,
                                               H5::DataSpace(H5S_SCALAR))
                               .write(H5::PredType::NATIVE_DOUBLE, &one);
                         } else {
                           const H5::StrType t(H5::PredType::C_S1, 1);
                           obj.createAttribute(n, t, H5::DataSpace(H5S_SCALAR)).write(t, "x");
                         }
                       });
                     }});
      if (!text && array)
        out.push_back({"empty " + where, p, [with_object, n](H5::H5File& h) {
                         with_object(h, [&](H5::H5Object& obj) {
                           obj.removeAttr(n);
                           const hsize_t zero = 0;
                           obj.createAttribute(n, H5::PredType::NATIVE_DOUBLE,
                                               H5::DataSpace(1, &zero));
                         });
                       }});
    }
  }
  return out;
}

// The figure script (Python and matplotlib, seconds a run) is walked over a sample: damage
// to what each figure draws from, of the kinds its own handling does not cover.
const std::set<std::string>& plot_sample() {
  static const std::set<std::string> sample = {
      "wrongly typed /states",
      "wrongly typed /isotropic/pressure_star",
      "wrongly typed /path/stress_star",
      "empty /path/fabric",
      "wrongly typed /states/a/envelopes/dynamic_0.002/stress_star",
      "empty /states/a/envelopes/dynamic_0.002/theta_deg",
      "wrongly typed /states/a/envelopes/dynamic_0.002/fit_stress @semi_axes",
      "wrongly typed /states/a/envelopes/dynamic_0.002 @amplitude",
  };
  return sample;
}
bool plot_walks(const Damage& d) { return plot_sample().count(d.what) > 0; }

TEST(FaultsSystem, EverySubcommandRefusesDamagedResultsFilesInOneLine) {
  const fs::path base = base_results();
  ASSERT_TRUE(fs::exists(base));
  const std::vector<Damage> damages = damages_of(base);
  const fs::path root = fresh_dir("walk");
  struct Run {
    std::size_t damage;
    std::string command;
  };
  std::vector<Run> runs;
  int plots = 0;
  for (std::size_t i = 0; i < damages.size(); ++i) {
    const fs::path f = root / std::to_string(i) / "results.h5";
    fs::create_directories(f.parent_path());
    fs::copy_file(base, f);
    {
      H5::H5File h(f.string(), H5F_ACC_RDWR);
      damages[i].apply(h);
    }
    for (const std::string c : {"inspect", "report --no-figures"}) runs.push_back({i, c});
    if (plot_walks(damages[i])) runs.push_back({i, "plot"}), ++plots;
    runs.push_back({i, "calibrate --model isotropic_elastic --max-iterations 5 --results"});
  }
  EXPECT_EQ(plots, static_cast<int>(plot_sample().size()));
  for (const auto& w : plot_sample())
    EXPECT_TRUE(std::any_of(damages.begin(), damages.end(), [&](auto& d) { return d.what == w; }))
        << "not among the walk's damage: " << w;
  // Two workers, each on whole copies: a copy's runs go in order (calibrate, last, changes
  // the file the others read).
  std::vector<CliResult> results(runs.size());
  std::vector<std::vector<std::size_t>> by_copy(damages.size());
  for (std::size_t k = 0; k < runs.size(); ++k) by_copy[runs[k].damage].push_back(k);
  std::atomic<std::size_t> next_copy{0};
  auto worker = [&] {
    for (std::size_t c; (c = next_copy++) < by_copy.size();)
      for (std::size_t k : by_copy[c]) {
        const fs::path f = root / std::to_string(c) / "results.h5";
        results[k] = rendulic::testing::run_rendulic(runs[k].command + " " + f.string(), false);
      }
  };
  std::thread t1(worker), t2(worker);
  t1.join();
  t2.join();

  // Every outcome, for a reader who wants to see what each command made of each damage.
  std::ofstream outcomes(kRoot / "walk-outcomes.txt");
  std::map<std::string, std::pair<int, int>> tally;  // command -> refused, accepted
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const Damage& d = damages[runs[k].damage];
    const CliResult& r = results[k];
    const std::string cmd = runs[k].command.substr(0, runs[k].command.find(' '));
    const std::string where = cmd + " on " + d.what + ": ";
    const fs::path dir = root / std::to_string(runs[k].damage);
    outcomes << where << "exit " << r.code << (r.code ? " " + r.err : std::string("\n"));
    EXPECT_TRUE(r.code == 0 || r.code == 2) << where << "exit " << r.code << "\n" << r.err;
    if (r.code == 2) {
      ++tally[cmd].first;
      EXPECT_EQ(lines(r.err), 1) << where << r.err;
      EXPECT_EQ(r.err.rfind("rendulic: ", 0), 0u) << where << r.err;
      EXPECT_NE(r.err.find("results.h5"), std::string::npos)
          << where << "names the file: " << r.err;
    } else {
      ++tally[cmd].second;
    }
    EXPECT_TRUE(temporaries(dir).empty()) << where << temporaries(dir).front();
  }
  std::ostringstream summary;
  for (const auto& [cmd, n] : tally)
    summary << cmd << ": " << n.first << " refused, " << n.second << " accepted; ";
  std::cout << damages.size() << " damaged copies, " << runs.size() << " runs: " << summary.str()
            << "\n";
  // A walk that refuses nothing tests nothing: every command must meet damage it needs.
  for (const char* cmd : {"inspect", "report", "plot", "calibrate"})
    EXPECT_GT(tally[cmd].first, 0) << cmd << " refused no damaged copy";
  // Damage every command needs: the schema, and the states as a group.
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const std::string& what = damages[runs[k].damage].what;
    const bool needed = what == "missing / @schema" || what == "wrongly typed / @schema" ||
                        (what == "wrongly typed /states" && runs[k].command != "inspect");
    if (needed) {
      EXPECT_EQ(results[k].code, 2) << runs[k].command << " on " << what;
    }
  }
  fs::remove_all(root);
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
  // Calibration without probes has no envelopes to fit: it fails after four stages.
  const CliResult r = rendulic::testing::run_rendulic(
      "run " + tiny_scenario().string() +
          " --quiet --threads 1 --set run.stages=prepare,isotropic,path,states,calibration --out " +
          out.string(),
      false);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(rendulic::testing::error_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("; completed stages (prepare, isotropic, path, states) kept in " +
                       (out / "results.h5.partial").string()),
            std::string::npos)
      << r.err;
  EXPECT_EQ(read_file(out / "results.h5"), earlier) << "never over a good results.h5";
  const rendulic::ResultsReader partial(out / "results.h5.partial");
  EXPECT_TRUE(partial.has_attr("/timings", "states"));
  EXPECT_FALSE(partial.has_attr("/timings", "calibration"));
  EXPECT_EQ(partial.children("/states"), (std::vector<std::string>{"a", "b"}));
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

// The children of `pid` (Linux /proc).
std::vector<pid_t> children_of(pid_t pid) {
  std::vector<pid_t> out;
  std::ifstream in("/proc/" + std::to_string(pid) + "/task/" + std::to_string(pid) + "/children");
  for (pid_t c; in >> c;) out.push_back(c);
  return out;
}

bool running(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string stat((std::istreambuf_iterator<char>(in)), {});
  const auto close = stat.rfind(')');
  return close != std::string::npos && close + 2 < stat.size() && stat[close + 2] != 'Z';
}

TEST(FaultsSystem, AnInterruptedPlotLeavesNoFigureScriptRunningNorItsFile) {
  // The figure script was a temporary file under /tmp, and its process went on writing
  // figures after rendulic was stopped.
  const fs::path base = base_results();
  const fs::path d = fresh_dir("signal_plot");
  fs::copy_file(base, d / "results.h5");
  const pid_t pid = start("plot " + (d / "results.h5").string(), d / "stderr.txt");
  pid_t script = 0;
  auto script_started = [&] {
    for (pid_t c : children_of(pid)) {
      // Between fork and exec the child still shows rendulic's own command line: wait for
      // the interpreter's.
      const std::string cmd = read_file("/proc/" + std::to_string(c) + "/cmdline");
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
  const std::string cmdline = read_file("/proc/" + std::to_string(script) + "/cmdline");
  const auto arg1 = cmdline.find('\0') + 1;
  EXPECT_EQ(cmdline.substr(arg1, 3), std::string("-c\0", 3));
  // With more than one core the script draws in worker processes: stop it while they draw
  // (if they are seen in time), and none may draw on after it.
  std::vector<pid_t> workers;
  wait_for(
      [&] {
        workers = children_of(script);
        return !workers.empty();
      },
      10);
  kill(pid, SIGTERM);
  int status = 0;
  waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFSIGNALED(status));
  EXPECT_TRUE(wait_for([&] { return !running(script); }, 30)) << "the figure script runs on";
  // The script ends only after its workers (terminated and joined on its way out).
  for (pid_t w : workers) EXPECT_FALSE(running(w)) << "a figure worker runs on";
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
