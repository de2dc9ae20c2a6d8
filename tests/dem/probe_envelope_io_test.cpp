// Envelopes in the results file (docs/results.md /states/<label>/envelopes/<name>): the
// datasets and attributes of the contract, and an exact round trip including diagnostics; a
// stored pair that is not finite (damage: rendulic writes none), a strain pair that is not the
// probe strain, or a response pair beyond the span an envelope can hold, is refused naming it.
#include <gtest/gtest.h>

#include <filesystem>
#include <initializer_list>
#include <limits>
#include <string>

#include "rendulic/core/envelope_io.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/dem/probe_envelope.hpp"

namespace rendulic::dem {
namespace {

Envelope sample_envelope() {
  Envelope env;
  env.method = "dynamic";
  env.amplitude = 5e-5;
  env.k_star = 5e10;
  for (int i = 0; i < 5; ++i) {
    const double t = 72.0 * i;
    Eigen::Matrix3d ds = Eigen::Matrix3d::Random() * 1e6;
    ds = 0.5 * (ds + ds.transpose()).eval();
    Eigen::Matrix3d df = Eigen::Matrix3d::Random() * 1e-4;
    df = 0.5 * (df + df.transpose()).eval();
    env.add(t, probe_strain(t, env.amplitude), ds, df);
    env.diagnostics["contacts_opened"].push_back(i);
    env.diagnostics["relax_time"].push_back(1e-4 * i);
  }
  env.attributes["rate"] = 79.5;
  return env;
}

TEST(EnvelopeIo, RoundTripWithTheContractNames) {
  const std::filesystem::path dir = std::filesystem::path(RENDULIC_TEST_TMP) / "envelope_io";
  std::filesystem::create_directories(dir);
  const std::filesystem::path file = dir / "results.h5";
  const Envelope env = sample_envelope();
  const std::string group = paths::envelope(paths::state("s0"), "elastic_dynamic");
  EXPECT_EQ(group, "/states/s0/envelopes/elastic_dynamic");
  {
    ResultsWriter out(file);
    write_envelope(out, group, env);
    out.commit();
  }
  const ResultsReader in(file);
  EXPECT_DOUBLE_EQ(in.attr_double(group, "amplitude"), 5e-5);
  EXPECT_EQ(in.attr_string(group, "method"), "dynamic");
  EXPECT_EQ(in.attr_int(group, "directions"), 5);
  for (const char* name : {"theta_deg", "strain", "stress_star", "fabric", "d_stress", "d_fabric"})
    EXPECT_TRUE(in.exists(group + "/" + name)) << name;
  EXPECT_EQ(in.shape(group + "/d_stress"), (std::vector<std::uint64_t>{5, 3, 3}));
  EXPECT_EQ(in.shape(group + "/strain"), (std::vector<std::uint64_t>{5, 2}));
  const Envelope back = read_envelope(in, group);
  EXPECT_EQ(back.name, "elastic_dynamic");  // the group's last part
  EXPECT_EQ(back.method, env.method);
  EXPECT_EQ(back.theta_deg, env.theta_deg);
  for (std::size_t i = 0; i < env.size(); ++i) {
    // The pairs in Pa are in memory only: the starred ones are they divided by k*.
    EXPECT_EQ(env.stress[i], rendulic_pair(env.d_stress[i]));
    EXPECT_EQ(env.stress_star[i], env.stress[i] / env.k_star);
    EXPECT_EQ(back.strain[i], env.strain[i]);
    EXPECT_EQ(back.stress_star[i], env.stress_star[i]);
    EXPECT_EQ(back.fabric[i], env.fabric[i]);
    EXPECT_EQ(back.d_stress[i], env.d_stress[i]);
    EXPECT_EQ(back.d_fabric[i], env.d_fabric[i]);
  }
  EXPECT_EQ(back.diagnostics, env.diagnostics);
  EXPECT_EQ(back.attributes, env.attributes);
  EXPECT_THROW(read_envelope(in, paths::envelope(paths::state("s0"), "missing")), InputError);
}

TEST(EnvelopeIo, APairThatIsNotFiniteIsRefusedNamingItsDatasetAndProbe) {
  // The report fitted such pairs for its claims: "internal error: fit_rendulic_map: strain
  // pairs are collinear", exit 1.
  const std::filesystem::path dir = std::filesystem::path(RENDULIC_TEST_TMP) / "envelope_io";
  std::filesystem::create_directories(dir);
  const std::string group = paths::envelope(paths::state("s0"), "dynamic_5e-05");
  const double bad[] = {std::numeric_limits<double>::quiet_NaN(),
                        std::numeric_limits<double>::infinity()};
  for (const char* dataset : {"theta_deg", "strain", "stress_star", "fabric"}) {
    Envelope env = sample_envelope();
    const std::string name = dataset;
    for (const double v : bad) {
      if (name == "theta_deg") env.theta_deg[3] = v;
      if (name == "strain") env.strain[3].y() = v;
      if (name == "stress_star") env.stress_star[3].x() = v;
      if (name == "fabric") env.fabric[3].y() = v;
      const std::filesystem::path file = dir / ("not_finite_" + name + ".h5");
      {
        ResultsWriter out(file);
        write_envelope(out, group, env);
        out.commit();
      }
      const ResultsReader in(file);
      try {
        read_envelope(in, group);
        ADD_FAILURE() << name << " " << v << " read";
      } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()),
                  file.string() + ": envelope " + group + "/" + name + ": probe 3 is not finite");
      }
    }
  }
}

