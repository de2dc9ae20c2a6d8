// Linear response of the contact network: closed-form elastic constants of a
// compressed FCC lattice including the pre-stress terms, detection of an unstable lattice,
// symmetries and positive definiteness on a jammed random packing, rattler handling, and the
// negative modes of a doubled packing counted against a dense eigensolver (docs/probes.md).
#include "rendulic/dem/linear_response.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>

#include "rendulic/core/errors.hpp"
#include "rendulic/dem/probe_campaign.hpp"
#include "rendulic/dem/probe_minimise.hpp"
#include "rendulic/dem/probe_options.hpp"
#include "rendulic/dem/protocols.hpp"
#include "rendulic/dem/rest.hpp"

namespace rendulic::dem {
namespace {

constexpr double kK = 1e8;

// n^3 cubic cells of a lattice with `basis` (fractional), cubic edge a, equal radii R.
PackingData cubic_lattice(int cells, double a, double radius,
                          const std::vector<Eigen::Vector3d>& basis) {
  const int n = cells * cells * cells * static_cast<int>(basis.size());
  Eigen::MatrixX3d x(n, 3);
  int p = 0;
  for (int i = 0; i < cells; ++i)
    for (int j = 0; j < cells; ++j)
      for (int k = 0; k < cells; ++k)
        for (const Eigen::Vector3d& b : basis) {
          x.row(p++) = (a * (Eigen::Vector3d(i, j, k) + b)).transpose();
        }
  return PackingData::orthorhombic(x, Eigen::VectorXd::Constant(n, radius),
                                   Eigen::Vector3d::Constant(cells * a));
}

// Compressed FCC lattice, nearest-neighbour distance r0 < 2R, contact force f = k (2R - r0),
// volume per particle V_a = a^3/4, 6 bonds per particle along <110>/sqrt2.
// Bond sums: sum n_x^4 = 1, sum n_x^2 n_y^2 = 1/2, sum n n = 2 I, so with B = k r0^2 + f r0:
//   Born:       C11_B = B / V_a,  C12_B = C44_B = B / (2 V_a)  (C44 as the tensor C_xyxy)
//   pressure:   p = 2 f r0 / V_a  (stress = p I, compression positive)
// The Cauchy stress rate of a probe (stress in the deformed cell) adds the pre-stress terms
// -p (d_ik d_jl + d_il d_jk) + p d_ij d_kl (tension frame; the matrix is the same in the
// compression frame), and the non-affine part vanishes (every site is a centre of inversion):
//   C11 = B/V_a - p,  C12 = B/(2 V_a) + p,  C44 = B/(2 V_a) - p.
// Check of the pre-stress terms by hand: isotropic compression by e changes
// p = 2 f r0 / V_a by dp = (2 k r0^2 + 4 f r0) e / V_a = (C11 + 2 C12) e.
TEST(LinearResponse, CompressedFccMatchesClosedForm) {
  const double radius = 1e-3, r0 = 1.98e-3;  // 1 % overlap: pre-stress terms ~ 1 % of Born
  const double a = r0 * std::numbers::sqrt2;
  const PackingData fcc =
      cubic_lattice(3, a, radius, {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}});
  LinearResponseOptions opt;
  opt.k = kK;
  const LinearResponse lr = linear_response(fcc, opt);
  ASSERT_TRUE(lr.ok) << lr.message;
  EXPECT_EQ(lr.n_rattlers, 0);
  EXPECT_EQ(lr.n_backbone_contacts, 6 * fcc.size());

