// Main loading paths driven through a law (compared with the DEM curves of the
// seed's Fig. 1 and the isotropic branch of docs/physics.md section 4): isotropic compression,
// undrained (constant-volume) axisymmetric deformation along x,
// d_eps = a diag(1, -1/2, -1/2) (compression positive; a < 0 is the seed's axial extension), and
// the drained triaxial path of the DEM's path.type = drained_* (docs/models.md "Paths").
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "rendulic/models/driver.hpp"

namespace rendulic::models {

// "" for a volume fraction a path may reach, else why not (outside [0, 1)); both path drivers
// (the laws' and a UMAT's) stop there.
std::string volume_fraction_problem(double nu);

struct PathOptions {
  static constexpr int kMaxSteps = 1000000;
  int steps = 200;  // recorded, equal strain steps; each is integrated with error control
  StepOptions step;
  // Called after each recorded step with (steps done, steps): the Python module reports
  // progress and honours Ctrl-C through it, throwing to end a path of minutes (docs/python.md).
  std::function<void(int, int)> after_step;
  bool IsValid(std::string* why) const;
};

// One row per recorded sample, the first being the start state.
struct PathSeries {
  bool success = false;
  std::string reason;
  std::vector<Eigen::Matrix3d> strain, stress, fabric;  // accumulated strain, compression +
  std::vector<double> eps_v, eps_dev, volume_fraction;  // eps_dev signed, docs/physics.md section 3
  std::vector<Vector6d> internal;
  double max_error_estimate = 0.0;
  int total_substeps = 0;
};

// Any proportional strain path from `start` to the strain `strain_end` (compression positive)
// in equal steps; the two below are its special cases.
PathSeries strain_path(const Law& law, const MaterialState& start,
                       const Eigen::Matrix3d& strain_end, const PathOptions& options = {});
// Isotropic compression from `start` to volumetric strain eps_v_end (> 0 compresses).
PathSeries isotropic_compression_path(const Law& law, const MaterialState& start, double eps_v_end,
                                      const PathOptions& options = {});
// The strain of the undrained axisymmetric path at signed deviatoric strain eps_dev: constant
// volume, axial along x, d_eps proportional to diag(1, -1/2, -1/2).
Eigen::Matrix3d undrained_axisymmetric_strain(double eps_dev);

// Undrained axisymmetric path from `start` to signed deviatoric strain eps_dev_end
// (negative: axial extension along x, as in the seed; e.g. -0.32).
PathSeries undrained_axisymmetric_path(const Law& law, const MaterialState& start,
                                       double eps_dev_end, const PathOptions& options = {});

// Drained triaxial path from `start` to axial strain eps_axial_end along x (compression
// positive; negative: drained extension): the lateral stresses sigma_yy, sigma_zz are held at
// their start values by the mixed-control driver (integrate_mixed), no shear strain, as the
// DEM's drained paths hold an orthorhombic cell's lateral stress. Built-in laws only: a UMAT is
// driven by strain (docs/umat.md).
PathSeries drained_triaxial_path(const Law& law, const MaterialState& start, double eps_axial_end,
                                 const PathOptions& options = {});

}  // namespace rendulic::models
