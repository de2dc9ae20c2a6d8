// `rendulic plot FILE.h5 [--out DIR] [--script FILE]` (docs/usage.md, docs/figures.md): the
// figures of a results file as PNG, PDF and SVG, drawn by app/plot.py with Debian's
// python3-matplotlib and python3-h5py. The script is an editable file (--script, the
// RENDULIC_PLOT_SCRIPT variable, or the copy installed beside the binary), so figures can be
// restyled without a rebuild; without one, the copy compiled into the binary is passed on the
// command line (no temporary file), so `plot` works from any folder. The file is checked to be
// ours and the output folder to be writable first, and the script reports data it cannot draw
// in one line (exit 2), so a bad file or folder is the usual one-line exit 2, never a Python
// traceback. Its process is stopped if ours is stopped by a signal, SIGKILL included.
#include <omp.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "cli_options.hpp"
#include "commands.hpp"
#include "plot_script.hpp"
#include "rendulic/core/cleanup.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/log.hpp"
#include "rendulic/core/results.hpp"
#include "rendulic/core/text_file.hpp"

namespace rendulic::app {
namespace {

struct Spawned {
  int code = -1;    // exit code, -1 if it did not exit normally
  std::string err;  // its stderr
};

// Runs argv without a shell (no quoting issues with odd file names) and collects its stderr.
// `env` is added to the environment (built here: the child of a threaded process must not
// allocate before exec).
Spawned spawn(const std::vector<std::string>& args, const std::vector<std::string>& env) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  std::vector<char*> envp;
  for (char** e = environ; *e; ++e) envp.push_back(*e);
  for (const auto& e : env) envp.push_back(const_cast<char*>(e.c_str()));
  envp.push_back(nullptr);
  int pipefd[2] = {-1, -1};
  if (::pipe(pipefd) != 0) throw std::runtime_error("plot: cannot create a pipe");
  const pid_t parent = ::getpid();
  const pid_t pid = fork();
  if (pid < 0) {
    ::close(pipefd[0]);
    ::close(pipefd[1]);
    throw std::runtime_error("plot: cannot start a process");
  }
  if (pid == 0) {
    // SIGTERM when rendulic dies, whatever kills it: a SIGKILL runs no handler of ours (below,
    // cleanup), and the script drew on for seconds, putting figures in place after the command
    // had ended. On SIGTERM the script ends its workers and removes its temporaries.
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() != parent) _exit(127);  // rendulic died before the line above
    ::dup2(pipefd[1], STDERR_FILENO);
    ::close(pipefd[0]);
    ::close(pipefd[1]);
    execvpe(argv[0], argv.data(), envp.data());
    _exit(127);
  }
  const int handle = cleanup::kill_on_death(pid);
  Spawned r;
  ::close(pipefd[1]);
  char buf[4096];
  for (;;) {
    const ssize_t n = ::read(pipefd[0], buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    r.err.append(buf, static_cast<std::size_t>(n));
  }
  ::close(pipefd[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  cleanup::forget(handle);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string last_line(const std::string& text) {
  std::istringstream in(text);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last;
}

}  // namespace

std::filesystem::path plot_script_file(const std::filesystem::path& script) {
  namespace fs = std::filesystem;
  auto must_exist = [](const fs::path& p, const std::string& how) {
    std::error_code ec;
    if (!fs::is_regular_file(p, ec))
      throw InputError(p.string() + ": no figure script there (" + how + ")");
    return p;
  };
  if (!script.empty()) return must_exist(script, "--script");
  if (const char* env = std::getenv("RENDULIC_PLOT_SCRIPT"); env && *env)
    return must_exist(env, "RENDULIC_PLOT_SCRIPT");
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return {};
  const fs::path bin = exe.parent_path();
  for (const fs::path& p : {bin / "plot.py", bin.parent_path() / RENDULIC_PLOT_SCRIPT_REL})
    if (fs::is_regular_file(p, ec)) return p;
  return {};
}

int plot_jobs_from_environment() {
  const char* jobs = std::getenv("RENDULIC_PLOT_JOBS");
  if (!jobs || !*jobs) return 0;
  // "abc" failed in the script, after the files were checked, as a Python ValueError.
  long long n = 0;
  const char* end = jobs + std::strlen(jobs);
  const auto [at, err] = std::from_chars(jobs, end, n);
  if (err != std::errc() || at != end || n < 1 || n > kMaxThreads)
    throw InputError("RENDULIC_PLOT_JOBS=" + printable(jobs) +
                     ": the processes to draw with are a whole number in [1, " +
                     std::to_string(kMaxThreads) + "]");
  return static_cast<int>(n);
}

int plot_results(const std::filesystem::path& file, const std::filesystem::path& out_dir,
                 const std::filesystem::path& script) {
  const std::filesystem::path script_file = plot_script_file(script);
  { ResultsReader check(file); }
  std::error_code ec;
  // The folders made here go again if they stay empty: a plot that fails, or that finds no
  // figure's data in the file, left an empty figures/ behind.
  const std::vector<std::filesystem::path> made = make_folders(out_dir, "figures folder");
  struct RemoveIfEmpty {
    const std::vector<std::filesystem::path>& folders;
    ~RemoveIfEmpty() {
      std::error_code e;
      for (const auto& d : folders) std::filesystem::remove(d, e);  // fails unless empty
    }
  } tidy{made};
  if (::access(out_dir.c_str(), W_OK) != 0)
    throw InputError(out_dir.string() + ": cannot write figures here: " + std::strerror(errno));
  // The figures are independent: plot.py draws them in as many processes as this run may
  // use threads (--threads; the user's own RENDULIC_PLOT_JOBS wins).
  std::vector<std::string> env;
  if (plot_jobs_from_environment() == 0)
    env.push_back("RENDULIC_PLOT_JOBS=" + std::to_string(omp_get_max_threads()));
  std::vector<std::string> args = {""};
  if (script_file.empty()) {
    args.insert(args.end(), {"-c", kPlotScript});
  } else {
    args.push_back(script_file.string());
    log::info("figures drawn by ", script_file.string());
  }
  args.insert(args.end(), {file.string(), out_dir.string()});
  // The first interpreter that has both modules draws: PATH's python3 may be a private build
  // (pyenv, conda) without Debian's packages, which live under /usr/bin/python3. The script
  // says so itself (exit 3, before it writes anything), so no interpreter is started only to
  // ask: that probe imported matplotlib once more, 0.35-0.9 s of every plot (docs/figures.md).
  std::string missing;  // the last interpreter's word on it
  for (const char* python : {"python3", "/usr/bin/python3"}) {
    args[0] = python;
    const Spawned r = spawn(args, env);
    if (r.code == 0) {
      // The figures it skipped, and why: one note per line, as every message of the tool.
      std::istringstream notes(r.err);
      for (std::string line; std::getline(notes, line);)
        if (!line.empty()) log::info(line);
      if (std::filesystem::is_empty(out_dir, ec))
        log::info(file.string(), ": no figure drawn (each one's data is absent, as said above)");
      return 0;
    }
    // No such interpreter (127), or one without the modules: plot.py's exit 3, or a user's
    // own script that does not say so (Python's exit 1 on the import).
    const std::string why = last_line(r.err);
    if (r.code == 127 || r.code == 3 || (r.code == 1 && why.rfind("ModuleNotFoundError", 0) == 0)) {
      if (!why.empty()) missing = ": " + printable(why);
      continue;
    }
    if (r.code == 2)  // plot.py's one line about data it cannot draw
      throw InputError(file.string() + ": cannot draw the figures: " + printable(why));
    throw std::runtime_error("plot: the figure script failed (exit " + std::to_string(r.code) +
                             "): " + printable(why));
  }
  throw InputError(
      "plot: needs python3 with matplotlib and h5py (bash .ci/setup.sh installs "
      "python3-matplotlib and python3-h5py)" +
      missing);
}

Subcommand add_plot(CLI::App& parent) {
  auto file = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto script = std::make_shared<std::string>();
  auto* sub = parent.add_subcommand("plot", "Figures of a results file (PNG, PDF and SVG)");
  sub->add_option("file", *file, "results file (HDF5, schema rendulic/2 or 1)")->required();
  sub->add_option("--out", *out, "output folder (default: FILE's folder/figures)");
  sub->add_option("--script", *script,
                  "figure script to run instead of the installed or compiled-in plot.py "
                  "(also: RENDULIC_PLOT_SCRIPT)");
  return {sub, [file, out, script]() -> int {
            std::filesystem::path dir = *out;
            if (dir.empty()) dir = std::filesystem::path(*file).parent_path() / "figures";
            return plot_results(*file, dir, *script);
          }};
}
}  // namespace rendulic::app
