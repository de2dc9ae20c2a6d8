// A file system without file locks (NFS without a lock daemon, some Lustre mounts), where
// flock fails with ENOLCK (docs/usage.md "File systems without locks"). HDF5 refuses to create or
// open a file there unless HDF5_USE_FILE_LOCKING=FALSE: the one line says so, instead of "cannot
// open (corrupt HDF5 file?): No locks available". An update there, HDF5's locking off, said it
// waited for another rendulic process, as if the folder's lock were held. This executable's
// flock stands in for the C library's, for HDF5's file driver too (the executable's symbols
// come first in the dynamic lookup), and fails with ENOLCK while a test asks it to: on every
// file, or on folders only (HDF5 reads its HDF5_USE_FILE_LOCKING once, when it starts, so a
// test cannot turn HDF5's locking off; refusing only the folder's lock is what that leaves).
#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <filesystem>

#include "input_error.hpp"
#include "rendulic/core/results.hpp"

namespace {
enum class Refuse { kNothing, kEveryLock, kFolderLocks };
std::atomic<Refuse> g_refuse{Refuse::kNothing};
}  // namespace

extern "C" int flock(int fd, int operation) {
  struct stat st {};
  const Refuse r = g_refuse.load();
  if (r == Refuse::kEveryLock ||
      (r == Refuse::kFolderLocks && ::fstat(fd, &st) == 0 && S_ISDIR(st.st_mode))) {
    errno = ENOLCK;
    return -1;
  }
  return static_cast<int>(::syscall(SYS_flock, fd, operation));
}

namespace rendulic {
namespace {
namespace fs = std::filesystem;
using rendulic::testing::input_error;

// Locks refused for the life of one object.
struct NoLocks {
  explicit NoLocks(Refuse what) { g_refuse = what; }
  ~NoLocks() { g_refuse = Refuse::kNothing; }
};

TEST(FileLocks, AFileSystemWithoutLocksIsNamedWithTheSettingThatUsesIt) {
  const fs::path d = fs::path(RENDULIC_TEST_TMP) / "core_file_locks";
  fs::remove_all(d);
  fs::create_directories(d);
  {
    ResultsWriter w(d / "kept.h5");
    w.attr("/", "seed", 7.0);
    w.commit();
  }
  const std::string hint =
      "this file system refuses file locks (No locks available); set "
      "HDF5_USE_FILE_LOCKING=FALSE to use it without them";
  {
    NoLocks no_locks(Refuse::kEveryLock);
    std::string msg = input_error([&] { ResultsWriter w(d / "new.h5"); });
    EXPECT_EQ(msg, (d / "new.h5").string() + ": cannot create results file: " + hint);
    msg = input_error([&] { ResultsReader r(d / "kept.h5"); });
    EXPECT_EQ(msg, (d / "kept.h5").string() + ": cannot open: " + hint);
    EXPECT_FALSE(fs::exists(d / "new.h5"));
  }
  // The folder's lock refused: updated and written without it, and without a word of waiting.
  NoLocks no_folder_locks(Refuse::kFolderLocks);
  ::testing::internal::CaptureStderr();
  {
    ResultsWriter u = ResultsWriter::update(d / "kept.h5");
    u.attr("/", "updated", 1.0);
    u.commit();
    ResultsWriter w(d / "new.h5");
    w.commit();
  }
  const std::string said = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(said.find("waiting"), std::string::npos) << said;
  EXPECT_EQ(ResultsReader(d / "kept.h5").attr_double("/", "updated"), 1.0);
  EXPECT_TRUE(fs::exists(d / "new.h5"));
}

}  // namespace
}  // namespace rendulic