  const double f = kK * (2.0 * radius - r0), va = a * a * a / 4.0;
  const double born = kK * r0 * r0 + f * r0, p = 2.0 * f * r0 / va;
  const double c11 = born / va - p, c12 = born / (2.0 * va) + p, c44 = born / (2.0 * va) - p;
  Matrix6d expected = Matrix6d::Zero();
  expected.topLeftCorner<3, 3>().setConstant(c12);
  expected.topLeftCorner<3, 3>().diagonal().setConstant(c11);
  expected.bottomRightCorner<3, 3>().diagonal().setConstant(2.0 * c44);  // Mandel: 2 C_xyxy
  // Round-off only: sums of ~10^3 terms of one sign.
  constexpr double kRelTol = 1e-10;
  EXPECT_LE((lr.stiffness - expected).cwiseAbs().maxCoeff(), kRelTol * c11)
      << "computed\n"
      << lr.stiffness << "\nexpected\n"
      << expected;
  EXPECT_NEAR(lr.stress(0, 0), p, kRelTol * p);
  EXPECT_LE((lr.stress - p * Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), kRelTol * p);
  // The pre-stress terms matter at this precision: without them C12 would be off by p.
  EXPECT_GT(p, 1e3 * kRelTol * c11);
  // A Bravais lattice has no non-affine relaxation.
  EXPECT_LE((lr.stiffness - lr.affine_stiffness).cwiseAbs().maxCoeff(), kRelTol * c11);
  EXPECT_LT(lr.residual_force_ratio, 1e-12);
}

// Frictionless simple cubic lattice under compression: shearing lattice planes over each other
// only meets the negative geometric stiffness -f/|l| of the loaded contacts, so the lattice is
// unstable. The linear response must say so instead of returning numbers.
TEST(LinearResponse, UnstableSimpleCubicIsDetected) {
  const PackingData sc = cubic_lattice(4, 1.98e-3, 1e-3, {{0, 0, 0}});
  const LinearResponse lr = linear_response(sc, LinearResponseOptions{});
  EXPECT_FALSE(lr.ok);
  EXPECT_GT(lr.n_negative_pivots, 0);
  EXPECT_NE(lr.message.find("unstable"), std::string::npos) << lr.message;
  EXPECT_TRUE(lr.stiffness.array().isNaN().all());
}

TEST(LinearResponse, GasHasNoBackbone) {
  const PackingData gas = cubic_lattice(3, 3e-3, 1e-3, {{0, 0, 0}});
  const LinearResponse lr = linear_response(gas, LinearResponseOptions{});
  EXPECT_FALSE(lr.ok);
  EXPECT_EQ(lr.n_rattlers, gas.size());
  EXPECT_NE(lr.message.find("not jammed"), std::string::npos) << lr.message;
}

TEST(LinearResponse, RejectsBadInput) {
  PackingData bad = cubic_lattice(3, 3e-3, 1e-3, {{0, 0, 0}});
  bad.radii(0) = std::nan("");
  EXPECT_THROW(linear_response(bad, LinearResponseOptions{}), InputError);
  LinearResponseOptions opt;
  opt.k = -1.0;
  std::string why;
  EXPECT_FALSE(opt.IsValid(&why));
  EXPECT_THROW(linear_response(cubic_lattice(3, 3e-3, 1e-3, {{0, 0, 0}}), opt), InputError);
}

// 250 random spheres at volume fraction `nu`, minimised (FIRE) to 1e-10 of the mean force.
PackingData jammed_packing(double nu, std::uint64_t seed) {
  GeneratedPackingOptions g;
  g.n = 250;
  g.volume_fraction = nu;
  g.seed = seed;
  g.minimise.force_tolerance = 1e-10;
  MinimiseSummary s;
  PackingData p = generate_packing(g, &s);
  EXPECT_TRUE(s.converged) << s.message;
  return p;
}

class JammedPacking : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    packing_ = new PackingData(jammed_packing(0.70, 7));
    response_ = new LinearResponse(linear_response(*packing_, LinearResponseOptions{}));
  }
  static void TearDownTestSuite() {
    delete packing_;
    delete response_;
  }
  static PackingData* packing_;
  static LinearResponse* response_;
};
PackingData* JammedPacking::packing_ = nullptr;
LinearResponse* JammedPacking::response_ = nullptr;

