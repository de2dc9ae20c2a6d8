// Conversions between Packing and DemSystem, and the checkpoint reader (see packing_system.hpp).
#include "packing_system.hpp"

#include <cmath>

#include "rendulic/core/errors.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/dem/protocols.hpp"

namespace rendulic::app {

Packing packing_of_system(const dem::DemSystem& s) {
  const dem::Particles& p = s.particles();
  Packing out;
  const auto n = static_cast<Eigen::Index>(p.size());
  out.positions.resize(n, 3);
  out.velocities.resize(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    out.positions.row(i) << p.x[k], p.y[k], p.z[k];
    out.velocities.row(i) << p.vx[k], p.vy[k], p.vz[k];
  }
  out.radii = p.radius;
  out.lengths = s.cell().lengths();
  return out;
}

dem::DemSystem system_of_packing(const Packing& packing, const dem::SystemOptions& options) {
  return dem::system_from_positions(packing.positions, packing.radii, packing.lengths, options);
}

namespace {
std::vector<double> column(const Eigen::MatrixXd& m, int c) {
  std::vector<double> v(static_cast<std::size_t>(m.rows()));
  for (Eigen::Index i = 0; i < m.rows(); ++i) v[static_cast<std::size_t>(i)] = m(i, c);
  return v;
}
// A checkpoint's [entries, 3] spring dataset as the State's history (3 doubles per entry); the
// caller has checked its columns.
std::vector<double> spring_history(const Eigen::MatrixXd& m) {
  if (m.rows() == 0) return {};
  using Rows = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  std::vector<double> h(static_cast<std::size_t>(m.rows()) * 3);
  Eigen::Map<Rows>(h.data(), m.rows(), 3) = m;
  return h;
}
// A checkpoint is restarted as it is, so a number that is not finite would become NaN
// trajectories (or a neighbour list built from NaN): each read is checked, naming its object.
template <class Values>
void check_finite(const ResultsReader& in, const std::string& path, const Values& v) {
  for (const double x : v)
    if (!std::isfinite(x))
      throw InputError(in.path().string() + ":" + path + " holds a number that is not finite");
}
Eigen::MatrixXd matrix(const ResultsReader& in, const std::string& path) {
  Eigen::MatrixXd m = in.read_matrix(path);
  check_finite(in, path, m.reshaped());
  return m;
}
std::vector<double> vector(const ResultsReader& in, const std::string& path) {
  std::vector<double> v = in.read_vector(path);
  check_finite(in, path, v);
  return v;
}
double number(const ResultsReader& in, const std::string& object, const char* name) {
  const double x = in.attr_double(object, name);
  if (!std::isfinite(x))
    throw InputError(in.path().string() + ":" + object + " attribute " + name + " is not finite");
  return x;
}
Eigen::Vector3d three(const ResultsReader& in, const std::string& path) {
  const std::vector<double> v = vector(in, path);
  if (v.size() != 3) throw InputError(in.path().string() + ": " + path + " must hold 3 numbers");
  return {v[0], v[1], v[2]};
}
}  // namespace

std::optional<dem::DemSystem> restore_checkpoint(const ResultsReader& in, const std::string& group,
                                                 const dem::SystemOptions& options) {
  const std::string cp = group + paths::kCheckpoint;
  if (!in.is_group(cp)) return std::nullopt;
  const std::string where = in.path().string() + ":" + cp;
  const Eigen::MatrixXd x = matrix(in, group + datasets::kPositions);
  const std::vector<double> radii = vector(in, group + datasets::kRadii);
  const Eigen::MatrixXd v = matrix(in, cp + datasets::kVelocities);
  const Eigen::MatrixXd f = matrix(in, cp + datasets::kForces);
  const Eigen::MatrixXd ref = matrix(in, cp + datasets::kReferencePositions);
  const auto n = static_cast<Eigen::Index>(radii.size());
  for (const Eigen::MatrixXd* m : {&x, &v, &f, &ref})
    if (m->rows() != n || m->cols() != 3)
      throw InputError(where +
                       ": positions, velocities, forces and reference positions must be "
                       "[N,3] with N = number of radii");
  dem::State s;
  dem::Particles& p = s.particles;
  p.resize(radii.size());
  p.x = column(x, 0), p.y = column(x, 1), p.z = column(x, 2);
  p.vx = column(v, 0), p.vy = column(v, 1), p.vz = column(v, 2);
  p.fx = column(f, 0), p.fy = column(f, 1), p.fz = column(f, 2);
  p.radius = radii;
  for (std::size_t i = 0; i < radii.size(); ++i) {
    if (!(radii[i] > 0)) throw InputError(where + ": radius " + std::to_string(i) + " <= 0");
    p.inv_mass[i] = 1.0 / options.material.sphere_mass(radii[i]);
  }
  s.lengths = three(in, group + datasets::kCellLengths);
  s.strain_E = three(in, cp + datasets::kStrainE);
  s.last_D = three(in, cp + datasets::kLastD);
  if (in.exists(cp + datasets::kLastStressDiag)) {
    s.last_stress_diag = three(in, cp + datasets::kLastStressDiag);
    s.last_stress_known = true;
  }
  s.time = number(in, cp, "time");
  s.steps = in.attr_int(cp, "steps");
  s.ref_x = column(ref, 0), s.ref_y = column(ref, 1), s.ref_z = column(ref, 2);
  s.ref_lengths = three(in, cp + datasets::kReferenceCellLengths);
  s.ref_half_skin = vector(in, cp + datasets::kReferenceHalfSkins);
  if (!s.ref_half_skin.empty() && s.ref_half_skin.size() != radii.size())
    throw InputError(where + ": reference_half_skins must hold one number per particle");
  // A frictional state's rotations and tangential springs (absent from frictionless files and
  // from files written before friction: such a state restarts its springs from zero).
  if (in.exists(cp + datasets::kTangentialSprings)) {
    const Eigen::MatrixXd w = matrix(in, cp + datasets::kAngularVelocities);
    const Eigen::MatrixXd t = matrix(in, cp + datasets::kTorques);
    const Eigen::MatrixXd xi = matrix(in, cp + datasets::kTangentialSprings);
    for (const Eigen::MatrixXd* m : {&w, &t})
      if (m->rows() != n || m->cols() != 3)
        throw InputError(where + ": angular velocities and torques must be [N,3]");
    if (xi.rows() > 0 && xi.cols() != 3)
      throw InputError(where + ": tangential springs must be [entries,3]");
    p.wx = column(w, 0), p.wy = column(w, 1), p.wz = column(w, 2);
    p.tx = column(t, 0), p.ty = column(t, 1), p.tz = column(t, 2);
    s.tangential_history = spring_history(xi);
    s.sliding_dissipation = number(in, cp, "sliding_dissipation");
    // With rolling resistance, its springs, one per entry as the tangential ones.
    if (in.exists(cp + datasets::kRollingSprings)) {
      const Eigen::MatrixXd xr = matrix(in, cp + datasets::kRollingSprings);
      if (xr.rows() != xi.rows() || (xr.rows() > 0 && xr.cols() != 3))
        throw InputError(where + ": rolling springs must be [entries,3] as the tangential ones");
      s.rolling_history = spring_history(xr);
    }
  }
  try {
    return dem::DemSystem::restore(s, options);
  } catch (const InputError& e) {  // e.g. another dem.skin than the state's list was made with
    throw InputError(where + ": " + e.what());
  }
}

}  // namespace rendulic::app
