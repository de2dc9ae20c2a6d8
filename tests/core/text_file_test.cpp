// read_input_text (core/text_file.hpp): a user's input file read whole, anything else refused in
// one line without being read or waited on.
// AtomicTextFile (core/text_file.hpp; docs/usage.md "Results are atomic"): the text reaches the
// final name whole or not at all. A file-size limit (RLIMIT_FSIZE, with SIGXFSZ ignored) makes
// the disk refuse bytes as a full one does, without needing a small mount; it is set in a
// child process so that this test's own output is not limited.
#include "rendulic/core/text_file.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "rendulic/core/errors.hpp"
#include "rendulic/core/results.hpp"

namespace {
namespace fs = std::filesystem;

fs::path fresh(const std::string& name) {
  const fs::path d = fs::path(RENDULIC_TEST_TMP) / "core_text_file" / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string contents(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

bool only_file_is(const fs::path& dir, const std::string& name) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().filename() != name) return false;
    ++n;
  }
  return n == 1;
}

// The law parameter and state files were read with toml++'s parse_file: a FIFO hung `rendulic
// envelope`, a folder or /dev/zero read as an empty file ("missing key 'stress'").
TEST(InputText, AFileIsReadWholeAndAnythingElseIsRefusedInOneLine) {
  const fs::path d = fresh("input");
  std::ofstream(d / "a.toml") << "K = 1.5e7\n";
  EXPECT_EQ(rendulic::read_input_text((d / "a.toml").string(), "parameter file", 1 << 20),
            "K = 1.5e7\n");
  auto refusal = [](const std::string& path, std::size_t max_bytes = 1 << 20) {
    try {
      rendulic::read_input_text(path, "parameter file", max_bytes);
    } catch (const rendulic::InputError& e) {
      return std::string(e.what());
    }
    return std::string("(read)");
  };
  EXPECT_EQ(refusal(d.string()), d.string() + ": is a folder, not a parameter file");
  EXPECT_EQ(refusal("/dev/zero"),
            "/dev/zero: not a regular file (a parameter file is a text file)");
  const fs::path fifo = d / "fifo.toml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(refusal(fifo.string()),
            fifo.string() + ": not a regular file (a parameter file is a text file)");
  EXPECT_EQ(refusal((d / "none.toml").string()),
            (d / "none.toml").string() + ": cannot read parameter file: No such file or directory");
  std::ofstream(d / "big.toml") << std::string((1 << 20) + 1, '#');
  EXPECT_EQ(refusal((d / "big.toml").string()),
            (d / "big.toml").string() + ": larger than 1 MiB, not a parameter file");
  EXPECT_EQ(refusal((d / "big.toml").string(), 2 << 20), "(read)");
}

TEST(AtomicTextFile, CommitPutsTheWholeTextUnderTheFinalName) {
  const fs::path d = fresh("commit");
  {
    rendulic::AtomicTextFile f(d / "a.txt", "the test text");
    f.stream() << "one\n" << 2 << "\n";
    EXPECT_FALSE(fs::exists(d / "a.txt")) << "nothing under the final name before commit";
    f.commit();
  }
  EXPECT_EQ(contents(d / "a.txt"), "one\n2\n");
  EXPECT_TRUE(only_file_is(d, "a.txt"));
}

TEST(AtomicTextFile, WithoutCommitTheEarlierFileStaysAndNoTemporaryIsLeft) {
  const fs::path d = fresh("abandon");
  std::ofstream(d / "a.txt") << "earlier\n";
  {
    rendulic::AtomicTextFile f(d / "a.txt", "the test text");
    f.stream() << "later\n";
    f.flush();
  }
  EXPECT_EQ(contents(d / "a.txt"), "earlier\n");
  EXPECT_TRUE(only_file_is(d, "a.txt"));
}

// `--out link.json` replaced the link by a file and left its target as it was.
TEST(AtomicTextFile, ALinkIsWrittenThroughAndKept) {
  const fs::path d = fresh("link");
  fs::create_directories(d / "real");
  std::ofstream(d / "real" / "a.txt") << "earlier\n";
  fs::create_symlink("real/a.txt", d / "link.txt");
  fs::create_symlink("real/new.txt", d / "dangling.txt");
  for (const char* name : {"link.txt", "dangling.txt"}) {
    rendulic::AtomicTextFile f(d / name, "the test text");
    f.stream() << "later\n";
    f.commit();
    EXPECT_TRUE(fs::is_symlink(d / name)) << name;
  }
  EXPECT_EQ(contents(d / "real" / "a.txt"), "later\n");
  EXPECT_EQ(contents(d / "real" / "new.txt"), "later\n");
}

