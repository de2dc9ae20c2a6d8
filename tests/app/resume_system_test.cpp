// `rendulic run --resume` (docs/usage.md "Resuming a run"): a run stopped by SIGTERM in a stage
// and resumed gives the results file of the uninterrupted run: every dataset and attribute
// equal bit for bit, except the wall-clock times (/timings, wall_time_s, seconds). Stopped
// before its states are stored, it starts over; from the states on it continues from the
// stages it kept. The run is stopped when its log says the stage started, so the signal
// lands inside that stage (or, for a short stage, just after it).
#include <H5Cpp.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <vector>

#include "cli_runner.hpp"
#include "rendulic/core/results.hpp"
#include "tiny_run.hpp"

namespace {
namespace fs = std::filesystem;

const fs::path kRoot = fs::path(RENDULIC_TEST_TMP) / "app_resume";

fs::path scenario() {
  std::string text = rendulic::testing::kTinyScenario;
  const std::string from =
      R"(stages = ["prepare", "isotropic", "path", "states", "probes", "fits", "calibration"])";
  text.replace(
      text.find(from), from.size(),
      R"(stages = ["prepare", "isotropic", "path", "states", "probes", "linear_response", "fits", "calibration"])");
  fs::create_directories(kRoot);
  // Written aside and renamed: tests running side by side read it while another writes it.
  const fs::path aside = kRoot / ("resume.toml." + std::to_string(::getpid()));
  std::ofstream(aside) << text;
  fs::rename(aside, kRoot / "resume.toml");
  return kRoot / "resume.toml";
}

// `rendulic run` into `dir`; with a stage, stopped by SIGTERM as soon as the log says the stage
// started. Returns the wait status.
int run(const fs::path& dir, const std::string& stop_in, bool resume = false) {
  const std::string s = scenario().string(), d = dir.string();
  int fds[2];
  if (pipe(fds) != 0) return -1;
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(fds[1], 2);
    const int null = open("/dev/null", O_WRONLY);  // the calibration's summary
    dup2(null, 1);
    close(fds[0]);
    close(fds[1]);
    std::vector<const char*> argv = {RENDULIC_EXE, "run",       s.c_str(), "--out",
                                     d.c_str(),    "--threads", "1"};
    if (resume) argv.push_back("--resume");
    argv.push_back(nullptr);
    execv(RENDULIC_EXE, const_cast<char* const*>(argv.data()));
    _exit(127);
  }
  close(fds[1]);
  FILE* log = fdopen(fds[0], "r");
  const std::string mark = "[" + stop_in + "] started";
  bool sent = false;
  char line[4096];
  while (std::fgets(line, sizeof line, log))
    if (!stop_in.empty() && !sent && std::strstr(line, mark.c_str())) {
      kill(pid, SIGTERM);
      sent = true;
    }
  std::fclose(log);
  int status = 0;
  waitpid(pid, &status, 0);
  return status;
}

// Every dataset and attribute of a results file as text (numbers in hex: exact), by path
// ("/a/b" for a dataset, "/a/b@name" for an attribute), without the wall-clock times.
using Contents = std::map<std::string, std::string>;

std::string hex_join(const std::vector<double>& v) {
  std::string s;
  char buf[64];
  for (double x : v) {
    std::snprintf(buf, sizeof buf, "%a ", x);
    s += buf;
  }
  return s;
}

struct Walk {
  const rendulic::ResultsReader* reader;
  hid_t file;
  Contents* out;
};

