// Model envelopes over the DEM probe set (envelope.hpp; docs/physics.md section 5).
#include "rendulic/models/envelope.hpp"

#include <algorithm>
#include <cmath>

#include "rendulic/core/errors.hpp"
#include "rendulic/models/umat.hpp"

namespace rendulic::models {

bool EnvelopeOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!(amplitude > 0.0 && amplitude < 1.0)) return fail("amplitude must be in (0, 1)");
  if (directions < 3 || directions > 100000) return fail("directions must be in [3, 100000]");
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
