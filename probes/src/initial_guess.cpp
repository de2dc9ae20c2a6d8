// Initial guesses of the ellipse fit (issue 5 item 1): the affine fit R(theta) = c + M u(theta)
// when the probe directions are known, and the direct algebraic fit of Halir and Flusser
// (1998, a numerically stable form of Fitzgibbon's ellipse-specific fit) when they are not.
// Both are linear algebra only; the geometric refinement is in ellipse_fit.cpp.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "fit_internal.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/probes/envelope_fit.hpp"

namespace rendulic {
namespace fit_detail {

double nearest_latent_angle(const Eigen::Vector2d& p, const Eigen::Vector2d& c, double a, double b,
                            double phi) {
  const Eigen::Vector2d q = rotation(phi).transpose() * (p - c);
  const double x = q.x(), y = q.y();
  auto f = [&](double t) {
    const double dx = a * std::cos(t) - x, dy = b * std::sin(t) - y;
    return dx * dx + dy * dy;
  };
  // A grid fine enough that the nearest point's basin contains a grid node even for thin
  // ellipses: the distance has at most four stationary points on the circle of t.
  constexpr int kGrid = 32;
  double best_t = 0.0, best_f = f(0.0);
  for (int k = 1; k < kGrid; ++k) {
    const double t = 2.0 * kPi * k / kGrid;
    const double v = f(t);
    if (v < best_f) best_f = v, best_t = t;
  }
  const double d2 = b * b - a * a;
  for (int it = 0; it < 12; ++it) {
    const double s = std::sin(best_t), co = std::cos(best_t);
    const double g = d2 * s * co + a * x * s - b * y * co;  // (1/2) df/dt
    const double h = d2 * (co * co - s * s) + a * x * co + b * y * s;
    if (!(h > 0.0)) break;  // not locally convex: keep the grid value
    const double t_new = best_t - g / h;
    const double v = f(t_new);
    if (!(v <= best_f)) break;
    const bool small = std::abs(t_new - best_t) < 1e-14;
    best_t = t_new, best_f = v;
    if (small) break;
  }
  return best_t;
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

}  // namespace fit_detail

AffineFit fit_affine(const std::vector<Eigen::Vector2d>& points,
                     const std::vector<double>& theta_deg) {
  AffineFit out;
  const auto n = static_cast<Eigen::Index>(points.size());
  if (n < 3 || theta_deg.size() != points.size()) return out;
  Eigen::MatrixXd X(n, 3), Y(n, 2);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double t = deg_to_rad(theta_deg[static_cast<std::size_t>(i)]);
    X.row(i) << 1.0, std::cos(t), std::sin(t);
    Y.row(i) = points[static_cast<std::size_t>(i)].transpose();
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(X);
  if (qr.rank() < 3) return out;  // fewer than three independent directions
  const Eigen::MatrixXd B = qr.solve(Y);
  out.center = B.row(0).transpose();
  out.M = B.bottomRows(2).transpose();
  out.rms = std::sqrt((X * B - Y).squaredNorm() / static_cast<double>(n));
  out.ok = out.center.allFinite() && out.M.allFinite();
  return out;
}

EllipseGuess ellipse_guess_from_affine(const AffineFit& affine,
                                       const std::vector<double>& theta_deg) {
  EllipseGuess g;
  if (!affine.ok) return g;
  // M u = U S V^T u. Writing U = R(phi) diag(1, det U) turns this into the ellipse
  // R(phi) diag(s0, det(U) s1) (cos t, sin t) with (cos t, sin t) = V^T u(theta).
  Eigen::JacobiSVD<Eigen::Matrix2d> svd(affine.M, Eigen::ComputeFullU | Eigen::ComputeFullV);
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
