// Tests of core/results.hpp (docs/results.md): HDF5 round trip of every dataset and attribute
// kind, growable series, and atomicity: a failure or a signal mid-write leaves no results.h5
// (and no temporary litter), an earlier results.h5 survives a failed run, and files that are
// not ours are refused with an InputError. Faults: damaged objects, names HDF5 cannot hold, a
// full file system (the kernel's file size limit, RLIMIT_FSIZE: a real refusal of the write,
// and one that needs no privileges), every terminating signal, stale temporary files of
// killed runs, a hard-link cycle, an unreadable file, two updates of one file at once.
#include "rendulic/core/results.hpp"

#include <H5Cpp.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <fstream>

#include "input_error.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/result_paths.hpp"

namespace rendulic {
namespace {
namespace fs = std::filesystem;
using rendulic::testing::input_error;

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::path(RENDULIC_TEST_TMP) / "core_results" / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

int count_files(const fs::path& d) {
  int n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(d)) ++n;
  return n;
}

TEST(Results, RoundTripOfEveryKind) {
  const fs::path d = fresh_dir("roundtrip");
  const fs::path f = d / "results.h5";
  Eigen::Matrix3d t;
  t << 1, 2, 3, 4, 5, 6, 7, 8, 9;  // not symmetric: catches a transposition
  Eigen::MatrixXd m(4, 3);
  m << 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12;
  {
    ResultsWriter w(f);
    w.attr("/material", "k", 1e8);
    w.attr("/material", "n_particles", std::int64_t{9261});
    w.attr("/", "scenario", std::string("[run]\nseed = 1\n"));
    w.attr("/states/s1", "center", std::vector<double>{0.5, -0.25});
    w.write("/isotropic/pressure", std::vector<double>{1.0, 2.0, 3.0});
    w.write("/states/s1/envelopes/e/strain", std::vector<Eigen::Vector2d>{{1, 2}, {3, 4}, {5, 6}});
    w.write("/path/stress", std::vector<Eigen::Matrix3d>{t, 2 * t});
    w.write("/states/s1/stress", t);
    w.write("/states/s1/positions", m);
    w.attr("/states/s1/positions", "unit", "m");  // attribute on a dataset
    for (int i = 0; i < 100; ++i) {               // more rows than one chunk
      w.append("/path/time", 0.1 * i);
      w.append("/path/pair", Eigen::Vector2d(i, -i));
      w.append("/path/fabric", Eigen::Matrix3d(t * i));
    }
    EXPECT_FALSE(fs::exists(f)) << "nothing at the final name before commit";
    w.commit();
  }
  ASSERT_TRUE(fs::exists(f));
  EXPECT_EQ(count_files(d), 1) << "no temporary left behind";

  ResultsReader r(f);
  EXPECT_EQ(r.attr_string("/", "schema"), "rendulic/2");
  EXPECT_FALSE(r.attr_string("/", "git_sha").empty());
  EXPECT_DOUBLE_EQ(r.attr_double("/material", "k"), 1e8);
  EXPECT_EQ(r.attr_int("/material", "n_particles"), 9261);
  EXPECT_EQ(r.attr_string("/", "scenario"), "[run]\nseed = 1\n");
  EXPECT_EQ(r.attr_doubles("/states/s1", "center"), (std::vector<double>{0.5, -0.25}));
  EXPECT_EQ(r.attr_string("/states/s1/positions", "unit"), "m");
  EXPECT_EQ(r.read_vector("/isotropic/pressure"), (std::vector<double>{1, 2, 3}));
  const auto pairs = r.read_pairs("/states/s1/envelopes/e/strain");
  ASSERT_EQ(pairs.size(), 3u);
  EXPECT_EQ(pairs[2], Eigen::Vector2d(5, 6));
  const auto ts = r.read_tensors("/path/stress");
  ASSERT_EQ(ts.size(), 2u);
  EXPECT_EQ(ts[1], 2 * t);
  EXPECT_EQ(r.read_tensor("/states/s1/stress"), t);
  EXPECT_EQ(r.read_matrix("/states/s1/positions"), m);
  EXPECT_EQ(r.shape("/path/fabric"), (std::vector<std::uint64_t>{100, 3, 3}));
  EXPECT_EQ(r.read_vector("/path/time").size(), 100u);
  EXPECT_DOUBLE_EQ(r.read_vector("/path/time")[99], 9.9);
  EXPECT_EQ(r.read_pairs("/path/pair")[42], Eigen::Vector2d(42, -42));
  EXPECT_EQ(r.read_tensors("/path/fabric")[7], 7 * t);
  EXPECT_TRUE(r.exists("/states/s1/envelopes/e"));
  EXPECT_FALSE(r.exists("/states/s2"));
  EXPECT_EQ(r.children("/states/s1").size(), 3u);  // envelopes, positions, stress

  const std::string summary = r.summary();
  EXPECT_NE(summary.find("stress [2,3,3]"), std::string::npos) << summary;
  EXPECT_NE(summary.find("@k = 1e+08"), std::string::npos) << summary;
  EXPECT_THROW(r.read_pairs("/path/stress"), InputError);  // wrong shape is named, not UB
  EXPECT_THROW(r.read_vector("/nothing/here"), InputError);
}

// Schema rendulic/2 (docs/results.md "Schema versions"): lists are string arrays, counters
// integers, float datasets carry their unit; a rendulic/1 file (lists joined by commas) is
// still read, and a file of an unknown schema is refused naming it.
TEST(Results, StateRootsAreTheRunsOwnAndEachPressureBranch) {
  const fs::path d = fresh_dir("roots");
  {
    ResultsWriter w(d / "plain.h5");
    w.attr(paths::state("a"), "volume_fraction", 0.82);
    w.commit();
  }
  const ResultsReader plain(d / "plain.h5");
  EXPECT_TRUE(pressure_branches(plain).empty());
  EXPECT_EQ(state_roots(plain), std::vector<std::string>{""});
  {
    ResultsWriter w(d / "branched.h5");
    w.attr(paths::state("a"), "volume_fraction", 0.82);
    w.attr(paths::state("a", paths::pressure_branch(0.7)), "volume_fraction", 0.7);
    w.attr(paths::pressure_branch(0.75), "volume_fraction", 0.75);
    w.commit();
  }
  const ResultsReader branched(d / "branched.h5");
  const std::vector<std::string> branches = {"/pressure/nu0.7", "/pressure/nu0.75"};
  EXPECT_EQ(pressure_branches(branched), branches);
  EXPECT_EQ(state_roots(branched),
            (std::vector<std::string>{"", "/pressure/nu0.7", "/pressure/nu0.75"}));
}

TEST(Results, ListsUnitsCountersAndTheFirstSchema) {
  const fs::path d = fresh_dir("schema2");
  const fs::path f = d / "results.h5";
  {
    ResultsWriter w(f);
    w.attr("/calibration/m", "param_names", std::vector<std::string>{"B", "G, with comma", ""});
    w.attr("/calibration/m", "at_bound", std::vector<std::string>{});
    w.write("/states/s/envelopes/e/contacts_opened", std::vector<double>{0, 3, 12});
    w.write("/states/s/envelopes/e/d_stress",
            std::vector<Eigen::Matrix3d>{Eigen::Matrix3d::Zero()});
    w.attr("/material", "k_star", 2.5e6);
    w.attr("/material", "w", 0.2);
    w.commit();
  }
  {
    const ResultsReader r(f);
    EXPECT_EQ(r.attr_strings("/calibration/m", "param_names"),
              (std::vector<std::string>{"B", "G, with comma", ""}));
    EXPECT_TRUE(r.attr_strings("/calibration/m", "at_bound").empty());
    EXPECT_EQ(r.read_vector("/states/s/envelopes/e/contacts_opened"),
              (std::vector<double>{0, 3, 12}));
    EXPECT_EQ(r.attr_string("/states/s/envelopes/e/d_stress", "units"), "Pa");
    EXPECT_FALSE(r.has_attr("/states/s/envelopes/e/contacts_opened", "units"));
    EXPECT_EQ(r.attr_string("/material", "k_star_units"), "Pa");
    EXPECT_FALSE(r.has_attr("/material", "w_units"));
  }
  {
    H5::H5File h(f.string(), H5F_ACC_RDONLY);
    EXPECT_EQ(h.openDataSet("/states/s/envelopes/e/contacts_opened").getTypeClass(), H5T_INTEGER);
  }
  // The same list as rendulic/1 stored it.
  {
    ResultsWriter w = ResultsWriter::update(f);
    w.attr("/", "schema", "rendulic/1");
    w.attr("/calibration/m", "param_names", "B,G");
    w.commit();
  }
  EXPECT_EQ(ResultsReader(f).attr_strings("/calibration/m", "param_names"),
            (std::vector<std::string>{"B", "G"}));
  {
    ResultsWriter w = ResultsWriter::update(f);
    w.attr("/", "schema", "rendulic/9");
    w.commit();
  }
  const std::string what = input_error([&] { ResultsReader r(f); });
  EXPECT_NE(what.find("rendulic/9"), std::string::npos) << what;
}

TEST(Results, FailureMidWriteLeavesNoResultsFile) {
  const fs::path d = fresh_dir("failure");
  try {
    ResultsWriter w(d / "results.h5");
    w.write("/isotropic/pressure", std::vector<double>(1000, 1.0));
    throw std::runtime_error("stage failed");
  } catch (const std::runtime_error&) {
  }
  EXPECT_FALSE(fs::exists(d / "results.h5"));
  EXPECT_EQ(count_files(d), 0) << "temporary removed";
}

TEST(Results, EarlierResultsSurviveAFailedRun) {
  const fs::path d = fresh_dir("survive");
  {
    ResultsWriter w(d / "results.h5");
    w.attr("/", "marker", std::string("first"));
    w.commit();
  }
  try {
    ResultsWriter w(d / "results.h5");
    w.attr("/", "marker", std::string("second"));
    throw std::runtime_error("stage failed");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(ResultsReader(d / "results.h5").attr_string("/", "marker"), "first");
}

TEST(Results, SignalMidWriteLeavesNoResultsFileNorTemporary) {
  const fs::path d = fresh_dir("signal");
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ResultsWriter w(d / "results.h5");
    for (int i = 0; i < 10; ++i) w.append("/path/time", double(i));
    std::raise(SIGTERM);  // interrupted mid-run
    _exit(0);             // not reached
  }
  int status = 0;
  waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFSIGNALED(status));
  EXPECT_FALSE(fs::exists(d / "results.h5"));
  EXPECT_EQ(count_files(d), 0);
}