// The Cauchy stress rate of a pre-stressed network is not major-symmetric: the volume change
// of the cell contributes sigma tr(d_eps), i.e. -sigma (x) I. The Kirchhoff stress rate
// d(J sigma) = (C - sigma (x) I) d_eps is the second derivative of the (relaxed) energy plus
// the symmetric term (d_eps sigma + sigma d_eps)/2, hence major-symmetric.
TEST_F(JammedPacking, KirchhoffStiffnessIsSymmetricAndPositiveDefinite) {
  const LinearResponse& lr = *response_;
  ASSERT_TRUE(lr.ok) << lr.message;
  EXPECT_LT(lr.residual_force_ratio, 1e-9);
  const double scale = lr.stiffness.cwiseAbs().maxCoeff();
  const Matrix6d kirchhoff =
      lr.stiffness - to_mandel(lr.stress) * to_mandel(Eigen::Matrix3d::Identity()).transpose();
  // Exact at equilibrium; the residual forces (1e-10 of the mean contact force) and round-off
  // break it at that order only.
  EXPECT_LE((kirchhoff - kirchhoff.transpose()).cwiseAbs().maxCoeff(), 1e-9 * scale);
  // The Cauchy rate itself is asymmetric by the anisotropic part of the stress (a few % of P
  // in a 250-particle packing): the test above is not vacuous.
  EXPECT_GT((lr.stiffness - lr.stiffness.transpose()).cwiseAbs().maxCoeff(), 1e-6 * scale);
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(0.5 *
                                                    (lr.stiffness + lr.stiffness.transpose()));
  EXPECT_GT(eig.eigenvalues()(0), 0.0) << eig.eigenvalues().transpose();
  // Relaxation only lowers the stiffness: affine - C = Xi^T H^-1 Xi / V is positive
  // semi-definite, and substantial in a disordered packing.
  const Matrix6d relax = lr.affine_stiffness - lr.stiffness;
  EXPECT_LE((relax - relax.transpose()).cwiseAbs().maxCoeff(), 1e-9 * scale);
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig_relax(0.5 * (relax + relax.transpose()));
  EXPECT_GT(eig_relax.eigenvalues()(0), -1e-9 * scale);
  EXPECT_GT(relax.trace(), 0.05 * lr.affine_stiffness.trace());
}

TEST_F(JammedPacking, RattlersAreRemovedIteratively) {
  const LinearResponse& lr = *response_;
  ASSERT_TRUE(lr.ok) << lr.message;
  // Every backbone particle keeps at least 4 backbone contacts.
  std::vector<int> count(packing_->size(), 0);
  for (const PairGeometry& c : find_pairs(*packing_, 0.0)) {
    if (c.overlap > 0 && lr.backbone[c.i] && lr.backbone[c.j]) {
      ++count[c.i];
      ++count[c.j];
    }
  }
  int kept = 0;
  for (int p = 0; p < packing_->size(); ++p) {
    if (lr.backbone[p]) {
      ++kept;
      EXPECT_GE(count[p], 4) << "particle " << p;
    }
  }
  EXPECT_EQ(kept + lr.n_rattlers, packing_->size());
  EXPECT_GT(kept, packing_->size() / 2);
  // Isostaticity bound: a stable backbone has at least 2 * 3 contacts per particle (minus
  // the global translations).
  EXPECT_GE(lr.n_backbone_contacts, 3 * (kept - 1));
}

// Two copies of a stable periodic packing side by side, along axis `axis`: the same contacts,
// each twice, in a cell twice as long. Every force still balances, but the new cell holds modes
// of twice the old period, which the small cell forbade.
PackingData doubled(const PackingData& p, int axis) {
  const int n = p.size();
  Eigen::MatrixX3d x(2 * n, 3);
  x << p.positions, p.positions;
  x.bottomRows(n).col(axis).array() += p.cell.lengths()(axis);
  Eigen::VectorXd r(2 * n);
  r << p.radii, p.radii;
  Eigen::Vector3d lengths = p.cell.lengths();
  lengths(axis) *= 2.0;
  return PackingData::orthorhombic(x, r, lengths);
}

