// Descriptions and rethrowing of errors in flight (errors.hpp), including HDF5's C++
// exceptions, which do not derive from std::exception (hdf5_reason.hpp).
#include "rendulic/core/errors.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>

#include "hdf5_reason.hpp"

namespace rendulic {
namespace detail {
namespace {

// The reason of the last failed HDF5 call on this thread. It must be taken while the call
// fails: by the time a C++ catch block runs, the destructors of the H5 objects unwound on
// the way have made API calls of their own, and each call clears the error stack. A plain
// buffer, not a std::string: HDF5 may fail again while it shuts down at exit, after the
// thread's objects are destroyed.
thread_local char g_last_reason[512];
// The last failure was HDF5's file driver meeting a file system without file locks.
thread_local bool g_locks_refused = false;

void set_reason(const char* text, std::size_t n) {
  n = std::min(n, sizeof g_last_reason - 1);
  std::memcpy(g_last_reason, text, n);
  g_last_reason[n] = '\0';
}

herr_t collect(unsigned, const H5E_error2_t* err, void* data) {
  auto* found = static_cast<int*>(data);  // 0: nothing yet, 1: a description, 2: a reason
  if (!err || !err->desc || !*err->desc || *found == 2) return 0;
  // A file system without locks (NFS without a lock daemon, some Lustre mounts) refuses
  // HDF5's flock with ENOLCK or EOPNOTSUPP (ENOSYS HDF5 passes over itself). HDF5 only reads
  // such a file with its locking off, which its user must ask for.
  const char* lock = "unable to lock file, errno = ";
  if (std::strncmp(err->desc, lock, std::strlen(lock)) == 0) {
    const int e = std::atoi(err->desc + std::strlen(lock));
    if (e == ENOLCK || e == EOPNOTSUPP || e == ENOSYS) {
      const std::string why = std::string("this file system refuses file locks (") +
                              std::strerror(e) +
                              "); set HDF5_USE_FILE_LOCKING=FALSE to use it without them";
      set_reason(why.c_str(), why.size());
      g_locks_refused = true;
      *found = 2;
      return 0;
    }
  }
  // The file drivers put the system's reason in their description.
  const char* key = "error message = '";
  if (const char* at = std::strstr(err->desc, key)) {
    const char* from = at + std::strlen(key);
    if (const char* end = std::strchr(from, '\'')) {
      set_reason(from, static_cast<std::size_t>(end - from));
      *found = 2;
      return 0;
    }
  }
  if (*found == 0) {  // innermost first: the first description is the most specific
    set_reason(err->desc, std::strlen(err->desc));
    *found = 1;
  }
  return 0;
}

herr_t record_reason(hid_t stack_id, void*) {
  int found = 0;
  g_last_reason[0] = '\0';
  g_locks_refused = false;
  H5Ewalk2(stack_id, H5E_WALK_UPWARD, collect, &found);
  return 0;
}

}  // namespace

void quiet_hdf5() {
  static const bool done = [] {
    // In place of HDF5's printing of its error stack: every failure becomes one line of ours.
    H5Eset_auto2(H5E_DEFAULT, record_reason, nullptr);
    return true;
  }();
  (void)done;
}

void forget_hdf5_reason() {
  g_last_reason[0] = '\0';
  g_locks_refused = false;
}

bool hdf5_refused_locks() { return g_locks_refused; }

std::string hdf5_reason() {
  return g_last_reason[0] ? std::string(g_last_reason) : std::string("HDF5 error");
}

std::string hdf5_reason(const H5::Exception& e) {
  if (g_last_reason[0]) return g_last_reason;
  const std::string msg = e.getDetailMsg();
  return msg.empty() ? std::string("HDF5 error") : msg;
}

}  // namespace detail

std::string printable(const std::string& text) {
  std::string out;
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (c < 0x20 || c == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    } else {
      out += ch;
    }
  }
  return out;
}

std::string describe_current_exception() {
  try {
    throw;
  } catch (const std::exception& e) {
    return e.what();
  } catch (const H5::Exception& e) {
    return "HDF5: " + e.getFuncName() + ": " + detail::hdf5_reason(e);
  } catch (...) {
    return "unknown exception";
  }
}

void rethrow_with_note(const std::string& note) {
  try {
    throw;
  } catch (const InputError& e) {
    throw InputError(e.what() + note);
  } catch (...) {
    throw std::runtime_error(describe_current_exception() + note);
  }
}

CaughtError CaughtError::current() {
  CaughtError c;
  try {
    throw;
  } catch (const InputError& e) {
    c = {e.what(), true};
  } catch (...) {
    c = {describe_current_exception(), false};
  }
  // The empty message means "nothing was caught": an exception without words must not pass
  // the loop unnoticed.
  if (c.message.empty()) c.message = "an error without a message";
  return c;
}

void CaughtError::rethrow(const std::string& prefix) const {
  if (input) throw InputError(prefix + message);
  throw std::runtime_error(prefix + message);
}

}  // namespace rendulic