// A FIFO (and a device: `--out /dev/null` as root replaced the system's /dev/null by a file)
// is written to as it is. On a FIFO the check for an HDF5 signature read it and hung. A child
// writes, killed by an alarm if it hangs; the parent reads without blocking.
TEST(AtomicTextFile, AFifoIsWrittenToAsItIsAndStaysAFifo) {
  const fs::path d = fresh("fifo");
  const fs::path fifo = d / "out.txt";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  const int reader = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(reader, 0);
  const pid_t child = fork();
  if (child == 0) {
    ::alarm(5);
    try {
      rendulic::AtomicTextFile f(fifo, "the test text");
      f.stream() << "through the fifo\n";
      f.commit();
    } catch (...) {
      _exit(1);
    }
    _exit(0);
  }
  int status = 0;
  waitpid(child, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status;
  char buf[64] = {};
  const ssize_t n = ::read(reader, buf, sizeof buf - 1);
  ::close(reader);
  EXPECT_EQ(std::string(buf, n > 0 ? static_cast<std::size_t>(n) : 0), "through the fifo\n");
  struct stat st {};
  ASSERT_EQ(::stat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  EXPECT_TRUE(only_file_is(d, "out.txt"));
}

TEST(AtomicTextFile, APlaceThatCannotBeWrittenIsRefusedAtOnceNamingIt) {
  const fs::path d = fresh("refused");
  try {
    rendulic::AtomicTextFile f(d / "no" / "such" / "a.txt", "the test text");
    FAIL() << "a missing folder was accepted";
  } catch (const rendulic::InputError& e) {
    // The folder is named (open() said "No such file or directory" of the file).
    EXPECT_EQ(std::string(e.what()), (d / "no/such/a.txt").string() +
                                         ": cannot write the test text: the folder " +
                                         (d / "no/such").string() + " does not exist");
  }
  std::ofstream(d / "plain") << "x";
  for (const fs::path& inside : {d / "plain" / "a.txt", d / "plain" / "sub" / "a.txt"}) {
    try {
      rendulic::AtomicTextFile f(inside, "the test text");
      FAIL() << "a file as its folder was accepted";
    } catch (const rendulic::InputError& e) {
      EXPECT_EQ(std::string(e.what()), (d / "plain").string() +
                                           ": is a file, not a folder (it cannot hold the test "
                                           "text " +
                                           inside.string() + ")");
    }
  }
  try {
    rendulic::AtomicTextFile f(d, "the test text");
    FAIL() << "a folder was accepted";
  } catch (const rendulic::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("is a folder"), std::string::npos) << e.what();
  }
}

// The check a run makes before any work says what make_folders would say later, and makes
// nothing: the report's pre-run check copied these words by hand.
TEST(MakeFolders, AFileInAFoldersPlaceIsRefusedAlikeBeforeAndWhenMaking) {
  const fs::path d = fresh("in_place");
  std::ofstream(d / "plain") << "x";
  for (const fs::path& dir : {d / "plain", d / "plain" / "sub" / "deeper"}) {
    std::string before, making;
    try {
      rendulic::refuse_file_in_place_of_folder(dir, "test folder");
    } catch (const rendulic::InputError& e) {
      before = e.what();
    }
    try {
      rendulic::make_folders(dir, "test folder");
    } catch (const rendulic::InputError& e) {
      making = e.what();
    }
    EXPECT_EQ(before, making);
    EXPECT_EQ(before, (d / "plain").string() + ": is a file, not a folder (" +
                          (dir == d / "plain" ? std::string("the test folder")
                                              : "it cannot hold the test folder " + dir.string()) +
                          ")");
  }
  rendulic::refuse_file_in_place_of_folder(d / "a" / "b", "test folder");
  rendulic::refuse_file_in_place_of_folder("", "test folder");
  EXPECT_FALSE(fs::exists(d / "a"));
}

// The replaced file keeps its permissions (a rename makes it the temporary's: 600 became 644);
// a new one gets 666 less the umask, as every other program's file (it got 644 whatever the
// umask said).
TEST(AtomicTextFile, ReplacingKeepsThePermissionsAndANewFileFollowsTheUmask) {
  const fs::path d = fresh("mode");
  const mode_t umask_before = ::umask(002);
  {
    rendulic::AtomicTextFile f(d / "a.txt", "the test text");
    f.stream() << "one";
    f.commit();
  }
  EXPECT_EQ(fs::status(d / "a.txt").permissions(),
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read |
                fs::perms::group_write | fs::perms::others_read);
  ::umask(umask_before);
  fs::permissions(d / "a.txt", fs::perms::owner_read | fs::perms::owner_write);
  {
    rendulic::AtomicTextFile f(d / "a.txt", "the test text");
    f.stream() << "two";
    f.commit();
  }
  EXPECT_EQ(contents(d / "a.txt"), "two");
  EXPECT_EQ(fs::status(d / "a.txt").permissions(), fs::perms::owner_read | fs::perms::owner_write);
}

// A file this user may not write is refused at once, not replaced (as root: run as nobody).
TEST(AtomicTextFile, AFileThisUserMayNotWriteIsRefusedAtOnce) {
  const fs::path d = fresh("read_only");
  { std::ofstream(d / "a.txt") << "kept"; }
  fs::permissions(d, fs::perms::all);
  fs::permissions(d / "a.txt", fs::perms::owner_read | fs::perms::others_read);
  const pid_t child = fork();
  if (child == 0) {
    if (geteuid() == 0 && setuid(65534) != 0) _exit(5);
    try {
      rendulic::AtomicTextFile f(d / "a.txt", "the test text");
      f.stream() << "replaced";
      f.commit();
    } catch (const rendulic::InputError& e) {
      _exit(std::string(e.what()) ==
                    (d / "a.txt").string() + ": cannot write the test text: Permission denied"
                ? 0
                : 3);
    }
    _exit(4);
  }
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "3: another message, 4: replaced, 5: cannot drop root";
  EXPECT_EQ(contents(d / "a.txt"), "kept");
  EXPECT_TRUE(only_file_is(d, "a.txt"));
}

TEST(AtomicTextFile, AnHdf5FileIsNeverReplacedByText) {
  // `rendulic export out/results.h5 --state a --lammps out/results.h5` replaced the run's
  // results by a LAMMPS data file, exit 0.
  const fs::path d = fresh("hdf5");
  {
    rendulic::ResultsWriter w(d / "results.h5");
    w.append("/path/time", 1.0);
    w.commit();
  }
  const std::string before = contents(d / "results.h5");
  try {
    rendulic::AtomicTextFile f(d / "results.h5", "the LAMMPS data file");
    FAIL() << "an HDF5 file was to be replaced";
  } catch (const rendulic::InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              (d / "results.h5").string() +
                  ": is an HDF5 file (a results file?), which the LAMMPS data file would replace; "
                  "give another name");
  }
  EXPECT_EQ(contents(d / "results.h5"), before);
  EXPECT_TRUE(only_file_is(d, "results.h5"));
  // Text that only begins like the signature is replaced as any text is.
  std::ofstream(d / "a.txt", std::ios::binary) << "\x89HDF";
  rendulic::AtomicTextFile f(d / "a.txt", "the test text");
  f.stream() << "text\n";
  f.commit();
  EXPECT_EQ(contents(d / "a.txt"), "text\n");
}

// The child's exit status: 0 refused with the expected message and the earlier file intact,
// 1 committed (the defect), 2 another outcome.
int write_past_a_size_limit(const fs::path& d) {
  const pid_t child = fork();
  if (child == 0) {
    signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{4096, 4096};
    setrlimit(RLIMIT_FSIZE, &limit);
    try {
      rendulic::AtomicTextFile f(d / "a.txt", "the test text");
      f.stream() << std::string(100000, 'x');
      f.commit();
      _exit(1);
    } catch (const rendulic::InputError& e) {
      const std::string what = e.what();
      _exit(what.find("a.txt: cannot write the test text: File too large") != std::string::npos
                ? 0
                : 2);
    }
    _exit(2);
  }
  int status = 0;
  waitpid(child, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 3;
}

TEST(AtomicTextFile, ADiskThatRefusesBytesLeavesTheEarlierFileWholeAndNoTemporary) {
  const fs::path d = fresh("limit");
  std::ofstream(d / "a.txt") << "earlier\n";
  EXPECT_EQ(write_past_a_size_limit(d), 0);
  EXPECT_EQ(contents(d / "a.txt"), "earlier\n");
  EXPECT_TRUE(only_file_is(d, "a.txt"));
}

}  // namespace
