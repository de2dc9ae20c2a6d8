// FIRE 2.0 energy minimisation of a periodic frictionless sphere packing at fixed cell, affine
// strain steps and generated jammed packings (docs/physics.md sections 1, 2, 5).
// See probe_minimise.hpp.
#include "rendulic/dem/probe_minimise.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>

#include "fire_forces.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/dem/contact.hpp"

namespace rendulic::dem {

bool MinimiseOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (!(k > 0.0) || !std::isfinite(k)) return fail("minimise: k must be positive and finite");
  if (!(force_tolerance > 0.0) || !(force_tolerance < 1.0))
    return fail("minimise: force_tolerance must be in (0, 1)");
  if (max_iterations < 1) return fail("minimise: max_iterations must be >= 1");
  if (!(skin > 0.0) || !(skin <= 1.0)) return fail("minimise: skin must be in (0, 1]");
  return true;
}

bool GeneratedPackingOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (n < 2) return fail("generated packing: n must be >= 2");
  if (!(w >= 1.0)) return fail("generated packing: w must be >= 1");
  if (!(r_mean > 0.0)) return fail("generated packing: r_mean must be positive");
  if (!(volume_fraction > 0.0) || !(volume_fraction < 1.5))
    return fail("generated packing: volume_fraction must be in (0, 1.5)");
  return minimise.IsValid(why);
}

namespace {

// The candidate pairs of `packing` (find_pairs' set) into `pairs`, in find_pairs' order (i, j);
// `found` holds the search's unordered pairs (kept, with its capacity, across rebuilds).
void pair_indices(const PackingData& packing, double skin, std::vector<PairGeometry>& found,
                  std::vector<FirePair>& pairs) {
  find_pairs_unordered(packing, skin, found);
  order_pairs(found, packing.size(), pairs, [](const PairGeometry& c) {
    return FirePair{c.i, c.j};
  });
}

}  // namespace

MinimiseSummary minimise_energy(PackingData& packing, const MinimiseOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  MinimiseSummary summary;
  const int n = packing.size();
  if (n < 2) {
    summary.converged = true;
    summary.message = "fewer than two particles";
    return summary;
  }
  const double r_mean = packing.radii.mean();
  const double skin = options.skin * r_mean;
  const Eigen::Matrix3d h_inv = packing.cell.h.inverse();
  const double k = options.k;
  const NormalContact law{k, 0.0};  // at rest: the spring alone

  // FIRE 2.0 parameters (Guenole et al. 2020, table 1), time in units of 1/sqrt(k/m), m = 1.
  // The largest vibration frequency is below sqrt(2 z_max k) ~ sqrt(30 k); semi-implicit Euler
  // is stable for dt < 2/omega_max ~ 0.36/sqrt(k), so dt_max sits just under it and FIRE's
  // uphill back-off handles the rare overshoot.
  const double t_unit = 1.0 / std::sqrt(k);
  const double dt_start = 0.05 * t_unit, dt_max = 0.3 * t_unit, dt_min = 0.001 * t_unit;
  const int n_delay = 20, n_negative_max = 2000;
  const double f_inc = 1.1, f_dec = 0.5, alpha_start = 0.25, f_alpha = 0.99;

  std::vector<FirePair> pairs;
  std::vector<PairGeometry> found;
  pair_indices(packing, skin, found, pairs);
  FireScratch scratch;
  Eigen::MatrixX3d reference = packing.positions;
  summary.pair_rebuilds = 1;
  Eigen::MatrixX3d force(n, 3), velocity = Eigen::MatrixX3d::Zero(n, 3);
  double sum_f = 0.0;
  int contacts = 0;
  auto evaluate = [&]() {
    summary.elastic_energy =
        fire_contact_forces(packing, h_inv, pairs, law, scratch, force, &sum_f, &contacts);
    summary.max_force = force.rowwise().norm().maxCoeff();
    summary.mean_contact_force = contacts > 0 ? sum_f / contacts : 0.0;
  };
  auto ratio = [&]() {
    const double reference_force =
        contacts > 0 ? summary.mean_contact_force : law.elastic_force(r_mean);
    return summary.max_force / reference_force;
  };
  auto converged = [&]() { return ratio() <= options.force_tolerance; };
  // The overlaps are differences of coordinates as large as the cell, so each contact force
  // carries a round-off of about k eps L, and the largest net force has a floor: 3e-14 of the
  // mean contact force on quick.toml's states at nu = 0.82 (N = 100), 2e-13 at nu = 0.665.
  // FIRE reaches it within a few thousand iterations and then only stirs the round-off: a
  // tolerance below it ran all max_iterations (20 s at N = 100) and failed as "not converged".
  // Below kRoundOffRegime, a best ratio that has not halved in kStallWindow iterations is that
  // floor (while converging, the ratio halves about every 50 iterations).
  constexpr double kRoundOffRegime = 1e-10;
  constexpr std::int64_t kStallWindow = 50000;
  double best = std::numeric_limits<double>::infinity();
  std::int64_t best_at = 0;
  evaluate();
  summary.start_ratio = ratio();
  double dt = dt_start, alpha = alpha_start;
  int n_positive = 0, n_negative = 0;
  for (std::int64_t it = 0; it < options.max_iterations; ++it) {
    if (converged()) {
      summary.converged = true;
      summary.iterations = it;
      summary.message = "converged";
      return summary;
    }
    if (const double r = ratio(); r < 0.5 * best) {
      best = r;
      best_at = it;
    } else if (best < kRoundOffRegime && it - best_at > kStallWindow) {
      summary.iterations = it;
      summary.stalled_at = best;
      std::ostringstream os;
      os << std::setprecision(3) << "FIRE stalled at " << best
         << " x the mean contact force: no halving in " << kStallWindow << " iterations";
      summary.message = os.str();
      return summary;
    }
    const double power = (force.array() * velocity.array()).sum();
    if (power > 0.0) {
      ++n_positive;
      n_negative = 0;
      if (n_positive > n_delay) {
        dt = std::min(dt * f_inc, dt_max);
        alpha *= f_alpha;
      }
    } else {
      n_positive = 0;
      if (++n_negative > n_negative_max) {
        summary.iterations = it;
        summary.message = "FIRE stalled: too many consecutive uphill steps";
        return summary;
      }
      if (it >= n_delay) {
        dt = std::max(dt * f_dec, dt_min);
        alpha = alpha_start;
      }
      packing.positions -= 0.5 * dt * velocity;
      velocity.setZero();
    }
    velocity += dt * force;
    const double f_norm = force.norm();
    if (f_norm > 0.0) {
      velocity = (1.0 - alpha) * velocity + (alpha * velocity.norm() / f_norm) * force;
    }
    packing.positions += dt * velocity;
    // Rebuild the candidate pairs once any particle may have closed the skin.
    if ((packing.positions - reference).rowwise().norm().maxCoeff() > 0.5 * skin) {
      pair_indices(packing, skin, found, pairs);
      reference = packing.positions;
      ++summary.pair_rebuilds;
    }
    evaluate();
  }
  summary.iterations = options.max_iterations;
  summary.converged = converged();
  std::ostringstream os;
  os << (summary.converged ? "converged" : "not converged") << " after " << options.max_iterations
     << " iterations";
  summary.message = os.str();
  return summary;
}

