// The tiny run shared by the system tests that need a real results file (faults, figures):
// N = 250 at fast rates, about 1.3 s of CPU (12 s sanitized), every stage a results file can
// hold at the lowest cost that still makes elastic and plastic envelopes, their fits and a
// calibration. Made once per build (again when the binary is newer) for each set of extra
// arguments, under a lock, and read by every test file that needs it: the tests copy it
// before they change anything.
#pragma once

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include "cli_runner.hpp"

namespace rendulic::testing {

inline const char* const kTinyScenario = R"(
[run]
stages = ["prepare", "isotropic", "path", "states", "probes", "fits", "calibration"]
[dem]
n_particles = 250
[preparation]
rate = 20000.0
gamma_b = 5.0
[relax]
kinetic_to_elastic = 1e-4
time_cap = 2e-4
[isotropic]
nu_max = 0.75
samples = 50
inertial_number = 5e-3
rate_max = 5000.0
rate_min = 500.0
[path]
rate = 5000.0
eps_dev_max = 0.05
samples = 10
[states]
eps_dev = [0.01, 0.05]
labels = ["a", "b"]
kinetic_to_elastic = 1e-4
time_cap = 1e-4
[probes]
directions = 8
inertial_number = 0.01
relax_kinetic_to_elastic = 1e-5
relax_time_cap = 1e-4
[calibration]
model = "isotropic_elastic"
max_iterations = 20
)";

// root/tiny.toml, written afresh.
inline std::filesystem::path tiny_scenario(const std::filesystem::path& root) {
  std::filesystem::create_directories(root);
  const std::filesystem::path s = root / "tiny.toml";
  std::ofstream(s) << kTinyScenario;
  return s;
}

// Whether a results file's dataset `path` (attribute "") or its attribute `attribute` holds a
// wall-clock time, which two runs of the same input do not share: /timings, wall_time_s,
// seconds.
inline bool is_wall_clock(const std::string& path, const std::string& attribute) {
  return path.rfind("/timings", 0) == 0 || attribute == "wall_time_s" || attribute == "seconds" ||
         (attribute.empty() && path.size() >= 8 && path.substr(path.size() - 8) == "/seconds");
}

// The shared tiny run of the extra command-line arguments `args`: its folder in
// RENDULIC_TEST_TMP/tiny_run, one per `args`, and the scenario file it reads, beside it (the
// stored scenario names that file: a resumed run must read the same one).
inline std::filesystem::path tiny_run_dir(const std::string& args = "") {
  return std::filesystem::path(RENDULIC_TEST_TMP) / "tiny_run" /
         (args.empty() ? "base" : "args-" + std::to_string(std::hash<std::string>{}(args)));
}
inline std::filesystem::path tiny_run_scenario(const std::string& args = "") {
  const std::filesystem::path dir = tiny_run_dir(args);
  return dir.parent_path() / (dir.filename().string() + "-scenario") / "tiny.toml";
}

// Makes `dir`/results.h5 with `make(dir)` once per build (again when the binary is newer than
// it), under a lock beside `dir`, for every test (each its own process under ctest) that reads
// it; `read(file)` runs under the same lock. Returns the file.
inline std::filesystem::path made_once(
    const std::filesystem::path& dir, const std::function<void(const std::filesystem::path&)>& make,
    const std::function<void(const std::filesystem::path&)>& read =
        [](const std::filesystem::path&) {}) {
  namespace fs = std::filesystem;
  const fs::path f = dir / "results.h5", root = dir.parent_path();
  fs::create_directories(root);
  const int lock = ::open((root / ("." + dir.filename().string() + ".lock")).c_str(),
                          O_CREAT | O_RDWR | O_CLOEXEC, 0644);
  flock(lock, LOCK_EX);
  std::error_code ec;
  if (!fs::exists(f) || fs::last_write_time(f, ec) < fs::last_write_time(RENDULIC_EXE, ec)) {
    fs::remove_all(dir);
    make(dir);
  }
  read(f);
  flock(lock, LOCK_UN);
  ::close(lock);
  return f;
}

// The results file of the tiny run with the extra command-line arguments `args` (e.g. --set
// overrides), shared by every test that reads it (made_once).
inline std::filesystem::path tiny_results(const std::string& args = "") {
  return made_once(tiny_run_dir(args), [&](const std::filesystem::path& dir) {
    const std::filesystem::path scenario = tiny_run_scenario(args);
    const CliResult r = run_rendulic("run " + tiny_scenario(scenario.parent_path()).string() + " " +
                                     args + " --quiet --threads 1 --out " + dir.string());
    EXPECT_EQ(r.code, 0) << r.out;
  });
}

}  // namespace rendulic::testing
