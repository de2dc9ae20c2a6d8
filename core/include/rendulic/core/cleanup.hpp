// Tidying up when the process dies before it can do so itself (docs/usage.md "Results are
// atomic"): temporary files that must not outlive a run, a saved copy of the completed stages
// that must become `results.h5.partial`, and child processes (the figure script) that must
// not keep writing. install_handlers() catches SIGHUP, SIGINT, SIGQUIT, SIGTERM, SIGUSR1,
// SIGUSR2, SIGALRM, SIGPIPE, SIGXCPU, SIGXFSZ and SIGABRT (std::terminate ends in abort()),
// does what is registered, then re-raises the signal with its default disposition, so the
// exit status still tells how the process ended. Crashes (SIGSEGV, SIGBUS, ...) are left to
// the default handler and to sanitizers.
//
// The handler may only call async-signal-safe functions: entries are fixed-size C strings
// formatted at registration, and it uses kill(), rename(), unlink() and write() alone.
#pragma once

#include <sys/types.h>

#include <filesystem>
#include <string>

namespace rendulic::cleanup {

// Installs the handlers once (later calls do nothing). main() calls it first; registering an
// entry calls it too, so library users are covered.
void install_handlers();

// Registration handles; -1 when the table is full or the path too long (that entry is then
// not tidied on a signal; normal code paths still tidy it).
int remove_on_death(const std::filesystem::path& path);
// On death, renames `from` onto `to` and, if that worked, writes `message` (one line) to
// stderr. Used for the saved copy of a run's completed stages.
int rename_on_death(const std::filesystem::path& from, const std::filesystem::path& to,
                    const std::string& message);
// On death, sends SIGTERM to this child process.
int kill_on_death(pid_t child);
// Drops an entry (the normal code path has dealt with it). Ignores -1.
void forget(int handle);

}  // namespace rendulic::cleanup
