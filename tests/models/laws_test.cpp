// Unit tests of the four laws (docs/models.md sections 1-4): parameter tables,
// tangents against central finite differences and against automatic differentiation
// (ceres::Jet through the templated laws), the pinned anisotropic form against its scalar
// form, the loading/unloading behaviour of elastoplastic_fabric, and every law's objectivity
// (a rotated state and strain give the rotated increments).
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>

#include "rendulic/models/elastic_laws.hpp"
#include "rendulic/models/elastoplastic_fabric.hpp"
#include "rendulic/models/hypoplastic_wu.hpp"
#include "rendulic/models/law.hpp"

namespace rendulic::models {
namespace {

// A generic (non-axisymmetric) compressive stress with some shear, Pa.
Eigen::Matrix3d test_stress(double p) {
  Eigen::Matrix3d s;
  s << 1.1, 0.05, -0.02, 0.05, 0.95, 0.03, -0.02, 0.03, 0.9;
  return p * s;
}
Eigen::Matrix3d test_fabric() {
  Eigen::Matrix3d f;
  f << 1.6, 0.04, 0.0, 0.04, 2.1, -0.03, 0.0, -0.03, 2.0;
  return f;
}
Eigen::Matrix3d test_strain() {
  Eigen::Matrix3d e;
  e << 0.7, 0.2, -0.1, 0.2, -0.4, 0.3, -0.1, 0.3, 0.2;
  return e / e.norm();
}

// Central differences of the rate in the Mandel components of d_eps. The laws are piecewise
// linear or smooth in d_eps at fixed state, so the truncation error vanishes (linear) or is
// O(h^2) relative to |d_eps| = 1; h = 1e-6 leaves rounding ~1e-16 * |D| / 1e-6 = 1e-10 |D|.
Matrix6d fd_tangent(const Law& law, const MaterialState& s, const Eigen::Matrix3d& de) {
  const double h = 1e-6;
  Matrix6d t;
  const Vector6d e0 = to_mandel(de);
  for (int j = 0; j < 6; ++j) {
    Vector6d ep = e0, em = e0;
    ep(j) += h;
    em(j) -= h;
    t.col(j) = (to_mandel(law.rate(s, from_mandel(ep)).d_stress) -
                to_mandel(law.rate(s, from_mandel(em)).d_stress)) /
               (2 * h);
  }
  return t;
}

// FD agreement: relative to the tangent's norm; 1e-7 is three orders above the rounding floor.
constexpr double kFdTol = 1e-7;

TEST(Laws, RegistryAndDefaultsWithinBounds) {
  for (const std::string& name : law_names()) {
    auto law = make_law(name);
    ASSERT_TRUE(law) << name;
    EXPECT_EQ(law->name(), name);
    for (size_t i = 0; i < law->parameter_info().size(); ++i) {
      const auto& p = law->parameter_info()[i];
      EXPECT_LE(p.lower, p.default_value) << name << "." << p.name;
      EXPECT_GE(p.upper, p.default_value) << name << "." << p.name;
      EXPECT_EQ(law->parameters()[i], p.default_value);
    }
  }
  EXPECT_EQ(make_law("cam_clay"), nullptr);
}

TEST(Laws, SetParametersChecksBoundsAndNamesTheCulprit) {
  auto law = make_law("anisotropic_elastic");
  std::string why;
  EXPECT_FALSE(law->set_parameter("B", -5.0, &why));
  EXPECT_NE(why.find("B"), std::string::npos);
  EXPECT_EQ(law->parameter("B"), 2.0e10);  // unchanged on failure
  EXPECT_FALSE(law->set_parameter("nope", 1.0, &why));
  EXPECT_NE(why.find("nope"), std::string::npos);
  EXPECT_FALSE(law->set_parameter("G", std::nan(""), &why));
  EXPECT_TRUE(law->set_parameter("beta_A", 0.7, &why));
  EXPECT_EQ(law->parameter("beta_A"), 0.7);
  EXPECT_FALSE(law->set_parameters({1.0, 2.0}, &why));
}

TEST(Laws, TangentsMatchFiniteDifferences) {
  for (const std::string& name : law_names()) {
    auto law = make_law(name);
    std::string why;
    ASSERT_TRUE(law->set_parameter(name == "hypoplastic_wu" ? "c1" : "n_p",
                                   name == "hypoplastic_wu" ? -120.0 : 0.5, &why));
    MaterialState s = law->make_state(test_stress(2e9), test_fabric(), 0.8);
    for (const Eigen::Matrix3d& de : {test_strain(), Eigen::Matrix3d(-test_strain())}) {
      const Matrix6d t = law->tangent(s, de);
      const Matrix6d fd = fd_tangent(*law, s, de);
      EXPECT_LE((t - fd).norm(), kFdTol * t.norm()) << name << "\n" << t << "\n" << fd;
    }
  }
}

TEST(Laws, ElastoplasticPlasticBranchTangentMatchesFiniteDifferences) {
  auto law = make_law("elastoplastic_fabric");
  MaterialState s = law->make_state(test_stress(2e9), test_fabric(), 0.8);
  // Put the state on the yield surface: alpha = r - m_e n for a direction n.
  const double p = s.stress.trace() / 3.0;
  const Eigen::Matrix3d r = deviator(s.stress) / p;
  Eigen::Matrix3d n = deviator(test_strain());
  n /= n.norm();
  s.internal = to_mandel(Eigen::Matrix3d(r - law->parameter("m_e") * n));
  // Loading along n is plastic; its tangent must differ from the elastic one.
  const Matrix6d t_load = law->tangent(s, n);
  const Matrix6d t_unload = law->tangent(s, -n);
  EXPECT_GT((t_load - t_unload).norm(), 1e-3 * t_unload.norm());
  EXPECT_LE((t_load - fd_tangent(*law, s, n)).norm(), kFdTol * t_load.norm());
  EXPECT_LE((t_unload - fd_tangent(*law, s, -n)).norm(), kFdTol * t_unload.norm());
  // Consistency: a plastic rate keeps the state on the surface to first order.
  const LawRate rate = law->rate(s, 1e-9 * n);
  const Eigen::Matrix3d sig = s.stress + rate.d_stress;
  const Eigen::Matrix3d xi =
      deviator(sig) / (sig.trace() / 3.0) - from_mandel(Vector6d(s.internal + rate.d_internal));
  // |xi| - m_e is second order in the 1e-9 step: ~ (1e-9 * |D|/P)^2 ~ 1e-17.
  EXPECT_NEAR(xi.norm(), law->parameter("m_e"), 1e-13);
}

// Jets through the templated law: an independent derivative of the same rate code path.
template <class M>
Matrix6d jet_tangent(const std::vector<double>& params, const MaterialState& s,
                     const Eigen::Matrix3d& de) {
  using J = ceres::Jet<double, 6>;
  std::vector<J> p(params.begin(), params.end());
  StateT<J> sj;
  sj.stress = s.stress.cast<J>();
  sj.fabric = s.fabric.cast<J>();
  sj.internal = s.internal.cast<J>();
  sj.volume_fraction = J(s.volume_fraction);
  Vec6<J> e;
  const Vector6d e0 = to_mandel(de);
  for (int i = 0; i < 6; ++i) e(i) = J(e0(i), i);
  const RateT<J> r = M::template rate<J>(p.data(), sj, from_mandel<J>(e));
  const Vec6<J> ds = to_mandel<J>(r.d_stress);
  Matrix6d t;
  for (int i = 0; i < 6; ++i) t.row(i) = ds(i).v.transpose();
  return t;
}

TEST(Laws, AutodiffThroughTemplatedLawsMatchesAnalyticTangent) {
  const MaterialState base = [] {
    MaterialState s;
    s.stress = test_stress(1e6);
    s.fabric = test_fabric();
    return s;
  }();
  const Eigen::Matrix3d de = test_strain();
  {
    auto law = make_law("anisotropic_elastic");
    const Matrix6d t = jet_tangent<AnisotropicElastic>(law->parameters(), base, de);
    EXPECT_LE((t - law->tangent(base, de)).norm(), 1e-12 * t.norm());
  }
  {
    auto law = make_law("hypoplastic_wu");
    const Matrix6d t = jet_tangent<HypoplasticWu>(law->parameters(), base, de);
    EXPECT_LE((t - law->tangent(base, de)).norm(), 1e-12 * t.norm());
  }
  {
    auto law = make_law("elastoplastic_fabric");
    MaterialState s = base;
    const double p = s.stress.trace() / 3.0;
    Eigen::Matrix3d n = deviator(de);
    n /= n.norm();
    s.internal = to_mandel(Eigen::Matrix3d(deviator(s.stress) / p - law->parameter("m_e") * n));
    const Matrix6d t = jet_tangent<ElastoplasticFabric>(law->parameters(), s, de);
    EXPECT_LE((t - law->tangent(s, de)).norm(), 1e-12 * t.norm());
  }
}

// Calibration differentiates with respect to the parameters: Jets seeded on the parameter
// vector must match central differences of the double-precision law (smooth laws; relative
// step 1e-6, agreement 1e-6 covers truncation ~1e-12 and rounding ~1e-10 relative).
template <class M>
void expect_parameter_jacobian(const Law& law, const MaterialState& s, const Eigen::Matrix3d& de) {
  constexpr int kN = 16;
  using J = ceres::Jet<double, kN>;
  const std::vector<double>& p0 = law.parameters();
  ASSERT_LE(p0.size(), static_cast<size_t>(kN));
  std::vector<J> p;
  for (size_t i = 0; i < p0.size(); ++i) p.push_back(J(p0[i], static_cast<int>(i)));
  StateT<J> sj;
  sj.stress = s.stress.cast<J>();
  sj.fabric = s.fabric.cast<J>();
  sj.internal = s.internal.cast<J>();
  sj.volume_fraction = J(s.volume_fraction);
  const Mat3<J> dej = de.cast<J>();
  const Vec6<J> ds = to_mandel<J>(M::template rate<J>(p.data(), sj, dej).d_stress);
  for (size_t k = 0; k < p0.size(); ++k) {
    const double h = 1e-6 * std::max(std::abs(p0[k]), 1e-3);
    std::vector<double> pp = p0, pm = p0;
    pp[k] += h;
    pm[k] -= h;
    const Vector6d fd = (to_mandel(M::template rate<double>(pp.data(), s, de).d_stress) -
                         to_mandel(M::template rate<double>(pm.data(), s, de).d_stress)) /
                        (2 * h);
    Vector6d jet;
    for (int i = 0; i < 6; ++i) jet(i) = ds(i).v(static_cast<int>(k));
    const double scale =
        std::max(to_mandel(law.rate(s, de).d_stress).norm() / std::abs(p0[k] + 1e-300), fd.norm());
    EXPECT_LE((jet - fd).norm(), 1e-6 * scale + 1e-12)
        << law.name() << " d/d" << law.parameter_info()[k].name;
  }
}

TEST(Laws, ParameterDerivativesThroughJetsMatchFiniteDifferences) {
  MaterialState s;
  s.stress = test_stress(1e9);
  s.fabric = test_fabric();
  const Eigen::Matrix3d de = 1e-4 * test_strain();
  s.volume_fraction = 0.8;
  auto iso = make_law("isotropic_elastic");
  std::string why;
  ASSERT_TRUE(iso->set_parameter("n_p", 0.4, &why));
  ASSERT_TRUE(iso->set_parameter("n_nu", 3.0, &why));
  expect_parameter_jacobian<IsotropicElastic>(*iso, s, de);
  auto ani = make_law("anisotropic_elastic");
  ASSERT_TRUE(ani->set_parameter("n_p", 0.4, &why));
  ASSERT_TRUE(ani->set_parameter("a_G", 2.0, &why));
  ASSERT_TRUE(ani->set_parameter("n_nu", 3.0, &why));
  expect_parameter_jacobian<AnisotropicElastic>(*ani, s, de);
  auto hyp = make_law("hypoplastic_wu");
  expect_parameter_jacobian<HypoplasticWu>(*hyp, s, de);
}

TEST(Laws, StateDependenceOfModuliIsTheDocumentedOne) {
  auto law = make_law("anisotropic_elastic");
  std::string why;
  ASSERT_TRUE(law->set_parameters({1e10, 2e9, 0.0, 0.5, 1e9, 2.0, 5.0, 3.0, 0.82}, &why)) << why;
  const Eigen::Matrix3d fabric = Eigen::Vector3d(1.6, 2.2, 2.2).asDiagonal();
  const MaterialState s = law->make_state(Eigen::Matrix3d::Identity() * 4e9, fabric, 0.8);
  const double factor = std::sqrt(4.0) * std::pow(0.8 / 0.82, 3.0);
  const double b = 1e10 * factor;
  const double g = 2e9 * factor / (1.0 + 2.0 * deviator(fabric).squaredNorm());
  const Eigen::Matrix3d iso = Eigen::Matrix3d::Identity() * 1e-5;
  EXPECT_NEAR(law->rate(s, iso).d_stress.trace() / 3.0, b * 3e-5, 1e-12 * b * 3e-5);
  const Eigen::Matrix3d shear = probe_strain(kDevCompressionDeg, 1e-5);
  EXPECT_NEAR(signed_deviator(law->rate(s, shear).d_stress), 2 * g * signed_deviator(shear),
              1e-12 * 2 * g * 1e-5);
  // Without a volume fraction in the state (nu = 0) the factor is 1, never 0 or NaN.
  MaterialState no_nu = s;
  no_nu.volume_fraction = 0.0;
  EXPECT_NEAR(law->rate(no_nu, iso).d_stress.trace() / 3.0, 1e10 * 2.0 * 3e-5, 1e-12 * 1e10);
}

TEST(Laws, AnisotropicTensorFormReducesToPinnedScalarForm) {
  auto law = make_law("anisotropic_elastic");
  const double b = law->parameter("B"), g = law->parameter("G"), beta = law->parameter("beta_A");
  // Axisymmetric fabric with extension (F_xx < F_yy = F_zz): F_dev < 0.
  const Eigen::Matrix3d fabric = Eigen::Vector3d(1.7, 2.1, 2.1).asDiagonal();
  const MaterialState s = law->make_state(Eigen::Matrix3d::Identity() * 1e9, fabric, 0.8);
  const double f_dev = signed_deviator(fabric);
  ASSERT_LT(f_dev, 0.0);
  const double a = beta * f_dev * b;
  for (double theta : {0.0, 35.26, 77.0, 125.26, 200.0, 305.26}) {
    const Eigen::Matrix3d de = probe_strain(theta, 1e-4);
    const double ev = volumetric_strain(de);
    // Axisymmetric signed deviator along the unit axial direction diag(2,-1,-1)/sqrt6.
    const Eigen::Matrix3d n_ax =
        Eigen::Vector3d(Eigen::Vector3d(2, -1, -1) / std::sqrt(6.0)).asDiagonal();
    const double ed = (de.array() * n_ax.array()).sum();
    const Eigen::Matrix3d ds = law->rate(s, de).d_stress;
    const double dp = ds.trace() / 3.0;
    const double dsd = (ds.array() * n_ax.array()).sum();
    const double scale = b * 1e-4;
    EXPECT_NEAR(dp, b * ev + a * ed, 1e-12 * scale) << theta;
    EXPECT_NEAR(dsd, a * ev + 2 * g * ed, 1e-12 * scale) << theta;
    // Stays axisymmetric.
    EXPECT_NEAR(ds(1, 1), ds(2, 2), 1e-12 * scale);
  }
}

TEST(Laws, HypoplasticIsRateIndependentAndStressHomogeneous) {
  auto law = make_law("hypoplastic_wu");
  const MaterialState s = law->make_state(test_stress(1e5), Eigen::Matrix3d::Zero(), 0.6);
  const Eigen::Matrix3d de = 1e-4 * test_strain();
  const Eigen::Matrix3d r1 = law->rate(s, de).d_stress;
  // Degree 1 in d_eps (rate independence) and in sigma (no intrinsic stress scale).
  EXPECT_LE((law->rate(s, 3.0 * de).d_stress - 3.0 * r1).norm(), 1e-12 * r1.norm());
  MaterialState s2 = s;
  s2.stress *= 7.0;
  EXPECT_LE((law->rate(s2, de).d_stress - 7.0 * r1).norm(), 1e-12 * 7.0 * r1.norm());
  // Loading isotropic compression is softer than unloading (incremental non-linearity).
  const MaterialState iso =
      law->make_state(1e5 * Eigen::Matrix3d::Identity(), Eigen::Matrix3d::Zero(), 0.6);
  const Eigen::Matrix3d c = 1e-4 * Eigen::Matrix3d::Identity();
  const double k_load = law->rate(iso, c).d_stress.trace();
  const double k_unload = -law->rate(iso, Eigen::Matrix3d(-c)).d_stress.trace();
  EXPECT_GT(k_load, 0.0);
  EXPECT_GT(k_unload, k_load);
  std::string why;
  MaterialState tension = iso;
  tension.stress *= -1.0;
  EXPECT_FALSE(law->admissible(tension, &why));
  EXPECT_NE(why.find("tr(sigma)"), std::string::npos);
}

TEST(Laws, ElastoplasticSmallProbesElasticLargeProbesNot) {
  auto ep = make_law("elastoplastic_fabric");
  auto el = make_law("anisotropic_elastic");
  const Eigen::Matrix3d stress = Eigen::Vector3d(1.8e9, 2.2e9, 2.2e9).asDiagonal();
  const Eigen::Matrix3d fabric = Eigen::Vector3d(1.8, 2.0, 2.0).asDiagonal();
  const MaterialState s = ep->make_state(stress, fabric, 0.82);
  // A relaxed state sits at the centre of its elastic domain: the first rate is elastic in
  // every direction, identical to anisotropic_elastic, with no deviatoric fabric change.
  for (double theta : {kIsoCompressionDeg, kDevCompressionDeg, kDevExtensionDeg, 10.0}) {
    const Eigen::Matrix3d de = probe_strain(theta, 5e-5);
    const LawRate r = ep->rate(s, de);
    const LawRate e = el->rate(s, de);
    EXPECT_LE((r.d_stress - e.d_stress).norm(), 1e-12 * r.d_stress.norm());
    EXPECT_LE((r.d_fabric - e.d_fabric).norm(), 1e-12 * std::max(e.d_fabric.norm(), 1e-12));
    EXPECT_EQ(r.d_internal.norm(), 0.0);
  }
  // A constant-volume probe changes no fabric at all while elastic (seed Fig. 4).
  EXPECT_LE(ep->rate(s, probe_strain(kDevExtensionDeg, 5e-5)).d_fabric.norm(), 1e-15);
  // On the yield surface (after loading along n), the same small probe along n is plastic:
  // the back ratio moves and the deviatoric fabric changes.
  MaterialState on = s;
  const Eigen::Matrix3d n =
      Eigen::Vector3d(Eigen::Vector3d(-2, 1, 1) / std::sqrt(6.0)).asDiagonal();
  on.internal -= to_mandel(Eigen::Matrix3d(ep->parameter("m_e") * n));
  const LawRate r = ep->rate(on, 5e-5 * n);
  EXPECT_GT(r.d_internal.norm(), 0.0);
  EXPECT_LT(signed_deviator(Eigen::Matrix3d(fabric + r.d_fabric)), signed_deviator(fabric));
}

// The laws are isotropic functions of their tensor arguments (objectivity, docs/models.md):
// rotating the state (stress, fabric, back ratio) and the strain increment by any Q rotates the
// increments by the same Q. DEM states and probes are axisymmetric along fixed axes, so no other
// test would see a law that used components in the lab's frame.
TEST(Laws, RotatingTheStateAndTheStrainRotatesTheRate) {
  const Eigen::Matrix3d Q =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.3, -0.5, 0.8).normalized()).toRotationMatrix();
  auto rotated = [&](const Eigen::Matrix3d& a) { return Eigen::Matrix3d(Q * a * Q.transpose()); };
  for (const std::string& name : law_names()) {
    auto law = make_law(name);
    for (const bool on_surface : {false, true}) {
      if (on_surface && name != "elastoplastic_fabric") continue;
      MaterialState s = law->make_state(test_stress(2e9), test_fabric(), 0.8);
      Eigen::Matrix3d de = test_strain();
      if (on_surface) {  // as in ElastoplasticPlasticBranchTangentMatchesFiniteDifferences
        Eigen::Matrix3d n = deviator(test_strain());
        n /= n.norm();
        s.internal = to_mandel(Eigen::Matrix3d(deviator(s.stress) / (s.stress.trace() / 3.0) -
                                               law->parameter("m_e") * n));
        de = n;
      }
      MaterialState r = s;
      r.stress = rotated(s.stress);
      r.fabric = rotated(s.fabric);
      r.internal = to_mandel(rotated(from_mandel(s.internal)));
      const LawRate a = law->rate(s, de);
      const LawRate b = law->rate(r, rotated(de));
      // Round-off: 2e-16 elastic; 4e-12 on the surface, where the plastic multiplier divides by
      // a difference of nearly equal terms.
      const double tol = on_surface ? 1e-10 : 1e-14;
      const std::string what = name + (on_surface ? " on its yield surface" : "");
      EXPECT_EQ(a.plastic, on_surface) << what;
      EXPECT_EQ(b.plastic, a.plastic) << what;
      EXPECT_LE((rotated(a.d_stress) - b.d_stress).norm(), tol * a.d_stress.norm()) << what;
      EXPECT_LE((rotated(a.d_fabric) - b.d_fabric).norm(), tol * a.d_fabric.norm()) << what;
      EXPECT_LE((rotated(from_mandel(a.d_internal)) - from_mandel(b.d_internal)).norm(),
                tol * std::max(1.0, a.d_internal.norm()))
          << what;
      const double f = law->yield_function(s);  // -inf without a yield surface
      if (std::isinf(f))
        EXPECT_EQ(law->yield_function(r), f) << what;
      else
        EXPECT_NEAR(law->yield_function(r), f, 1e-12) << what;
      EXPECT_LE((from_mandel(law->initial_internal(r.stress, r.fabric)) -
                 rotated(from_mandel(law->initial_internal(s.stress, s.fabric))))
                    .norm(),
                1e-14)
          << what;
    }
  }
}

}  // namespace
}  // namespace rendulic::models
