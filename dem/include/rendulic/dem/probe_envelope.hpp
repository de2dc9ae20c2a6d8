// Response envelopes of strain probes (docs/physics.md sections 5 and 6; docs/results.md
// /states/<label>/envelopes/<name>): the data of one envelope whatever made it (dynamic
// probes, quasi-static minimisation probes or the linear response), the elastic envelope of a
// linear-response stiffness, and the 2x2 Rendulic map of an envelope with its exact ellipse
// (semi-axes = singular values, docs/physics.md section 6) used to compare methods.
#pragma once

#include <Eigen/Dense>
#include <map>
#include <string>
#include <vector>

#include "rendulic/core/envelope_record.hpp"
#include "rendulic/dem/linear_response.hpp"

namespace rendulic::dem {

// An envelope of the DEM is core's envelope record (core/envelope_record.hpp): the one type
// that the results file stores and every reader takes its view from.
using Envelope = EnvelopeRecord;

// The elastic envelope of the linear response for the given directions and amplitude in a
// probe plane: the probe strain of core plane_strain(plane, theta, amplitude) (probe_strain in
// the Rendulic plane), d_sigma = C d_eps, d_F = G d_eps. Throws std::invalid_argument if the
// response is not ok (it holds no stiffness).
Envelope linear_response_envelope(const LinearResponse& response,
                                  const std::vector<double>& theta_deg, double amplitude,
                                  double k_star, const ProbePlane& plane = rendulic_plane());

// The Rendulic map of an envelope: response = map * strain + center, fitted by least squares
// over the probes (core/affine_map.hpp; exact for a linear law, where center = 0), and its
// ellipse: semi-axes a >= b (singular values times the amplitude) and the inclination of the
// major axis in [0, 180) deg from the sqrt(2)-lateral axis.
struct RendulicMap {
  Eigen::Matrix2d map = Eigen::Matrix2d::Zero();
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double semi_major = 0.0;
  double semi_minor = 0.0;
  double inclination_deg = 0.0;
  double rms = 0.0;  // root-mean-square residual of the fit
};
// Needs at least 3 probes with non-collinear strain pairs (std::invalid_argument otherwise).
RendulicMap fit_rendulic_map(const std::vector<Eigen::Vector2d>& strain,
                             const std::vector<Eigen::Vector2d>& response);
// The exact map of a 6x6 Mandel stiffness restricted to axisymmetric strains:
// (sqrt2 lat, ax) of d_eps -> (sqrt2 lat, ax) of M d_eps.
Eigen::Matrix2d rendulic_map_of(const Matrix6d& stiffness);
// The same in any probe plane: the plane's pair of d_eps -> the plane's pair of M d_eps (the
// projection of the response on the plane; rendulic_map_of for the Rendulic plane).
Eigen::Matrix2d plane_map_of(const Matrix6d& stiffness, const ProbePlane& plane);
// Ellipse of a 2x2 map for a given strain amplitude (center 0).
RendulicMap ellipse_of(const Eigen::Matrix2d& map, double amplitude);

}  // namespace rendulic::dem
