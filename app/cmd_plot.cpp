// `rendulic plot FILE.h5 [--out DIR]` (interfaces.md; issue 8 item 2): the figures of a results
// file as PNG and SVG, drawn by the embedded app/plot.py with Debian's python3-matplotlib and
// python3-h5py. The file is checked to be ours first, so a bad file is the usual one-line
// exit 2, not a Python traceback.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "plot_script.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/results.hpp"

namespace rendulic::app {
namespace {

// Runs argv without a shell (no quoting issues with odd file names); returns the exit code.
int spawn(const std::vector<std::string>& args, bool silence) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    if (silence) {
      std::freopen("/dev/null", "w", stdout);
      std::freopen("/dev/null", "w", stderr);
    }
    execvp(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

int plot_results(const std::filesystem::path& file, const std::filesystem::path& out_dir) {
  { ResultsReader check(file); }
  // The first interpreter that has both modules: PATH's python3 may be a private build
  // (pyenv, conda) without Debian's packages, which live under /usr/bin/python3.
  std::string python;
  for (const char* candidate : {"python3", "/usr/bin/python3"})
    if (spawn({candidate, "-c", "import h5py, matplotlib"}, true) == 0) {
      python = candidate;
      break;
    }
  if (python.empty())
    throw InputError(
        "plot: needs python3 with matplotlib and h5py (bash .ci/setup.sh installs "
        "python3-matplotlib and python3-h5py)");
  char tmpl[] = "/tmp/rendulic-plot-XXXXXX.py";
  const int fd = mkstemps(tmpl, 3);
  if (fd < 0) throw std::runtime_error("plot: cannot create a temporary script");
  close(fd);
  { std::ofstream(tmpl) << kPlotScript; }
  const int rc = spawn({python, tmpl, file.string(), out_dir.string()}, false);
  std::filesystem::remove(tmpl);
  if (rc != 0)
    throw std::runtime_error("plot: the figure script failed (exit " + std::to_string(rc) + ")");
  return 0;
}

Subcommand add_plot(CLI::App& parent) {
  auto file = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto* sub = parent.add_subcommand("plot", "Figures of a results file (PNG and SVG)");
  sub->add_option("file", *file, "results file (HDF5, schema rendulic/1)")->required();
  sub->add_option("--out", *out, "output folder (default: FILE's folder/figures)");
  return {sub, [file, out]() -> int {
            std::filesystem::path dir = *out;
            if (dir.empty()) dir = std::filesystem::path(*file).parent_path() / "figures";
            return plot_results(*file, dir);
          }};
}
}  // namespace rendulic::app
