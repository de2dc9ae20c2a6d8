// Envelope features for the models layer (docs/physics.md sections 5 and 6):
// directional stiffnesses along the axes (semi-axis / amplitude), inclination, centre shift
// (absolute and relative to the major axis), the symmetric 2x2 Rendulic stiffness from the
// affine fit R = c + D e (e the strain point), and the elastic/plastic comparison of two
// envelopes of one state (shift, thinning, rotation). Standard errors propagate the fits'
// covariances to first order; the two fits of a comparison are independent data.
#pragma once

#include <Eigen/Dense>
#include <optional>

#include "rendulic/probes/envelope.hpp"
#include "rendulic/probes/envelope_fit.hpp"

namespace rendulic {

struct EnvelopeFeatures {
  double amplitude = 0.0;
  // a / amplitude and b / amplitude: the response per unit strain along the axes.
  double stiffness_major = 0.0, stiffness_major_stderr = 0.0;
  double stiffness_minor = 0.0, stiffness_minor_stderr = 0.0;
  // b / a: 1 for a circle, 0 for a line.
  double aspect_ratio = 0.0, aspect_ratio_stderr = 0.0;
  std::optional<double> inclination_deg, inclination_stderr_deg;  // empty for a circle
  // The centre itself, its distance from the origin, and that distance over a.
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  Eigen::Vector2d center_iso_dev = Eigen::Vector2d::Zero();  // the centre in (iso, dev)
  double center_shift = 0.0, center_shift_stderr = 0.0;
  double center_shift_relative = 0.0, center_shift_relative_stderr = 0.0;
  bool has_stderr = false;
};

// InputError unless amplitude > 0 (finite).
EnvelopeFeatures envelope_features(const EnvelopeFit& fit, double amplitude);

// Symmetric Rendulic stiffness: least squares of R_i = c + D e_i over c (2) and symmetric D
// (3), e_i the strain points. Exact for a linear law plus a shift (docs/physics.md section 6: the
// envelope is then an ellipse with semi-axes amplitude * singular values of D). A hyperelastic
// law gives a symmetric D in these orthonormal coordinates; `asymmetry` measures how far the
// unconstrained 2x2 fit is from symmetric, ||M - M^T|| / (2 ||M||), and `rms` what the linear
// law leaves unexplained (incremental non-linearity of plastic envelopes).
struct RendulicStiffness {
  Eigen::Matrix2d D = Eigen::Matrix2d::Zero();
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  // Standard errors of D11, D12 (= D21), D22 and the centre.
  Eigen::Vector3d D_stderr = Eigen::Vector3d::Zero();
  Eigen::Vector2d center_stderr = Eigen::Vector2d::Zero();
  Eigen::Matrix2d M = Eigen::Matrix2d::Zero();  // unconstrained fit
  double asymmetry = 0.0;
  double rms = 0.0;  // rms of the 2D residual vectors of the symmetric fit
};

// InputError when the envelope has no strain points (neither `strain` nor theta with an
// amplitude) or fewer than 3 independent directions.
RendulicStiffness fit_rendulic_stiffness(const Envelope& envelope);

// Plastic envelope (large amplitude) against the elastic one (small amplitude) of one state.
struct ElasticPlasticComparison {
  // Centres per unit amplitude (stiffness units): plastic minus elastic; its norm, and the
  // norm over the plastic major stiffness (the shift relative to the envelope's size).
  Eigen::Vector2d shift = Eigen::Vector2d::Zero();
  double shift_norm = 0.0, shift_norm_stderr = 0.0;
  double shift_relative = 0.0;
  // (b/a)_plastic / (b/a)_elastic: below 1 the plastic envelope is thinner. Empty when the
  // elastic envelope is a line.
  std::optional<double> thinning, thinning_stderr;
  // Stiffness ratios plastic / elastic along the major and minor axes.
  double major_ratio = 0.0, major_ratio_stderr = 0.0;
  std::optional<double> minor_ratio, minor_ratio_stderr;
  // Inclination plastic minus elastic, in (-90, 90] deg; empty if either is a circle.
  std::optional<double> rotation_deg, rotation_stderr_deg;
};

ElasticPlasticComparison compare_elastic_plastic(const EnvelopeFit& elastic,
                                                 double elastic_amplitude,
                                                 const EnvelopeFit& plastic,
                                                 double plastic_amplitude);

}  // namespace rendulic
