// The calibration's path block on the paths other than the undrained one (docs/dem.md "Paths",
// docs/calibration.md): a drained-like path stored with its strain tensors is loaded with that
// strain, the law is driven by its increments, and the law that made the data fits them to
// round-off; read as if it were undrained (the strain of its eps_dev alone) it would not. An
// undrained file keeps the undrained strain of its eps_dev. A row that is not finite, in any
// series, is refused.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "rendulic/calibration/calibrate.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/results.hpp"
#include "synthetic.hpp"
#include "synthetic_file.hpp"

namespace rendulic::calibration {
namespace {

namespace fs = std::filesystem;
constexpr double kKStar = 5e10;

fs::path path_file(const std::string& name, const std::string& type, const models::PathSeries& ps,
                   const CalibrationData& d) {
  const fs::path dir = fs::temp_directory_path() / "rendulic_path_block";
  fs::create_directories(dir);
  const fs::path file = dir / (name + ".h5");
  fs::remove(file);
  ResultsWriter w(file);
  testing::write_results(w, d, kKStar);
  w.create_group("/path");
  w.attr("/path", "type", type);
  w.write("/path/eps_dev", ps.eps_dev);
  w.write("/path/strain", ps.strain);
  w.write("/path/stress", ps.stress);
  w.write("/path/fabric", ps.fabric);
  w.write("/path/volume_fraction", ps.volume_fraction);
  w.commit();
  return file;
}

// Synthetic envelopes of an isotropic elastic law and its path in `steps` steps to `end`:
// axial compression with lateral expansion, not isochoric, so not an undrained strain.
struct DrainedData {
  std::unique_ptr<models::Law> law =
      testing::law_with("isotropic_elastic", {{"K", 2.0e10}, {"G", 3e9}, {"c_F", 4.0}});
  CalibrationData d = testing::synthetic_data(*law, testing::SyntheticSpec{});
  Eigen::Matrix3d end = Eigen::Vector3d(0.01, -0.002, -0.002).asDiagonal();
  models::PathSeries ps;
  explicit DrainedData(int steps) {
    const StateData& s0 = d.states.front();
    models::PathOptions po;
    po.steps = steps;
    po.step.tolerance = 1e-12;
    ps = models::strain_path(*law, law->make_state(s0.stress, s0.fabric, s0.volume_fraction), end,
                             po);
  }
};

TEST(PathBlock, ADrainedPathIsFittedAlongItsOwnStrain) {
  const DrainedData dd(12);
  const CalibrationData& d = dd.d;
  const models::PathSeries& ps = dd.ps;
  const Eigen::Matrix3d& end = dd.end;
  ASSERT_TRUE(ps.success) << ps.reason;

  const CalibrationData drained =
      load_calibration_data(path_file("drained", "drained_compression", ps, d));
  ASSERT_EQ(drained.path.strain.size(), drained.path.eps_dev.size());
  ASSERT_GE(drained.path.eps_dev.size(), 10u);
  Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
  for (std::size_t k = 1; k < drained.path.eps_dev.size(); ++k) sum += drained.path.increment(k);
  EXPECT_LT((sum - end).norm(), 1e-15);

  CalibrationOptions o;
  o.model = "isotropic_elastic";
  o.holdout = {};
  const CalibrationSummary fit = calibrate(drained, o);
  ASSERT_GE(fit.path_misfit, 0.0);
  EXPECT_LT(fit.path_misfit, 1e-6);

  // The same file read as undrained: the path's strain would be taken from eps_dev alone,
  // and the law that made the data no longer follows it.
  const CalibrationData as_undrained =
      load_calibration_data(path_file("as_undrained", "undrained_compression", ps, d));
  EXPECT_TRUE(as_undrained.path.strain.empty());
  const CalibrationSummary wrong = calibrate(as_undrained, o);
  EXPECT_GT(wrong.path_misfit, 100 * std::max(fit.path_misfit, 1e-9));
}

// Every row of the path's series is checked, not only the rows sampled for the fit: a NaN in
// eps_dev stopped the sampling at its row and silently dropped the rest of the path (rc 0).
// Each is one line naming the dataset and the row.
TEST(PathBlock, ARowThatIsNotFiniteIsRefusedNamingItsDataset) {
  const DrainedData dd(40);
  const CalibrationData& d = dd.d;
  const models::PathSeries& ps = dd.ps;
  ASSERT_TRUE(ps.success) << ps.reason;
  ASSERT_GT(ps.eps_dev.size(), 30u);
  LoadOptions few;
  few.max_path_samples = 4;  // rows 7 and 23 are not among the sampled ones
  const double nan = std::nan("");
  for (const std::string dataset : {"eps_dev", "strain", "stress", "fabric"})
    for (const std::size_t row : {std::size_t{7}, std::size_t{23}}) {
      SCOPED_TRACE(dataset + " row " + std::to_string(row));
      models::PathSeries bad = ps;
      if (dataset == "eps_dev") bad.eps_dev[row] = nan;
      if (dataset == "strain") bad.strain[row](1, 1) = nan;
      if (dataset == "stress") bad.stress[row](0, 2) = nan;
      if (dataset == "fabric") bad.fabric[row](2, 2) = nan;
      const fs::path file = path_file("nan", "drained_compression", bad, d);
      try {
        load_calibration_data(file, few);
        ADD_FAILURE() << "loaded";
      } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()), file.string() + ": /path/" + dataset + " row " +
                                             std::to_string(row) + " is not finite");
      }
    }
  EXPECT_NO_THROW(load_calibration_data(path_file("fine", "drained_compression", ps, d), few));
}

}  // namespace
}  // namespace rendulic::calibration