// The negative eigenvalues of the Hessian of the backbone's energy, by a dense eigensolver: a
// second method for the LDL^T's pivot count. Each contact of stiffness k and force f = k
// overlap adds k n n^T - (f / |l|) (I - n n^T) to its two diagonal blocks and minus that to its
// off-diagonal ones.
Eigen::MatrixXd dense_hessian(const PackingData& p, const std::vector<char>& backbone) {
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(3 * p.size(), 3 * p.size());
  for (const PairGeometry& c : find_pairs(p, 0.0)) {
    if (!(c.overlap > 0.0) || !backbone[c.i] || !backbone[c.j]) continue;
    const Eigen::Vector3d n = c.l / c.distance;
    const Eigen::Matrix3d nn = n * n.transpose();
    const Eigen::Matrix3d block =
        kK * nn - (kK * c.overlap / c.distance) * (Eigen::Matrix3d::Identity() - nn);
    h.block<3, 3>(3 * c.i, 3 * c.i) += block;
    h.block<3, 3>(3 * c.j, 3 * c.j) += block;
    h.block<3, 3>(3 * c.i, 3 * c.j) -= block;
    h.block<3, 3>(3 * c.j, 3 * c.i) -= block;
  }
  return h;
}
Eigen::VectorXd dense_eigenvalues(const PackingData& p, const std::vector<char>& backbone) {
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(dense_hessian(p, backbone),
                                                        Eigen::EigenvaluesOnly)
      .eigenvalues();
}
int negative_eigenvalues(const PackingData& p, const std::vector<char>& backbone) {
  const Eigen::VectorXd w = dense_eigenvalues(p, backbone);
  // Rattlers and the translations are exact zeros; round-off leaves them at 1e-12 k or so.
  return static_cast<int>((w.array() < -1e-9 * kK).count());
}

// Replicating a periodic packing is a common way to make a larger one, and it need not give a
// stable one: of 54 doublings of 250-sphere packings (nu 0.66, 0.70, 0.75; seeds 1-6; each
// axis), 15 had modes of negative stiffness (docs/probes.md, "Replicated packings"). This packing,
// doubled along each axis, has 1, 2 and 1. The linear response must count the same negative
// modes as the dense eigensolver, refuse those doublings, and keep every contact twice.
TEST(LinearResponse, ADoubledPackingsNegativeModesAreCountedExactly) {
  const PackingData one = jammed_packing(0.70, 6);
  const LinearResponse single = linear_response(one, LinearResponseOptions{});
  ASSERT_TRUE(single.ok) << single.message;
  int unstable = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const PackingData two = doubled(one, axis);
    const LinearResponse lr = linear_response(two, LinearResponseOptions{});
    const int negative = negative_eigenvalues(two, lr.backbone);
    EXPECT_EQ(lr.n_negative_pivots, negative) << "axis " << axis;
    EXPECT_EQ(lr.ok, negative == 0) << "axis " << axis << ": " << lr.message;
    EXPECT_EQ(lr.n_contacts, 2 * single.n_contacts) << "axis " << axis;
    EXPECT_EQ(lr.n_rattlers, 2 * single.n_rattlers) << "axis " << axis;
    unstable += negative > 0;
  }
  // Not vacuous: if the generator changes and no doubling is unstable, choose another seed.
  EXPECT_GE(unstable, 1);

  // As a state to probe (`rendulic probe` of such a file): minimising first cannot leave a
  // saddle whose forces balance, and the reason says what the state is.
  const PackingData two = doubled(one, 1);
  const std::vector<double> radii(two.radii.data(), two.radii.data() + two.size());
  const LinearResponse lr = state_linear_response(
      system_from_positions(two.positions, radii, two.cell.lengths(), SystemOptions{}),
      ProbeOptions{});
  EXPECT_FALSE(lr.ok);
  EXPECT_TRUE(lr.minimised_first);
  EXPECT_EQ(lr.n_negative_pivots, 2);
  EXPECT_NE(lr.message.find("unstable (2 negative"), std::string::npos) << lr.message;
  EXPECT_NE(lr.message.find("a saddle of its energy, not a minimum"), std::string::npos)
      << lr.message;
}

