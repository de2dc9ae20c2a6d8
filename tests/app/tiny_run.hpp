// The tiny run shared by the system tests that need a real results file with every stage
// (faults, output): N = 250 at fast rates, about 3 s of CPU. Its file is made once per build
// (again when the binary is newer) under a test's own root, behind a lock, so tests running in
// parallel share it.
#pragma once

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "cli_runner.hpp"

namespace rendulic::testing {

// Every stage a results file can hold, at the lowest cost that still makes envelopes, fits and
// a calibration.
inline const char* const kTiny = R"(
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

inline std::filesystem::path tiny_scenario(const std::filesystem::path& root) {
  std::filesystem::create_directories(root);
  const std::filesystem::path s = root / "tiny.toml";
  std::ofstream(s) << kTiny;
  return s;
}

// root/base/results.h5 of the tiny run.
inline std::filesystem::path tiny_results(const std::filesystem::path& root) {
  namespace fs = std::filesystem;
  const fs::path dir = root / "base", f = dir / "results.h5";
  fs::create_directories(root);
  const int lock = ::open((root / ".base.lock").c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0644);
  flock(lock, LOCK_EX);
  std::error_code ec;
  if (!fs::exists(f) || fs::last_write_time(f, ec) < fs::last_write_time(RENDULIC_EXE, ec)) {
    fs::remove_all(dir);
    const CliResult r = run_rendulic("run " + tiny_scenario(root).string() +
                                     " --quiet --threads 1 --out " + dir.string());
    EXPECT_EQ(r.code, 0) << r.out;
  }
  flock(lock, LOCK_UN);
  ::close(lock);
  return f;
}

}  // namespace rendulic::testing
