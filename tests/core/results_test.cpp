// Tests of core/results.hpp (issue 2, item 5): HDF5 round trip of every dataset and attribute
// kind, growable series, and atomicity: a failure or a signal mid-write leaves no results.h5
// (and no temporary litter), an earlier results.h5 survives a failed run, and files that are
// not ours are refused with an InputError.
#include "rendulic/core/results.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <fstream>

#include "rendulic/core/errors.hpp"

namespace rendulic {
namespace {
namespace fs = std::filesystem;

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
  EXPECT_EQ(r.attr_string("/", "schema"), "rendulic/1");
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
  try {
    ResultsReader r(d / "text.h5");
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not an HDF5 file"), std::string::npos);
  }
}

}  // namespace
}  // namespace rendulic
