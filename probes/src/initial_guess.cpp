// Initial guesses of the ellipse fit: the affine fit R(theta) = c + M u(theta)
// when the probe directions are known, and the direct algebraic fit of Halir and Flusser
// (1998, a numerically stable form of Fitzgibbon's ellipse-specific fit) when they are not.
// Both are linear algebra only; the geometric refinement is in ellipse_fit.cpp.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "fit_internal.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/probes/envelope_fit.hpp"

namespace rendulic {
namespace fit_detail {
namespace {

// In the ellipse's frame, with the point at (x, y): f(t) = |e(t) - q|^2 and
// g(t) = (1/2) f'(t), h(t) = g'(t). Everything from one (cos t, sin t): trigonometric calls
// are the cost of the whole fit.
struct NearestPoint {
  double x, y, a, b;
  double f_cs(double c, double s) const {
    const double dx = a * c - x, dy = b * s - y;
    return dx * dx + dy * dy;
  }
  double f(double t) const { return f_cs(std::cos(t), std::sin(t)); }
  double g_cs(double c, double s) const { return (b * b - a * a) * s * c + a * x * s - b * y * c; }
  double g(double t) const { return g_cs(std::cos(t), std::sin(t)); }
  double h_cs(double c, double s) const {
    return (b * b - a * a) * (c * c - s * s) + a * x * c + b * y * s;
  }
  // Size of g's terms: what "g = 0" means to rounding.
  double g_scale() const { return a * a + b * b + a * std::abs(x) + b * std::abs(y); }

  // Guarded Newton descent from t; stops where f is not locally convex. Returns whether it
  // ended at a stationary point (to rounding).
  double descend(double t, bool* stationary) const {
    double c = std::cos(t), s = std::sin(t);
    double ft = f_cs(c, s);
    *stationary = false;
    for (int it = 0; it < 30; ++it) {
      const double gv = g_cs(c, s), hv = h_cs(c, s);
      if (std::abs(gv) <= 1e-13 * g_scale()) {
        *stationary = true;
        break;
      }
      if (!(hv > 0.0)) break;
      const double t_new = t - gv / hv;
      const double cn = std::cos(t_new), sn = std::sin(t_new);
      const double v = f_cs(cn, sn);
      if (!(v <= ft)) {
        *stationary = std::abs(gv) <= 1e-9 * g_scale();  // rounding-level stall
        break;
      }
      t = t_new, c = cn, s = sn, ft = v;
    }
    return t;
  }