TEST(Results, UpdateIsAtomicToo) {
  const fs::path d = fresh_dir("update");
  {
    ResultsWriter w(d / "results.h5");
    w.attr("/", "marker", std::string("v1"));
    w.commit();
  }
  try {
    ResultsWriter w = ResultsWriter::update(d / "results.h5");
    w.attr("/calibration/x", "converged", std::int64_t{1});
    throw std::runtime_error("calibration failed");
  } catch (const std::runtime_error&) {
  }
  EXPECT_FALSE(ResultsReader(d / "results.h5").exists("/calibration"));
  {
    ResultsWriter w = ResultsWriter::update(d / "results.h5");
    w.attr("/calibration/x", "converged", std::int64_t{1});
    w.commit();
  }
  ResultsReader r(d / "results.h5");
  EXPECT_EQ(r.attr_int("/calibration/x", "converged"), 1);
  EXPECT_EQ(r.attr_string("/", "marker"), "v1");
  EXPECT_EQ(count_files(d), 1);
}

// Two updates of one file at once (two `calibrate`s of different laws): the second waits for
// the first's rename and copies its result, instead of renaming its own copy over it. Without
// the folder's lock the parent copied the file during the child's 0.3 s and "first" was lost.
TEST(Results, UpdatesOfOneFileAtOnceEachKeepTheOthers) {
  const fs::path d = fresh_dir("concurrent_update");
  {
    ResultsWriter w(d / "results.h5");
    w.attr("/", "marker", std::string("v1"));
    w.commit();
  }
  int ready[2];
  ASSERT_EQ(pipe(ready), 0);
  const pid_t child = fork();
  if (child == 0) {
    close(ready[0]);
    int code = 0;
    try {
      ResultsWriter w = ResultsWriter::update(d / "results.h5");
      w.attr("/calibration/first", "converged", std::int64_t{1});
      if (write(ready[1], "x", 1) != 1) code = 2;  // the parent's update starts now
      usleep(300000);
      w.commit();
    } catch (...) {
      code = 1;
    }
    _exit(code);
  }
  close(ready[1]);
  char c = 0;
  ASSERT_EQ(read(ready[0], &c, 1), 1);
  close(ready[0]);
  {
    ResultsWriter w = ResultsWriter::update(d / "results.h5");
    w.attr("/calibration/second", "converged", std::int64_t{1});
    w.commit();
  }
  int status = 0;
  waitpid(child, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
  ResultsReader r(d / "results.h5");
  EXPECT_TRUE(r.exists("/calibration/first"));
  EXPECT_TRUE(r.exists("/calibration/second"));
  EXPECT_EQ(r.attr_string("/", "marker"), "v1");
  EXPECT_EQ(count_files(d), 1);
}

// One process's own writers in one folder share the lock: an update held open while another
// writer of the folder commits does not wait on itself.
TEST(Results, AProcesssOwnWritersInOneFolderDoNotWaitOnEachOther) {
  const fs::path d = fresh_dir("own_writers");
  {
    ResultsWriter w(d / "results.h5");
    w.commit();
  }
  ResultsWriter update = ResultsWriter::update(d / "results.h5");
  update.attr("/calibration/x", "converged", std::int64_t{1});
  ResultsWriter other(d / "other.h5");
  other.commit();
  ResultsWriter again = ResultsWriter::update(d / "other.h5");
  again.commit();
  update.commit();
  EXPECT_TRUE(ResultsReader(d / "results.h5").exists("/calibration/x"));
  EXPECT_EQ(count_files(d), 2);
}

TEST(Results, RefusesFilesThatAreNotOurs) {
  const fs::path d = fresh_dir("refuse");
  std::ofstream(d / "text.h5") << "hello, not hdf5\n";
  EXPECT_THROW(ResultsReader(d / "text.h5"), InputError);
  EXPECT_THROW(ResultsReader(d / "missing.h5"), InputError);
  // A valid HDF5 file without our schema attribute.
  {
    ResultsWriter w(d / "ours.h5");
    w.commit();
  }
  // Truncated copy of a real file: HDF5 signature intact, body gone.
  {
    std::ifstream in(d / "ours.h5", std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    std::ofstream(d / "truncated.h5", std::ios::binary) << bytes.substr(0, 600);
  }
  EXPECT_THROW(ResultsReader(d / "truncated.h5"), InputError);
  const std::string what = input_error([&] { ResultsReader r(d / "text.h5"); });
  EXPECT_NE(what.find("not an HDF5 file"), std::string::npos) << what;
  EXPECT_EQ(input_error([&] { ResultsReader r(d / "missing.h5"); }),
            (d / "missing.h5").string() + ": no such file");
  // A folder, a device and a FIFO (which must not block) in the words of every input file.
  fs::create_directories(d / "folder.h5");
  EXPECT_EQ(input_error([&] { ResultsReader r(d / "folder.h5"); }),
            (d / "folder.h5").string() + ": is a folder, not a results file");
  EXPECT_EQ(input_error([&] { ResultsReader r("/dev/zero"); }),
            "/dev/zero: not a regular file (a results file is an HDF5 file)");
  ASSERT_EQ(::mkfifo((d / "fifo.h5").c_str(), 0600), 0);
  EXPECT_EQ(input_error([&] { ResultsReader r(d / "fifo.h5"); }),
            (d / "fifo.h5").string() + ": not a regular file (a results file is an HDF5 file)");
  // An HDF5 file of another program, and one whose schema is a number (reported as no schema
  // at all).
  H5::H5File((d / "other.h5").string(), H5F_ACC_TRUNC).close();
  EXPECT_EQ(input_error([&] { ResultsReader r(d / "other.h5"); }),
            (d / "other.h5").string() + ": not a rendulic results file (no schema attribute)");
  {
    H5::H5File h((d / "number.h5").string(), H5F_ACC_TRUNC);
    const int two = 2;
    h.createAttribute("schema", H5::PredType::NATIVE_INT, H5::DataSpace(H5S_SCALAR))
        .write(H5::PredType::NATIVE_INT, &two);
  }
  EXPECT_EQ(input_error([&] { ResultsReader r(d / "number.h5"); }),
            (d / "number.h5").string() +
                ": not a rendulic results file (its schema attribute is not one text)");
}

// Runs `fn` in a child process (for limits and signals that must not touch the test runner);
// returns its wait status.
template <class Fn>
int in_child(Fn&& fn) {
  const pid_t pid = fork();
  if (pid == 0) {
    const rlimit no_core{0, 0};
    setrlimit(RLIMIT_CORE, &no_core);
    fn();
    _exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return status;
}

fs::path small_file(const fs::path& d) {
  ResultsWriter w(d / "results.h5");
  w.attr("/material", "k_star", 0.5);
  w.write("/path/time", std::vector<double>{1, 2, 3});
  w.write("/path/pairs", std::vector<Eigen::Vector2d>{{1, 2}, {3, 4}});
  w.create_group("/states/a");
  w.commit();
  return d / "results.h5";
}

TEST(Results, EveryHdf5FailureOfTheReaderIsOneInputErrorNamingFileAndObject) {
  // HDF5 1.10's exceptions are not std::exception: they used to abort the process.
  const fs::path d = fresh_dir("damaged");
  const fs::path f = small_file(d);
  {
    H5::H5File h(f.string(), H5F_ACC_RDWR);
    h.openGroup("/material")
        .createAttribute("rho", H5::StrType(H5::PredType::C_S1, 8), H5::DataSpace(H5S_SCALAR));
    const hsize_t two = 2;
    h.openGroup("/material")
        .createAttribute("pair", H5::PredType::NATIVE_DOUBLE, H5::DataSpace(1, &two));
    h.createDataSet("/path/text", H5::StrType(H5::PredType::C_S1, 4), H5::DataSpace(1, &two));
    H5Lcreate_soft("/nowhere", h.getId(), "/path/dangling", H5P_DEFAULT, H5P_DEFAULT);
    h.unlink("/states");
    h.createDataSet("/states", H5::PredType::NATIVE_DOUBLE, H5::DataSpace(1, &two));
  }
  const ResultsReader r(f);
  auto msg = input_error([&] { r.attr_double("/material", "rho"); });
  EXPECT_EQ(msg, f.string() + ": /material @rho: is not a number");
  msg = input_error([&] { r.attr_double("/material", "pair"); });  // used to overflow a double
  EXPECT_EQ(msg, f.string() + ": /material @pair: holds 2 values, not 1");
  msg = input_error([&] { r.attr_string("/material", "k_star"); });
  EXPECT_EQ(msg, f.string() + ": /material @k_star: is not text");
  msg = input_error([&] { r.read_vector("/path/text"); });
  EXPECT_EQ(msg, f.string() + ": /path/text: does not hold numbers");
  msg = input_error([&] { r.read_pairs("/path/time"); });
  EXPECT_EQ(msg, f.string() + ": /path/time: has an unexpected shape");
  EXPECT_FALSE(r.exists("/path/dangling"));
  msg = input_error([&] { r.read_vector("/path/dangling"); });
  EXPECT_EQ(msg, f.string() + ": /path/dangling: missing");
  msg = input_error([&] { r.children("/states"); });
  EXPECT_EQ(msg, f.string() + ": /states: is not a group");
  msg = input_error([&] { r.read_vector("/material"); });
  EXPECT_EQ(msg, f.string() + ": /material: is not a dataset");
  EXPECT_NO_THROW(r.summary());
}

// A dataset whose extent was grown over chunks never written (a damaged or unfinished file; HDF5
// reads them as fill values) declared 2^40 values: the reader asked for 8 TiB and the commands
// ended in "internal error: std::bad_alloc", exit 1. It is refused by what the file holds,
// while a compressed copy (h5repack's deflate), whose bytes are far fewer than its values, is
// read as it was written.
TEST(Results, ADatasetDeclaringMoreValuesThanItHoldsIsRefusedACompressedOneIsRead) {
  const fs::path d = fresh_dir("declared");
  const fs::path f = small_file(d);
  const hsize_t rows = 100000;
  std::vector<double> values(rows);
  for (hsize_t i = 0; i < rows; ++i) values[i] = i % 7 == 0 ? 0.25 * static_cast<double>(i) : 0.0;
  {
    H5::H5File h(f.string(), H5F_ACC_RDWR);
    auto chunked = [&](const char* name, std::vector<hsize_t> dims, int deflate) {
      std::vector<hsize_t> max(dims.size(), H5S_UNLIMITED), chunk(dims);
      chunk[0] = 64;
      H5::DSetCreatPropList plist;
      plist.setChunk(static_cast<int>(chunk.size()), chunk.data());
      if (deflate) plist.setDeflate(deflate);
      return h.createDataSet(name, H5::PredType::NATIVE_DOUBLE,
                             H5::DataSpace(static_cast<int>(dims.size()), dims.data(), max.data()),
                             plist);
    };
    chunked("/path/grown", {hsize_t{1} << 40}, 0);
    chunked("/path/grown_rows", {hsize_t{1} << 33, 3}, 0);
    // 64 values written, then the extent grown to a million.
    H5::DataSet part = chunked("/path/part", {64}, 0);
    part.write(values.data(), H5::PredType::NATIVE_DOUBLE);
    const hsize_t million = 1000000;
    part.extend(&million);
    chunked("/path/deflated", {rows}, 9).write(values.data(), H5::PredType::NATIVE_DOUBLE);
  }
  const ResultsReader r(f);
  EXPECT_EQ(input_error([&] { r.read_vector("/path/grown"); }),
            f.string() +
                ": /path/grown: declares 1099511627776 values but holds the bytes of 0 "
                "(a damaged or unfinished file)");
  EXPECT_EQ(input_error([&] { r.read_matrix("/path/grown_rows"); }),
            f.string() +
                ": /path/grown_rows: declares 25769803776 values but holds the bytes "
                "of 0 (a damaged or unfinished file)");
  EXPECT_EQ(input_error([&] { r.read_vector("/path/part"); }),
            f.string() +
                ": /path/part: declares 1000000 values but holds the bytes of 64 (a "
                "damaged or unfinished file)");
  // Deflate's ratio: most values are zeros, so the bytes are far fewer than the values'.
  const H5::DataSet deflated = H5::H5File(f.string(), H5F_ACC_RDONLY).openDataSet("/path/deflated");
  ASSERT_LT(deflated.getStorageSize(), rows * sizeof(double) / 4);
  EXPECT_EQ(r.read_vector("/path/deflated"), values);
  EXPECT_EQ(r.read_vector("/path/time"), (std::vector<double>{1, 2, 3}));
}

TEST(Results, NamesHdf5CannotHoldAreRefusedBeforeWriting) {
  // A state label "." named the group itself; a NUL cut the name short.
  const fs::path d = fresh_dir("names");
  {
    ResultsWriter w(d / "results.h5");
    for (const std::string& bad : {std::string("/states/./x"), std::string("/states/.."),
                                   std::string("/states/a\0b", 11), std::string("/a\nb")}) {
      const auto msg = input_error([&] { w.attr(bad, "eps_dev", 1.0); });
      EXPECT_NE(msg.find("the name '"), std::string::npos) << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
    EXPECT_NE(input_error([&] { w.attr("/", "d", std::string("a\0b", 3)); }).find("NUL"),
              std::string::npos);
  }
  EXPECT_EQ(count_files(d), 0);
  EXPECT_EQ(invalid_object_name_reason("a"), "");
  EXPECT_NE(invalid_object_name_reason("."), "");
  EXPECT_NE(invalid_object_name_reason(""), "");
  EXPECT_NE(invalid_object_name_reason("a/b"), "");
  EXPECT_NE(invalid_object_name_reason(std::string("\0", 1)), "");
}

TEST(Results, AWriteTheFileSystemRefusesIsOneInputErrorAndLeavesNothing) {
  // The kernel's file size limit refuses the write (EFBIG) as a full disk does (ENOSPC).
  const fs::path d = fresh_dir("full");
  const fs::path existing = small_file(d);
  {
    std::ofstream pad(existing, std::ios::app | std::ios::binary);
    pad << std::string(80 * 1024, '\0');  // larger than the limit; HDF5 ignores the tail
  }
  const int status = in_child([&] {
    std::signal(SIGXFSZ, SIG_IGN);  // the write fails instead of killing the process
    const rlimit limit{64 * 1024, 64 * 1024};
    setrlimit(RLIMIT_FSIZE, &limit);
    int failures = 0;
    try {
      ResultsWriter w(d / "big" / "results.h5");
      w.write("/path/time", std::vector<double>(100000, 1.0));
      w.commit();
    } catch (const InputError& e) {
      const std::string m = e.what();
      failures +=
          m.find("big/results.h5: cannot write /path/time: File too large") != std::string::npos;
    }
    // `calibrate` on a full disk: the copy fails; the destructor used to dereference the
    // file it never opened (a segfault).
    try {
      ResultsWriter w = ResultsWriter::update(existing);
    } catch (const InputError& e) {
      failures += std::string(e.what()).find("cannot copy for update") != std::string::npos;
    }
    _exit(failures == 2 ? 0 : 3);
  });
  ASSERT_TRUE(WIFEXITED(status)) << "died by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 0) << "an expected InputError is missing";
  EXPECT_FALSE(fs::exists(d / "big")) << "the folder it created is removed again";
  EXPECT_EQ(count_files(d), 1) << "only the original results.h5";
}

TEST(Results, EverySignalRemovesTheTemporaryAndKeepsTheSavedStages) {
  const fs::path d = fresh_dir("signals");
  // -1: std::terminate (an exception nobody catches), which ends in SIGABRT.
  for (const int sig : {SIGHUP, SIGINT, SIGQUIT, SIGTERM, SIGUSR1, SIGUSR2, SIGALRM, SIGPIPE,
                        SIGXCPU, SIGXFSZ, SIGABRT, -1}) {
    const int status = in_child([&] {
      ResultsWriter w(d / "results.h5");
      for (int i = 0; i < 10; ++i) w.append("/path/time", double(i));
      if (!w.save_partial("completed stages (path)")) _exit(3);
      for (int i = 0; i < 10; ++i) w.append("/path/time", double(i));
      if (sig < 0) std::terminate();
      std::raise(sig);
      _exit(4);  // not reached
    });
    ASSERT_TRUE(WIFSIGNALED(status)) << sig;
    EXPECT_EQ(WTERMSIG(status), sig < 0 ? SIGABRT : sig) << "the exit status tells the signal";
    ASSERT_TRUE(fs::exists(d / "results.h5.partial")) << sig;
    EXPECT_EQ(ResultsReader(d / "results.h5.partial").read_vector("/path/time").size(), 10u)
        << "the copy as saved, not what followed";
    EXPECT_EQ(count_files(d), 1) << sig << ": no temporary left";
    fs::remove(d / "results.h5.partial");
  }
  // Without a saved copy nothing at all is left.
  const int status = in_child([&] {
    ResultsWriter w(d / "results.h5");
    w.append("/path/time", 1.0);
    std::raise(SIGHUP);
  });
  EXPECT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(count_files(d), 0);
}

TEST(Results, AFailureKeepsTheSavedCopyAsPartialOnlyWhenAsked) {
  const fs::path d = fresh_dir("partial");
  std::string note;
  {
    ResultsWriter w(d / "results.h5");
    w.append("/path/time", 1.0);
    ASSERT_TRUE(w.save_partial("completed stages (prepare)"));
    w.append("/path/time", 2.0);
    ASSERT_TRUE(w.save_partial("completed stages (prepare, path)"));
    w.append("/path/time", 3.0);
    note = w.keep_partial();
  }
  EXPECT_EQ(note,
            "; completed stages (prepare, path) kept in " + (d / "results.h5.partial").string());
  EXPECT_EQ(ResultsReader(d / "results.h5.partial").read_vector("/path/time").size(), 2u);
  EXPECT_FALSE(fs::exists(d / "results.h5")) << "never over the final name";
  {
    ResultsWriter w(d / "other.h5");
    ASSERT_TRUE(w.save_partial("completed stages (prepare)"));
    w.commit();  // a whole file supersedes the saved copy
  }
  EXPECT_FALSE(fs::exists(d / "other.h5.partial"));
  EXPECT_EQ(count_files(d), 2);  // results.h5.partial, other.h5
}

TEST(Results, StaleTemporariesOfKilledRunsAreTidiedByTheNextWriter) {
  const fs::path d = fresh_dir("stale");
  const pid_t dead = fork();
  if (dead == 0) _exit(0);
  waitpid(dead, nullptr, 0);  // its pid now names no process
  const std::string tag = std::to_string(dead);
  std::ofstream(d / (".results.h5.tmp-" + tag)) << "half a file";
  {
    ResultsWriter w(d / ("stages.h5"));
    w.append("/path/time", 1.0);
    w.commit();
  }
  fs::rename(d / "stages.h5", d / (".results.h5.tmp-" + tag + ".partial"));
  std::ofstream(d / ".results.h5.tmp-1") << "pid 1 lives";
  // Held open and locked, as HDF5 does for a file it writes: a run we cannot see (another
  // PID namespace) is left alone even though its pid looks dead here.
  const pid_t dead2 = fork();
  if (dead2 == 0) _exit(0);
  waitpid(dead2, nullptr, 0);
  const fs::path locked = d / (".results.h5.tmp-" + std::to_string(dead2));
  std::ofstream(locked) << "locked";
  const int fd = ::open(locked.c_str(), O_RDONLY);
  ASSERT_EQ(flock(fd, LOCK_EX), 0);
  {
    ResultsWriter w(d / "results.h5");
    ASSERT_EQ(w.notes().size(), 2u);
    EXPECT_NE(w.notes()[0].find("process " + tag), std::string::npos) << w.notes()[0];
  }
  ::close(fd);
  EXPECT_FALSE(fs::exists(d / (".results.h5.tmp-" + tag)));
  EXPECT_TRUE(fs::exists(d / ".results.h5.tmp-1"));
  EXPECT_TRUE(fs::exists(locked));
  EXPECT_EQ(ResultsReader(d / "results.h5.partial").read_vector("/path/time").size(), 1u);
}

// A child process writes results.h5 and holds it (as a run does from its first stage to its
// commit) while the parent tries to write it too. With `hdf5_locking` false the child drops
// HDF5's flock on its temporary, as HDF5_USE_FILE_LOCKING=FALSE leaves it (HDF5 reads that
// variable once, when the library starts, so setting it in a forked child does nothing).
void expect_refused_beside_a_writing_child(const fs::path& d, bool hdf5_locking) {
  int ready[2], go[2];
  ASSERT_EQ(::pipe(ready), 0);
  ASSERT_EQ(::pipe(go), 0);
  const pid_t child = fork();
  if (child == 0) {
    int code = 1;
    try {
      ResultsWriter w(d / "results.h5");
      w.append("/path/time", 1.0);
      if (!hdf5_locking) {
        struct stat tmp {};
        ::stat((d / (".results.h5.tmp-" + std::to_string(::getpid()))).c_str(), &tmp);
        for (const auto& e : fs::directory_iterator("/proc/self/fd")) {
          struct stat open {};
          if (::stat(e.path().c_str(), &open) == 0 && open.st_ino == tmp.st_ino &&
              open.st_dev == tmp.st_dev)
            ::flock(std::stoi(e.path().filename().string()), LOCK_UN);
        }
      }
      char c = 'r';
      if (::write(ready[1], &c, 1) == 1 && ::read(go[0], &c, 1) >= 0) {
        w.commit();
        code = 0;
      }
    } catch (...) {
    }
    _exit(code);
  }
  char c = 0;
  ASSERT_EQ(::read(ready[0], &c, 1), 1);
  const fs::path temporary = d / (".results.h5.tmp-" + std::to_string(child));
  const int fd = ::open(temporary.c_str(), O_RDONLY);
  EXPECT_EQ(flock(fd, LOCK_SH | LOCK_NB) == 0, !hdf5_locking) << "HDF5's flock not as assumed";
  ::close(fd);
  const std::string who = "(pid " + std::to_string(child) + ")";
  const std::string refused =
      rendulic::testing::input_error([&] { ResultsWriter w(d / "results.h5"); });
  EXPECT_EQ(refused, (d / "results.h5").string() + ": another rendulic process " + who +
                         " is writing this file now; let it finish, or write elsewhere (--out)");
  EXPECT_NE(
      rendulic::testing::input_error([&] { ResultsWriter::resume(d / "results.h5"); }).find(who),
      std::string::npos);
  // Another file of the folder is not that writer's.
  {
    ResultsWriter other(d / "other.h5");
    other.commit();
  }
  ASSERT_EQ(::write(go[1], &c, 1), 1);
  int status = 0;
  waitpid(child, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  EXPECT_EQ(ResultsReader(d / "results.h5").read_vector("/path/time").size(), 1u);
  // Once it is done, the next writer goes ahead.
  ResultsWriter next(d / "results.h5");
  next.commit();
  for (int f : {ready[0], ready[1], go[0], go[1]}) ::close(f);
}

TEST(Results, ASecondNewWriterOfAFileAnotherProcessIsWritingIsRefused) {
  // Two runs into one --out each finished before: the later file replaced the earlier one and
  // their reports and figures mixed in one folder.
  expect_refused_beside_a_writing_child(fresh_dir("two_writers"), true);
  // Under HDF5_USE_FILE_LOCKING=FALSE (set on many clusters) the writer's temporary has no
  // flock, and both runs went ahead again.
  expect_refused_beside_a_writing_child(fresh_dir("two_writers_unlocked"), false);
}

TEST(Results, ASecondWriterOfAFileThisProcessIsWritingIsRefusedAndTheFirstCompletes) {
  // Two Python threads given one output: the writers share the temporary's name (one pid), so
  // the second failed on HDF5's "unable to truncate a file which is already open", and its
  // tidying removed the first's temporary, which then failed too ("no such file").
  const fs::path d = fresh_dir("two_threads");
  {
    ResultsWriter earlier(d / "results.h5");
    earlier.append("/path/time", 0.5);
    earlier.commit();
  }
  ResultsWriter first(d / "results.h5");
  first.append("/path/time", 1.0);
  const std::string refused = (d / "results.h5").string() +
                              ": another writer in this process (another thread) is writing "
                              "this file now; give each its own output";
  EXPECT_EQ(rendulic::testing::input_error([&] { ResultsWriter w(d / "results.h5"); }), refused);
  // The same file by another spelling of its path.
  const fs::path alias = d / "." / "results.h5";
  EXPECT_EQ(rendulic::testing::input_error([&] { ResultsWriter w(alias); }),
            alias.string() + refused.substr((d / "results.h5").string().size()));
  EXPECT_NE(rendulic::testing::input_error([&] {
              ResultsWriter::resume(d / "results.h5");
            }).find("another writer in this process"),
            std::string::npos);
  EXPECT_NE(rendulic::testing::input_error([&] {
              ResultsWriter::update(d / "results.h5");
            }).find("another writer in this process"),
            std::string::npos);
  first.append("/path/time", 2.0);
  first.commit();
  EXPECT_EQ(ResultsReader(d / "results.h5").read_vector("/path/time"),
            (std::vector<double>{1.0, 2.0}));
  for (const auto& e : fs::directory_iterator(d))
    EXPECT_EQ(e.path().filename(), "results.h5") << "left behind: " << e.path();
  // Once the first is gone, the file is free again.
  {
    ResultsWriter next = ResultsWriter::update(d / "results.h5");
    next.commit();
  }
  ResultsWriter again(d / "results.h5");
  again.commit();
}

// `fit --results link.h5` and `calibrate --results link.h5` renamed the updated copy onto the
// link: the link became a file and the file it pointed to never got the fits.
TEST(Results, AWriterOfALinkWritesItsTargetAndKeepsTheLink) {
  const fs::path d = fresh_dir("link");
  fs::create_directories(d / "real");
  {
    ResultsWriter w(d / "real" / "results.h5");
    w.append("/path/time", 1.0);
    w.commit();
  }
  fs::create_symlink("real/results.h5", d / "link.h5");
  {
    ResultsWriter u = ResultsWriter::update(d / "link.h5");
    u.append("/path/time", 2.0);
    u.commit();
  }
  EXPECT_TRUE(fs::is_symlink(d / "link.h5"));
  EXPECT_EQ(ResultsReader(d / "real" / "results.h5").read_vector("/path/time"),
            (std::vector<double>{1.0, 2.0}));
  {
    ResultsWriter w(d / "link.h5");  // a new file, through the link
    w.append("/path/time", 3.0);
    w.commit();
  }
  EXPECT_TRUE(fs::is_symlink(d / "link.h5"));
  EXPECT_EQ(ResultsReader(d / "real" / "results.h5").read_vector("/path/time"),
            (std::vector<double>{3.0}));
  EXPECT_EQ(count_files(d), 2);  // the link and the folder: no temporary left
}

TEST(Results, AFileAnotherProgramHoldsForWritingIsSaidSoNotCalledCorrupt) {
  // h5py's "r+" in a notebook, or a run's temporary file: HDF5 keeps an exclusive flock on a
  // file it writes, and the reader's open failed as "cannot open (corrupt HDF5 file?)".
  const fs::path d = fresh_dir("held");
  const fs::path f = small_file(d);
  const int fd = ::open(f.c_str(), O_RDONLY);
  ASSERT_EQ(flock(fd, LOCK_EX), 0);
  EXPECT_EQ(rendulic::testing::input_error([&] { ResultsReader r(f); }),
            f.string() +
                ": another program has it open for writing (HDF5's file lock); close "
                "it there, or wait for it to finish");
  ::close(fd);
  EXPECT_NO_THROW(ResultsReader r(f));
}

TEST(Results, SummaryOfAHardLinkCycleEnds) {
  const fs::path d = fresh_dir("cycle");
  const fs::path f = small_file(d);
  {
    H5::H5File h(f.string(), H5F_ACC_RDWR);
    ASSERT_GE(
        H5Lcreate_hard(h.getId(), "/states", h.getId(), "/states/a/loop", H5P_DEFAULT, H5P_DEFAULT),
        0);
  }
  const std::string s = ResultsReader(f).summary();
  EXPECT_NE(s.find("loop/ -> same group as /states"), std::string::npos) << s;
}

TEST(Results, AnUnreadableFileIsSaidToBeUnreadable) {
  const fs::path d = fresh_dir("unreadable");
  const fs::path f = small_file(d);
  fs::permissions(f, fs::perms::none);
  fs::permissions(d, fs::perms::owner_all | fs::perms::others_exec | fs::perms::group_exec);
  const int status = in_child([&] {
    if (geteuid() == 0 && setuid(65534) != 0) _exit(5);  // root reads anything: be nobody
    try {
      ResultsReader r(f);
    } catch (const InputError& e) {
      _exit(std::string(e.what()) == f.string() + ": cannot read: Permission denied" ? 0 : 3);
    }
    _exit(4);
  });
  fs::permissions(f, fs::perms::owner_read | fs::perms::owner_write);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "3: another message, 4: no error, 5: cannot drop root";
}

// A rename onto a file makes it the temporary's: `fit --results` turned a results file of mode
// 600 into one of 644, readable by all (docs/usage.md "Results are atomic").
TEST(Results, AnUpdateKeepsTheFilesPermissions) {
  const fs::path d = fresh_dir("mode");
  const fs::path f = small_file(d);
  for (const fs::perms mode : {fs::perms::owner_read | fs::perms::owner_write,
                               fs::perms::owner_read | fs::perms::owner_write |
                                   fs::perms::group_read | fs::perms::group_write}) {
    fs::permissions(f, mode);
    ResultsWriter u = ResultsWriter::update(f);
    u.attr("/", "note", std::string("updated"));
    u.commit();
    EXPECT_EQ(fs::status(f).permissions(), mode);
    fs::permissions(f, mode);
    ResultsWriter w(f);  // a new file over it
    w.attr("/", "note", std::string("new"));
    w.commit();
    EXPECT_EQ(fs::status(f).permissions(), mode);
  }
}

// A file this user may not write (chmod a-w, or another user's) is refused before any work:
// the rename onto it needed only the folder's permission, and it was replaced without a word.
// Root writes any file, so the check runs as nobody.
TEST(Results, AFileThisUserMayNotWriteIsRefusedAndStaysAsItWas) {
  const fs::path d = fresh_dir("read_only");
  const fs::path f = small_file(d);
  fs::permissions(d, fs::perms::all);
  fs::permissions(f, fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  const std::string before = [&] {
    std::ifstream in(f, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  const std::string expected = f.string() + ": cannot write the results file: Permission denied";
  const int status = in_child([&] {
    if (geteuid() == 0 && setuid(65534) != 0) _exit(5);
    int refused = 0;
    for (int kind = 0; kind < 3; ++kind) {
      try {
        if (kind == 0) ResultsWriter::update(f);
        if (kind == 1) ResultsWriter w(f);
        if (kind == 2) ResultsWriter::resume(f);
      } catch (const InputError& e) {
        refused += std::string(e.what()) == expected;
      }
    }
    _exit(refused == 3 ? 0 : 3);
  });
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "3: not refused or another message, 5: cannot drop root";
  std::ifstream in(f, std::ios::binary);
  EXPECT_TRUE(std::string(std::istreambuf_iterator<char>(in), {}) == before);
  EXPECT_EQ(count_files(d), 1);
}

}  // namespace
}  // namespace rendulic
