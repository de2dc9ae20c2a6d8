// Test support shared by the tests that run the real `rendulic` binary: run it with arguments
// and capture the exit code, stdout and stderr; make a fresh scratch folder. One runner so
// every CLI test judges exit codes and messages the same way.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>

namespace rendulic::testing {

struct CliResult {
  int code = -1;
  std::string out;  // stdout, and stderr too when merged
  std::string err;  // stderr when not merged
};

// A whole file's bytes ("" when it cannot be read).
inline std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

// Runs a shell command line (e.g. `mpirun ... rendulic ...`); with merge_stderr its stderr
// lands in `out`.
inline CliResult run_command(std::string cmd, bool merge_stderr = true) {
  CliResult r;
  std::string err_file;
  if (merge_stderr) {
    cmd += " 2>&1";
  } else {
    char tmpl[] = "/tmp/rendulic-test-stderr-XXXXXX";
    const int fd = mkstemp(tmpl);
    if (fd >= 0) close(fd);
    err_file = tmpl;
    cmd += " 2>" + err_file;
  }
  FILE* p = popen(cmd.c_str(), "r");
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), buf.size(), p)) r.out += buf.data();
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (!err_file.empty()) {
    r.err = read_file(err_file);
    std::filesystem::remove(err_file);
  }
  return r;
}

// Runs `rendulic ARGS`; with merge_stderr the one-line errors land in `out`.
inline CliResult run_rendulic(const std::string& args, bool merge_stderr = true) {
  return run_command(std::string(RENDULIC_EXE) + " " + args, merge_stderr);
}

// Whether Debian's LAMMPS (`lmp`, installed by .ci/setup.sh) is on the PATH: the checks that run
// our packings in LAMMPS skip without it.
inline bool have_lammps() { return run_command("command -v lmp > /dev/null").code == 0; }

// An empty folder RENDULIC_TEST_TMP/name (removed and recreated).
inline std::filesystem::path fresh_dir(const std::string& name) {
  const std::filesystem::path d = std::filesystem::path(RENDULIC_TEST_TMP) / name;
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

// The lines of a command's stderr that are not warnings: --quiet keeps warnings (docs/usage.md
// "Progress and messages"), and a failure is still one line beside them.
inline int error_lines(const std::string& err) {
  int n = 0;
  std::istringstream in(err);
  for (std::string line; std::getline(in, line);)
    n += line.rfind("rendulic: warning: ", 0) == 0 ? 0 : 1;
  return n;
}

}  // namespace rendulic::testing