  // Root of g in [lo, hi] with g(lo) <= 0 <= g(hi): Newton steps kept inside the bracket,
  // bisection otherwise. Needed near the tips of thin ellipses, where the convex basin of
  // the minimum is narrower than any grid spacing and plain Newton stalls.
  double bracketed(double lo, double hi) const {
    double t = 0.5 * (lo + hi);
    for (int it = 0; it < 100; ++it) {
      const double c = std::cos(t), s = std::sin(t);
      const double gv = g_cs(c, s);
      (gv <= 0.0 ? lo : hi) = t;
      const double hv = h_cs(c, s);
      double t_new = hv > 0.0 ? t - gv / hv : 0.5 * (lo + hi);
      if (!(t_new > lo && t_new < hi)) t_new = 0.5 * (lo + hi);
      if (std::abs(t_new - t) < 1e-16 * (1.0 + std::abs(t)) || hi - lo < 1e-15) return t_new;
      t = t_new;
    }
    return t;
  }
};

constexpr int kGrid = 32;
constexpr double kStep = 2.0 * kPi / kGrid;
struct GridTable {
  double c[kGrid], s[kGrid];
  GridTable() {
    for (int k = 0; k < kGrid; ++k) c[k] = std::cos(kStep * k), s[k] = std::sin(kStep * k);
  }
};

}  // namespace

double nearest_latent_angle(const Eigen::Vector2d& p, const Eigen::Vector2d& c, double a, double b,
                            double phi) {
  static const GridTable grid;
  ++point_operations();
  const Eigen::Vector2d q = rotation(phi).transpose() * (p - c);
  const NearestPoint np{q.x(), q.y(), a, b};
  // The distance has at most four stationary points on the circle of t, but near the tips
  // of a thin ellipse the far side is almost as close as the near one: refine every local
  // minimum of a 32-node grid and keep the best, not just the best node.
  double fg[kGrid], gg[kGrid];
  for (int k = 0; k < kGrid; ++k)
    fg[k] = np.f_cs(grid.c[k], grid.s[k]), gg[k] = np.g_cs(grid.c[k], grid.s[k]);
  double best_t = 0.0, best_f = std::numeric_limits<double>::infinity();
  for (int k = 0; k < kGrid; ++k) {
    const int km = (k + kGrid - 1) % kGrid, kp = (k + 1) % kGrid;
    if (fg[k] > fg[km] || fg[k] > fg[kp]) continue;
    double t;
    bool stationary = false;
    if (gg[km] <= 0.0 && gg[kp] >= 0.0)
      t = np.bracketed(kStep * (k - 1), kStep * (k + 1));
    else
      t = np.descend(kStep * k, &stationary);
    const double v = np.f(t);
    if (v < best_f) best_f = v, best_t = t;
  }
  return best_t;
}

double nearest_latent_angle_from(const Eigen::Vector2d& p, const Eigen::Vector2d& c, double a,
                                 double b, double phi, double t_start) {
  ++point_operations();
  const Eigen::Vector2d q = rotation(phi).transpose() * (p - c);
  const NearestPoint np{q.x(), q.y(), a, b};
  bool stationary = false;
  const double t = np.descend(t_start, &stationary);
  if (stationary) return t;
  return nearest_latent_angle(p, c, a, b, phi);
}

double ellipse_distance(const Eigen::Vector2d& p, const Eigen::Vector2d& c, double a, double b,
                        double phi) {
  const double t = nearest_latent_angle(p, c, a, b, phi);
  return (p - ellipse_point(c, a, b, phi, t)).norm();
}

double mad_scale(std::vector<double> d) {
  if (d.empty()) return 0.0;
  for (double& v : d) v = std::abs(v);
  const auto mid = d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2);
  std::nth_element(d.begin(), mid, d.end());
  return 1.4826 * *mid;
}

namespace {

double median_of(std::vector<double> v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// Sampson distance |Q| / |grad Q| of p to the ellipse Q = (x/a)^2 + (y/b)^2 - 1 (local frame).
double sampson_distance(const Eigen::Vector2d& p, const EllipseGuess& g) {
  const Eigen::Vector2d l = rotation(g.phi).transpose() * (p - g.center);
  const double ia2 = 1.0 / (g.a * g.a), ib2 = 1.0 / (g.b * g.b);
  const double Q = l.x() * l.x() * ia2 + l.y() * l.y() * ib2 - 1.0;
  const double gx = 2.0 * l.x() * ia2, gy = 2.0 * l.y() * ib2;
  return std::abs(Q) / std::max(std::hypot(gx, gy), 1e-300);
}

}  // namespace

EllipseGuess robust_guess(const std::vector<Eigen::Vector2d>& q, const std::vector<double>& theta,
                          bool use_theta, std::uint64_t seed, bool* used_theta) {
  // 200 subsets: with 20% outliers a clean 5-subset comes up with probability 0.33 per draw,
  // so all 200 fail with probability 1e-35; each costs a few microseconds.
  constexpr int kTrials = 200;
  const std::size_t n = q.size();
  std::mt19937_64 rng(seed);
  std::vector<std::size_t> idx(n);
  for (std::size_t i = 0; i < n; ++i) idx[i] = i;
  auto draw = [&](std::size_t k) {
    for (std::size_t j = 0; j < k; ++j) {
      std::uniform_int_distribution<std::size_t> u(j, n - 1);
      std::swap(idx[j], idx[u(rng)]);
    }
  };
  const bool affine = use_theta && theta.size() == n && n >= 3;
  double best = std::numeric_limits<double>::infinity();
  EllipseGuess best_g;
  std::vector<double> d(n);
  if (affine) {
    AffineMapFit best_a;
    for (int trial = 0; trial < kTrials; ++trial) {
      draw(3);
      std::vector<Eigen::Vector2d> sp = {q[idx[0]], q[idx[1]], q[idx[2]]};
      std::vector<double> st = {theta[idx[0]], theta[idx[1]], theta[idx[2]]};
      const AffineMapFit af = affine_fit(sp, st);
      if (!af.ok) continue;
      point_operations() += static_cast<std::int64_t>(n);
      for (std::size_t i = 0; i < n; ++i) {
        const double r = deg_to_rad(theta[i]);
        d[i] = (af.center + af.map * Eigen::Vector2d(std::cos(r), std::sin(r)) - q[i]).norm();
      }
      const double med = median_of(d);
      if (med < best) best = med, best_a = af;
    }
    best_g = ellipse_guess_from_affine(best_a, theta);
    if (best_g.ok) {
      *used_theta = true;
      return best_g;
    }
  }
  *used_theta = false;
  if (n >= 5) {
    best = std::numeric_limits<double>::infinity();
    for (int trial = 0; trial < kTrials; ++trial) {
      draw(5);
      std::vector<Eigen::Vector2d> sp;
      for (int j = 0; j < 5; ++j) sp.push_back(q[idx[static_cast<std::size_t>(j)]]);
      EllipseGuess g = ellipse_guess_algebraic(sp);
      if (!g.ok || !(g.b > 0.0)) continue;
      point_operations() += static_cast<std::int64_t>(n);
      for (std::size_t i = 0; i < n; ++i) d[i] = sampson_distance(q[i], g);
      const double med = median_of(d);
      if (med < best) best = med, best_g = g;
    }
    if (best_g.ok) {
      best_g.t.clear();
      for (const auto& p : q)
        best_g.t.push_back(nearest_latent_angle(p, best_g.center, best_g.a, best_g.b, best_g.phi));
      return best_g;
    }
  }
  return best_guess(q, theta, false, used_theta);  // collinear points: principal axes
}

}  // namespace fit_detail

EllipseGuess ellipse_guess_from_affine(const AffineMapFit& affine,
                                       const std::vector<double>& theta_deg) {
  EllipseGuess g;
  if (!affine.ok) return g;
  // M u = U S V^T u. Writing U = R(phi) diag(1, det U) turns this into the ellipse
  // R(phi) diag(s0, det(U) s1) (cos t, sin t) with (cos t, sin t) = V^T u(theta).
  Eigen::JacobiSVD<Eigen::Matrix2d> svd(affine.map, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix2d U = svd.matrixU(), V = svd.matrixV();
  const Eigen::Vector2d s = svd.singularValues();
  g.center = affine.center;
  g.phi = std::atan2(U(1, 0), U(0, 0));
  g.a = s(0);
  g.b = U.determinant() < 0.0 ? -s(1) : s(1);
  g.t.reserve(theta_deg.size());
  for (double th : theta_deg) {
    const double r = deg_to_rad(th);
    const Eigen::Vector2d w = V.transpose() * Eigen::Vector2d(std::cos(r), std::sin(r));
    g.t.push_back(std::atan2(w.y(), w.x()));
  }
  g.ok = s(0) > 0.0 && std::isfinite(g.phi);
  return g;
}

EllipseGuess ellipse_guess_algebraic(const std::vector<Eigen::Vector2d>& points) {
  EllipseGuess g;
  const auto n = static_cast<Eigen::Index>(points.size());
  if (n < 5) return g;
  fit_detail::point_operations() += n;
  // Centre and scale first: the scatter matrices of raw stress values (1e-4 .. 1e6) would
  // otherwise be hopelessly conditioned.
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : points) mean += p;
  mean /= static_cast<double>(n);
  double scale = 0.0;
  for (const auto& p : points) scale += (p - mean).squaredNorm();
  scale = std::sqrt(scale / static_cast<double>(n));
  if (!(scale > 0.0)) return g;
  Eigen::MatrixXd D1(n, 3), D2(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector2d q = (points[static_cast<std::size_t>(i)] - mean) / scale;
    D1.row(i) << q.x() * q.x(), q.x() * q.y(), q.y() * q.y();
    D2.row(i) << q.x(), q.y(), 1.0;
  }
  const Eigen::Matrix3d S1 = D1.transpose() * D1, S2 = D1.transpose() * D2,
                        S3 = D2.transpose() * D2;
  Eigen::FullPivLU<Eigen::Matrix3d> lu(S3);
  if (!lu.isInvertible()) return g;  // collinear points: no conic through them is an ellipse
  const Eigen::Matrix3d T = -lu.solve(S2.transpose());
  const Eigen::Matrix3d M = S1 + S2 * T;
  Eigen::Matrix3d Mc;  // C1^{-1} M with C1 the constraint 4 a c - b^2 = 1
  Mc.row(0) = M.row(2) / 2.0;
  Mc.row(1) = -M.row(1);
  Mc.row(2) = M.row(0) / 2.0;
  Eigen::EigenSolver<Eigen::Matrix3d> es(Mc);
  if (es.info() != Eigen::Success) return g;
  Eigen::Vector3d a1 = Eigen::Vector3d::Zero();
  bool found = false;
  double best = 0.0;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d v = es.eigenvectors().col(k).real();
    const double cond = 4.0 * v(0) * v(2) - v(1) * v(1);
    if (cond > best) best = cond, a1 = v, found = true;
  }
  if (!found) return g;
  const Eigen::Vector3d a2 = T * a1;
  const double A = a1(0), B = a1(1), C = a1(2), D = a2(0), E = a2(1), F = a2(2);
  Eigen::Matrix2d Q;
  Q << A, B / 2.0, B / 2.0, C;
  const Eigen::Vector2d c = Q.fullPivLu().solve(Eigen::Vector2d(-D / 2.0, -E / 2.0));
  const double F0 = F + 0.5 * (D * c.x() + E * c.y());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> qs(Q);
  const Eigen::Vector2d lam = qs.eigenvalues();  // ascending: the smaller is the major axis
  const double a2n = -F0 / lam(0), b2n = -F0 / lam(1);
  if (!(a2n > 0.0 && b2n > 0.0) || !c.allFinite()) return g;
  g.center = mean + scale * c;
  g.a = scale * std::sqrt(a2n);
  g.b = scale * std::sqrt(b2n);
  const Eigen::Vector2d major = qs.eigenvectors().col(0);
  g.phi = std::atan2(major.y(), major.x());
  g.t.reserve(points.size());
  for (const auto& p : points)
    g.t.push_back(fit_detail::nearest_latent_angle(p, g.center, g.a, g.b, g.phi));
  g.ok = std::isfinite(g.a) && std::isfinite(g.b) && std::isfinite(g.phi);
  return g;
}

}  // namespace rendulic
