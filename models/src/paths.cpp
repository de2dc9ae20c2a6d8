// Isotropic compression, undrained axisymmetric and drained triaxial paths through a law
// (paths.hpp, docs/models.md "Paths").
#include "rendulic/models/paths.hpp"

#include <cmath>

#include "rendulic/core/decimal.hpp"
#include "rendulic/models/umat.hpp"

namespace rendulic::models {
namespace {

void record(PathSeries* s, const Eigen::Matrix3d& eps, const MaterialState& y) {
  s->strain.push_back(eps);
  s->eps_v.push_back(volumetric_strain(eps));
  s->eps_dev.push_back(signed_deviator(eps));
  s->stress.push_back(y.stress);
  s->fabric.push_back(y.fabric);
  s->volume_fraction.push_back(y.volume_fraction);
  s->internal.push_back(y.internal);
}

std::string step_failure(int k, const PathOptions& o, const std::string& why) {
  return "step " + std::to_string(k + 1) + " of " + std::to_string(o.steps) + ": " + why;
}

// One recorded step of a path: whether it succeeded (else why not), the state it ends in, the
// strain it applied and its driver's figures.
struct PathStep {
  bool success = false;
  std::string reason;
  MaterialState end;
  Eigen::Matrix3d d_eps;
  double error_estimate = 0.0;
  int substeps = 0;
};

// The steps of a path from `start` with options `o` (checked first), `step(y)` taking each from
// the state y: recorded, checked for the volume fraction, reported to PathOptions::after_step.
template <class Step>
PathSeries follow(const MaterialState& start, const PathOptions& o, Step&& step) {
  PathSeries s;
  if (std::string why; !o.IsValid(&why)) {
    s.reason = "invalid path options: " + why;
    return s;
  }
  Eigen::Matrix3d eps = Eigen::Matrix3d::Zero();
  MaterialState y = start;
  record(&s, eps, y);
  for (int k = 0; k < o.steps; ++k) {
    const PathStep r = step(y);
    if (!r.success) {
      s.reason = step_failure(k, o, r.reason);
      return s;
    }
    y = r.end;
    eps += r.d_eps;
    if (const std::string bad = volume_fraction_problem(y.volume_fraction); !bad.empty()) {
      s.reason = step_failure(k, o, bad);
      return s;
    }
    s.max_error_estimate = std::max(s.max_error_estimate, r.error_estimate);
    s.total_substeps += r.substeps;
    record(&s, eps, y);
    if (o.after_step) o.after_step(k + 1, o.steps);
  }
  s.success = true;
  return s;
}

PathSeries run_path(const Law& law, const MaterialState& start, const Eigen::Matrix3d& total,
                    const PathOptions& o) {
  if (!total.allFinite()) {
    PathSeries s;
    s.reason = "the path's end strain is not finite";  // before its first step, for a UMAT too
    return s;
  }
  // A UMAT's path carries its whole STATEV (umat.hpp).
  if (const auto* umat = dynamic_cast<const UmatLaw*>(&law)) return umat->run_path(start, total, o);
  return follow(start, o, [&](const MaterialState& y) {
    const Eigen::Matrix3d de = total / o.steps;  // after follow's check of o.steps
    const StepResult r = integrate(law, y, de, o.step);
    return PathStep{r.success, r.reason, r.end, de, r.error_estimate, r.substeps};
  });
}

}  // namespace

std::string volume_fraction_problem(double nu) {
  // A packing cannot be compressed beyond solid (the state files' own range is [0, 1), 0 for a
  // state that gives none): material_point_path(kind="isotropic", end=50) returned 3e21.
  if (nu >= 0.0 && nu < 1.0) return "";
  return "the volume fraction reached " + decimal_g(nu) +
         ", outside [0, 1): the path strains the packing beyond what it can take";
}

bool PathOptions::IsValid(std::string* why) const {
  // Each step is kept (strain, stress, fabric, ...): 2^31 steps asked for ~700 GB.
  if (steps < 1 || steps > kMaxSteps) {
    if (why) *why = "steps must be in [1, " + std::to_string(kMaxSteps) + "]";
    return false;
  }
  return step.IsValid(why);
}

PathSeries strain_path(const Law& law, const MaterialState& start,
                       const Eigen::Matrix3d& strain_end, const PathOptions& options) {
  return run_path(law, start, strain_end, options);
}

PathSeries isotropic_compression_path(const Law& law, const MaterialState& start, double eps_v_end,
                                      const PathOptions& options) {
  return run_path(law, start, (eps_v_end / 3.0) * Eigen::Matrix3d::Identity(), options);
}

Eigen::Matrix3d undrained_axisymmetric_strain(double eps_dev) {
  // diag(1, -1/2, -1/2) has signed deviator +sqrt(3/2), so a = eps_dev / sqrt(3/2).
  const double a = eps_dev / std::sqrt(1.5);
  return a * Eigen::Vector3d(1.0, -0.5, -0.5).asDiagonal().toDenseMatrix();
}

PathSeries undrained_axisymmetric_path(const Law& law, const MaterialState& start,
                                       double eps_dev_end, const PathOptions& options) {
  return run_path(law, start, undrained_axisymmetric_strain(eps_dev_end), options);
}

PathSeries drained_triaxial_path(const Law& law, const MaterialState& start, double eps_axial_end,
                                 const PathOptions& o) {
  PathSeries s;
  if (!std::isfinite(eps_axial_end)) {
    s.reason = "the path's end strain is not finite";
    return s;
  }
  // integrate_mixed drives the law through its rate; a UMAT's STATEV beyond the six internal
  // variables would be lost between its calls (UmatLaw::run_path carries them).
  if (dynamic_cast<const UmatLaw*>(&law)) {
    s.reason =
        "a drained path is for the built-in laws: a UMAT is driven by strain only (a "
        "proportional strain path with the strains it should follow)";
    return s;
  }
  MixedOptions mixed;
  mixed.step = o.step;
  MixedControl c;
  c.stress_controlled = {false, true, true, false, false, false};  // Mandel: xx yy zz yz xz xy
  const Vector6d held = to_mandel(start.stress);
  return follow(start, o, [&](const MaterialState& y) {
    // Each step aims at the start's lateral stresses, not at a zero increment, so that Newton's
    // residuals (1e-9 relative) do not add up over the steps.
    c.strain_increment(0) = eps_axial_end / o.steps;  // after follow's check of o.steps
    const Vector6d now = to_mandel(y.stress);
    for (int i : {1, 2}) c.stress_increment(i) = held(i) - now(i);
    const MixedResult r = integrate_mixed(law, y, c, mixed);
    return PathStep{r.step.success,       r.step.reason,
                    r.step.end,           from_mandel(r.strain_increment),
                    r.max_error_estimate, r.substeps};
  });
}

}  // namespace rendulic::models