// leave_saddle (`rendulic probe --leave-saddle`) steps off along the LDL^T's negative direction
// and minimises until no negative mode is left: the dense eigensolver then finds none either,
// the forces balance, and the linear response exists. A stable packing is left untouched.
TEST(LinearResponse, ASaddleIsLeftAlongItsNegativeModesToAMinimum) {
  const PackingData one = jammed_packing(0.70, 6);
  const PackingData two = doubled(one, 1);
  const std::vector<double> radii(two.radii.data(), two.radii.data() + two.size());
  // The direction is one of negative curvature: its Rayleigh quotient with the dense Hessian
  // lies between the lowest eigenvalue and zero.
  const LinearResponse at_saddle = linear_response(two, LinearResponseOptions{});
  ASSERT_EQ(at_saddle.negative_direction.rows(), two.size());
  const Eigen::MatrixX3d& u = at_saddle.negative_direction;
  Eigen::VectorXd flat(3 * two.size());
  for (int i = 0; i < two.size(); ++i) flat.segment<3>(3 * i) = u.row(i).transpose();
  const double rayleigh =
      flat.dot(dense_hessian(two, at_saddle.backbone) * flat) / flat.squaredNorm();
  const double lowest = dense_eigenvalues(two, at_saddle.backbone).minCoeff();
  EXPECT_LT(rayleigh, -1e-6 * kK);
  EXPECT_GE(rayleigh, lowest * (1 + 1e-9));
  EXPECT_EQ(linear_response(one, LinearResponseOptions{}).negative_direction.rows(), 0);

  DemSystem sys = system_from_positions(two.positions, radii, two.cell.lengths(), SystemOptions{});
  MinimiseOptions mo;
  mo.force_tolerance = 1e-10;
  const SaddleEscape e = leave_saddle(sys, mo);
  EXPECT_EQ(e.negative_modes, 2);
  EXPECT_TRUE(e.left) << e.message;
  EXPECT_EQ(e.remaining, 0);
  EXPECT_GE(e.rounds, 1);
  const PackingData moved = packing_of(sys);
  const LinearResponse lr = linear_response(moved, LinearResponseOptions{});
  ASSERT_TRUE(lr.ok) << lr.message;
  EXPECT_EQ(negative_eigenvalues(moved, lr.backbone), 0);
  EXPECT_LT(force_balance(moved, sys.material().k).ratio, kEquilibrium);
  // A minimum below the saddle, not a packing come apart. Near jamming (nu = 0.70) the way down
  // is an avalanche: every particle moved, rms 0.37 <r>, largest 1.5 <r>; the pressure fell by
  // 10 % and the shear stiffness C44 rose by 24 %, against 1 % fewer contacts. The run reports
  // these (`rendulic probe --leave-saddle`); the bounds here only catch a packing come apart.
  const LinearResponse single = linear_response(one, LinearResponseOptions{});
  EXPECT_GT(e.max_displacement, 0.0);
  EXPECT_NEAR(lr.stress.trace() / single.stress.trace(), 1.0, 0.2);
  EXPECT_NEAR(lr.n_contacts / (2.0 * single.n_contacts), 1.0, 0.05);

  // A minimum is not a saddle: nothing to do and nothing moved.
  DemSystem stable = system_from_positions(
      one.positions, std::vector<double>(one.radii.data(), one.radii.data() + one.size()),
      one.cell.lengths(), SystemOptions{});
  const Eigen::MatrixX3d before = packing_of(stable).positions;
  const SaddleEscape none = leave_saddle(stable, mo);
  EXPECT_EQ(none.negative_modes, 0);
  EXPECT_FALSE(none.left);
  EXPECT_EQ(none.rounds, 0);
  EXPECT_EQ(packing_of(stable).positions, before);
}

}  // namespace
}  // namespace rendulic::dem
