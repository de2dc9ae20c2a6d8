// Entry point of the `rendulic` executable (docs/usage.md):
// parses with CLI11, dispatches to one subcommand, and maps failures to exit codes: 0
// success, 2 bad input (one line on stderr naming the culprit), 1 an internal error. Nothing
// escapes uncaught: an exception of any type (HDF5's are not std::exception) unwinds, so the
// destructors remove temporary files, and signals tidy up through cleanup.hpp.
#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <vector>

#include "cli_options.hpp"
#include "commands.hpp"
#include "rendulic/calibration/solver.hpp"
#include "rendulic/core/cleanup.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/log.hpp"
#include "rendulic/core/version.hpp"

namespace {
// Ends a failed command without the libraries' exit handlers: HDF5 1.10 crashes in its own
// shutdown (H5D_close from H5close) when a dataset's close failed before, as it does on a full
// disk. Our streams are flushed first; the temporary files are already gone (destructors ran).
[[noreturn]] void fail_with(int code) {
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  std::_Exit(code);
}

// std::cout's buffer, writing into C's stdout as the standard one does (so that its text and
// printf's keep their order), which keeps the reason of the first write that failed. The
// stream stops writing after it, and by the end errno no longer said why: `inspect FILE >
// /dev/full` said "cannot write" without "No space left on device".
class StdoutBuffer : public std::streambuf {
 public:
  int first_error() const { return first_error_; }

 protected:
  int overflow(int c) override {
    if (c == traits_type::eof()) return traits_type::not_eof(c);
    if (std::fputc(c, stdout) == EOF) return failed(), traits_type::eof();
    return c;
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    const std::size_t written = std::fwrite(s, 1, static_cast<std::size_t>(n), stdout);
    if (written < static_cast<std::size_t>(n)) failed();
    return static_cast<std::streamsize>(written);
  }
  int sync() override { return std::fflush(stdout) == 0 ? 0 : (failed(), -1); }

 private:
  void failed() {
    if (first_error_ == 0) first_error_ = errno;
  }
  int first_error_ = 0;
};

// Never destroyed: std::cout is flushed at exit after the function's statics are gone.
StdoutBuffer& stdout_buffer() {
  static auto* buffer = new StdoutBuffer;
  return *buffer;
}

// A command's output on stdout that could not all be written (a full disk under `fit --json >
// fit.json`, /dev/full) was lost with exit 0: the stream's failure is one line and exit 2.
int with_stdout_written(int code) {
  errno = 0;  // the flush that fails sets it
  std::cout.flush();
  if (std::fflush(stdout) == 0 && !std::ferror(stdout) && !std::cout.bad()) return code;
  const int err = stdout_buffer().first_error() != 0 ? stdout_buffer().first_error() : errno;
  std::string line = "rendulic: standard output: cannot write";
  if (err != 0) line.append(": ").append(std::strerror(err));
  std::cerr << line << "\n";
  return code == 0 ? rendulic::kExitInput : code;
}
}  // namespace

int main(int argc, char** argv) {
  using namespace rendulic;
  log::keep_standard_streams_open();
  std::cout.rdbuf(&stdout_buffer());
  cleanup::install_handlers();
  calibration::quiet_solver_logging();
  CLI::App cli{"rendulic: calibrate constitutive models of granular soils from DEM envelopes"};
  cli.set_version_flag("--version", std::string("rendulic ") + kVersion + " (" + kGitSha + ")");
  cli.require_subcommand(1);
  std::vector<app::Subcommand> subs = {
      app::add_run(cli),   app::add_fit(cli),     app::add_envelope(cli), app::add_calibrate(cli),
      app::add_bench(cli), app::add_inspect(cli), app::add_plot(cli),     app::add_keys(cli),
      app::add_sweep(cli), app::add_report(cli),  app::add_probe(cli),    app::add_export(cli)};
  app::name_words_that_are_not_numbers(cli);
  try {
    cli.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return with_stdout_written(cli.exit(e));
  } catch (const CLI::CallForAllHelp& e) {
    return with_stdout_written(cli.exit(e));
  } catch (const CLI::CallForVersion& e) {
    return with_stdout_written(cli.exit(e));
  } catch (const CLI::ParseError& e) {
    std::cerr << "rendulic: " << e.what() << " (see rendulic --help)\n";
    return kExitInput;
  }
  try {
    for (const auto& sub : subs)
      if (sub.app->parsed()) return with_stdout_written(sub.action());
  } catch (const InputError& e) {
    std::cerr << "rendulic: " << printable(e.what()) << "\n";
    fail_with(kExitInput);
  } catch (...) {
    std::cerr << "rendulic: internal error: " << printable(describe_current_exception()) << "\n";
    fail_with(1);
  }
  return 1;
}
