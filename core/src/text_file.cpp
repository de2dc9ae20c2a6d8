// AtomicTextFile (core/include/rendulic/core/text_file.hpp; docs/usage.md "Results are
// atomic"): a temporary beside the final file, written with POSIX calls so that every failure
// (ENOSPC, EFBIG under a file-size limit, EIO) has its errno, fsynced before the rename so that
// a crash after it cannot leave an empty file under the final name.
#include "rendulic/core/text_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iostream>
#include <utility>

#include "rendulic/core/cleanup.hpp"
#include "rendulic/core/errors.hpp"

namespace rendulic {

namespace fs = std::filesystem;

namespace {
// An empty name (a shell variable that is not set) said ": cannot read ...: No such file or
// directory", a message that begins with nothing.
void refuse_empty_name(const std::string& path, const std::string& what) {
  if (path.empty()) throw InputError("the name of the " + what + " is empty");
}
}  // namespace

std::string read_input_text(const std::string& path, const std::string& what,
                            std::size_t max_bytes) {
  refuse_empty_name(path, what);
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw InputError(path + ": cannot read " + what + ": " + std::strerror(errno));
  struct FdCloser {
    int fd;
    ~FdCloser() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0)
    throw InputError(path + ": cannot read " + what + ": " + std::strerror(errno));
  refuse_unless_regular_mode(st.st_mode, path, what, "a text file");
  std::string text;
  char buf[65536];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw InputError(path + ": cannot read " + what + ": " + std::strerror(errno));
    if (n == 0) break;
    text.append(buf, static_cast<std::size_t>(n));
    if (text.size() > max_bytes)
      throw InputError(path + ": larger than " + std::to_string(max_bytes >> 20) + " MiB, not a " +
                       what);
  }
  return text;
}

void refuse_unless_regular_mode(unsigned mode, const std::string& shown, const std::string& what,
                                const std::string& form) {
  if (S_ISDIR(mode)) throw InputError(shown + ": is a folder, not a " + what);
  if (!S_ISREG(mode))
    throw InputError(shown + ": not a regular file (a " + what + " is " + form + ")");
}

void refuse_unless_regular_file(const fs::path& path, const std::string& shown,
                                const std::string& what, const std::string& form) {
  refuse_empty_name(path.string(), what);
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    throw InputError(shown + (errno == ENOENT
                                  ? std::string(": no such file")
                                  : ": cannot read " + what + ": " + std::strerror(errno)));
  refuse_unless_regular_mode(st.st_mode, shown, what, form);
}

namespace {

// The innermost part of `dir` that exists ("" if none does); `missing` gets the parts below
// it, innermost first.
fs::path innermost_existing(const fs::path& dir, std::vector<fs::path>* missing = nullptr) {
  std::error_code ec;
  fs::path existing = dir;
  for (; !existing.empty() && !fs::exists(existing, ec); existing = existing.parent_path()) {
    if (missing) missing->push_back(existing);
    if (existing == existing.parent_path()) break;
  }
  return existing;
}

// "F: is a file, not a folder (why)" where a file stands at `dir` or at a folder above it
// (`existing`, from innermost_existing); `why` is `itself` for `dir` itself, else `above`.
void refuse_file_in_the_way(const fs::path& existing, const fs::path& dir,
                            const std::string& itself, const std::string& above) {
  std::error_code ec;
  if (!existing.empty() && fs::exists(existing, ec) && !fs::is_directory(existing, ec))
    throw InputError(existing.string() + ": is a file, not a folder (" +
                     (existing == dir ? itself : above) + ")");
}

// The words of both make_folders and refuse_file_in_place_of_folder.
void refuse_file_in_place_of(const fs::path& existing, const fs::path& dir,
                             const std::string& what) {
  refuse_file_in_the_way(existing, dir, "the " + what,
                         "it cannot hold the " + what + " " + dir.string());
}

}  // namespace

void refuse_file_in_place_of_folder(const fs::path& dir, const std::string& what) {
  if (!dir.empty()) refuse_file_in_place_of(innermost_existing(dir), dir, what);
}

