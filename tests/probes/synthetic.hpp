// Synthetic envelopes for the probes/ tests: points of a known ellipse or line, with and
// without probe directions, Gaussian noise and outliers, drawn from a seeded generator so
// that every test is reproducible.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <vector>

#include "rendulic/core/conventions.hpp"
#include "rendulic/probes/envelope.hpp"

namespace rendulic::test {

struct TrueEllipse {
  Eigen::Vector2d c{0.0, 0.0};
  double a = 1.0, b = 0.5, phi_deg = 30.0;
  Eigen::Vector2d at(double t) const {
    const double p = deg_to_rad(phi_deg);
    Eigen::Matrix2d R;
    R << std::cos(p), -std::sin(p), std::sin(p), std::cos(p);
    return c + R * Eigen::Vector2d(a * std::cos(t), b * std::sin(t));
  }
};

// m points at latent angles t0 + k * span / m (span 2 pi: the whole ellipse). The latent
// angle is reported as theta_deg when with_theta: the envelope of the linear law
// R(phi) diag(a, b) applied to u(theta), plus the centre c.
inline Envelope ellipse_envelope(const TrueEllipse& e, int m, double sigma = 0.0,
                                 std::uint64_t seed = 1, bool with_theta = false,
                                 double span = 2.0 * kPi, double t0 = 0.1) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Envelope env;
  const bool closed = std::abs(span - 2.0 * kPi) < 1e-12;
  for (int k = 0; k < m; ++k) {
    const double t = t0 + span * k / (closed ? m : m - 1);
    env.response.push_back(e.at(t) + sigma * Eigen::Vector2d(normal(rng), normal(rng)));
    if (with_theta) env.theta_deg.push_back(rad_to_deg(t));
  }
  return env;
}

// Degenerate ellipse b = 0: points c + a cos(t) (cos phi, sin phi).
inline Envelope line_envelope(const Eigen::Vector2d& c, double a, double phi_deg, int m,
                              double sigma = 0.0, std::uint64_t seed = 1, bool with_theta = false) {
  TrueEllipse e;
  e.c = c, e.a = a, e.b = 0.0, e.phi_deg = phi_deg;
  return ellipse_envelope(e, m, sigma, seed, with_theta);
}

// Difference of two axis angles in degrees, modulo 180, in [0, 90].
inline double angle_diff_deg(double x, double y) {
  double d = std::fmod(std::abs(x - y), 180.0);
  return d > 90.0 ? 180.0 - d : d;
}

}  // namespace rendulic::test
