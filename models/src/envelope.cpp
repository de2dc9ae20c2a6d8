// Model envelopes over the DEM probe set (envelope.hpp; docs/physics.md section 5).
#include "rendulic/models/envelope.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "rendulic/core/errors.hpp"
#include "rendulic/models/umat.hpp"

namespace rendulic::models {

bool EnvelopeOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!(amplitude > 0.0 && amplitude < 1.0)) return fail("amplitude must be in (0, 1)");
  if (directions < kEnvelopeDirectionsMin || directions > kEnvelopeDirectionsMax)
    return fail("directions must be in [" + std::to_string(kEnvelopeDirectionsMin) + ", " +
                std::to_string(kEnvelopeDirectionsMax) + "]");
  return step.IsValid(why);
}

EnvelopeRecord model_envelope(const Law& law, const MaterialState& state,
                              const EnvelopeOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("invalid envelope options: " + why);
  if (!law.admissible(state, &why)) throw InputError("start state: " + why);
  // A UMAT's rate is DDSDDE : d_eps; its failures name the UMAT's increment (umat.hpp).
  const auto* umat = dynamic_cast<const UmatLaw*>(&law);
  const int m = options.directions;
  const Eigen::VectorXd theta = probe_directions_deg(m);
  EnvelopeRecord env;
  env.method = "model";
  env.amplitude = options.amplitude;
  double max_error_estimate = 0.0;
  bool within_tolerance = true;
  int total_substeps = 0;
  for (int i = 0; i < m; ++i) {
    const std::string probe = "probe theta = " + format_g(theta(i)) + " deg: ";
    const Eigen::Matrix3d de = probe_strain(theta(i), options.amplitude);
    Eigen::Matrix3d d_stress, d_fabric;
    if (options.method == EnvelopeMethod::kRate) {
      LawRate r;
      if (umat && !umat->rate_checked(state, de, &r, &why)) throw InputError(probe + why);
      if (!umat) r = law.rate(state, de);
      d_stress = r.d_stress;
      d_fabric = r.d_fabric;
      ++total_substeps;
    } else {
      const StepResult res = integrate(law, state, de, options.step);
      if (!res.success) throw InputError(probe + res.reason);
      d_stress = res.end.stress - state.stress;
      d_fabric = res.end.fabric - state.fabric;
      max_error_estimate = std::max(max_error_estimate, res.error_estimate);
      within_tolerance = within_tolerance && res.within_tolerance;
      total_substeps += res.substeps;
    }
    if (!d_stress.allFinite() || !d_fabric.allFinite())
      throw InputError(probe + "non-finite response");
    env.theta_deg.push_back(theta(i));
    env.strain.push_back(rendulic_pair(de));
    env.stress.push_back(rendulic_pair(d_stress));
    env.fabric.push_back(rendulic_pair(d_fabric));
    env.d_stress.push_back(d_stress);
    env.d_fabric.push_back(d_fabric);
  }
  // An integrated probe's response is end stress minus start stress: when the increments are
  // near the rounding of the stress itself, the difference is rounding noise (amplitude 1e-18
  // on 1e5 Pa gave a lopsided envelope, 1e-300 a zero one, both "within tolerance"). The rate
  // method takes no difference; a law whose response is zero is exactly zero either way.
  if (options.method == EnvelopeMethod::kIntegrated) {
    double largest = 0.0;
    // Largest entries, not norms: the squares of increments near 1e-300 underflow to zero.
    for (const auto& ds : env.d_stress) largest = std::max(largest, ds.lpNorm<Eigen::Infinity>());
    const double rounding =
        std::numeric_limits<double>::epsilon() * state.stress.lpNorm<Eigen::Infinity>();
    const double wanted = rounding / options.step.tolerance;
    bool unresolved = largest < wanted;
    if (unresolved && largest == 0.0) {
      const Eigen::Matrix3d de = probe_strain(theta(0), options.amplitude);
      LawRate r;
      if (umat) {
        unresolved =
            umat->rate_checked(state, de, &r, &why) && r.d_stress.lpNorm<Eigen::Infinity>() > 0.0;
      } else {
        unresolved = law.rate(state, de).d_stress.lpNorm<Eigen::Infinity>() > 0.0;
      }
    }
    if (unresolved) {
      std::ostringstream msg;
      msg << "amplitude " << options.amplitude << ": the largest stress increment, " << largest
          << " Pa, is below the rounding of the stress (" << rounding
          << " Pa) divided by the tolerance " << options.step.tolerance
          << ": the integrated envelope would be rounding noise; use a larger amplitude or the "
             "rate method";
      throw InputError(msg.str());
    }
  }
  env.attributes["max_error_estimate"] = max_error_estimate;
  env.attributes["within_tolerance"] = within_tolerance ? 1.0 : 0.0;
  env.attributes["total_substeps"] = total_substeps;
  return env;
}

Eigen::Matrix2d rendulic_tangent(const Law& law, const MaterialState& state, double theta_deg) {
  const Matrix6d t = law.tangent(state, probe_strain(theta_deg, 1.0));
  Eigen::Matrix2d d;
  for (int j = 0; j < 2; ++j) {
    const Eigen::Matrix3d e = from_rendulic_pair(Eigen::Vector2d::Unit(j));
    d.col(j) = rendulic_pair(from_mandel(Vector6d(t * to_mandel(e))));
  }
  return d;
}

}  // namespace rendulic::models
