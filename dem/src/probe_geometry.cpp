// Contact geometry of a periodic packing for the probe tools (docs/physics.md sections 1-3): cell
// lists over fractional coordinates, minimum image, static stress and fabric. See
// probe_geometry.hpp.
#include "rendulic/dem/probe_geometry.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <sstream>

#include "rendulic/core/errors.hpp"
#include "rendulic/dem/contact.hpp"

namespace rendulic::dem {

PackingData PackingData::orthorhombic(Eigen::MatrixX3d positions, Eigen::VectorXd radii,
                                      const Eigen::Vector3d& cell_lengths) {
  PackingData p;
  p.positions = std::move(positions);
  p.radii = std::move(radii);
  p.cell = PeriodicCell::orthorhombic(cell_lengths);
  return p;
}

namespace {

void check_packing(const PackingData& packing) {
  const int n = packing.size();
  if (packing.positions.rows() != n) {
    std::ostringstream os;
    os << "packing: " << packing.positions.rows() << " positions but " << n << " radii";
    throw InputError(os.str());
  }
  if (!(packing.volume() > 0.0) || !std::isfinite(packing.volume()) ||
      !packing.cell.h.allFinite()) {
    throw InputError("packing: the cell matrix is not finite with a positive volume");
  }
  if (!packing.positions.allFinite() || !packing.radii.allFinite() ||
      (n > 0 && !(packing.radii.minCoeff() > 0.0))) {
    throw InputError("packing: positions and radii must be finite, radii positive");
  }
}

}  // namespace

void find_pairs_unordered(const PackingData& packing, double skin,
                          std::vector<PairGeometry>& pairs) {
  check_packing(packing);
  const int n = packing.size();
  pairs.clear();
  if (n < 2) return;
  const Eigen::Matrix3d& h = packing.cell.h;
  const Eigen::Matrix3d h_inv = h.inverse();
  const double cutoff = 2.0 * packing.radii.maxCoeff() + skin;
  // Perpendicular width of the cell along each fractional axis: V / |h_b x h_c|.
  const double volume = packing.volume();
  Eigen::Vector3d widths;
  for (int a = 0; a < 3; ++a) {
    const double width = volume / h.col((a + 1) % 3).cross(h.col((a + 2) % 3)).norm();
    widths[a] = width;
  }
  require_minimum_image(widths, cutoff);
  const std::array<int, 3> bins = cell_list_bins(widths, cutoff, static_cast<std::size_t>(n));
  const int n_bins = bins[0] * bins[1] * bins[2];
  // Bin of each particle from its wrapped fractional coordinates; counting sort into cells.
  std::vector<int> bin_of(n);
  std::vector<Eigen::Vector3d> wrapped(n);  // h f, f the wrapped fractional coordinates
  for (int p = 0; p < n; ++p) {
    Eigen::Vector3d s = h_inv * packing.positions.row(p).transpose();
    // A finite position can still be beyond the cell's coordinates (-1e308 m: s = -inf), whose
    // wrap is NaN and whose bin was out of the table (a crash).
    if (!s.allFinite()) {
      std::ostringstream os;
      os << "packing: particle " << p << " at " << packing.positions.row(p)
         << " m is too far from the cell to be wrapped into it";
      throw InputError(os.str());
    }
    int b[3];
    for (int a = 0; a < 3; ++a) {
      double f = s(a) - std::floor(s(a));
      b[a] = std::min(bins[a] - 1, static_cast<int>(f * bins[a]));
      s(a) = f;
    }
    bin_of[p] = (b[0] * bins[1] + b[1]) * bins[2] + b[2];
    wrapped[p] = h * s;
  }
  std::vector<int> start(n_bins + 1, 0), members(n);
  for (int p = 0; p < n; ++p) ++start[bin_of[p] + 1];
  for (int b = 0; b < n_bins; ++b) start[b + 1] += start[b];
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int p = 0; p < n; ++p) members[fill[bin_of[p]]++] = p;
  }
  // With three or more bins along every axis, each neighbouring bin is one image of a bin
  // (below). With fewer, the neighbours of each bin along each axis without repeats (they would
  // otherwise visit a bin twice and count its pairs twice), made once, not per particle.
  const bool imaged = bins[0] >= 3 && bins[1] >= 3 && bins[2] >= 3;
  std::array<std::vector<std::vector<int>>, 3> neighbours;
  for (int a = 0; a < 3; ++a) {
    neighbours[a].resize(bins[a]);
    for (int b0 = 0; b0 < bins[a]; ++b0)
      for (int d = -1; d <= 1; ++d) {
        const int v = ((b0 + d) % bins[a] + bins[a]) % bins[a];
        auto& out = neighbours[a][b0];
        if (std::find(out.begin(), out.end(), v) == out.end()) out.push_back(v);
      }
  }
  const bool orthorhombic = packing.cell.is_orthorhombic();
  const Eigen::Vector3d h_diagonal = h.diagonal(), h_inv_diagonal = h_inv.diagonal();
  // Pair (i, j), i < j, with l = x_i - x_j by the minimum image, if r_i + r_j - |l| > -skin
  // (reach = r_i + r_j + skin). The test on |l|^2 first, with a margin that can only keep a pair
  // the exact test then decides.
  auto consider = [&](int i, int j, double reach) {
    const Eigen::Vector3d dx = (packing.positions.row(i) - packing.positions.row(j)).transpose();
    const Eigen::Vector3d l = orthorhombic
                                  ? minimum_image_orthorhombic(h_diagonal, h_inv_diagonal, dx)
                                  : minimum_image(packing.cell, h_inv, dx);
    if (l.squaredNorm() > reach * reach * (1.0 + 1e-9)) return;
    const double r = l.norm();
    const double overlap = packing.radii(i) + packing.radii(j) - r;
    if (overlap > -skin) pairs.push_back({i, j, l, r, overlap});
  };
  if (imaged) {
    // The members' wrapped positions and radii in bin order, 4 doubles each: a bin's
    // candidates are read in sequence.
    std::vector<double> binned(4 * static_cast<std::size_t>(n));
    for (int m = 0; m < n; ++m) {
      const int p = members[m];
      for (int a = 0; a < 3; ++a) binned[4 * m + a] = wrapped[p](a);
      binned[4 * m + 3] = packing.radii(p);
    }
    // Bin by bin with half of the neighbouring bins (itself and 13 ahead), each unordered pair
    // of bins, and so each pair of particles, once; a candidate is first tested on
    // h f_p - (h f_q + h n) through the neighbour's image n, without the minimum image's
    // roundings. That differs from the minimum image by roundings (1e-16 of the cell), far
    // inside the margin of 2e-9: a pair it skips has |l| > reach, which consider() would not
    // keep either, so the set is the same.
    for (int bx = 0; bx < bins[0]; ++bx)
      for (int by = 0; by < bins[1]; ++by)
        for (int bz = 0; bz < bins[2]; ++bz) {
          const int b = (bx * bins[1] + by) * bins[2] + bz;
          for (int o = 13; o < 27; ++o) {  // offsets (0,0,0) and the 13 after it
            const int d[3] = {o / 9 - 1, (o / 3) % 3 - 1, o % 3 - 1};
            const int c[3] = {bx + d[0], by + d[1], bz + d[2]};
            Eigen::Vector3d image;
            int wrapped_bin[3];
            for (int a = 0; a < 3; ++a) {
              image(a) = c[a] < 0 ? -1.0 : (c[a] >= bins[a] ? 1.0 : 0.0);
              wrapped_bin[a] = c[a] - static_cast<int>(image(a)) * bins[a];
            }
            const int nb = (wrapped_bin[0] * bins[1] + wrapped_bin[1]) * bins[2] + wrapped_bin[2];
            const Eigen::Vector3d shift = h * image;
            for (int m = start[b]; m < start[b + 1]; ++m) {
              const double* wp = binned.data() + 4 * m;
              const double px = wp[0] - shift(0), py = wp[1] - shift(1), pz = wp[2] - shift(2);
              for (int k = o == 13 ? m + 1 : start[nb]; k < start[nb + 1]; ++k) {
                const double* wq = binned.data() + 4 * k;
                const double reach = wp[3] + wq[3] + skin;
                const double lx = px - wq[0], ly = py - wq[1], lz = pz - wq[2];
                if (lx * lx + ly * ly + lz * lz > reach * reach * (1.0 + 2e-9)) continue;
                const int p = members[m], q = members[k];
                consider(std::min(p, q), std::max(p, q), reach);
              }
            }
          }
        }
  } else {
    for (int p = 0; p < n; ++p) {
      const int b = bin_of[p];
      const int bx = b / (bins[1] * bins[2]), by = (b / bins[2]) % bins[1], bz = b % bins[2];
      for (int nx : neighbours[0][bx])
        for (int ny : neighbours[1][by])
          for (int nz : neighbours[2][bz]) {
            const int nb = (nx * bins[1] + ny) * bins[2] + nz;
            for (int m = start[nb]; m < start[nb + 1]; ++m) {
              const int q = members[m];
              if (q > p) consider(p, q, packing.radii(p) + packing.radii(q) + skin);
            }
          }
    }
  }
}

