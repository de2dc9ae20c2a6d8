// The probe plane of an envelope in the results file (docs/results.md, attributes `plane` and
// `plane_basis`): a deviatoric envelope reads back with its plane, so that its strain tensors
// are rebuilt in that plane; an envelope written without the attribute (every file before it)
// reads as the Rendulic plane; an unknown plane name is refused with one line naming it. Its
// name does not collide with the Rendulic envelope's.
#include <gtest/gtest.h>

#include <filesystem>

#include "input_error.hpp"
#include "rendulic/core/envelope_io.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/dem/probe_envelope.hpp"

namespace rendulic::dem {
namespace {

using rendulic::testing::input_error;

std::filesystem::path test_file(const char* name) {
  const std::filesystem::path dir = std::filesystem::path(RENDULIC_TEST_TMP) / "probe_plane_io";
  std::filesystem::create_directories(dir);
  return dir / name;
}

Envelope deviatoric_envelope() {
  Envelope env;
  env.method = "dynamic";
  env.amplitude = 5e-5;
  env.k_star = 5e10;
  env.plane = deviatoric_plane();
  std::srand(11);
  for (int i = 0; i < 6; ++i) {
    const double t = 60.0 * i + 7.0;
    Eigen::Matrix3d ds = Eigen::Matrix3d::Random() * 1e6;
    ds = (ds + ds.transpose()).eval();
    env.add(t, plane_strain(env.plane, t, env.amplitude), ds, 1e-12 * ds);
  }
  return env;
}

TEST(ProbePlaneIo, DeviatoricEnvelopeRoundTripsWithItsPlane) {
  const std::filesystem::path file = test_file("deviatoric.h5");
  const Envelope env = deviatoric_envelope();
  const std::string rendulic_name = paths::envelope_name("dynamic", 5e-5);
  const std::string name = paths::envelope_name("dynamic", 5e-5, env.plane.name);
  EXPECT_EQ(rendulic_name, "dynamic_5e-05");  // today's name, unchanged
  EXPECT_EQ(name, "dynamic_deviatoric_5e-05");
  const std::string group = paths::envelope(paths::state("a"), name);
  {
    ResultsWriter out(file);
    write_envelope(out, group, env);
    out.commit();
  }
  const ResultsReader in(file);
  EXPECT_EQ(in.attr_string(group, "plane"), "deviatoric");
  const std::vector<double> basis = in.attr_doubles(group, "plane_basis");
  ASSERT_EQ(basis.size(), 6u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(basis[k], env.plane.u(k));
    EXPECT_EQ(basis[3 + k], env.plane.v(k));
  }
  const Envelope back = read_envelope(in, group);
  EXPECT_EQ(back.plane.name, "deviatoric");
  EXPECT_EQ(back.plane.u, env.plane.u);
  EXPECT_EQ(back.plane.v, env.plane.v);
  ASSERT_EQ(back.size(), env.size());
  for (std::size_t i = 0; i < env.size(); ++i) {
    EXPECT_EQ(back.strain[i], env.strain[i]);
    EXPECT_EQ(back.stress_star[i], env.stress_star[i]);
    // The strain tensor is rebuilt in the plane: a constant-volume, non-axisymmetric strain.
    const Eigen::Matrix3d e = plane_strain(env.plane, env.theta_deg[i], env.amplitude);
    EXPECT_LE((back.strain_tensor(i) - e).norm(), 1e-15 * env.amplitude) << i;
    EXPECT_LE(std::abs(back.strain_tensor(i).trace()), 1e-15 * env.amplitude) << i;
    // Read as a Rendulic pair it would be an axisymmetric tensor, which it is not.
    EXPECT_GT((from_rendulic_pair(back.strain[i]) - e).norm(), 0.1 * env.amplitude) << i;
  }
}

TEST(ProbePlaneIo, EnvelopeWithoutThePlaneAttributeReadsAsRendulic) {
  const std::filesystem::path file = test_file("old.h5");
  const std::string group = paths::envelope(paths::state("a"), "dynamic_5e-05");
  std::vector<double> theta;
  std::vector<Eigen::Vector2d> strain;
  for (int i = 0; i < 4; ++i) {
    theta.push_back(kIsoCompressionDeg + 90.0 * i);
    strain.push_back(rendulic_pair(probe_strain(theta.back(), 5e-5)));
  }
  {
    // What files before the attribute hold (the schema's datasets, written by hand).
    ResultsWriter out(file);
    out.create_group(group);
    out.attr(group, "amplitude", 5e-5);
    out.attr(group, "method", "dynamic");
    out.write(group + datasets::kThetaDeg, theta);
    out.write(group + datasets::kStrain, strain);
    out.commit();
  }
  const Envelope back = read_envelope(ResultsReader(file), group);
  EXPECT_TRUE(back.plane.rendulic());
  for (std::size_t i = 0; i < back.size(); ++i)
    EXPECT_EQ(back.strain_tensor(i), from_rendulic_pair(strain[i]));
}

TEST(ProbePlaneIo, UnknownPlaneInAFileIsRefusedNamingIt) {
  const std::filesystem::path file = test_file("unknown.h5");
  const std::string group = paths::envelope(paths::state("a"), "dynamic_x_5e-05");
  {
    ResultsWriter out(file);
    out.create_group(group);
    out.attr(group, "amplitude", 5e-5);
    out.attr(group, "plane", "octahedral");
    out.commit();
  }
  const std::string what = input_error([&] { read_envelope(ResultsReader(file), group); });
  EXPECT_NE(what.find("octahedral"), std::string::npos) << what;
  EXPECT_EQ(what.find('\n'), std::string::npos) << what;
}

}  // namespace
}  // namespace rendulic::dem
