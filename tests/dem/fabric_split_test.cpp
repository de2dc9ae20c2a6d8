// The fabric split (docs/probes.md "Fabric split") against closed forms of an affine step of a
// disordered packing: with A = exp(-eps) applied to positions and cell, the volume part is
// F0 (exp(tr eps) - 1), the rotation part (1/V1) sum_{c in C0} w (n1 n1 - n0 n0) with
// n1 = A n0 / |A n0|, and the contact-set part the contacts made minus those lost,
// (1/V1) (sum_{C1 \ C0} - sum_{C0 \ C1}) w n1 n1; each computed here with its own O(N^2) pair
// search. And the linear response's two parts: F tr(d_eps) and the rest of its fabric rate.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>

#include "rendulic/core/conventions.hpp"
#include "rendulic/dem/linear_response.hpp"
#include "rendulic/dem/probe_geometry.hpp"
#include "rendulic/dem/probe_minimise.hpp"

namespace rendulic::dem {
namespace {

using Key = std::pair<int, int>;

// Every pair in contact, by brute force over all pairs and the 27 nearest images; `overlaps`
// (if given) receives each contact's overlap.
std::map<Key, Eigen::Vector3d> contacts_of(const PackingData& p,
                                           std::map<Key, double>* overlaps = nullptr) {
  std::map<Key, Eigen::Vector3d> out;  // (i, j) -> unit normal from j to i
  const Eigen::Vector3d L = p.cell.lengths();
  for (int i = 0; i < p.size(); ++i)
    for (int j = i + 1; j < p.size(); ++j) {
      Eigen::Vector3d best = Eigen::Vector3d::Constant(1e300);
      for (int a = -1; a <= 1; ++a)
        for (int b = -1; b <= 1; ++b)
          for (int c = -1; c <= 1; ++c) {
            const Eigen::Vector3d l = (p.positions.row(i) - p.positions.row(j)).transpose() +
                                      Eigen::Vector3d(a * L[0], b * L[1], c * L[2]);
            if (l.norm() < best.norm()) best = l;
          }
      if (best.norm() < p.radii(i) + p.radii(j)) {
        out[{i, j}] = best.normalized();
        if (overlaps) (*overlaps)[{i, j}] = p.radii(i) + p.radii(j) - best.norm();
      }
    }
  return out;
}

double weight(const PackingData& p, int i, int j) {
  return 4.0 / 3.0 * std::numbers::pi * (std::pow(p.radii(i), 3) + std::pow(p.radii(j), 3));
}

Eigen::Matrix3d fabric_of(const PackingData& p, const std::map<Key, Eigen::Vector3d>& cs) {
  Eigen::Matrix3d f = Eigen::Matrix3d::Zero();
  for (const auto& [k, n] : cs) f += weight(p, k.first, k.second) * n * n.transpose();
  return f / p.volume();
}

class FabricSplitAffine : public ::testing::TestWithParam<double> {};

TEST_P(FabricSplitAffine, AffineStepMatchesTheClosedForms) {
  GeneratedPackingOptions g;
  g.n = 120;
  g.volume_fraction = 0.72;
  g.seed = 4;
  const PackingData before = generate_packing(g, nullptr);
  const double amplitude = GetParam();
  const Eigen::Matrix3d eps = probe_strain(131.0, amplitude);  // a mixed direction
  const Eigen::Matrix3d A = (-eps.diagonal()).array().exp().matrix().asDiagonal();
  PackingData after = before;
  after.positions = before.positions * A.transpose();
  after.cell.h = A * before.cell.h;

  std::map<Key, double> overlap0;
  const auto c0 = contacts_of(before, &overlap0), c1 = contacts_of(after);
  const Eigen::Matrix3d f0 = fabric_of(before, c0), f1 = fabric_of(after, c1);
  std::vector<std::pair<int, int>> pairs;
  for (const auto& [k, n] : c0) pairs.push_back(k);
  const FabricSplit s = split_fabric_change(before, after, pairs, f0, f1);

  const Eigen::Matrix3d volume = f0 * (std::exp(eps.trace()) - 1.0);
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Zero(), contacts = Eigen::Matrix3d::Zero();
  for (const auto& [k, n0] : c0) {
    const Eigen::Vector3d n1 = (A * n0).normalized();
    rotation += weight(before, k.first, k.second) * (n1 * n1.transpose() - n0 * n0.transpose());
    if (!c1.count(k)) contacts -= weight(before, k.first, k.second) * n1 * n1.transpose();
  }
  for (const auto& [k, n1] : c1)
    if (!c0.count(k)) contacts += weight(before, k.first, k.second) * n1 * n1.transpose();
  rotation /= after.volume();
  contacts /= after.volume();

  const double scale = f0.norm();
  EXPECT_LE((s.volume - volume).norm(), 1e-13 * scale);
  EXPECT_LE((s.rotation - rotation).norm(), 1e-13 * scale);
  EXPECT_LE((s.contacts - contacts).norm(), 1e-13 * scale);
  EXPECT_LE((s.volume + s.rotation + s.contacts - (f1 - f0)).norm(), 1e-14 * scale);
  int changed = 0;
  for (const auto& [k, n] : c0) changed += !c1.count(k);
  for (const auto& [k, n] : c1) changed += !c0.count(k);
  if (amplitude < 1e-6) {
    // A tiny step changes only touches without force (rattlers at the minimum): every contact
    // lost had an overlap within the step's reach.
    for (const auto& [k, n] : c0)
      if (!c1.count(k)) {
        EXPECT_LT(overlap0.at(k), 10 * amplitude * before.radii.maxCoeff());
      }
  } else {
    EXPECT_GT(changed, 10);  // the closed form of the contact part is exercised
    EXPECT_GT(s.contacts.norm(), 1e-3 * scale);
  }
}

INSTANTIATE_TEST_SUITE_P(Amplitudes, FabricSplitAffine, ::testing::Values(1e-8, 2e-2));

// The linear response's parts: the volume part is F tr(d_eps) exactly, and for a Bravais
// lattice (no non-affine motion) the rotation part is the first-order affine rotation, which
// the split of a small affine step reproduces to O(amplitude).
TEST(FabricSplitLinearResponse, VolumeAndRotationParts) {
  const double radius = 1e-3, r0 = 1.99e-3, a = r0 * std::numbers::sqrt2;
  const Eigen::Vector3d basis[4] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  Eigen::MatrixX3d x(108, 3);
  int p = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k)
        for (const auto& b : basis) x.row(p++) = (a * (Eigen::Vector3d(i, j, k) + b)).transpose();
  const PackingData fcc = PackingData::orthorhombic(x, Eigen::VectorXd::Constant(108, radius),
                                                    Eigen::Vector3d::Constant(3 * a));
  const LinearResponse lr = linear_response(fcc, LinearResponseOptions{});
  ASSERT_TRUE(lr.ok) << lr.message;
  const double amplitude = 1e-7;
  for (double theta : {20.0, 125.26, 250.0}) {
    const Eigen::Matrix3d eps = probe_strain(theta, amplitude);
    const Eigen::Matrix3d vol = from_mandel(lr.fabric_volume_stiffness * to_mandel(eps));
    const Eigen::Matrix3d rot = from_mandel(lr.fabric_rotation_stiffness * to_mandel(eps));
    EXPECT_LE((vol - lr.fabric * eps.trace()).norm(), 1e-14 * lr.fabric.norm());
    EXPECT_LE((vol + rot - lr.fabric_increment(eps)).norm(), 1e-14 * lr.fabric.norm());
    const Eigen::Matrix3d A = (-eps.diagonal()).array().exp().matrix().asDiagonal();
    PackingData after = fcc;
    after.positions = fcc.positions * A.transpose();
    after.cell.h = A * fcc.cell.h;
    std::vector<std::pair<int, int>> pairs;
    for (const PairGeometry& c : find_pairs(fcc, 0.0))
      if (c.overlap > 0) pairs.emplace_back(c.i, c.j);
    const FabricSplit s =
        split_fabric_change(fcc, after, pairs, lr.fabric, fabric_of_pairs(after, pairs));
    EXPECT_LE((s.rotation - rot).norm(), 1e-5 * rot.norm() + 1e-18) << theta;
    EXPECT_LE((s.volume - vol).norm(), 1e-5 * vol.norm() + 1e-18) << theta;
  }
}

}  // namespace
}  // namespace rendulic::dem
