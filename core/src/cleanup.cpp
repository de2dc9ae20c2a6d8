// Tidying up on signals and std::terminate (see cleanup.hpp; docs/usage.md "Results are
// atomic"). A fixed table of entries, each claimed with a compare-and-swap and published
// with a release store, so the handler reads only complete entries and never allocates.
#include "rendulic/core/cleanup.hpp"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <exception>

namespace rendulic::cleanup {
namespace {

enum Kind : int { kFree = 0, kClaimed = -1, kRemove = 1, kRename = 2, kKill = 3 };

struct Entry {
  std::atomic<int> kind{kFree};
  pid_t pid = 0;
  std::array<char, 4096> path{};
  std::array<char, 4096> target{};
  std::array<char, 512> message{};
};

constexpr int kEntries = 32;
std::array<Entry, kEntries> g_entries;
std::terminate_handler g_previous_terminate = nullptr;

constexpr int kSignals[] = {SIGHUP,  SIGINT,  SIGQUIT, SIGTERM, SIGUSR1, SIGUSR2,
                            SIGALRM, SIGPIPE, SIGXCPU, SIGXFSZ, SIGABRT};

// Children first (they may be writing into the folder), then the saved copies, then the
// temporary files: a copy renamed into place must not be unlinked by a later entry.
void run_entries() {
  for (auto& e : g_entries)
    if (e.kind.load(std::memory_order_acquire) == kKill) ::kill(e.pid, SIGTERM);
  for (auto& e : g_entries) {
    if (e.kind.load(std::memory_order_acquire) != kRename) continue;
    if (::rename(e.path.data(), e.target.data()) == 0) {
      const auto n = std::strlen(e.message.data());
      if (n > 0 && ::write(STDERR_FILENO, e.message.data(), n) < 0) {
      }
    }
  }
  for (auto& e : g_entries)
    if (e.kind.load(std::memory_order_acquire) == kRemove) ::unlink(e.path.data());
}

extern "C" void on_fatal_signal(int sig) {
  const int saved_errno = errno;
  run_entries();
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  ::sigaction(sig, &dfl, nullptr);
  // Delivered with the default disposition as soon as this handler returns (the signal is
  // blocked while it runs), so the exit status is the signal's.
  ::raise(sig);
  errno = saved_errno;
}

void on_terminate() {
  run_entries();
  if (g_previous_terminate) g_previous_terminate();  // libstdc++'s: prints the exception
  std::abort();
}

bool copy_c_string(std::array<char, 4096>& dst, const std::string& s) {
  if (s.size() + 1 > dst.size() || s.find('\0') != std::string::npos) return false;
  std::memcpy(dst.data(), s.c_str(), s.size() + 1);
  return true;
}

template <class Fill>
int add(Kind kind, Fill&& fill) {
  install_handlers();
  for (int i = 0; i < kEntries; ++i) {
    int expected = kFree;
    if (!g_entries[i].kind.compare_exchange_strong(expected, kClaimed)) continue;
    if (!fill(g_entries[i])) {
      g_entries[i].kind.store(kFree, std::memory_order_release);
      return -1;
    }
    g_entries[i].kind.store(kind, std::memory_order_release);
    return i;
  }
  return -1;
}

}  // namespace

void install_handlers() {
  static const bool installed = [] {
    for (int sig : kSignals) {
      struct sigaction old {};
      if (::sigaction(sig, nullptr, &old) != 0) continue;
      // A signal the parent chose to ignore (nohup: SIGHUP) stays ignored.
      if (!(old.sa_flags & SA_SIGINFO) && old.sa_handler == SIG_IGN) continue;
      struct sigaction sa {};
      sa.sa_handler = on_fatal_signal;
      sigfillset(&sa.sa_mask);  // no other handler runs while this one does
      ::sigaction(sig, &sa, nullptr);
    }
    g_previous_terminate = std::set_terminate(on_terminate);
    return true;
  }();
  (void)installed;
}

int remove_on_death(const std::filesystem::path& path) {
  return add(kRemove, [&](Entry& e) { return copy_c_string(e.path, path.string()); });
}

int rename_on_death(const std::filesystem::path& from, const std::filesystem::path& to,
                    const std::string& message) {
  return add(kRename, [&](Entry& e) {
    if (!copy_c_string(e.path, from.string()) || !copy_c_string(e.target, to.string()))
      return false;
    const std::string line = message.empty() ? "" : message + "\n";
    const std::size_t n = std::min(line.size(), e.message.size() - 1);
    std::memcpy(e.message.data(), line.data(), n);
    if (n > 0) e.message[n - 1] = '\n';  // a cut message still ends its line
    e.message[n] = '\0';
    return true;
  });
}

int kill_on_death(pid_t child) {
  return add(kKill, [&](Entry& e) {
    e.pid = child;
    return child > 0;
  });
}

void forget(int handle) {
  if (handle >= 0 && handle < kEntries)
    g_entries[handle].kind.store(kFree, std::memory_order_release);
}

}  // namespace rendulic::cleanup