std::string round_off_refusal(const MinimiseSummary& summary, const std::string& key,
                              double tolerance) {
  // A tenfold margin over the floor, rounded up to a power of ten.
  const double reached = std::pow(10.0, std::ceil(std::log10(10.0 * summary.stalled_at)));
  std::ostringstream os;
  os << key << " = " << tolerance << " is below the round-off floor of this state's forces ("
     << summary.message << "); use " << reached << " or more";
  return os.str();
}

void apply_affine_strain(PackingData& packing, const Eigen::Matrix3d& eps) {
  packing.deform(Eigen::Matrix3d::Identity() - eps);
}

PackingData generate_packing(const GeneratedPackingOptions& options, MinimiseSummary* summary) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  std::mt19937_64 rng(options.seed);
  // Own uniform draw (53 random bits) so that the packing does not depend on the standard
  // library's distribution implementation.
  auto uniform = [&rng]() { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
  const double r_min = 2.0 * options.r_mean / (1.0 + options.w);
  const double r_max = options.w * r_min;
  Eigen::VectorXd radii(options.n);
  double solid = 0.0;
  for (int p = 0; p < options.n; ++p) {
    radii(p) = r_min + (r_max - r_min) * uniform();
    solid += 4.0 / 3.0 * std::numbers::pi * std::pow(radii(p), 3);
  }
  const double length = std::cbrt(solid / options.volume_fraction);
  Eigen::MatrixX3d positions(options.n, 3);
  for (int p = 0; p < options.n; ++p) {
    for (int a = 0; a < 3; ++a) positions(p, a) = length * uniform();
  }
  PackingData packing = PackingData::orthorhombic(std::move(positions), std::move(radii),
                                                  Eigen::Vector3d::Constant(length));
  MinimiseOptions minimise = options.minimise;
  const MinimiseSummary s = minimise_energy(packing, minimise);
  if (summary) *summary = s;
  return packing;
}

}  // namespace rendulic::dem
