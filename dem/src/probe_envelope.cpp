// Envelope data, the linear-response envelope and the Rendulic map of an envelope
// (docs/physics.md sections 5 and 6). See probe_envelope.hpp.
#include "rendulic/dem/probe_envelope.hpp"

#include <cmath>
#include <stdexcept>

#include "rendulic/core/affine_map.hpp"
#include "rendulic/core/conventions.hpp"

namespace rendulic::dem {

Envelope linear_response_envelope(const LinearResponse& response,
                                  const std::vector<double>& theta_deg, double amplitude,
                                  double k_star, const ProbePlane& plane) {
  if (!response.ok) {
    throw std::invalid_argument("linear_response_envelope: no stiffness (" + response.message +
                                ")");
  }
  Envelope env;
  env.method = "linear_response";
  env.amplitude = amplitude;
  env.k_star = k_star;
  env.plane = plane;
  for (double theta : theta_deg) {
    const Eigen::Matrix3d d_eps = plane_strain(plane, theta, amplitude);
    // No contact opens or closes in the linear response: its fabric rate is the volume and
    // rotation parts alone.
    const FabricSplit split{from_mandel(response.fabric_volume_stiffness * to_mandel(d_eps)),
                            from_mandel(response.fabric_rotation_stiffness * to_mandel(d_eps)),
                            Eigen::Matrix3d::Zero()};
    env.add(theta, d_eps, response.stress_increment(d_eps), response.fabric_increment(d_eps),
            split.volume, split.rotation, split.contacts);
  }
  env.attributes["n_rattlers"] = response.n_rattlers;
  env.attributes["n_backbone_contacts"] = response.n_backbone_contacts;
  env.attributes["residual_force_ratio"] = response.residual_force_ratio;
  env.attributes["seconds"] = response.seconds_total;
  env.attributes["minimised_first"] = response.minimised_first ? 1.0 : 0.0;
  if (response.frictional) {
    // docs/probes.md "Linear response of a frictional packing": with contacts at the Coulomb
    // limit the response depends on the direction and this envelope is not elastic.
    env.attributes["frictional"] = 1.0;
    env.attributes["n_coulomb_limit"] = response.n_coulomb_limit;
    env.attributes["coulomb_limit_fraction"] = response.coulomb_limit_fraction;
    env.attributes["direction_dependent"] = response.direction_dependent() ? 1.0 : 0.0;
    env.attributes["n_floppy"] = response.n_floppy;
    env.attributes["n_rolling_limit"] = response.n_rolling_limit;
  }
  return env;
}

RendulicMap ellipse_of(const Eigen::Matrix2d& map, double amplitude) {
  RendulicMap out;
  out.map = map;
  const MapEllipse e = ellipse_of_map(map);
  out.semi_major = amplitude * e.semi_major;
  out.semi_minor = amplitude * e.semi_minor;
  out.inclination_deg = e.inclination_deg;
  return out;
}

RendulicMap fit_rendulic_map(const std::vector<Eigen::Vector2d>& strain,
                             const std::vector<Eigen::Vector2d>& response) {
  const std::size_t m = strain.size();
  if (m != response.size() || m < 3) {
    throw std::invalid_argument("fit_rendulic_map: needs >= 3 probes with matching responses");
  }
  const AffineMapFit fit = fit_affine_map(strain, response);
  if (fit.rank < 3) throw std::invalid_argument("fit_rendulic_map: strain pairs are collinear");
  double amplitude = 0.0;
  for (std::size_t r = 0; r < m; ++r) amplitude += strain[r].norm() / static_cast<double>(m);
  RendulicMap out = ellipse_of(fit.map, amplitude);
  out.center = fit.center;
  out.rms = fit.rms;
  return out;
}

Eigen::Matrix2d rendulic_map_of(const Matrix6d& stiffness) {
  return plane_map_of(stiffness, rendulic_plane());
}

Eigen::Matrix2d plane_map_of(const Matrix6d& stiffness, const ProbePlane& plane) {
  Eigen::Matrix2d map;
  for (int c = 0; c < 2; ++c) {
    Eigen::Vector2d s = Eigen::Vector2d::Zero();
    s(c) = 1.0;
    map.col(c) = plane_pair(plane, from_mandel(stiffness * to_mandel(from_plane_pair(plane, s))));
  }
  return map;
}

}  // namespace rendulic::dem