std::vector<fs::path> make_folders(const fs::path& dir, const std::string& what) {
  std::vector<fs::path> made;
  if (dir.empty()) return made;
  std::error_code ec;
  refuse_file_in_place_of(innermost_existing(dir, &made), dir, what);
  fs::create_directories(dir, ec);
  if (!ec && !fs::is_directory(dir, ec)) ec = std::make_error_code(std::errc::not_a_directory);
  if (ec) {
    std::error_code ignored;
    for (const fs::path& d : made) fs::remove(d, ignored);  // fails unless empty
    throw InputError(dir.string() + ": cannot create the " + what + ": " + ec.message());
  }
  return made;
}

void AtomicTextFile::refuse_folder(const fs::path& file, const std::string& what) {
  std::error_code ec;
  if (fs::is_directory(file, ec))
    throw InputError(file.string() + ": is a folder (" + what + " is a file)");
}

void refuse_read_only(const fs::path& target, const fs::path& shown, const std::string& what) {
  std::error_code ec;
  if (fs::exists(fs::symlink_status(target, ec)) && ::access(target.c_str(), W_OK) != 0)
    throw InputError(shown.string() + ": cannot write " + what + ": " + std::strerror(errno));
}

void keep_mode(const fs::path& existing, const fs::path& replacement) {
  struct stat st {};
  if (::stat(existing.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return;
  // Owner only as root, group where this user belongs to it; a refusal keeps this process's,
  // and the permissions are given whatever the owner became.
  [[maybe_unused]] const int owned = ::chown(
      replacement.c_str(), ::geteuid() == 0 ? st.st_uid : static_cast<uid_t>(-1), st.st_gid);
  [[maybe_unused]] const int moded = ::chmod(replacement.c_str(), st.st_mode & 07777);
}

fs::path link_target(fs::path p) {
  std::error_code ec;
  for (int depth = 0; depth < 40 && fs::is_symlink(fs::symlink_status(p, ec)); ++depth) {
    const fs::path target = fs::read_symlink(p, ec);
    if (ec) break;
    p = target.is_absolute() ? target : p.parent_path() / target;
  }
  return p;
}

AtomicTextFile::AtomicTextFile(fs::path file, std::string what)
    : final_(std::move(file)), what_(std::move(what)) {
  if (final_.empty()) throw InputError("the file name of " + what_ + " is empty");
  // A link is written through, not replaced by a file: `--out link.json` broke the link and
  // left its target as it was. A device, a FIFO or a socket is written to as it is, without a
  // temporary: `--out /dev/null` (as root) replaced the system's /dev/null with a file, and a
  // FIFO hung in the check below, which read it.
  // /dev/stdout and /proc/self/fd/N are links the kernel resolves, which a path cannot name.
  std::error_code ec;
  const fs::file_status st = fs::status(final_, ec);
  const std::string abs = fs::absolute(final_, ec).lexically_normal().string();
  direct_ = (fs::exists(st) && !fs::is_regular_file(st) && !fs::is_directory(st)) ||
            abs.starts_with("/dev/") || abs.starts_with("/proc/");
  target_ = direct_ ? final_ : link_target(final_);
  refuse_folder(target_, what_);
  if (!direct_) refuse_read_only(target_, final_, what_);
  if (direct_) {
    if (::access(target_.c_str(), W_OK) != 0)
      throw InputError(final_.string() + ": cannot write " + what_ + ": " + std::strerror(errno));
    return;
  }
  const fs::path folder = target_.has_parent_path() ? target_.parent_path() : fs::path(".");
  // open() said only "No such file or directory" or "Not a directory" of the file itself
  // (`export --lammps out/a.data` before out/ is made).
  if (!fs::is_directory(folder, ec)) {
    const std::string holds = "it cannot hold " + what_ + " " + final_.string();
    refuse_file_in_the_way(innermost_existing(folder), folder, holds, holds);
    throw InputError(final_.string() + ": cannot write " + what_ + ": the folder " +
                     folder.string() + " does not exist");
  }
  std::string name = target_.filename().string();
  name.insert(name.begin(), '.');
  name += ".tmp-" + std::to_string(::getpid());
  tmp_ = folder / name;
  {
    // No text output replaces an HDF5 file: `export --lammps out/results.h5` replaced the run's
    // results by a LAMMPS data file, `calibrate --out` of the results file failed only after
    // the calibration. HDF5's signature opens every file rendulic writes.
    static constexpr char kSignature[8] = {'\x89', 'H', 'D', 'F', '\r', '\n', '\x1a', '\n'};
    char head[8] = {};
    std::ifstream in(target_, std::ios::binary);
    if (in.read(head, sizeof head) && std::equal(head, head + 8, kSignature))
      throw InputError(final_.string() + ": is an HDF5 file (a results file?), which " + what_ +
                       " would replace; give another name");
  }
  handle_ = cleanup::remove_on_death(tmp_);
  const int fd = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0) {
    const int err = errno;
    cleanup::forget(handle_);
    throw InputError(final_.string() + ": cannot write " + what_ + ": " + std::strerror(err));
  }
  ::close(fd);
}

AtomicTextFile::~AtomicTextFile() {
  std::error_code ec;
  if (!done_ && !tmp_.empty()) fs::remove(tmp_, ec);
  cleanup::forget(handle_);
}

void AtomicTextFile::flush() {
  if (direct_) return;  // a device or a FIFO takes the text once, at commit()
  write_to(tmp_, O_TRUNC, true);
  flushed_ = true;
}

namespace {
// The descriptor a name of this process's own streams stands for (/dev/stdout, /dev/fd/2,
// /proc/self/fd/1), or -1. Opened by name, a regular file behind it got a second description at
// offset 0, and the text overwrote what the command had printed before.
int own_descriptor(const fs::path& p) {
  const std::string s = p.lexically_normal().string();
  if (s == "/dev/stdout") return 1;
  if (s == "/dev/stderr") return 2;
  for (const char* prefix : {"/dev/fd/", "/proc/self/fd/"}) {
    const std::string rest = s.starts_with(prefix) ? s.substr(std::strlen(prefix)) : "";
    if (!rest.empty() && rest.size() < 6 &&
        std::all_of(rest.begin(), rest.end(), [](char c) { return c >= '0' && c <= '9'; }))
      return std::stoi(rest);
  }
  return -1;
}
}  // namespace

void AtomicTextFile::write_to(const fs::path& file, int flags, bool sync) {
  const std::string text = text_.str();
  const int own = direct_ ? own_descriptor(fs::absolute(file)) : -1;
  if (own >= 0) {
    std::cout.flush();  // what the command printed before comes first
    std::cerr.flush();
  }
  const int fd = own >= 0 ? own : ::open(file.c_str(), O_WRONLY | flags | O_CLOEXEC);
  int err = fd < 0 ? errno : 0;
  for (std::size_t at = 0; err == 0 && at < text.size();) {
    const ssize_t n = ::write(fd, text.data() + at, text.size() - at);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0)
      err = n < 0 ? errno : EIO;
    else
      at += static_cast<std::size_t>(n);
  }
  if (err == 0 && sync && ::fsync(fd) != 0) err = errno;
  if (fd >= 0 && own < 0 && ::close(fd) != 0 && err == 0) err = errno;
  std::error_code ec;
  if (err != 0) {
    if (!direct_) fs::remove(tmp_, ec);
    throw InputError(final_.string() + ": cannot write " + what_ + ": " + std::strerror(err));
  }
}

void AtomicTextFile::commit() {
  if (direct_) {
    write_to(target_, 0, false);
    done_ = true;
    return;
  }
  if (!flushed_) flush();
  keep_mode(target_, tmp_);
  std::error_code ec;
  fs::rename(tmp_, target_, ec);
  if (ec) {
    const std::string why = ec.message();
    fs::remove(tmp_, ec);
    throw InputError(final_.string() + ": cannot move " + what_ + " into place: " + why);
  }
  done_ = true;
}

}  // namespace rendulic
