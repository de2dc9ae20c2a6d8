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

#include "rendulic/dem/linear_response.hpp"

namespace rendulic::dem {

struct Envelope {
  std::string method;      // "dynamic" | "minimisation" | "linear_response"
  double amplitude = 0.0;  // |d_eps| (Frobenius)
  double k_star = 0.0;     // Pa, the stress scale of stress_star
  std::vector<double> theta_deg;
  std::vector<Eigen::Vector2d> strain;       // Rendulic pairs of d_eps
  std::vector<Eigen::Vector2d> stress_star;  // Rendulic pairs of d_sigma / k*
  std::vector<Eigen::Vector2d> fabric;       // Rendulic pairs of d_F
  std::vector<Eigen::Matrix3d> d_stress;     // Pa, compression positive
  std::vector<Eigen::Matrix3d> d_fabric;
  // d_fabric split with the contact set of the starting state held fixed (FabricSplit,
  // probe_geometry.hpp): volume change, rotation of the normals, contacts made and lost.
  // Empty for envelopes made without it; otherwise one entry per probe each.
  std::vector<Eigen::Matrix3d> d_fabric_volume, d_fabric_rotation, d_fabric_contacts;
  // Per-probe diagnostics ([m] each), e.g. contacts_opened, contacts_closed, relax_time,
  // relax_steps, kinetic_to_elastic, converged; written as datasets next to the envelope.
  std::map<std::string, std::vector<double>> diagnostics;
  // Per-envelope scalars (attributes), e.g. rate, inertial_number, n_rattlers.
  std::map<std::string, double> attributes;

  std::size_t size() const { return theta_deg.size(); }
  // Appends one probe; the pairs follow from the tensors (core/conventions.hpp).
  void add(double theta, const Eigen::Matrix3d& d_eps, const Eigen::Matrix3d& d_sigma,
           const Eigen::Matrix3d& d_f);
  void add(double theta, const Eigen::Matrix3d& d_eps, const Eigen::Matrix3d& d_sigma,
           const Eigen::Matrix3d& d_f, const FabricSplit& split);
};

// The elastic envelope of the linear response for the given directions and amplitude: the
// probe strain of core probe_strain(theta, amplitude), d_sigma = C d_eps, d_F = G d_eps.
// Throws std::invalid_argument if the response is not ok (it holds no stiffness).
Envelope linear_response_envelope(const LinearResponse& response,
                                  const std::vector<double>& theta_deg, double amplitude,
                                  double k_star);

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
// Ellipse of a 2x2 map for a given strain amplitude (center 0).
RendulicMap ellipse_of(const Eigen::Matrix2d& map, double amplitude);

}  // namespace rendulic::dem
