// System tests of the figures (docs/figures.md): the real binary draws every figure of a
// synthetic results file; the figure script, imported by Python, draws every figure of a tiny
// run's results file and the figure objects are checked (equal-aspect Rendulic planes in
// square frames, fits and special directions in the legends, Fig. 7's error bars, PNG at
// 300 dpi, PDF and SVG); a crowded sweep file gives a Pareto chart whose labels do not
// overlap; `rendulic plot` runs the script given by --script, RENDULIC_PLOT_SCRIPT, or the one
// installed beside the binary, with /usr/bin/python3 where PATH's python3 lacks the modules;
// a file that is not ours is refused with exit 2.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <string>

#include "cli_runner.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/core/results.hpp"
#include "synthetic_results.hpp"
#include "tiny_run.hpp"

namespace {
namespace fs = std::filesystem;
using rendulic::testing::CliResult;

const fs::path kRoot = fs::path(RENDULIC_TEST_TMP) / "app_plot_system";
const fs::path kScript = fs::path(RENDULIC_SOURCE_DIR) / "app" / "plot.py";

int run(const std::string& args) {
  const int status =
      std::system((std::string(RENDULIC_EXE) + " " + args + " >/dev/null 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// The interpreter with Debian's matplotlib and h5py (PATH's python3 may be another build).
std::string python() {
  for (const char* p : {"python3", "/usr/bin/python3"})
    if (rendulic::testing::run_command(std::string(p) + " -c 'import h5py, matplotlib'").code == 0)
      return p;
  return "";
}

fs::path write_file(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
  return p;
}

// The tiny run with the linear response too, so the elastic figures hold all three kinds of
// point (dynamic probes, their fits, the exact linear response).
fs::path tiny_results() {
  return rendulic::testing::tiny_results(
      "--set run.stages=prepare,isotropic,path,states,probes,linear_response,fits,"
      "calibration");
}

// Imports plot.py (argv[1]), draws every figure of argv[2] into argv[3] keeping the figure
// objects, and prints one line per failed check ("FAIL ...") and "checked N" at the end.
const char* const kFigureChecks = R"PY(
import importlib.util, os, sys
from matplotlib.container import ErrorbarContainer
spec = importlib.util.spec_from_file_location("plot", sys.argv[1])
plot = importlib.util.module_from_spec(spec)
spec.loader.exec_module(plot)
written, notes, figs = plot.draw_all(sys.argv[2], sys.argv[3], keep=True)
checked = 0
def check(ok, what):
    global checked
    checked += 1
    if not ok:
        print("FAIL", what)
planes = ["fig2_strain_circle", "fig3_elastic_stress", "fig4_elastic_fabric",
          "fig5_plastic_stress", "fig6_plastic_fabric", "models_elastic_stress",
          "models_plastic_stress", "models_elastic_fabric", "models_plastic_fabric"]
others = ["isotropic_branch", "fig1_path", "fig7_features", "models_path"]
for name in planes + others:
    check(name in figs, f"{name} not drawn; notes: {notes}")
    for ext in ("png", "pdf", "svg"):
        p = os.path.join(sys.argv[3], f"{name}.{ext}")
        check(os.path.exists(p) and os.path.getsize(p) > 1000, f"{p} missing or empty")
    p = os.path.join(sys.argv[3], f"{name}.png")
    if os.path.exists(p):  # pHYs: pixels per metre, 300 dpi = 11811
        data = open(p, "rb").read()
        i = data.find(b"pHYs")
        ppm = int.from_bytes(data[i + 4:i + 8], "big") if i > 0 else 0
        check(abs(ppm - 11811) <= 1, f"{p}: {ppm} px/m, not 300 dpi")
def legend_texts(fig):
    out = []
    for lg in list(fig.legends) + [a.get_legend() for a in fig.axes]:
        if lg is not None:
            out += [t.get_text() for t in lg.get_texts()]
    return out
for name in planes:
    fig = figs.get(name)
    if fig is None:
        continue
    fig.canvas.draw()
    axes = [a for a in fig.axes if (a.get_gid() or "").startswith(plot.RENDULIC_GID)]
    check(len(axes) == (1 if name.startswith("fig2") else 2), f"{name}: {len(axes)} planes")
    for a in axes:
        asp = a.get_aspect()
        check(asp == "equal" or asp == 1.0, f"{name} {a.get_gid()}: aspect {asp}")
        x0, x1 = a.get_xlim()
        y0, y1 = a.get_ylim()
        check(abs((x1 - x0) - (y1 - y0)) <= 1e-9 * abs(x1 - x0), f"{name}: limits not square")
        box = a.get_position()  # after the draw: the box the aspect left
        w, h = box.width * fig.get_figwidth(), box.height * fig.get_figheight()
        check(abs(w - h) <= 1e-6 * w, f"{name} {a.get_gid()}: frame {w} x {h} in")
    texts = legend_texts(fig)
    if name.startswith("fig") and not name.startswith("fig2"):
        check(any(" fit: " in t for t in texts), f"{name}: no fit in the legend {texts}")
        check(any("I.C." in t for t in texts), f"{name}: no special direction in {texts}")
        check(any(t.startswith("dynamic") for t in texts), f"{name}: no dynamic in {texts}")
    if name.startswith("fig3") or name.startswith("fig4"):
        check(any(t.startswith("linear_response") for t in texts), f"{name}: {texts}")
    if name.startswith("models"):
        check(any(t.startswith("DEM fit: ") for t in texts), f"{name}: {texts}")
        check(any(t.startswith("isotropic_elastic") for t in texts), f"{name}: {texts}")
    if name in ("fig4_elastic_fabric", "fig6_plastic_fabric"):
        print("SHAPES", name, " ".join(sorted(t.split(": ")[1] for t in texts if " fit: " in t)))
fig = figs.get("fig7_features")
if fig is not None:
    for a in fig.axes:
        bars = [c for c in a.containers if isinstance(c, ErrorbarContainer)]
        check(len(bars) >= 1, f"fig7 {a.get_title()}: no error bars")
        seg = [s for c in bars for coll in c.lines[2] for s in coll.get_segments()]
        check(any(abs(s[1][1] - s[0][1]) > 0 for s in seg),
              f"fig7 {a.get_title()}: every error bar of zero length")
fig = figs.get("fig1_path")
if fig is not None:
    for a in fig.axes:
        check(a.get_ylabel() != "", "fig1: an axis without a y label")
        labels = {t.get_text() for t in a.texts}
        check({"a", "b"} <= labels, f"fig1: states not labelled ({labels})")
print("checked", checked)
)PY";

TEST(Plot, EveryFigureOfATinyRunHasEqualAxesLegendsAndErrorBars) {
  const std::string py = python();
  if (py.empty()) GTEST_SKIP() << "no python3 with matplotlib and h5py";
  const fs::path f = tiny_results();
  ASSERT_TRUE(fs::exists(f));
  const fs::path out = kRoot / "figs_checked";
  fs::remove_all(out);
  const fs::path checks = write_file(kRoot / "checks.py", kFigureChecks);
  const CliResult r = rendulic::testing::run_command(
      py + " " + checks.string() + " " + kScript.string() + " " + f.string() + " " + out.string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.find("FAIL"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("checked "), std::string::npos) << r.out;
  // The fabric envelopes' shape is chosen by the test of docs/fitting.md (not imposed), and
  // the legends name the shapes the file stores.
  const rendulic::ResultsReader rd(f);
  std::set<std::string> stored;
  for (const auto& label : rd.children(rendulic::paths::kStates)) {
    const std::string eg = rendulic::paths::envelopes(rendulic::paths::state(label));
    for (const auto& name : rd.children(eg)) {
      const std::string g = rendulic::paths::envelope(rendulic::paths::state(label), name) +
                            rendulic::paths::kFitFabric;
      if (!rd.has_attr(g, "selection")) continue;
      EXPECT_EQ(rd.attr_string(g, "selection").rfind("auto: ", 0), 0u) << g;
      stored.insert(rd.attr_string(g, "shape"));
    }
  }
  EXPECT_FALSE(stored.empty());
  for (const std::string& shape : stored)
    EXPECT_NE(r.out.find(" " + shape), std::string::npos) << shape << "\n" << r.out;
}

// A crowded sweep file (clusters of points at nearly the same CPU time and error, as real
// sweeps give) and long findings: no two value labels overlap, every label is inside its
// axes, and every finding is printed in full.
const char* const kParetoChecks = R"PY(
import importlib.util, sys, h5py, numpy as np
spec = importlib.util.spec_from_file_location("plot", sys.argv[1])
plot = importlib.util.module_from_spec(spec)
spec.loader.exec_module(plot)
path, out = sys.argv[2], sys.argv[3]
rng = np.random.default_rng(1)
breaks = ["dt_factor = 0.3 (dynamic): refused: beyond stability (dem.dt_factor = 0.3 gives "
          "dt = 6.8e-08 s, beyond the explicit stability limit 4.2e-08 s (= 0.18 t_c); "
          "choose at most 0.18) " + "x" * 80, "relax: noise floor error 0.0013 reached"]
with h5py.File(path, "w") as f:
    f.attrs["schema"] = "rendulic/1"
    g = f.create_group("sweep")
    g.attrs["target"] = 0.02
    g.attrs["plastic_amplitude"] = 0.002
    g.attrs["breaks"] = "\n".join(breaks) + "\n"
    k = 0
    for envelope in ("elastic", "plastic"):
        for factor, vals in (("inertial_number", [1e-5, 3e-5, 1e-4, 3e-4, 1e-3]),
                             ("dt_factor", [0.05, 0.1, 0.15, 0.18]),
                             ("relax", [1e-8, 1e-9, 1e-10]),
                             ("method", ["dynamic", "minimisation", "linear_response"])):
            for v in vals:
                p = g.create_group(f"points/p{k:03d}")
                k += 1
                p.attrs["factor"] = factor
                p.attrs["envelope"] = envelope
                p.attrs["method"] = v if factor == "method" else "dynamic"
                p.attrs["value"] = 0.0 if factor == "method" else float(v)
                p.attrs["cpu_s"] = 3.0 * (1 + 0.02 * rng.standard_normal())
                p.attrs["error"] = 0.04 * (1 + 0.05 * rng.standard_normal())
                p.attrs["meets_target"] = 0
                p.attrs["pareto"] = 0
                p.attrs["status"] = "ok"
    p = g.create_group("points/p999")
    for key, val in (("factor", "dt_factor"), ("envelope", "elastic"), ("method", "dynamic"),
                     ("value", 0.3), ("cpu_s", 0.0), ("error", 0.0), ("meets_target", 0),
                     ("pareto", 0), ("status", "refused")):
        p.attrs[key] = val
written, notes, figs = plot.draw_all(path, out, keep=True)
fig = figs["pareto"]
fig.canvas.draw()
r = fig.canvas.get_renderer()
bad = 0
for a in fig.axes:
    boxes = [t.get_window_extent(r) for t in a.texts if t.get_gid() == plot.LABEL_GID]
    frame = a.get_window_extent(r)
    for i, b in enumerate(boxes):
        if not (b.x0 >= frame.x0 - 0.5 and b.x1 <= frame.x1 + 0.5 and
                b.y0 >= frame.y0 - 0.5 and b.y1 <= frame.y1 + 0.5):
            print("FAIL label outside its axes"); bad += 1
        for c in boxes[i + 1:]:
            if plot.overlap(b, c) > 0:
                print("FAIL labels overlap", b, c); bad += 1
    print("labels", len(boxes))
text = " ".join(t.get_text().replace("\n    ", " ").replace("\n", " ") for t in fig.texts)
for b in breaks:
    if b not in text:
        print("FAIL finding cut:", b[:40])
if "dt_factor = 0.3: refused" not in text:
    print("FAIL the refused setting is not listed")
for ext in ("png", "pdf", "svg"):
    if not any(w.endswith("pareto." + ext) for w in written):
        print("FAIL no pareto." + ext)
# List attributes in both stored forms: one joined string, or an HDF5 string array.
with h5py.File(path, "a") as f:
    g = f["sweep"]
    g.attrs["free_joined"] = "B,G,beta_A"
    g.attrs.create("free_array", ["B", "G", "beta_A"], dtype=h5py.string_dtype())
    g.attrs.create("breaks_array", breaks, dtype=h5py.string_dtype())
    for name, sep, want in (("free_joined", ",", ["B", "G", "beta_A"]),
                            ("free_array", ",", ["B", "G", "beta_A"]),
                            ("breaks", "\n", breaks), ("breaks_array", "\n", breaks)):
        got = plot.attr_list(g, name, sep)
        if got != want:
            print("FAIL attr_list", name, got)
)PY";

TEST(Plot, ParetoChartLabelsDoNotOverlapAndFindingsAreWhole) {
  const std::string py = python();
  if (py.empty()) GTEST_SKIP() << "no python3 with matplotlib and h5py";
  const fs::path dir = rendulic::testing::fresh_dir("app_plot_system/pareto");
  const fs::path checks = write_file(dir / "checks.py", kParetoChecks);
  const CliResult r =
      rendulic::testing::run_command(py + " " + checks.string() + " " + kScript.string() + " " +
                                     (dir / "sweep.h5").string() + " " + (dir / "figs").string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.find("FAIL"), std::string::npos) << r.out;
  // Most labels find a free place (the rest are listed under the chart instead).
  EXPECT_NE(r.out.find("labels "), std::string::npos) << r.out;
}

TEST(Plot, DrawsEveryFigureOfASeedLikeFile) {
  const fs::path f = rendulic::app::testing::seed_like("plot", false);
  const fs::path out = f.parent_path() / "figs";
  ASSERT_EQ(run("plot " + f.string() + " --out " + out.string()), 0);
  for (const char* name :
       {"fig1_path", "fig2_strain_circle", "fig3_elastic_stress", "fig4_elastic_fabric",
        "fig5_plastic_stress", "fig6_plastic_fabric", "fig7_features"})
    for (const char* ext : {".png", ".pdf", ".svg"}) {
      const fs::path p = out / (std::string(name) + ext);
      EXPECT_TRUE(fs::exists(p)) << p;
      if (fs::exists(p)) {
        EXPECT_GT(fs::file_size(p), 1000u) << p;
      }
    }
}

// A python3 for the front of PATH that notes each start in dir/tried.txt: Debian's, or with
// `modules` false Debian's without its site directories (-S), a real interpreter without
// matplotlib and h5py, as PATH's python3 may be (pyenv, conda). Returns its folder.
fs::path counting_python(const fs::path& dir, bool modules) {
  const fs::path shim =
      write_file(dir / "bin" / "python3",
                 "#!/bin/sh\necho tried >> " + (dir / "tried.txt").string() +
                     "\nexec /usr/bin/python3 " + (modules ? "" : "-S ") + "\"$@\"\n");
  fs::permissions(shim, fs::perms::owner_all, fs::perm_options::add);
  return dir / "bin";
}

std::size_t lines_of(const fs::path& p) {
  std::ifstream in(p);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

bool debian_python_draws() {
  return rendulic::testing::run_command("/usr/bin/python3 -c 'import h5py, matplotlib'").code == 0;
}

// The compiled-in plot.py says it lacks the modules (exit 3) before it writes anything, and
// /usr/bin/python3 draws instead.
TEST(Plot, DrawsWithDebiansPythonWhenPathsOneLacksTheModules) {
  if (!debian_python_draws()) GTEST_SKIP() << "no /usr/bin/python3 with matplotlib and h5py";
  const fs::path f = rendulic::app::testing::seed_like("plot_fallback", false);
  const fs::path dir = rendulic::testing::fresh_dir("app_plot_system/fallback");
  const std::string path = "PATH=" + counting_python(dir, false).string() + ":\"$PATH\" ";
  const CliResult r = rendulic::testing::run_command(path + RENDULIC_EXE + " plot " + f.string() +
                                                     " --out " + (dir / "o").string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(lines_of(dir / "tried.txt"), 1u);
  for (const char* name : {"fig1_path.png", "fig3_elastic_stress.pdf", "fig7_features.svg"})
    EXPECT_TRUE(fs::exists(dir / "o" / name)) << name;
}

// A disk that refuses bytes (a file-size limit of 8 KiB; Python ignores SIGXFSZ) while the
// figures are drawn again: one line, exit 2, and every figure of the earlier plot keeps its
// bytes, none truncated under its name, no temporary left.
TEST(Plot, ADiskThatRefusesBytesLeavesTheEarlierFiguresWhole) {
  if (!debian_python_draws()) GTEST_SKIP() << "no /usr/bin/python3 with matplotlib and h5py";
  const fs::path f = rendulic::app::testing::seed_like("plot_limit", false);
  const fs::path dir = rendulic::testing::fresh_dir("app_plot_system/limit");
  const std::string plot =
      std::string(RENDULIC_EXE) + " plot " + f.string() + " --out " + (dir / "o").string();
  ASSERT_EQ(rendulic::testing::run_command(plot).code, 0);
  std::map<std::string, std::string> before;
  for (const auto& e : fs::directory_iterator(dir / "o"))
    before[e.path().filename().string()] = rendulic::testing::read_file(e.path());
  ASSERT_GT(before.size(), 3u);
  const CliResult r =
      rendulic::testing::run_command("trap '' XFSZ; ulimit -f 8; exec " + plot, false);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(rendulic::testing::error_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("File too large"), std::string::npos) << r.err;
  std::map<std::string, std::string> after;
  for (const auto& e : fs::directory_iterator(dir / "o"))
    after[e.path().filename().string()] = rendulic::testing::read_file(e.path());
  EXPECT_EQ(after.size(), before.size());
  for (const auto& [name, bytes] : after) {
    const auto it = before.find(name);
    ASSERT_NE(it, before.end()) << name << " is new";
    EXPECT_TRUE(it->second == bytes) << name << " changed";
  }
}

// A script runs with the first interpreter that has its modules, started once (no interpreter
// is started only to ask): a user's own script too, which need not say that it lacks a module
// (Python's exit 1 on the import). One that imports what neither interpreter has is refused
// in one line naming it, exit 2.
TEST(Plot, AUsersScriptRunsWithTheInterpreterThatHasItsModules) {
  if (!debian_python_draws()) GTEST_SKIP() << "no /usr/bin/python3 with matplotlib and h5py";
  const fs::path f = rendulic::app::testing::seed_like("plot_fallback_script", false);
  const fs::path mine =
      write_file(rendulic::testing::fresh_dir("app_plot_system/fallback_script") / "mine.py",
                 "import sys\nimport h5py, matplotlib\nopen(sys.argv[2] + '/ran.txt', "
                 "'w').write(sys.argv[0])\n");
  CliResult r;
  for (const bool modules : {true, false}) {
    const fs::path dir = rendulic::testing::fresh_dir(
        std::string("app_plot_system/fallback_script/") + (modules ? "with" : "without"));
    const std::string path = "PATH=" + counting_python(dir, modules).string() + ":\"$PATH\" ";
    r = rendulic::testing::run_command(path + RENDULIC_EXE + " plot " + f.string() + " --out " +
                                       (dir / "o").string() + " --script " + mine.string());
    EXPECT_EQ(r.code, 0) << r.out;
    EXPECT_EQ(lines_of(dir / "tried.txt"), 1u) << modules;  // with the modules: no probe first
    EXPECT_TRUE(fs::exists(dir / "o" / "ran.txt")) << modules;
  }
  const fs::path dir = rendulic::testing::fresh_dir("app_plot_system/fallback_script/needs");
  const std::string path = "PATH=" + counting_python(dir, false).string() + ":\"$PATH\" ";
  const fs::path needs = write_file(dir / "needs.py", "import rendulic_no_such_module\n");
  r = rendulic::testing::run_command(path + RENDULIC_EXE + " plot " + f.string() + " --out " +
                                     (dir / "o").string() + " --script " + needs.string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("needs python3 with matplotlib and h5py"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("No module named 'rendulic_no_such_module'"), std::string::npos) << r.out;
}

// A stand-in figure script that records that it ran and with which arguments.
const char* const kMarkerScript =
    "import os, sys\nopen(sys.argv[2] + '/ran.txt', 'w').write(__file__ + ' ' + sys.argv[1] + "
    "' jobs=' + os.environ.get('RENDULIC_PLOT_JOBS', ''))\n";

TEST(Plot, RunsTheScriptOfTheOptionTheEnvironmentOrTheInstallPrefix) {
  if (python().empty()) GTEST_SKIP() << "no python3 with matplotlib and h5py";
  const fs::path f = rendulic::app::testing::seed_like("plot_script", false);
  const fs::path dir = rendulic::testing::fresh_dir("app_plot_system/script");
  const fs::path mine = write_file(dir / "mine.py", kMarkerScript);
  auto ran = [](const fs::path& out) {
    std::ifstream in(out / "ran.txt");
    std::string text;
    std::getline(in, text);
    return text;
  };
  CliResult r = rendulic::testing::run_rendulic(
      "plot " + f.string() + " --out " + (dir / "o1").string() + " --script " + mine.string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(ran(dir / "o1").rfind(mine.string(), 0), 0u) << ran(dir / "o1");
  r = rendulic::testing::run_command("RENDULIC_PLOT_SCRIPT=" + mine.string() + " " + RENDULIC_EXE +
                                     " plot " + f.string() + " --out " + (dir / "o2").string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(ran(dir / "o2").rfind(mine.string(), 0), 0u);
  // Installed: bin/rendulic finds share/rendulic/plot.py of its prefix.
  fs::create_directories(dir / "prefix" / "bin");
  fs::copy_file(RENDULIC_EXE, dir / "prefix" / "bin" / "rendulic");
  const fs::path installed =
      write_file(dir / "prefix" / "share" / "rendulic" / "plot.py", kMarkerScript);
  r = rendulic::testing::run_command((dir / "prefix" / "bin" / "rendulic").string() + " plot " +
                                     f.string() + " --out " + (dir / "o3").string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(ran(dir / "o3").find("share/rendulic/plot.py"), std::string::npos) << ran(dir / "o3");
  EXPECT_NE(r.out.find("figures drawn by"), std::string::npos) << r.out;
  // The script may draw in as many processes as rendulic may use threads; the user's own
  // RENDULIC_PLOT_JOBS wins.
  r = rendulic::testing::run_command("OMP_NUM_THREADS=3 " + std::string(RENDULIC_EXE) + " plot " +
                                     f.string() + " --out " + (dir / "o4").string() + " --script " +
                                     mine.string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(ran(dir / "o4").find(" jobs=3"), std::string::npos) << ran(dir / "o4");
  r = rendulic::testing::run_command("RENDULIC_PLOT_JOBS=5 OMP_NUM_THREADS=3 " +
                                     std::string(RENDULIC_EXE) + " plot " + f.string() + " --out " +
                                     (dir / "o5").string() + " --script " + mine.string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(ran(dir / "o5").find(" jobs=5"), std::string::npos) << ran(dir / "o5");
  // A count of processes that is not one: one line naming it, exit 2 (it failed in the script
  // as a Python ValueError), and a run with the report stage is refused before any work.
  for (const char* jobs : {"abc", "0", "1.5"}) {
    r = rendulic::testing::run_command("RENDULIC_PLOT_JOBS=" + std::string(jobs) + " " +
                                       RENDULIC_EXE + " plot " + f.string() + " --out " +
                                       (dir / "o6").string());
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_EQ(r.out, "rendulic: RENDULIC_PLOT_JOBS=" + std::string(jobs) +
                         ": the processes to draw with are a whole number in [1, 4096]\n");
  }
  EXPECT_FALSE(fs::exists(dir / "o6"));
  r = rendulic::testing::run_command("RENDULIC_PLOT_JOBS=abc " + std::string(RENDULIC_EXE) +
                                     " run " + rendulic::testing::tiny_scenario(dir).string() +
                                     " --set run.stages=prepare,report --out " +
                                     (dir / "run").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("RENDULIC_PLOT_JOBS=abc: "), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "run"));
  r = rendulic::testing::run_command(
      "RENDULIC_PLOT_SCRIPT=" + (dir / "nope.py").string() + " " + RENDULIC_EXE + " run " +
      rendulic::testing::tiny_scenario(dir).string() + " --set run.stages=prepare,report --out " +
      (dir / "run").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("nope.py: no figure script there (RENDULIC_PLOT_SCRIPT)"), std::string::npos)
      << r.out;
  EXPECT_FALSE(fs::exists(dir / "run"));
  // A script that is not there: one line naming it, exit 2.
  r = rendulic::testing::run_rendulic("plot " + f.string() + " --script " +
                                      (dir / "nope.py").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("nope.py: no figure script there (--script)"), std::string::npos) << r.out;
}

// Drawn in two processes, the figures are the same files, listed in the same order, as drawn
// in one (the PNG bytes too: each figure is drawn by the same code from the same data).
TEST(Plot, TwoProcessesDrawTheSameFiguresAsOne) {
  if (python().empty()) GTEST_SKIP() << "no python3 with matplotlib and h5py";
  const fs::path f = rendulic::app::testing::seed_like("plot_jobs", false);
  const fs::path dir = rendulic::testing::fresh_dir("app_plot_system/jobs");
  // One process, two, and two asked for where no process can be forked (the script then draws
  // every share itself).
  const std::string variants[3] = {"1", "2", "2-nofork"};
  std::string listed[3];
  for (int v = 0; v < 3; ++v) {
    const fs::path out = dir / variants[v];
    const std::string args = f.string() + " " + out.string();
    const std::string command =
        v < 2 ? python() + " " + kScript.string() + " " + args
              : python() +
                    " -c 'import os, runpy, sys\n"
                    "def no(): raise OSError(11, \"Resource temporarily unavailable\")\n"
                    "os.fork = no\n"
                    "sys.argv = sys.argv[1:]\n"
                    "runpy.run_path(sys.argv[0], run_name=\"__main__\")' " +
                    kScript.string() + " " + args;
    const CliResult r = rendulic::testing::run_command(
        "RENDULIC_PLOT_JOBS=" + variants[v].substr(0, 1) + " " + command + " 2>/dev/null");
    ASSERT_EQ(r.code, 0) << variants[v] << ": " << r.out;
    listed[v] = r.out;
    // Paths differ only by the folder name.
    for (std::size_t at; (at = listed[v].find(out.string())) != std::string::npos;)
      listed[v].replace(at, out.string().size(), "DIR");
  }
  EXPECT_EQ(listed[0], listed[1]);
  EXPECT_EQ(listed[0], listed[2]);
  int compared = 0;
  for (const auto& e : fs::directory_iterator(dir / "1")) {
    if (e.path().extension() != ".png") continue;
    for (const char* v : {"2", "2-nofork"}) {
      const fs::path other = dir / v / e.path().filename();
      ASSERT_TRUE(fs::exists(other)) << other;
      std::ifstream a(e.path(), std::ios::binary), b(other, std::ios::binary);
      const std::string da((std::istreambuf_iterator<char>(a)), {}),
          db((std::istreambuf_iterator<char>(b)), {});
      EXPECT_EQ(da, db) << v << " " << e.path().filename();
    }
    ++compared;
  }
  EXPECT_GE(compared, 7);
}

// rendulic never stores a value that is not finite in the series and envelope pairs the
// figures draw: one is damage, and its figure is skipped naming the dataset and row, while the
// others are drawn. Matplotlib left such a point out with a bare "posx and posy should be
// finite values", exit 0.
TEST(Plot, AValueThatIsNotFiniteSkipsItsFigureNamingIt) {
  if (python().empty()) GTEST_SKIP() << "no python3 with matplotlib and h5py";
  const fs::path dir = rendulic::testing::fresh_dir("app_plot_system/not_finite");
  const fs::path f = dir / "results.h5";
  fs::copy_file(tiny_results(), f);
  const std::string envelope = "/states/a/envelopes/dynamic_0.002/stress_star";
  const CliResult damage = rendulic::testing::run_command(
      python() + " -c \"import h5py, numpy as np\nwith h5py.File('" + f.string() +
      "', 'r+') as h:\n  for name, row in (('/path/stress_star', 3), ('" + envelope +
      "', 2)):\n    d = h[name]; a = d[...]; a[row] = np.nan; d[...] = a\"");
  ASSERT_EQ(damage.code, 0) << damage.out;
  const CliResult r = rendulic::testing::run_rendulic(
      "plot " + f.string() + " --out " + (dir / "figs").string(), false);
  EXPECT_EQ(r.code, 0) << r.err;
  const std::string notes[] = {"skipped: Fig. 1: /path/stress_star: row 3 is not finite",
                               "skipped: Fig. 5: " + envelope + ": row 2 is not finite",
                               "skipped: models path: /path/stress_star: row 3 is not finite"};
  for (const std::string& note : notes)
    EXPECT_NE(r.err.find(note), std::string::npos) << note << "\n" << r.err;
  EXPECT_EQ(r.err.find("posx"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "figs" / "fig1_path.png"));
  EXPECT_FALSE(fs::exists(dir / "figs" / "fig5_plastic_stress.png"));
  EXPECT_TRUE(fs::exists(dir / "figs" / "fig3_elastic_stress.png"));
  EXPECT_TRUE(fs::exists(dir / "figs" / "isotropic_branch.png"));
}

TEST(Plot, AFolderItMadeAndDrewNothingInIsRemovedAgain) {
  // A file without any figure's data, and a script that fails: each left an empty figures
  // folder (and the folders above it that --out named) behind.
  if (python().empty()) GTEST_SKIP() << "no python3 with matplotlib and h5py";
  const fs::path dir = rendulic::testing::fresh_dir("app_plot_system/nothing");
  {
    rendulic::ResultsWriter w(dir / "results.h5");
    w.attr("/material", "k_star", 1.0);
    w.commit();
  }
  CliResult r = rendulic::testing::run_rendulic("plot " + (dir / "results.h5").string() +
                                                " --out " + (dir / "a" / "b").string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("no figure drawn"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "a"));
  const fs::path failing = write_file(dir / "fails.py",
                                      "import sys\nprint('bad data', "
                                      "file=sys.stderr)\nsys.exit(2)\n");
  r = rendulic::testing::run_rendulic("plot " + (dir / "results.h5").string() + " --script " +
                                      failing.string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_FALSE(fs::exists(dir / "figures"));
  // A folder that was there before stays, empty or not.
  fs::create_directories(dir / "mine");
  r = rendulic::testing::run_rendulic("plot " + (dir / "results.h5").string() + " --out " +
                                      (dir / "mine").string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(fs::is_directory(dir / "mine"));
  // A run's report with nothing to draw: it read the removed folder (an internal error, exit 1).
  r = rendulic::testing::run_rendulic(
      "run " + rendulic::testing::tiny_scenario(dir).string() +
      " --quiet --threads 1 --set run.stages=prepare,report --out " + (dir / "run").string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_FALSE(fs::exists(dir / "run" / "figures"));
  EXPECT_NE(rendulic::testing::read_file(dir / "run" / "report.md")
                .find("this file holds none of their data"),
            std::string::npos);
}

TEST(Plot, RefusesAFileThatIsNotOurs) {
  const fs::path dir = fs::path(RENDULIC_TEST_TMP) / "app_plot_bad";
  fs::create_directories(dir);
  std::ofstream(dir / "x.h5") << "text";
  EXPECT_EQ(run("plot " + (dir / "x.h5").string()), 2);
}

}  // namespace
