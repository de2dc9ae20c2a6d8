// The logging facility of core/log.hpp (docs/usage.md "Progress and messages").
#include "rendulic/core/log.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <mutex>

namespace rendulic::log {
namespace {

std::atomic<int> g_level{static_cast<int>(Level::kInfo)};
std::mutex g_mutex;
std::string g_live;  // the live line currently on screen ("" if none)

void write_locked(const char* prefix, std::string_view message) {
  if (!g_live.empty()) std::fputs("\r\033[K", stderr);
  std::fprintf(stderr, "rendulic: %s%.*s\n", prefix, static_cast<int>(message.size()),
               message.data());
  if (!g_live.empty()) std::fputs(g_live.c_str(), stderr);
  std::fflush(stderr);
}

void write(Level at, const char* prefix, std::string_view message) {
  if (!enabled(at)) return;
  const std::lock_guard<std::mutex> lock(g_mutex);
  write_locked(prefix, message);
}

}  // namespace

void set_level(Level level) { g_level.store(static_cast<int>(level)); }
Level level() { return static_cast<Level>(g_level.load()); }
bool enabled(Level level) { return static_cast<int>(level) <= g_level.load(); }

void error(std::string_view message) { write(Level::kError, "error: ", message); }
void warning(std::string_view message) { write(Level::kWarning, "warning: ", message); }
void info(std::string_view message) { write(Level::kInfo, "", message); }
void debug(std::string_view message) { write(Level::kDebug, "debug: ", message); }

void live(std::string_view text) {
  const std::lock_guard<std::mutex> lock(g_mutex);
  g_live = "\r\033[K";
  g_live.append(text);
  std::fputs(g_live.c_str(), stderr);
  std::fflush(stderr);
}

void clear_live() {
  const std::lock_guard<std::mutex> lock(g_mutex);
  if (g_live.empty()) return;
  std::fputs("\r\033[K", stderr);
  std::fflush(stderr);
  g_live.clear();
}

void keep_standard_streams_open() {
  for (int fd = 0; fd <= 2; ++fd) {
    if (::fcntl(fd, F_GETFD) != -1 || errno != EBADF) continue;
    const int null = ::open("/dev/null", (fd == 0 ? O_RDONLY : O_WRONLY));
    if (null >= 0 && null != fd) {  // the lower ones are open, so this is rare
      ::dup2(null, fd);
      ::close(null);
    }
  }
}

}  // namespace rendulic::log
