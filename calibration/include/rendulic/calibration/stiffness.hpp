// Level one of the calibration (docs/calibration.md "Two levels", per state): the elastic envelope
// determines the symmetric 2x2 Rendulic stiffness in the (iso, dev) frame,
//   D = [[3B, sqrt(3) A], [sqrt(3) A, 2G]],  (d_sigma_iso, d_sigma_dev) = D (d_eps_iso, d_eps_dev),
// three numbers B, G, A fitted by linear least squares to every probe (and, optionally, a
// centre c that an elastic envelope should not have: its size is a check of linearity). The
// elasto-plastic envelope adds the features the elastic one lacks: the centre shift
// (incremental non-linearity) and the thinning b/a (docs/physics.md section 5), from the affine
// map fit R(theta) = c + M u(theta) of core/affine_map.hpp. Model-free: no constitutive law here.
#pragma once

#include <Eigen/Dense>
#include <string>

#include "rendulic/calibration/data.hpp"

namespace rendulic::calibration {

struct RendulicStiffness {
  bool ok = false;
  std::string note;                  // why not ok, or a caution (e.g. a large centre)
  double B = 0.0, G = 0.0, A = 0.0;  // Pa
  // 1-sigma standard errors from s^2 (X^T X)^-1, s^2 the residual variance; zero for exact data.
  double B_stderr = 0.0, G_stderr = 0.0, A_stderr = 0.0;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  // of (B, G, A)
  Eigen::Vector2d center = Eigen::Vector2d::Zero();      // Pa, Rendulic frame (0 if not fitted)
  double rms = 0.0;                                      // Pa, rms of the residual components
  int n_points = 0;
  // The ellipse this stiffness draws at the envelope's amplitude (docs/physics.md section 6:
  // semi-axes are singular values of D times |d_eps|; inclination of the major axis in the Rendulic
  // frame).
  double a = 0.0, b = 0.0, inclination_deg = 0.0;

  Eigen::Matrix2d iso_dev_matrix() const;   // D in the (iso, dev) frame
  Eigen::Matrix2d rendulic_matrix() const;  // R^T D R: acts on (sqrt2 lat, ax) pairs
};

struct StiffnessOptions {
  bool fit_center = true;
  bool IsValid(std::string* why) const;
};

RendulicStiffness fit_rendulic_stiffness(const EnvelopeRecord& envelope,
                                         const StiffnessOptions& options = {});

// Features of an elasto-plastic envelope (stress and fabric), from the affine fit.
struct PlasticFeatures {
  bool ok = false;
  std::string note;
  double amplitude = 0.0;
  Eigen::Vector2d shift = Eigen::Vector2d::Zero();  // Pa: centre of the stress envelope
  double a = 0.0, b = 0.0, inclination_deg = 0.0;   // Pa, Pa, deg of the stress envelope
  double thinning = 0.0;                            // b / a of the stress envelope
  double shift_ratio = 0.0;                         // |shift| / a
  double rms = 0.0;  // Pa, rms residual of the affine fit (non-ellipticity)
  Eigen::Vector2d fabric_shift = Eigen::Vector2d::Zero();
  double fabric_a = 0.0, fabric_b = 0.0, fabric_inclination_deg = 0.0;
};

PlasticFeatures plastic_features(const EnvelopeRecord& envelope);

}  // namespace rendulic::calibration
