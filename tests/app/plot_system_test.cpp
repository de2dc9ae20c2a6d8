// System test of `rendulic plot`: the real binary draws every figure of a
// synthetic results file as PNG and SVG; a file that is not ours is refused with exit 2.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>

#include "synthetic_results.hpp"

namespace {
namespace fs = std::filesystem;

int run(const std::string& args) {
  const int status =
      std::system((std::string(RENDULIC_EXE) + " " + args + " >/dev/null 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(Plot, DrawsEveryFigureOfASeedLikeFile) {
  const fs::path f = rendulic::app::testing::seed_like("plot", false);
  const fs::path out = f.parent_path() / "figs";
  ASSERT_EQ(run("plot " + f.string() + " --out " + out.string()), 0);
  for (const char* name :
       {"fig1_path", "fig2_strain_circle", "fig3_elastic_stress", "fig4_elastic_fabric",
        "fig5_plastic_stress", "fig6_plastic_fabric", "fig7_features"})
    for (const char* ext : {".png", ".svg"}) {
      const fs::path p = out / (std::string(name) + ext);
      EXPECT_TRUE(fs::exists(p)) << p;
      if (fs::exists(p)) {
        EXPECT_GT(fs::file_size(p), 1000u) << p;
      }
    }
}

TEST(Plot, RefusesAFileThatIsNotOurs) {
  const fs::path dir = fs::path(RENDULIC_TEST_TMP) / "app_plot_bad";
  fs::create_directories(dir);
  std::ofstream(dir / "x.h5") << "text";
  EXPECT_EQ(run("plot " + (dir / "x.h5").string()), 2);
}

}  // namespace
