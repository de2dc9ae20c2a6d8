// The UMAT adapter (models/umat.hpp, docs/umat.md) against closed forms and the built-in laws: the
// example UMATs of data/umat (a Fortran linear elastic one, hypoplastic_wu in C) loaded as a user
// would load them. The linear elastic UMAT's envelopes are the closed form to 1e-10; the
// hypoplastic UMAT's rate envelope is the built-in law's to rounding (DDSDDE : d_eps is the rate
// law), its integrated envelope and path the built-in law's to the drivers' tolerance; PNEWDT
// cuts are honoured and leave no trace of the abandoned increments in the state; NaN from the
// UMAT and a missing file or entry are errors that say where.
#include "rendulic/models/umat.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <thread>

#include "ellipse_of.hpp"
#include "input_error.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/models/envelope.hpp"
#include "rendulic/models/material_io.hpp"
#include "rendulic/models/paths.hpp"

namespace rendulic::models {
namespace {

using rendulic::testing::input_error;

using testing::rows_of;

std::string umat_lib(const std::string& name) {
  return std::string(RENDULIC_UMAT_DIR) + "/" + name + ".so";
}
std::string umat_params(const std::string& name) {
  return std::string(RENDULIC_SOURCE_DIR) + "/data/umat/" + name + "_params.toml";
}
bool have(const std::string& name) { return std::filesystem::exists(umat_lib(name)); }

UmatSpec spec_of(const std::string& name) { return load_umat_parameters_toml(umat_params(name)); }

MaterialState isotropic(const Law& law, double p) {
  return law.make_state(Eigen::Matrix3d::Identity() * p, Eigen::Matrix3d::Identity() * 2.0, 0.82);
}

// A deviatoric, non-axisymmetric state: the hypoplastic law's non-linear term N then has every
// Voigt component, so the conversions of stress, strain and DDSDDE are all exercised.
MaterialState sheared(const Law& law) {
  Eigen::Matrix3d s;
  s << 2.0e5, 0.3e5, -0.2e5, 0.3e5, 1.4e5, 0.1e5, -0.2e5, 0.1e5, 1.1e5;
  return law.make_state(s, Eigen::Matrix3d::Zero(), 0.6);
}

EnvelopeOptions options(EnvelopeMethod method, double amplitude, double tolerance = 1e-6) {
  EnvelopeOptions o;
  o.amplitude = amplitude;
  o.method = method;
  o.step.tolerance = tolerance;
  return o;
}

double relative(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / b.norm();
}

TEST(Umat, LinearElasticFortranUmatEnvelopesAreTheClosedForm) {
  if (!have("linear_elastic"))
    GTEST_SKIP() << "no Fortran compiler: " << umat_lib("linear_elastic");
  const UmatLaw law(umat_lib("linear_elastic"), spec_of("linear_elastic"));
  EXPECT_EQ(law.symbol(), "umat_");
  const double k = law.parameter("K"), g = law.parameter("G");
  const MaterialState s = isotropic(law, 2e9);
  for (const auto method : {EnvelopeMethod::kIntegrated, EnvelopeMethod::kRate}) {
    const EnvelopeRecord env = model_envelope(law, s, options(method, 5e-5));
    Eigen::MatrixXd expect(env.size(), 2);
    for (std::size_t i = 0; i < env.size(); ++i) {
      const Eigen::Matrix3d de = probe_strain(env.theta_deg[i], 5e-5);
      const Eigen::Matrix3d ds = k * de.trace() * Eigen::Matrix3d::Identity() +
                                 2.0 * g * (de - de.trace() / 3.0 * Eigen::Matrix3d::Identity());
      expect.row(static_cast<Eigen::Index>(i)) = rendulic_pair(ds).transpose();
    }
    EXPECT_LE(relative(rows_of(env.stress), expect), 1e-10);
    EXPECT_EQ(rows_of(env.fabric).norm(), 0.0);  // a UMAT knows no fabric
  }
  // The Mandel tangent is the isotropic stiffness, shear block included (engineering strains).
  const Matrix6d t = law.tangent(s, probe_strain(10.0, 1.0));
  Matrix6d c = Matrix6d::Zero();
  c.topLeftCorner<3, 3>().setConstant(k - 2.0 * g / 3.0);
  c.diagonal().head<3>().array() += 2.0 * g;
  c.diagonal().tail<3>().setConstant(2.0 * g);
  EXPECT_LE((t - c).norm(), 1e-12 * c.norm());
}

TEST(Umat, LinearElasticShearAndStatevRoundTrip) {
  if (!have("linear_elastic")) GTEST_SKIP();
  const UmatLaw law(umat_lib("linear_elastic"), spec_of("linear_elastic"));
  const double k = law.parameter("K"), g = law.parameter("G");
  Eigen::Matrix3d de;
  de << 1e-5, 2e-6, -3e-6, 2e-6, -4e-6, 5e-6, -3e-6, 5e-6, 2e-6;
  const MaterialState s = sheared(law);
  UmatState end;
  const StepResult r = law.integrate(law.umat_state(s), de, {}, &end);
  ASSERT_TRUE(r.success) << r.reason;
  const Eigen::Matrix3d expect = s.stress + k * de.trace() * Eigen::Matrix3d::Identity() +
                                 2.0 * g * (de - de.trace() / 3.0 * Eigen::Matrix3d::Identity());
  EXPECT_LE((r.end.stress - expect).norm(), 1e-12 * expect.norm());
  // STATEV(2) = STRAN(1) + DSTRAN(1): tension positive, the total strain 11.
  EXPECT_NEAR(end.statev[1], -de(0, 0), 1e-18);
  EXPECT_DOUBLE_EQ(end.point.internal(1), end.statev[1]);
  EXPECT_LE((end.strain - de).norm(), 1e-20);
}

TEST(Umat, HypoplasticUmatRateEnvelopeIsTheBuiltInLaws) {
  auto builtin = make_law("hypoplastic_wu");
  const UmatLaw law(umat_lib("hypoplastic_wu"), spec_of("hypoplastic_wu"));
  EXPECT_EQ(law.symbol(), "umat");
  for (const MaterialState& s : {isotropic(law, 1e5), sheared(law)}) {
    const EnvelopeRecord a = model_envelope(law, s, options(EnvelopeMethod::kRate, 5e-5));
    const EnvelopeRecord b = model_envelope(*builtin, s, options(EnvelopeMethod::kRate, 5e-5));
    EXPECT_LE(relative(rows_of(a.stress), rows_of(b.stress)), 1e-12);
    // And the full tensors, off-axis components included, for a non-axisymmetric probe.
    Eigen::Matrix3d de;
    de << 1e-5, 2e-6, -3e-6, 2e-6, -4e-6, 5e-6, -3e-6, 5e-6, 2e-6;
    const Eigen::Matrix3d ra = law.rate(s, de).d_stress, rb = builtin->rate(s, de).d_stress;
    EXPECT_LE((ra - rb).norm(), 1e-12 * rb.norm());
    EXPECT_LE((law.tangent(s, de) - builtin->tangent(s, de)).norm(),
              1e-12 * builtin->tangent(s, de).norm());
  }
}

TEST(Umat, HypoplasticUmatIntegratedEnvelopeAndPathAreTheBuiltInLaws) {
  auto builtin = make_law("hypoplastic_wu");
  const UmatLaw law(umat_lib("hypoplastic_wu"), spec_of("hypoplastic_wu"));
  // Both drivers at tolerance 1e-8: each is then within ~1e-8 of the exact response (modified
  // Euler, and step doubling with the stress extrapolated), and the two agree to twice that.
  // 12 directions: the 2e-3 probes at this tolerance are what costs.
  constexpr double tol = 1e-8;
  for (const MaterialState& s : {isotropic(law, 1e5), sheared(law)}) {
    for (double amp : {5e-5, 2e-3}) {
      EnvelopeOptions eo = options(EnvelopeMethod::kIntegrated, amp, tol);
      eo.directions = 12;
      const EnvelopeRecord a = model_envelope(law, s, eo), b = model_envelope(*builtin, s, eo);
      std::cout << "amplitude " << amp << ": UMAT against built-in, relative "
                << relative(rows_of(a.stress), rows_of(b.stress)) << "\n";
      EXPECT_LE(relative(rows_of(a.stress), rows_of(b.stress)), 2 * tol) << "amplitude " << amp;
    }
  }
  PathOptions po;
  po.steps = 20;
  po.step.tolerance = tol;
  const MaterialState s = isotropic(law, 1e5);
  const PathSeries a = undrained_axisymmetric_path(law, s, -0.02, po);
  const PathSeries b = undrained_axisymmetric_path(*builtin, s, -0.02, po);
  ASSERT_TRUE(a.success && b.success) << a.reason << b.reason;
  ASSERT_EQ(a.stress.size(), b.stress.size());
  for (std::size_t k = 0; k < a.stress.size(); ++k) {
    EXPECT_LE((a.stress[k] - b.stress[k]).norm(), 2 * tol * b.stress[k].norm()) << "row " << k;
    EXPECT_NEAR(a.eps_dev[k], b.eps_dev[k], 1e-15);
  }
}

// A drained path holds stresses through the laws' rate (integrate_mixed), which would lose a
// UMAT's STATEV beyond the six internal variables between calls: refused with the reason, not
// run wrong.
TEST(Umat, ADrainedPathIsRefusedForAUmat) {
  const UmatLaw law(umat_lib("hypoplastic_wu"), spec_of("hypoplastic_wu"));
  const PathSeries d = drained_triaxial_path(law, isotropic(law, 1e5), 0.01);
  EXPECT_FALSE(d.success);
  EXPECT_TRUE(d.stress.empty());
  EXPECT_NE(d.reason.find("a drained path is for the built-in laws"), std::string::npos)
      << d.reason;
}

TEST(Umat, PnewdtCutsAreHonouredAndLeaveNoTrace) {
  const double limit = 1e-6;
  UmatSpec spec = spec_of("hypoplastic_wu");
  spec.props.push_back(limit);  // PROPS(5): the largest |DSTRAN| the UMAT accepts
  spec.prop_names.push_back("dstran_max");
  spec.lower.push_back(0.0);
  spec.upper.push_back(1.0);
  spec.nstatv = 8;  // beyond MaterialState's six: STATEV(8) sums DSTRAN(1)
  spec.statev.assign(8, 0.0);
  const UmatLaw law(umat_lib("hypoplastic_wu"), spec);
  auto builtin = make_law("hypoplastic_wu");
  const MaterialState s = sheared(law);
  const Eigen::Matrix3d de = probe_strain(100.0, 5e-5);
  StepOptions o;
  o.tolerance = 1e-8;
  UmatState end;
  const StepResult r = law.integrate(law.umat_state(s), de, o, &end);
  ASSERT_TRUE(r.success) << r.reason;
  EXPECT_GT(r.rejected, 0);
  EXPECT_GE(r.substeps, 50);  // 5e-5 in increments of at most 1e-6
  EXPECT_LE(end.statev[0], limit);
  // Only accepted increments reach the state: the strain and the sums add up to the increment.
  EXPECT_NEAR(end.statev[1], -de(0, 0), 1e-15);
  EXPECT_NEAR(end.statev[7], -de(0, 0), 1e-15);
  EXPECT_LE((end.strain - de).norm(), 1e-15);
  const StepResult b = integrate(*builtin, s, de, o);
  ASSERT_TRUE(b.success);
  EXPECT_LE((r.end.stress - b.end.stress).norm(), 20 * o.tolerance * b.end.stress.norm());
  // Without step doubling (one call per increment), the cuts alone decide the increments.
  o.adaptive = false;
  const StepResult f = law.integrate(law.umat_state(s), de, o, &end);
  ASSERT_TRUE(f.success) << f.reason;
  EXPECT_LE(end.statev[0], limit);
  EXPECT_NEAR(end.statev[7], -de(0, 0), 1e-15);
  // A path carries the whole STATEV from step to step.
  PathOptions po;
  po.steps = 4;
  const PathSeries p = law.run_path(s, 4.0 * de, po, &end);
  ASSERT_TRUE(p.success) << p.reason;
  EXPECT_NEAR(end.statev[7], -4.0 * de(0, 0), 1e-14);
  // The 50 increments the cuts need do not fit under a cap of 20: flagged as the cap, which
  // the calibration counts apart from other failures.
  o.max_substeps = 20;
  const StepResult c = law.integrate(law.umat_state(s), de, o, &end);
  EXPECT_FALSE(c.success);
  EXPECT_TRUE(c.on_substep_limit) << c.reason;
  EXPECT_NE(c.reason.find("more than 20 increments"), std::string::npos) << c.reason;
}

TEST(Umat, FortranPnewdtUmatStaysExact) {
  if (!have("linear_elastic")) GTEST_SKIP();
  UmatSpec spec = spec_of("linear_elastic");
  spec.props.push_back(3e-6);
  spec.prop_names.push_back("dstran_max");
  spec.lower.push_back(0.0);
  spec.upper.push_back(1.0);
  const UmatLaw law(umat_lib("linear_elastic"), spec);
  const EnvelopeRecord env =
      model_envelope(law, isotropic(law, 2e9), options(EnvelopeMethod::kIntegrated, 5e-5));
  const double k = law.parameter("K"), g = law.parameter("G");
  for (std::size_t i = 0; i < env.size(); ++i) {
    const Eigen::Matrix3d de = probe_strain(env.theta_deg[i], 5e-5);
    const Eigen::Matrix3d ds = k * de.trace() * Eigen::Matrix3d::Identity() +
                               2.0 * g * (de - de.trace() / 3.0 * Eigen::Matrix3d::Identity());
    EXPECT_LE((env.d_stress[i] - ds).norm(), 1e-10 * ds.norm());
  }
  EXPECT_GE(env.attributes.at("total_substeps"), 36 * 17);  // 5e-5 / 3e-6 > 16 increments per probe
}

TEST(Umat, EndlessPnewdtIsAClearError) {
  UmatSpec spec = spec_of("hypoplastic_wu");
  spec.props.push_back(1e-300);  // no increment is small enough
  spec.prop_names.push_back("dstran_max");
  spec.lower.push_back(0.0);
  spec.upper.push_back(1.0);
  const UmatLaw law(umat_lib("hypoplastic_wu"), spec);
  const StepResult r = law.integrate(law.umat_state(sheared(law)), probe_strain(0.0, 1e-4), {});
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.reason.find("PNEWDT"), std::string::npos) << r.reason;
  EXPECT_FALSE(r.on_substep_limit);  // it failed on the smallest increment, not on the cap
}

TEST(Umat, NanFromTheUmatNamesTheIncrement) {
  UmatSpec spec = spec_of("hypoplastic_wu");
  spec.props.push_back(0.0);     // no PNEWDT
  spec.props.push_back(1.5e-3);  // NaN once |STRAN + DSTRAN| > 1.5e-3
  spec.prop_names.insert(spec.prop_names.end(), {"dstran_max", "nan_beyond"});
  spec.lower.insert(spec.lower.end(), {0.0, 0.0});
  spec.upper.insert(spec.upper.end(), {1.0, 1.0});
  const UmatLaw law(umat_lib("hypoplastic_wu"), spec);
  PathOptions po;
  po.steps = 10;
  const PathSeries p = undrained_axisymmetric_path(law, isotropic(law, 1e5), -0.01, po);
  ASSERT_FALSE(p.success);
  EXPECT_NE(p.reason.find("NaN"), std::string::npos) << p.reason;
  EXPECT_NE(p.reason.find("STRESS"), std::string::npos) << p.reason;
  EXPECT_NE(p.reason.find("KINC = "), std::string::npos) << p.reason;
  EXPECT_EQ(p.reason.rfind("step 2 of 10", 0), 0u) << p.reason;  // |eps| passes 1.5e-3 in step 2
}

// A UMAT need not be thread-safe: with PROPS(7) the example UMAT keeps its new stress in a static
// buffer (as Fortran SAVE variables do). Two threads computing envelopes of two states at once
// got each other's stresses (envelopes 100x off); the adapter makes the calls take turns.
TEST(Umat, CallsFromTwoThreadsAtOnceTakeTurns) {
  UmatSpec spec = spec_of("hypoplastic_wu");
  spec.props.insert(spec.props.end(), {0.0, 0.0, 1.0});  // no PNEWDT, no NaN, a SAVE buffer
  spec.prop_names.insert(spec.prop_names.end(), {"dstran_max", "nan_beyond", "saved"});
  spec.lower.insert(spec.lower.end(), {0.0, 0.0, 0.0});
  spec.upper.insert(spec.upper.end(), {1.0, 1.0, 1.0});
  const UmatLaw law(umat_lib("hypoplastic_wu"), spec);
  const MaterialState a = isotropic(law, 1e5), b = sheared(law);
  EnvelopeOptions o = options(EnvelopeMethod::kIntegrated, 5e-5);
  o.directions = 360;
  const EnvelopeRecord serial_a = model_envelope(law, a, o), serial_b = model_envelope(law, b, o);
  for (int round = 0; round < 3; ++round) {
    EnvelopeRecord at_once_a, at_once_b;
    std::thread other([&] { at_once_b = model_envelope(law, b, o); });
    at_once_a = model_envelope(law, a, o);
    other.join();
    EXPECT_TRUE(rows_of(at_once_a.stress) == rows_of(serial_a.stress)) << "round " << round;
    EXPECT_TRUE(rows_of(at_once_b.stress) == rows_of(serial_b.stress)) << "round " << round;
  }
}

// A UMAT whose finite stresses (1e160 Pa, PROPS(8) of the example UMAT) change sign with the
// increment size: their squares overflowed norm(), the error estimate was NaN, which passed the
// tolerance test, and the first step was kept as exact (error estimate 0, stress -3e160). The
// estimate is now finite and rejects it; a stress that overflows the difference itself is a
// failure that says so.
TEST(Umat, StressesBeyondTheRangeOfTheirSquaresAreStillErrorControlled) {
  UmatSpec spec = spec_of("hypoplastic_wu");
  spec.props.insert(spec.props.end(), {0.0, 0.0, 0.0, 1e160});
  spec.prop_names.insert(spec.prop_names.end(), {"dstran_max", "nan_beyond", "saved", "huge"});
  spec.lower.insert(spec.lower.end(), {0.0, 0.0, 0.0, 0.0});
  spec.upper.insert(spec.upper.end(), {1.0, 1.0, 1.0, 1e300});
  const UmatLaw law(umat_lib("hypoplastic_wu"), spec);
  UmatState end;
  const StepResult r =
      law.integrate(law.umat_state(isotropic(law, 1e5)), probe_strain(30.0, 5e-5), {}, &end);
  ASSERT_TRUE(r.success) << r.reason;
  EXPECT_GT(r.rejected, 0);
  EXPECT_EQ(end.point.stress(0, 0), 1e160);  // compression positive: STRESS(1) = -1e160
  spec.props.back() = 1.7e308;               // the difference of two such stresses is not finite
  const UmatLaw beyond(umat_lib("hypoplastic_wu"), spec);
  const StepResult b = beyond.integrate(beyond.umat_state(isotropic(beyond, 1e5)),
                                        probe_strain(30.0, 5e-5), {}, &end);
  EXPECT_FALSE(b.success);
  EXPECT_NE(b.reason.find("the UMAT's stresses are too large for the driver"), std::string::npos)
      << b.reason;
}

TEST(Umat, MissingFileSymbolOrKeyIsAnInputError) {
  const UmatSpec spec = spec_of("hypoplastic_wu");
  EXPECT_NE(input_error([&] { UmatLaw("/nonexistent/umat.so", spec); }).find("no such file"),
            std::string::npos);
  EXPECT_NE(input_error([&] { UmatLaw(umat_lib("no_entry"), spec); }).find("exports no UMAT entry"),
            std::string::npos);
  // A file that is not a shared library: named once, though dlerror names it again.
  const std::string not_so = umat_params("hypoplastic_wu");
  const std::string why = input_error([&] { UmatLaw(not_so, spec); });
  EXPECT_EQ(why.rfind(not_so + ": cannot load the UMAT library: ", 0), 0u) << why;
  EXPECT_EQ(why.find("hypoplastic_wu_params.toml", not_so.size()), std::string::npos) << why;
  EXPECT_FALSE(input_error([&] { load_umat_parameters_toml("/nonexistent/p.toml"); }).empty());
  EXPECT_NE(
      input_error([&] { make_umat_law(umat_lib("hypoplastic_wu"), ""); }).find("parameters file"),
      std::string::npos);
}

TEST(Umat, APropNameGivenTwiceIsRefusedNamingIt) {
  const std::filesystem::path dir = std::filesystem::path(RENDULIC_TEST_TMP) / "umat_names";
  std::filesystem::create_directories(dir);
  const std::filesystem::path file = dir / "twice.toml";
  std::ofstream(file) << "props = [2e10, 2.5e9, 1.0]\nprop_names = [\"K\", \"G\", \"K\"]\n";
  EXPECT_EQ(input_error([&] { load_umat_parameters_toml(file.string()); }),
            file.string() + ": prop name 'K' given twice");
  // An empty list fell back to prop1, prop2, ...; a name with a comma was accepted and then
  // split by --free ("unknown parameter 'bad name'").
  std::ofstream(file) << "props = [2e10, 2.5e9]\nprop_names = []\n";
  EXPECT_EQ(input_error([&] { load_umat_parameters_toml(file.string()); }),
            file.string() + ": 'prop_names' has 0 names for 2 props");
  for (const char* bad : {"K,G", "bad name", "E=1", "3"}) {
    std::ofstream(file) << "props = [2e10, 2.5e9]\nprop_names = [\"" << bad << "\", \"G2\"]\n";
    EXPECT_EQ(input_error([&] { load_umat_parameters_toml(file.string()); }),
              file.string() + ": prop name '" + bad +
                  "' must be letters, digits and '_', starting with a letter or '_'");
  }
  std::ofstream(file) << "props = [2e10, 2.5e9]\n";  // no names: prop1, prop2
  EXPECT_EQ(load_umat_parameters_toml(file.string()).prop_names,
            (std::vector<std::string>{"prop1", "prop2"}));
}

}  // namespace
}  // namespace rendulic::models
