// `rendulic envelope --model umat --umat PATH.so` run as a user would (docs/umat.md): the JSON
// envelope of the hypoplastic UMAT equals the built-in law's, both methods; a missing file, a
// folder, a device or a FIFO in its place, a library without a UMAT entry, a UMAT without --umat
// and a UMAT returning NaN exit 2 with one line that names the culprit.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_runner.hpp"

namespace rendulic::models {
namespace {

using rendulic::testing::error_lines;
using rendulic::testing::fresh_dir;
using rendulic::testing::run_rendulic;

std::string lib(const std::string& name) {
  return std::string(RENDULIC_UMAT_DIR) + "/" + name + ".so";
}
std::string src(const std::string& rel) { return std::string(RENDULIC_SOURCE_DIR) + "/" + rel; }

std::string envelope_args(const std::string& method) {
  return "envelope --state " + src("data/models/isotropic_state.toml") +
         " --amplitude 5e-5 --json --tolerance 1e-8 --method " + method;
}

std::vector<double> stresses(const std::string& json) {
  std::vector<double> v;
  const nlohmann::json j = nlohmann::json::parse(json);  // kept: the loop reads into it
  for (const auto& p : j.at("stress"))
    for (const auto& x : p) v.push_back(x.get<double>());
  return v;
}

TEST(UmatCli, HypoplasticUmatEnvelopeEqualsTheBuiltInLaw) {
  for (const std::string method : {"rate", "integrated"}) {
    const auto u =
        run_rendulic(envelope_args(method) + " --model umat --umat " + lib("hypoplastic_wu") +
                         " --params " + src("data/umat/hypoplastic_wu_params.toml"),
                     false);
    ASSERT_EQ(u.code, 0) << u.err;
    const auto b = run_rendulic(envelope_args(method) + " --model hypoplastic_wu --params " +
                                    src("data/models/hypoplastic_wu_params.toml"),
                                false);
    ASSERT_EQ(b.code, 0) << b.err;
    EXPECT_EQ(nlohmann::json::parse(u.out).at("model"), "umat");
    const auto su = stresses(u.out), sb = stresses(b.out);
    ASSERT_EQ(su.size(), sb.size());
    double diff = 0.0, norm = 0.0;
    for (std::size_t i = 0; i < su.size(); ++i) {
      diff += (su[i] - sb[i]) * (su[i] - sb[i]);
      norm += sb[i] * sb[i];
    }
    EXPECT_LE(std::sqrt(diff / norm), method == "rate" ? 1e-12 : 2e-7)
        << method << ": " << diff << " / " << norm;
  }
}

TEST(UmatCli, BadUmatInputExitsTwoWithOneLine) {
  const auto d = fresh_dir("models_umat_cli");
  const std::string params = src("data/umat/hypoplastic_wu_params.toml");
  const std::string base = envelope_args("integrated") + " --model umat --params " + params;
  // NaN once |STRAN + DSTRAN| exceeds 1e-4: the probes of amplitude 2e-4 run into it.
  std::ofstream(d / "nan.toml") << "props = [-101.2, -962.1, -877.7, 1229.2, 0.0, 1e-4]\n";
  // dlopen would block on a FIFO and call a folder "cannot read file data": each is refused first.
  ASSERT_EQ(::mkfifo((d / "fifo.so").c_str(), 0600), 0);
  const struct {
    std::string args, culprit;
  } cases[] = {
      {base + " --umat " + (d / "missing.so").string(), "missing.so: no such file"},
      {base + " --umat " + d.string(), d.string() + ": is a folder, not a UMAT library"},
      {base + " --umat /dev/zero", "/dev/zero: not a regular file (a UMAT library is a .so file)"},
      {base + " --umat " + (d / "fifo.so").string(), "fifo.so: not a regular file"},
      {base + " --umat " + lib("no_entry"), "exports no UMAT entry"},
      {envelope_args("rate") + " --model umat --params " + params, "--umat"},
      {envelope_args("rate") + " --model umat --umat " + lib("hypoplastic_wu"), "--params"},
      {envelope_args("rate") + " --model hypoplastic_wu --umat " + lib("hypoplastic_wu"), "--umat"},
      {"envelope --state " + src("data/models/isotropic_state.toml") +
           " --amplitude 2e-4 --model umat --umat " + lib("hypoplastic_wu") + " --params " +
           (d / "nan.toml").string(),
       "NaN"},
  };
  for (const auto& c : cases) {
    const auto r = run_rendulic(c.args, false);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
    EXPECT_EQ(error_lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(c.culprit), std::string::npos) << r.err;
  }
  const auto nan = run_rendulic(cases[8].args, false);
  EXPECT_NE(nan.err.find("KINC = "), std::string::npos) << nan.err;
  EXPECT_NE(nan.err.find("probe theta = "), std::string::npos) << nan.err;
}

}  // namespace
}  // namespace rendulic::models
