// The consumer of tests/install: calls into the installed libraries and checks two closed forms,
// so that a package whose headers, libraries or dependencies are incomplete fails to build,
// link or run. Exit 0 only when both hold.
#include <cmath>
#include <cstdio>
#include <numbers>

#include "rendulic/core/conventions.hpp"
#include "rendulic/dem/contact.hpp"
#ifndef DEM_ONLY
#include "rendulic/probes/envelope.hpp"
#include "rendulic/probes/envelope_fit.hpp"
#endif

int main() {
  // Contact duration of an undamped pair: t_c = pi sqrt(m_red / k).
  const rendulic::dem::NormalContact c{1e8, 0.0};
  const double m = 1e-5;
  const double tc = rendulic::dem::contact_time(c, m);
  if (std::abs(tc - std::numbers::pi * std::sqrt(m / 1e8)) > 1e-12 * tc) return 1;
#ifndef DEM_ONLY
  // An exact ellipse (semi-axes 3 and 1, inclined 30 deg) is fitted back.
  rendulic::Envelope e;
  const double phi = std::numbers::pi / 6;
  for (double th : rendulic::probe_directions_deg(24)) {
    const double t = th * std::numbers::pi / 180;
    const double u = 3 * std::cos(t), v = std::sin(t);
    e.response.push_back(
        {u * std::cos(phi) - v * std::sin(phi), u * std::sin(phi) + v * std::cos(phi)});
    e.theta_deg.push_back(th);
  }
  rendulic::FitOptions o;
  o.shape = rendulic::FitShape::kEllipse;
  const rendulic::EnvelopeFit f = rendulic::fit_envelope(e, o);
  if (std::abs(f.a - 3) > 1e-6 || std::abs(f.b - 1) > 1e-6) return 2;
#endif
  std::puts("consumer: ok");
  return 0;
}
