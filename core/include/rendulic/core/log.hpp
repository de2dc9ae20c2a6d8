// The one logging facility (docs/usage.md "Progress and messages"): every message of the tool
// goes to stderr through here, one message per line, prefixed "rendulic: " (and "warning: " or
// "error: "), under one lock so that lines of concurrent threads never interleave. A live
// progress line (a terminal's status bar, app/progress.hpp) is owned here as well: a message
// first clears it, then the bar is drawn again below the message, so warnings never land on
// the bar.
//
// Levels: error < warning < info < debug. `--quiet` sets warning (errors and warnings still
// print: they say something went wrong); the default is info.
#pragma once

#include <sstream>
#include <string>
#include <string_view>

namespace rendulic::log {

enum class Level { kError = 0, kWarning = 1, kInfo = 2, kDebug = 3 };

void set_level(Level level);
Level level();
bool enabled(Level level);

void error(std::string_view message);
void warning(std::string_view message);
void info(std::string_view message);
void debug(std::string_view message);

// The same, built from parts as a stream would print them (numbers as %g does):
// log::warning("state ", label, ": yield strain ", 2e-3).
template <class... Parts>
std::string join(const Parts&... parts) {
  std::ostringstream s;
  (s << ... << parts);
  return s.str();
}
template <class First, class... Parts>
void error(const First& first, const Parts&... parts) {
  error(std::string_view(join(first, parts...)));
}
template <class First, class... Parts>
void warning(const First& first, const Parts&... parts) {
  warning(std::string_view(join(first, parts...)));
}
template <class First, class... Parts>
void info(const First& first, const Parts&... parts) {
  if (enabled(Level::kInfo)) info(std::string_view(join(first, parts...)));
}
template <class First, class... Parts>
void debug(const First& first, const Parts&... parts) {
  if (enabled(Level::kDebug)) debug(std::string_view(join(first, parts...)));
}

// The live line: drawn in place (carriage return, erase) and kept under later messages until
// clear_live(). For terminals only; a log file gets plain lines (info) instead.
void live(std::string_view text);
void clear_live();

// Opens /dev/null on any of descriptors 0, 1 and 2 that is closed (a parent that closed them:
// `2>&-`, some batch systems). Called first by the executable and the Python module: the next
// file opened takes the lowest free number, and a results file that took 2 received the log
// lines (a run with stdout and stderr closed wrote its messages into results.h5, exit 0).
void keep_standard_streams_open();

}  // namespace rendulic::log
