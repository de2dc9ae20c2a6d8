// AtomicTextFile (core/include/rendulic/core/text_file.hpp; docs/usage.md "Results are
// atomic"): a temporary beside the final file, written with POSIX calls so that every failure
// (ENOSPC, EFBIG under a file-size limit, EIO) has its errno, fsynced before the rename so that
// a crash after it cannot leave an empty file under the final name.
#include "rendulic/core/text_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <utility>

#include "rendulic/core/cleanup.hpp"
#include "rendulic/core/errors.hpp"

namespace rendulic {

namespace fs = std::filesystem;

void AtomicTextFile::refuse_folder(const fs::path& file, const std::string& what) {
  std::error_code ec;
  if (fs::is_directory(file, ec))
    throw InputError(file.string() + ": is a folder (" + what + " is a file)");
}

AtomicTextFile::AtomicTextFile(fs::path file, std::string what)
    : final_(std::move(file)), what_(std::move(what)) {
  if (final_.empty()) throw InputError("the file name of " + what_ + " is empty");
  const fs::path folder = final_.has_parent_path() ? final_.parent_path() : fs::path(".");
  std::string name = final_.filename().string();
  name.insert(name.begin(), '.');
  name += ".tmp-" + std::to_string(::getpid());
  tmp_ = folder / name;
  refuse_folder(final_, what_);
  {
    // No text output replaces an HDF5 file: `export --lammps out/results.h5` replaced the run's
    // results by a LAMMPS data file, `calibrate --out` of the results file failed only after
    // the calibration. HDF5's signature opens every file rendulic writes.
    static constexpr char kSignature[8] = {'\x89', 'H', 'D', 'F', '\r', '\n', '\x1a', '\n'};
    char head[8] = {};
    std::ifstream in(final_, std::ios::binary);
    if (in.read(head, sizeof head) && std::equal(head, head + 8, kSignature))
      throw InputError(final_.string() + ": is an HDF5 file (a results file?), which " + what_ +
                       " would replace; give another name");
  }
  handle_ = cleanup::remove_on_death(tmp_);
  const int fd = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    const int err = errno;
    cleanup::forget(handle_);
    throw InputError(final_.string() + ": cannot write " + what_ + ": " + std::strerror(err));
  }
  ::close(fd);
}

AtomicTextFile::~AtomicTextFile() {
  std::error_code ec;
  if (!done_) fs::remove(tmp_, ec);
  cleanup::forget(handle_);
}

void AtomicTextFile::flush() {
  const std::string text = text_.str();
  const int fd = ::open(tmp_.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);
  int err = fd < 0 ? errno : 0;
  for (std::size_t at = 0; err == 0 && at < text.size();) {
    const ssize_t n = ::write(fd, text.data() + at, text.size() - at);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0)
      err = n < 0 ? errno : EIO;
    else
      at += static_cast<std::size_t>(n);
  }
  if (err == 0 && ::fsync(fd) != 0) err = errno;
  if (fd >= 0 && ::close(fd) != 0 && err == 0) err = errno;
  std::error_code ec;
  if (err != 0) {
    fs::remove(tmp_, ec);
    throw InputError(final_.string() + ": cannot write " + what_ + ": " + std::strerror(err));
  }
  flushed_ = true;
}

void AtomicTextFile::commit() {
  if (!flushed_) flush();
  std::error_code ec;
  fs::rename(tmp_, final_, ec);
  if (ec) {
    const std::string why = ec.message();
    fs::remove(tmp_, ec);
    throw InputError(final_.string() + ": cannot move " + what_ + " into place: " + why);
  }
  done_ = true;
}

}  // namespace rendulic
