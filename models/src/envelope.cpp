// Model envelopes over the DEM probe set (envelope.hpp; docs/physics.md section 5).
#include "rendulic/models/envelope.hpp"

#include <cmath>

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

ModelEnvelope model_envelope(const Law& law, const MaterialState& state,
                             const EnvelopeOptions& options) {
  ModelEnvelope env;
  std::string why;
  if (!options.IsValid(&why)) {
    env.reason = "invalid envelope options: " + why;
    return env;
  }
  if (!law.admissible(state, &why)) {
    env.reason = "start state: " + why;
    return env;
  }
  // A UMAT's rate is DDSDDE : d_eps; its failures name the UMAT's increment (umat.hpp).
  const auto* umat = dynamic_cast<const UmatLaw*>(&law);
  const int m = options.directions;
  env.theta_deg = probe_directions_deg(m);
  env.strain.resize(m, 2);
  env.stress.resize(m, 2);
  env.fabric.resize(m, 2);
  env.d_stress.resize(m);
  env.d_fabric.resize(m);
  for (int i = 0; i < m; ++i) {
    const Eigen::Matrix3d de = probe_strain(env.theta_deg(i), options.amplitude);
    if (options.method == EnvelopeMethod::kRate) {
      LawRate r;
      if (umat && !umat->rate_checked(state, de, &r, &why)) {
        env.reason = "probe theta = " + format_g(env.theta_deg(i)) + " deg: " + why;
        return env;
      }
      if (!umat) r = law.rate(state, de);
      env.d_stress[i] = r.d_stress;
      env.d_fabric[i] = r.d_fabric;
      ++env.total_substeps;
    } else {
      const StepResult res = integrate(law, state, de, options.step);
      if (!res.success) {
        env.reason = "probe theta = " + format_g(env.theta_deg(i)) + " deg: " + res.reason;
        return env;
      }
      env.d_stress[i] = res.end.stress - state.stress;
      env.d_fabric[i] = res.end.fabric - state.fabric;
      env.max_error_estimate = std::max(env.max_error_estimate, res.error_estimate);
      env.within_tolerance = env.within_tolerance && res.within_tolerance;
      env.total_substeps += res.substeps;
    }
    if (!env.d_stress[i].allFinite() || !env.d_fabric[i].allFinite()) {
      env.reason = "probe theta = " + format_g(env.theta_deg(i)) + " deg: non-finite response";
      return env;
    }
    env.strain.row(i) = rendulic_pair(de).transpose();
    env.stress.row(i) = rendulic_pair(env.d_stress[i]).transpose();
    env.fabric.row(i) = rendulic_pair(env.d_fabric[i]).transpose();
  }
  env.success = true;
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