std::vector<PairGeometry> find_pairs(const PackingData& packing, double skin) {
  std::vector<PairGeometry> pairs;
  find_pairs_unordered(packing, skin, pairs);
  std::vector<PairGeometry> sorted;
  order_pairs(pairs, packing.size(), sorted, [](const PairGeometry& c) { return c; });
  return sorted;
}

StressFabric measure_stress_fabric(const PackingData& packing, double k,
                                   const std::vector<char>* include, double min_overlap) {
  StressFabric out;
  const double volume = packing.volume();
  const NormalContact law{k, 0.0};  // at rest: the spring alone
  for (const PairGeometry& c : find_pairs(packing, 0.0)) {
    if (c.overlap <= min_overlap) continue;
    if (include && (!(*include)[c.i] || !(*include)[c.j])) continue;
    const Eigen::Vector3d n = c.l / c.distance;
    const double f = law.elastic_force(c.overlap);
    // l (x) f with f = f n along l: compression positive.
    out.stress += (f * c.distance) * (n * n.transpose());
    const double ri = packing.radii(c.i), rj = packing.radii(c.j);
    const double vp = 4.0 / 3.0 * std::numbers::pi * (ri * ri * ri + rj * rj * rj);
    out.fabric += vp * (n * n.transpose());
    out.elastic_energy += law.energy(c.overlap);
    ++out.contacts;
  }
  out.stress /= volume;
  out.fabric /= volume;
  return out;
}