// A damage applied to the sample envelope, and what reading it says: the start of the error
// after "FILE: envelope GROUP", or "" where it is read.
struct Damage {
  void (*damage)(Envelope&);
  std::string says;
};

// Writes each damaged envelope to `name` and reads it back: refused with `says`, or read.
void expect_reads(const char* name, std::initializer_list<Damage> cases, const char* also = "") {
  const std::filesystem::path dir = std::filesystem::path(RENDULIC_TEST_TMP) / "envelope_io";
  std::filesystem::create_directories(dir);
  const std::string group = paths::envelope(paths::state("s0"), "dynamic_5e-05");
  const std::filesystem::path file = dir / name;
  for (const Damage& c : cases) {
    Envelope env = sample_envelope();
    c.damage(env);
    {
      ResultsWriter out(file);
      write_envelope(out, group, env);
      out.commit();
    }
    const ResultsReader in(file);
    if (c.says.empty()) {
      EXPECT_NO_THROW(read_envelope(in, group));
      continue;
    }
    try {
      read_envelope(in, group);
      ADD_FAILURE() << c.says << ": read";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(file.string() + ": envelope " + group + c.says, 0), 0u) << what;
      EXPECT_NE(what.find(also), std::string::npos) << what;
    }
  }
}

// The strain pair of every probe is amplitude (cos t, sin t) (docs/probes.md); a finite pair
// that is not, or a direction that does not match its pair, is damage and refused naming the
// probe: -1e308 there gave a calibration of NaN with exit 0, and the report an internal error.
// Round-off far above rendulic's own (1e-12 of the amplitude) is still read.
TEST(EnvelopeIo, AStrainPairThatIsNotTheProbeStrainIsRefused) {
  const std::string says = " is not the probe strain @amplitude (cos, sin) of its theta_deg";
  expect_reads("not_the_probe_strain.h5",
               {{[](Envelope& e) { e.strain[3].x() = -1e308; }, "/strain: probe 3" + says},
                {[](Envelope& e) { e.theta_deg[2] = -1e308; }, "/strain: probe 2" + says},
                {[](Envelope& e) { e.strain[1] *= 1.0 + 1e-6; }, "/strain: probe 1" + says},
                {[](Envelope& e) { e.strain[1] *= 1.0 + 1e-12; }, ""}});
}

// A response pair more than kMaxEnvelopeSpan times the median pair's size is damage too
// (rendulic's envelopes span a few decades): 1e290 in a stress pair silenced that envelope in a
// calibration with exit 0. Refused naming the dataset and the probe; a span of 1e90 is read.
TEST(EnvelopeIo, AResponsePairBeyondTheEnvelopesSpanIsRefused) {
  expect_reads(
      "beyond_the_span.h5",
      {{[](Envelope& e) { e.stress_star[3].y() = 1e290; }, "/stress_star: probe 3 reaches 1e+290"},
       {[](Envelope& e) { e.fabric[0].x() = -1e200; }, "/fabric: probe 0 reaches 1e+200"},
       {[](Envelope& e) { e.stress_star[3].y() = 1e90 * e.stress_star[3].norm(); }, ""}},
      ", more than 1e+100 times the median probe's");
}

}  // namespace
}  // namespace rendulic::dem