herr_t visit_attribute(hid_t object, const char* name, const H5A_info_t*, void* data) {
  auto* w = static_cast<Walk*>(data);
  char path[1024];
  H5Iget_name(object, path, sizeof path);
  if (rendulic::testing::is_wall_clock(path, name)) return 0;
  const hid_t a = H5Aopen(object, name, H5P_DEFAULT);
  const hid_t type = H5Aget_type(a), space = H5Aget_space(a);
  std::string value;
  if (H5Tget_class(type) == H5T_STRING || H5Tget_class(type) == H5T_ARRAY) {
    if (H5Sget_simple_extent_type(space) == H5S_SCALAR && H5Tget_class(type) == H5T_STRING)
      value = w->reader->attr_string(path, name);
    else
      for (const auto& t : w->reader->attr_strings(path, name)) value += t + "\n";
  } else {
    std::vector<double> v(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
    H5Aread(a, H5T_NATIVE_DOUBLE, v.data());
    value = hex_join(v);
  }
  H5Sclose(space);
  H5Tclose(type);
  H5Aclose(a);
  (*w->out)[std::string(path) + "@" + name] = value;
  return 0;
}

herr_t visit_object(hid_t root, const char* name, const H5O_info_t* info, void* data) {
  auto* w = static_cast<Walk*>(data);
  const std::string path = std::string("/") + (std::strcmp(name, ".") == 0 ? "" : name);
  if (rendulic::testing::is_wall_clock(path, "")) return 0;
  const hid_t o = H5Oopen(root, name, H5P_DEFAULT);
  hsize_t idx = 0;
  H5Aiterate2(o, H5_INDEX_NAME, H5_ITER_INC, &idx, visit_attribute, data);
  if (info->type == H5O_TYPE_DATASET) {
    const hid_t space = H5Dget_space(o);
    std::vector<double> v(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
    if (!v.empty()) H5Dread(o, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
    H5Sclose(space);
    (*w->out)[path] = hex_join(v);
  } else {
    (*w->out)[path] = "group";
  }
  H5Oclose(o);
  return 0;
}

Contents contents(const fs::path& file) {
  Contents c;
  const rendulic::ResultsReader reader(file);
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  Walk w{&reader, f, &c};
  H5Ovisit(f, H5_INDEX_NAME, H5_ITER_INC, visit_object, &w);
  H5Fclose(f);
  return c;
}

void expect_same(const Contents& a, const Contents& b) {
  for (const auto& [k, v] : a) {
    const auto it = b.find(k);
    if (it == b.end()) {
      ADD_FAILURE() << k << " missing from the resumed run";
      continue;
    }
    EXPECT_EQ(v, it->second) << k;
  }
  for (const auto& [k, v] : b)
    if (!a.count(k)) ADD_FAILURE() << k << " only in the resumed run";
}

// The uninterrupted run, made once per build and shared by the tests (tiny_run.hpp's made_once).
const Contents& uninterrupted() {
  static const Contents c = [] {
    Contents out;
    rendulic::testing::made_once(
        kRoot / "uninterrupted", [](const fs::path& dir) { EXPECT_EQ(run(dir, ""), 0); },
        [&](const fs::path& f) { out = contents(f); });
    return out;
  }();
  return c;
}

class Resume : public ::testing::TestWithParam<const char*> {};

TEST_P(Resume, AfterSigtermGivesTheUninterruptedRunsFile) {
  const std::string stage = GetParam();
  const fs::path dir = rendulic::testing::fresh_dir("app_resume/stopped_in_" + stage);
  const int stopped = run(dir, stage);
  // Stopped by the signal (or finished, if the stage was over before it arrived).
  EXPECT_TRUE((WIFSIGNALED(stopped) && WTERMSIG(stopped) == SIGTERM) ||
              (WIFEXITED(stopped) && WEXITSTATUS(stopped) == 0))
      << stopped;
  if (WIFSIGNALED(stopped)) {
    EXPECT_FALSE(fs::exists(dir / "results.h5"));
  }
  const int resumed = run(dir, "", true);
  ASSERT_TRUE(WIFEXITED(resumed) && WEXITSTATUS(resumed) == 0) << resumed;
  EXPECT_FALSE(fs::exists(dir / "results.h5.partial"));
  expect_same(uninterrupted(), contents(dir / "results.h5"));
}

INSTANTIATE_TEST_SUITE_P(EachStage, Resume,
                         ::testing::Values("states", "probes", "linear_response", "fits",
                                           "calibration"));

std::string bytes(const fs::path& f) {
  std::ifstream in(f, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

// A batch job requeued after its run had finished ran every stage again. --resume of a whole
// run of the same scenario, with nothing kept to resume, now runs none and keeps the file; a
// file of another scenario is still replaced by a plain run.
// The shared tiny run (tiny_run.hpp) is such a run, resumed with the scenario file it read.
TEST(Resume, OfAFinishedRunRunsNoStageAndKeepsItsFile) {
  const fs::path dir = rendulic::testing::fresh_dir("app_resume/finished");
  fs::copy_file(rendulic::testing::tiny_results(), dir / "results.h5");
  const std::string before = bytes(dir / "results.h5");
  const std::string command = "run " + rendulic::testing::tiny_run_scenario().string() + " --out " +
                              dir.string() + " --resume --threads 1";
  const auto same = rendulic::testing::run_rendulic(command, false);
  EXPECT_EQ(same.code, 0) << same.err;
  EXPECT_NE(same.err.find("resume: " + (dir / "results.h5").string() +
                          " already holds every stage of this scenario; nothing to run"),
            std::string::npos)
      << same.err;
  EXPECT_EQ(same.err.find("started"), std::string::npos) << same.err;
  EXPECT_TRUE(bytes(dir / "results.h5") == before) << "the file changed";
  // The same scenario by another path (here a copy) is the same run: compared as text, the
  // header line that names the file as given made it "another scenario".
  const fs::path copy = dir / "copy of the scenario.toml";
  fs::copy_file(rendulic::testing::tiny_run_scenario(), copy);
  const auto by_copy = rendulic::testing::run_rendulic(
      "run '" + copy.string() + "' --out " + dir.string() + " --resume --threads 1", false);
  EXPECT_EQ(by_copy.code, 0) << by_copy.err;
  EXPECT_NE(by_copy.err.find("already holds every stage of this scenario; nothing to run"),
            std::string::npos)
      << by_copy.err;
  EXPECT_TRUE(bytes(dir / "results.h5") == before) << "the file changed";
  // Its first stage is enough to show a plain run (the whole run would be the tiny run again).
  const auto other = rendulic::testing::run_rendulic(
      command + " --set run.seed=2 --set run.stages=prepare", false);
  EXPECT_EQ(other.code, 0) << other.err;
  EXPECT_NE(other.err.find("[prepare] started"), std::string::npos) << other.err;
  EXPECT_FALSE(bytes(dir / "results.h5") == before) << "the file did not change";
}

TEST(ResumeRefusal, AnotherScenariosKeptStagesAreRefused) {
  const fs::path dir = rendulic::testing::fresh_dir("app_resume/other");
  run(dir, "probes");
  ASSERT_TRUE(fs::exists(dir / "results.h5.partial"));
  const auto r = rendulic::testing::run_rendulic(
      "run " + scenario().string() + " --out " + dir.string() + " --resume --set run.seed=2",
      false);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(rendulic::testing::error_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("another scenario (run.seed = 1 there, 2 now); give the interrupted "
                       "run's settings"),
            std::string::npos)
      << r.err;
  // Named as the file the user has, not the working copy the run reads.
  EXPECT_NE(r.err.find((dir / "results.h5.partial").string() + " holds"), std::string::npos)
      << r.err;
  EXPECT_TRUE(fs::exists(dir / "results.h5.partial"));
}

// A kept state is restarted from its checkpoint as it is: a number there that is not finite
// (here one force) would have become NaN trajectories, and a broken half skin an internal
// error. Both are one line naming the object in DIR/results.h5.partial, exit 2, and the kept
// file stays as it was.
TEST(ResumeRefusal, AKeptCheckpointWithANumberThatIsNotFiniteIsRefusedNamingIt) {
  const fs::path dir = rendulic::testing::fresh_dir("app_resume/nan");
  run(dir, "probes");
  const fs::path partial = dir / "results.h5.partial";
  ASSERT_TRUE(fs::exists(partial));
  for (const std::string object :
       {"/states/b/checkpoint/forces", "/states/a/checkpoint/reference_half_skins"}) {
    {
      H5::H5File h(partial.string(), H5F_ACC_RDWR);
      H5::DataSet d = h.openDataSet(object);
      std::vector<double> v(static_cast<std::size_t>(d.getSpace().getSimpleExtentNpoints()));
      d.read(v.data(), H5::PredType::NATIVE_DOUBLE);
      v[1] = std::nan("");
      d.write(v.data(), H5::PredType::NATIVE_DOUBLE);
    }
    std::ifstream in(partial, std::ios::binary);
    const std::string before((std::istreambuf_iterator<char>(in)), {});
    const auto r = rendulic::testing::run_rendulic(
        "run " + scenario().string() + " --out " + dir.string() + " --resume --threads 1 --quiet",
        false);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(rendulic::testing::error_lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(partial.string() + ":" + object + " holds a number that is not finite"),
              std::string::npos)
        << r.err;
    std::ifstream again(partial, std::ios::binary);
    EXPECT_EQ(std::string((std::istreambuf_iterator<char>(again)), {}), before);
    EXPECT_FALSE(fs::exists(dir / "results.h5"));
  }
}

}  // namespace