Eigen::Matrix3d fabric_of_pairs(const PackingData& packing,
                                const std::vector<std::pair<int, int>>& pairs) {
  const Eigen::Matrix3d h_inv = packing.cell.h.inverse();
  Eigen::Matrix3d f = Eigen::Matrix3d::Zero();
  for (const auto& [i, j] : pairs) {
    const Eigen::Vector3d l = minimum_image(
        packing.cell, h_inv, (packing.positions.row(i) - packing.positions.row(j)).transpose());
    const Eigen::Vector3d n = l.normalized();
    const double w = 4.0 / 3.0 * std::numbers::pi *
                     (std::pow(packing.radii(i), 3) + std::pow(packing.radii(j), 3));
    f += w * (n * n.transpose());
  }
  return f / packing.volume();
}

FabricSplit split_fabric_change(const PackingData& before, const PackingData& after,
                                const std::vector<std::pair<int, int>>& contacts_before,
                                const Eigen::Matrix3d& fabric_before,
                                const Eigen::Matrix3d& fabric_after) {
  const Eigen::Matrix3d fixed0 = fabric_of_pairs(before, contacts_before);
  const Eigen::Matrix3d fixed1 = fabric_of_pairs(after, contacts_before);
  const double shrink = before.volume() / after.volume();
  FabricSplit s;
  s.volume = fixed0 * (shrink - 1.0);
  s.rotation = fixed1 - fixed0 * shrink;
  s.contacts = (fabric_after - fabric_before) - s.volume - s.rotation;
  return s;
}

}  // namespace rendulic::dem
