// Protocols of docs/physics.md section 4 and the probe primitives of section 5 (see protocols.hpp).
#include "rendulic/dem/protocols.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

#include "rendulic/core/comma_list.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/dem/cell.hpp"

namespace rendulic::dem {
namespace {
bool fail(std::string* why, const std::string& m) {
  if (why) *why = m;
  return false;
}
}  // namespace

bool GasOptions::IsValid(std::string* why) const {
  if (n_particles < 2) return fail(why, "n_particles must be at least 2");
  if (!(volume_fraction >= kGasVolumeFractionMin && volume_fraction <= kGasVolumeFractionMax))
    return fail(why, "gas volume fraction must be in [" + decimal_g(kGasVolumeFractionMin) + ", " +
                         decimal_g(kGasVolumeFractionMax) + "]");
  if (!(velocity >= 0 && std::isfinite(velocity))) return fail(why, "gas velocity must be >= 0");
  return true;
}
bool RelaxOptions::IsValid(std::string* why) const {
  if (!(kinetic_to_elastic > 0)) return fail(why, "relax threshold must be positive");
  if (!(time_cap > 0 && std::isfinite(time_cap))) return fail(why, "relax time cap must be > 0");
  if (check_every < 1) return fail(why, "relax check interval must be >= 1");
  return true;
}
bool CompressOptions::IsValid(std::string* why) const {
  if (!(target_nu > 0 && target_nu < 1)) return fail(why, "target volume fraction in (0, 1)");
  if (!(rate_max > 0 && std::isfinite(rate_max))) return fail(why, "rate_max must be > 0");
  if (!(rate_min > 0 && rate_min <= rate_max)) return fail(why, "rate_min in (0, rate_max]");
  if (!(inertial_number >= 0)) return fail(why, "inertial number must be >= 0");
  if (samples < 0 || samples == 1) return fail(why, "samples must be 0 or >= 2");
  for (double nu : snapshot_nu)
    if (!(nu > 0 && nu < 1)) return fail(why, "snapshot volume fractions in (0, 1)");
  if (!(target_pressure_star >= 0 && std::isfinite(target_pressure_star)))
    return fail(why, "target pressure must be >= 0");
  return true;
}
bool PathOptions::IsValid(std::string* why) const {
  if (!(rate > 0 && std::isfinite(rate))) return fail(why, "path rate must be > 0");
  if (!(inertial_number >= 0 && std::isfinite(inertial_number)))
    return fail(why, "the path's inertial number must be >= 0");
  if (inertial_number > 0 && !(rate_min > 0 && rate_min <= rate))
    return fail(why, "the path's rate_min must be in (0, rate]");
  if (!(eps_dev_max > 0)) return fail(why, "eps_dev_max must be > 0");
  if (samples < 2) return fail(why, "path samples must be >= 2");
  for (double e : snapshot_eps_dev)
    if (!(e > 0 && e <= eps_dev_max))
      return fail(why, "every snapshot -eps_dev must be in (0, eps_dev_max]");
  if (const std::string bad = choice_refusal(type, path_type_choices()); !bad.empty())
    return fail(why, "path type " + bad);
  if (path_type(type).kind == PathKind::kProportional) {
    if (direction.size() != 3) return fail(why, "the path direction needs 3 components");
    double largest = 0;
    for (double d : direction) {
      if (!std::isfinite(d)) return fail(why, "the path direction must be finite");
      largest = std::max(largest, std::abs(d));
    }
    if (!(largest > 0)) return fail(why, "the path direction must not be zero");
  }
  if (!(servo_gain > 0 && std::isfinite(servo_gain)))
    return fail(why, "servo gain must be positive");
  if (!(servo_integral_gain >= 0 && std::isfinite(servo_integral_gain)))
    return fail(why, "servo integral gain must be >= 0");
  if (!(servo_max_rate_factor >= 1 && std::isfinite(servo_max_rate_factor)))
    return fail(why, "the servo's rate factor must be >= 1");
  if (!(servo_tolerance > 0)) return fail(why, "the servo tolerance must be > 0");
  return true;
}

ServoOptions PathOptions::servo(const Material& m) const {
  const double t_c = contact_duration(m);
  return {.gain = servo_gain / t_c,
          .integral_gain = servo_integral_gain / (t_c * t_c),
          .max_rate = servo_max_rate_factor * rate};
}

namespace {
const std::vector<std::pair<std::string, PathType>>& path_types() {
  using K = PathKind;
  static const std::vector<std::pair<std::string, PathType>> types = {
      {"undrained_extension", {K::kUndrained, 1.0}},
      {"undrained_compression", {K::kUndrained, -1.0}},
      {"drained_extension", {K::kDrained, 1.0}},
      {"drained_compression", {K::kDrained, -1.0}},
      {"constant_p_extension", {K::kConstantMeanStress, 1.0}},
      {"constant_p_compression", {K::kConstantMeanStress, -1.0}},
      {"isotropic_loading", {K::kIsotropic, -1.0}},
      {"isotropic_unloading", {K::kIsotropic, 1.0}},
      {"proportional", {K::kProportional, 1.0}}};
  return types;
}
}  // namespace

const std::vector<std::string>& path_type_choices() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const auto& t : path_types()) n.push_back(t.first);
    return n;
  }();
  return names;
}

PathType path_type(const std::string& name) {
  for (const auto& [n, t] : path_types())
    if (n == name) return t;
  PathOptions o;
  o.type = name;
  std::string why;
  o.IsValid(&why);
  throw InputError(why);
}

DemSystem make_gas(const SystemOptions& options, const GasOptions& gas, std::uint64_t seed) {
  std::string why;
  if (!gas.IsValid(&why)) throw InputError("gas: " + why);
  Rng rng(seed);
  Particles p = make_particles(options.material, gas.n_particles, rng);
  const double L = std::cbrt(p.total_volume() / gas.volume_fraction);
  const double r_max = *std::max_element(p.radius.begin(), p.radius.end());
  const int nb = cell_list_bins(Eigen::Vector3d::Constant(L), 2.0 * r_max, p.size())[0];
  const double bin = L / nb;
  std::vector<std::vector<std::int32_t>> bins(static_cast<std::size_t>(nb) * nb * nb);
  std::vector<std::size_t> order(p.size());
  std::iota(order.begin(), order.end(), 0);
  // Largest first: the hard part of random insertion is finding room for big spheres.
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return p.radius[a] > p.radius[b]; });
  auto wrap = [&](int c) { return ((c % nb) + nb) % nb; };
  constexpr int kMaxTries = 100000;
  for (std::size_t i : order) {
    bool placed = false;
    for (int t = 0; t < kMaxTries && !placed; ++t) {
      const Eigen::Vector3d q(rng.uniform(0, L), rng.uniform(0, L), rng.uniform(0, L));
      const int cx = std::min(nb - 1, int(q[0] / bin)), cy = std::min(nb - 1, int(q[1] / bin)),
                cz = std::min(nb - 1, int(q[2] / bin));
      bool ok = true;
      const int span = nb >= 3 ? 1 : 0;
      for (int dz = -span; dz <= span && ok; ++dz)
        for (int dy = -span; dy <= span && ok; ++dy)
          for (int dx = -span; dx <= span && ok; ++dx) {
            const auto& members =
                nb >= 3 ? bins[wrap(cx + dx) + nb * (wrap(cy + dy) + nb * wrap(cz + dz))] : bins[0];
            for (std::int32_t j : members) {
              Eigen::Vector3d d = q - p.position(j);
              for (int a = 0; a < 3; ++a) d[a] -= L * std::round(d[a] / L);
              const double R = p.radius[i] + p.radius[j];
              if (d.squaredNorm() < R * R) {
                ok = false;
                break;
              }
            }
          }
      if (!ok) continue;
      p.x[i] = q[0], p.y[i] = q[1], p.z[i] = q[2];
      const int c = nb >= 3 ? cx + nb * (cy + nb * cz) : 0;
      bins[c].push_back(static_cast<std::int32_t>(i));
      placed = true;
    }
    if (!placed)
      throw InputError("gas: could not place particle " + std::to_string(i) +
                       " without overlap; lower the gas volume fraction");
  }
  // Random velocities without net momentum.
  Eigen::Vector3d momentum = Eigen::Vector3d::Zero();
  double mass = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    p.vx[i] = gas.velocity * rng.normal();
    p.vy[i] = gas.velocity * rng.normal();
    p.vz[i] = gas.velocity * rng.normal();
    momentum += p.mass(i) * p.velocity(i);
    mass += p.mass(i);
  }
  const Eigen::Vector3d v0 = momentum / mass;
  for (std::size_t i = 0; i < p.size(); ++i) {
    p.vx[i] -= v0[0];
    p.vy[i] -= v0[1];
    p.vz[i] -= v0[2];
  }
  // Number the particles along the bins (z, y, x): neighbours in space are then close in
  // memory, which the contact loop's gathers like. Dense packings diffuse little, so the
  // order stays good for the whole run.
  std::vector<std::size_t> perm(p.size());
  std::iota(perm.begin(), perm.end(), 0);
  auto key = [&](std::size_t i) {
    const int cx = std::min(nb - 1, int(p.x[i] / bin)), cy = std::min(nb - 1, int(p.y[i] / bin)),
              cz = std::min(nb - 1, int(p.z[i] / bin));
    return cx + nb * (cy + nb * cz);
  };
  std::stable_sort(perm.begin(), perm.end(),
                   [&](std::size_t a, std::size_t b) { return key(a) < key(b); });
  Particles q;
  q.resize(p.size());
  for (std::size_t k = 0; k < perm.size(); ++k) {
    const std::size_t i = perm[k];
    q.x[k] = p.x[i], q.y[k] = p.y[i], q.z[k] = p.z[i];
    q.vx[k] = p.vx[i], q.vy[k] = p.vy[i], q.vz[k] = p.vz[i];
    q.radius[k] = p.radius[i], q.inv_mass[k] = p.inv_mass[i];
  }
  return DemSystem(std::move(q), PeriodicCell::orthorhombic(Eigen::Vector3d::Constant(L)), options);
}

double inertial_number(const Material& m, double rate, double pressure) {
  if (rate == 0) return 0.0;
  if (!(pressure > 0)) return std::numeric_limits<double>::infinity();
  return std::abs(rate) * 2.0 * m.r_mean * std::sqrt(m.density / pressure);
}

double rate_for_inertial_number(const Material& m, double inertial, double pressure) {
  return pressure > 0 ? inertial * std::sqrt(pressure / m.density) / (2.0 * m.r_mean) : 0.0;
}

double relax_ratio(const DemSystem& sys) {
  const Material& m = sys.material();
  const double floor = static_cast<double>(sys.particles().size()) *
                       m.contact().energy(kRelaxFloorOverlap * m.r_mean);
  return sys.kinetic_energy() / std::max(sys.elastic_energy(), floor);
}

double relax_fraction(double start_ratio, double ratio, double target, double time_fraction) {
  double towards = 0.0;
  if (start_ratio > target && ratio > 0 && std::isfinite(start_ratio) && std::isfinite(ratio))
    towards = std::log(start_ratio / ratio) / std::log(start_ratio / target);
  else if (ratio <= target)
    towards = 1.0;
  return std::clamp(std::max(towards, time_fraction), 0.0, 1.0);
}

namespace {
// The loop of relax() and relax_at_pressure(): `advance(n)` moves the system by n steps, and
// `held()` is a further condition of convergence. Converged only when the kinetic energy is
// below the threshold AND decaying, after at least one check interval. Right after a slow
// strain increment the kinetic energy is still tiny (the loading lasts a few hundred steps,
// far less than the non-affine relaxation), so the ratio alone would stop at once and the
// probe would record an almost affine, too stiff response; the relaxation peak that follows
// must be waited out first.
template <class Advance, class Held>
RelaxSummary relax_loop(DemSystem& sys, const RelaxOptions& options, const ProgressFn& progress,
                        Advance advance, Held held) {
  RelaxSummary s;
  const double t0 = sys.time();
  s.ratio = relax_ratio(sys);
  const double r0 = s.ratio;
  double previous = std::numeric_limits<double>::infinity();
  auto done = [&] { return s.ratio < options.kinetic_to_elastic && s.ratio <= previous && held(); };
  bool first = true;
  while (first || !done()) {
    if (sys.time() - t0 >= options.time_cap) break;
    first = false;
    previous = s.ratio;
    advance(options.check_every);
    s.steps += options.check_every;
    s.ratio = relax_ratio(sys);
    if (!std::isfinite(s.ratio)) (void)sys.measure();  // throws with a clear message
    if (progress)
      progress(relax_fraction(r0, s.ratio, options.kinetic_to_elastic,
                              (sys.time() - t0) / options.time_cap));
  }
  s.converged = done();
  s.time = sys.time() - t0;
  if (progress) progress(1.0);
  return s;
}
}  // namespace

RelaxSummary relax(DemSystem& sys, const RelaxOptions& options, const ProgressFn& progress) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("relax: " + why);
  const Eigen::Vector3d still = Eigen::Vector3d::Zero();
  return relax_loop(
      sys, options, progress, [&](std::int64_t n) { sys.advance(n, still); }, [] { return true; });
}

RelaxSummary relax_at_pressure(DemSystem& sys, double target, const RelaxOptions& options,
                               const ServoOptions& servo, const ProgressFn& progress) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("relax at pressure: " + why);
  if (!servo.IsValid(&why)) throw InputError("relax at pressure: " + why);
  if (!(target > 0 && std::isfinite(target)))
    throw InputError("relax at pressure: the pressure must be > 0");
  CellControl control;
  control.servo = servo;
  for (AxisControl& a : control.axis) {
    a.mode = AxisControl::Mode::kStress;
    a.target_stress = target;
  }
  const double k_star = sys.material().k_star();
  const double dt = sys.dt();
  Eigen::Vector3d integral = Eigen::Vector3d::Zero();
  Eigen::Vector3d stress_diag = sys.stress().diagonal();
  return relax_loop(
      sys, options, progress,
      [&](std::int64_t n) {
        for (std::int64_t k = 0; k < n; ++k) {
          sys.step_measuring_stress(control.velocity_gradient(stress_diag, k_star, dt, integral));
          stress_diag = sys.last_stress_diag();
        }
      },
      [&] { return std::abs(stress_diag.sum() / 3.0 - target) / target < kPressureHold; });
}

namespace {
// A rate that holds an inertial number (isotropic.inertial_number, path.inertial_number):
// clamp(I sqrt(P / rho) / (2 <r>), lo, hi), recomputed every kSteps steps from the pressure that
// the step before summed in its own force loop (step_measuring_stress; the first time, before
// any step, from stress()). stress() lists every contact on one thread: every 20 steps it cost
// the isotropic stage two fifths of its time at N = 9261 (docs/performance.md "The isotropic
// stage's pressure").
// Loading to a pressure checks its target on the same measured steps (compress_isotropic).
struct HeldRate {
  static constexpr int kSteps = 20;
  double inertial = 0, lo = 0, hi = 0;
  bool held() const { return inertial > 0; }
  // Step `it` (from 0) is one that sums the stress: the step before each update.
  static bool due(std::int64_t it) { return (it + 1) % kSteps == 0; }
  // The pressure of the last measured step.
  static double measured_pressure(const DemSystem& sys) {
    return sys.last_stress_diag().sum() / 3.0;
  }
  // Before step `it`: the rate of the coming steps, if it is due for an update.
  void update(std::int64_t it, const DemSystem& sys, double* rate) const {
    if (!held() || it % kSteps != 0) return;
    const double P = it == 0 ? pressure(sys.stress()) : measured_pressure(sys);
    *rate = std::clamp(rate_for_inertial_number(sys.material(), inertial, P), lo, hi);
  }
  bool measures(std::int64_t it) const { return held() && due(it); }
};
}  // namespace

double path_strain(const PathType& type, const Eigen::Matrix3d& strain) {
  return type.mixed() ? std::abs(strain(0, 0)) : strain.norm();
}

CompressSummary compress_isotropic(DemSystem& sys, const CompressOptions& o, const SampleFn& sample,
                                   const ProgressFn& progress) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError("isotropic compression: " + why);
  CompressSummary s;
  const double t0 = sys.time();
  const double ln_start = std::log(sys.volume_fraction());
  const double ln_target = std::log(o.target_nu);
  const double total = ln_target - ln_start;  // > 0: compression
  const double sign = total >= 0 ? 1.0 : -1.0;
  const double dt = sys.dt();
  const Material& mat = sys.material();
  const bool to_pressure = o.target_pressure_star > 0;
  // The fewest steps a loading to its volume fraction can take (at rate_max throughout): beyond
  // kMaxSteps it never ends. A stiffness of 1e300 kg/s^2 (dt = 2e-154 s) made the preparation
  // run for ever. A loading to a pressure may stop before its bound, but where the whole span
  // needs that many steps each step moves ln(nu) by less than 1e-15 of it, and a loading that
  // starts below its P* does not reach it in any run's time either (isotropic.rate_max =
  // 1e-300 1/s ran for ever, its progress line estimating 4e8 years).
  if (!to_pressure || pressure(sys.stress()) / mat.k_star() < o.target_pressure_star)
    (void)step_count(
        std::abs(total) / (3.0 * o.rate_max * dt),
        "isotropic compression from nu = " + decimal_g(sys.volume_fraction()) + " to " +
            (to_pressure ? "its bound " : "") + decimal_g(o.target_nu) +
            (to_pressure ? " (loading to P* = " + decimal_g(o.target_pressure_star) + ")" : "") +
            " at " + o.rate_key + " = " + decimal_g(o.rate_max) + " 1/s (dt = " + decimal_g(dt) +
            " s, set by material.k, density and r_mean)");
  int next_sample = 0;
  double rate = o.rate_max;
  // Samples carry the loading's rate (the first one: at rest), not the shortened last step's.
  bool loading = false;
  auto record = [&](Measures m) {
    m.strain_rate = loading ? rate : 0.0;
    m.inertial_number = inertial_number(mat, m.strain_rate, m.pressure);
    if (m.pressure_star > kJammedPressureStar && m.strain_rate > 0)
      s.max_inertial_number = std::max(s.max_inertial_number, m.inertial_number);
    if (sample) sample(m);
  };
  auto sample_point = [&](int k) { return ln_start + total * k / (o.samples - 1); };
  if (o.samples >= 2) {
    record(sys.measure());
    next_sample = 1;
  }
  loading = true;
  const HeldRate held{o.inertial_number, o.rate_min, o.rate_max};
  // Snapshots at the requested volume fractions leave the loading itself untouched (a run with
  // snapshots is the same run as one without): the system is copied after the step that
  // reaches or passes one, and the copy alone takes the fraction of a step back onto it.
  std::vector<double> snap_at;  // ln(nu) - ln_start, in loading order
  for (double nu : o.snapshot_nu) snap_at.push_back(std::log(nu) - ln_start);
  std::sort(snap_at.begin(), snap_at.end(),
            [&](double a, double b) { return sign * a < sign * b; });
  for (double e : snap_at)
    if (!(sign * e > 0 && sign * e < sign * total))
      throw InputError(
          "isotropic compression: snapshot volume fractions must lie strictly "
          "between the start and the target");
  std::size_t next_snap = 0;
  bool reached = false;
  for (std::int64_t it = 0;; ++it) {
    const double done = std::log(sys.volume_fraction()) - ln_start;
    const double remaining = sign * (total - done);
    held.update(it, sys, &rate);
    const bool last = remaining <= 3.0 * rate * dt;
    // d ln(nu) / dt = -tr(D) = 3 * rate for D = -rate I.
    const double r = last ? std::max(remaining, 0.0) / (3.0 * dt) : rate;
    const bool check = to_pressure && HeldRate::due(it);
    if (held.measures(it) || check)
      sys.step_measuring_stress(Eigen::Vector3d::Constant(-sign * r));
    else
      sys.step(Eigen::Vector3d::Constant(-sign * r));
    ++s.steps;
    while (next_snap < snap_at.size() &&
           sign * (std::log(sys.volume_fraction()) - ln_start) >= sign * snap_at[next_snap]) {
      DemSystem copy = sys;
      const double back = std::log(copy.volume_fraction()) - ln_start - snap_at[next_snap];
      copy.step(Eigen::Vector3d::Constant(back / (3.0 * dt)));
      s.snapshots.push_back(std::move(copy));
      ++next_snap;
    }
    const double now = sign * (std::log(sys.volume_fraction()) - ln_start);
    while (o.samples >= 2 && next_sample < o.samples &&
           (last || now >= sign * (sample_point(next_sample) - ln_start))) {
      record(sys.measure());
      ++next_sample;
    }
    if (check) {
      const double p_star = HeldRate::measured_pressure(sys) / mat.k_star();
      if (progress) progress(std::clamp(p_star / o.target_pressure_star, 0.0, 1.0));
      if (p_star >= o.target_pressure_star) {
        if (o.samples >= 2) record(sys.measure());
        reached = true;
        break;
      }
    } else if (!to_pressure && progress && it % 256 == 0) {
      progress(std::abs(total) > 0 ? now / std::abs(total) : 1.0);
    }
    if (last) break;
  }
  if (to_pressure && !reached)
    throw InputError("isotropic compression: P* = " + decimal_g(o.target_pressure_star) +
                     " not reached by the volume fraction bound " + decimal_g(o.target_nu) +
                     " (P* there " + decimal_g(pressure(sys.stress()) / mat.k_star()) +
                     "); raise the bound");
  if (next_snap < snap_at.size())
    throw InputError("isotropic compression: a snapshot volume fraction lies beyond " +
                     decimal_g(sys.volume_fraction()) + ", where P* reached its target");
  s.time = sys.time() - t0;
  if (progress) progress(1.0);
  return s;
}

PathSummary run_path(DemSystem& sys, const PathOptions& o, const SampleFn& sample,
                     const ProgressFn& progress) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError("path: " + why);
  const PathType type = path_type(o.type);
  PathSummary s;
  const double t0 = sys.time();
  sys.reset_strain();
  // shape: D of the strain-controlled axes at unit rate (its largest |component| is 1). The
  // path's strain s is kFactor |E_a| on an axis a with |shape_a| = 1: the norm of E along a
  // constant D (kFactor = |shape|) or the axial strain of a mixed path (kFactor = 1).
  Eigen::Vector3d shape;
  switch (type.kind) {
    case PathKind::kUndrained:
    case PathKind::kDrained:
    case PathKind::kConstantMeanStress:
      shape = type.sense * Eigen::Vector3d(1.0, -0.5, -0.5);
      break;
    case PathKind::kIsotropic:
      shape = Eigen::Vector3d::Constant(type.sense);
      break;
    case PathKind::kProportional: {
      shape = Eigen::Vector3d(o.direction[0], o.direction[1], o.direction[2]);
      shape /= shape.cwiseAbs().maxCoeff();
      break;
    }
  }
  int axis = 0;  // the axis whose strain measures s: one with |shape_a| = 1
  shape.cwiseAbs().maxCoeff(&axis);
  const bool mixed = type.mixed();
  const double kFactor = mixed ? 1.0 : std::sqrt(shape.squaredNorm());
  const double dt = sys.dt();
  // The rate of the coming steps: o.rate, or the one that holds o.inertial_number at the
  // pressure (as the isotropic loading does).
  const HeldRate held_rate{o.inertial_number, o.rate_min, o.rate};
  const bool held = held_rate.held();
  const Material& mat = sys.material();
  double rate = o.rate;
  auto path_strain = [&] { return kFactor * std::abs(sys.strain_E()[axis]); };
  std::vector<std::size_t> snap_order(o.snapshot_eps_dev.size());
  std::iota(snap_order.begin(), snap_order.end(), 0);
  std::stable_sort(snap_order.begin(), snap_order.end(), [&](std::size_t a, std::size_t b) {
    return o.snapshot_eps_dev[a] < o.snapshot_eps_dev[b];
  });
  std::vector<DemSystem> snaps(o.snapshot_eps_dev.size(), sys);
  std::size_t next_snap = 0;
  int next_sample = 1;
  auto sample_at = [&](int k) { return o.eps_dev_max * k / (o.samples - 1); };
  // Mixed paths: the lateral axes follow the servo, which reads the stress of the last step
  // (the first one: measured now) and holds the target from the start's mean stress p0.
  CellControl control;
  control.servo = o.servo(sys.material());
  Eigen::Vector3d integral = Eigen::Vector3d::Zero();
  Eigen::Vector3d stress_diag = Eigen::Vector3d::Zero();
  double p0 = 0;
  auto lateral_target = [&](const Eigen::Vector3d& sd) {
    return type.kind == PathKind::kDrained ? p0 : 0.5 * (3.0 * p0 - sd[0]);
  };
  if (mixed) {
    stress_diag = sys.stress().diagonal();
    p0 = stress_diag.sum() / 3.0;
    if (!(p0 > 0))
      throw InputError("path: a " + o.type +
                       " path needs a packing under pressure at its start (p = " + decimal_g(p0) +
                       " Pa)");
    for (int a = 1; a < 3; ++a) control.axis[a].mode = AxisControl::Mode::kStress;
  }
  // Samples carry the path's rate (max |D_aa| of the imposed axes = rate) and the inertial
  // number it has at the sample's pressure; the first sample is the state at rest before the
  // path. On mixed paths they also measure how well the servo holds its target.
  auto record = [&](Measures m, bool moving) {
    m.strain_rate = moving ? rate : 0.0;
    m.inertial_number = inertial_number(mat, m.strain_rate, m.pressure);
    if (m.pressure > 0 && std::isfinite(m.inertial_number))
      s.max_inertial_number = std::max(s.max_inertial_number, m.inertial_number);
    if (mixed && moving && path_strain() >= 0.1 * o.eps_dev_max) {
      // What the path promises: the lateral stresses at p0 (drained), the mean stress at p0
      // (constant p; its lateral target moves with the fluctuating axial stress).
      const Eigen::Vector3d sd = m.stress.diagonal();
      if (type.kind == PathKind::kDrained)
        for (int a = 1; a < 3; ++a)
          s.servo_error = std::max(s.servo_error, std::abs(sd[a] - p0) / p0);
      else
        s.servo_error = std::max(s.servo_error, std::abs(sd.sum() / 3.0 - p0) / p0);
    }
    if (sample) sample(m);
  };
  record(sys.measure(), false);
  // Events (samples, snapshots, the end) are hit exactly by shortening the step's rate; a path
  // whose strain stops growing (a servo that cannot hold its target) is stopped by the cap.
  constexpr double kHit = 1e-12;  // relative tolerance of landing on an event
  const std::int64_t max_steps =
      step_count(10.0 * o.eps_dev_max / (kFactor * (held ? o.rate_min : o.rate) * dt),
                 std::string("path: ten times the path's steps at ") +
                     (held ? "path.rate_min" : "path.rate")) +
      10 * (o.samples + 10);
  for (std::int64_t it = 0;; ++it) {
    held_rate.update(it, sys, &rate);
    const double inc = kFactor * rate * dt;
    if (it > max_steps)
      throw InputError("path: " + o.type + " did not reach s = " + decimal_g(o.eps_dev_max) +
                       " in " + std::to_string(max_steps) + " steps (the strain stopped growing)");
    const double now = path_strain();
    double event =
        std::min(o.eps_dev_max, next_sample < o.samples ? sample_at(next_sample) : 1e300);
    if (next_snap < snap_order.size())
      event = std::min(event, o.snapshot_eps_dev[snap_order[next_snap]]);
    const double f = std::min(1.0, (event - now) / inc);
    if (mixed) {
      control.axis[0].rate = rate * std::max(f, 0.0) * shape[0];
      for (int a = 1; a < 3; ++a) control.axis[a].target_stress = lateral_target(stress_diag);
      sys.step_measuring_stress(control.velocity_gradient(stress_diag, mat.k_star(), dt, integral));
      stress_diag = sys.last_stress_diag();
    } else if (held_rate.measures(it)) {
      sys.step_measuring_stress(rate * std::max(f, 0.0) * shape);
    } else {
      sys.step(rate * std::max(f, 0.0) * shape);
    }
    ++s.steps;
    const double after = path_strain();
    const double tol = kHit * std::max(1.0, o.eps_dev_max);
    while (next_snap < snap_order.size() &&
           after >= o.snapshot_eps_dev[snap_order[next_snap]] - tol) {
      snaps[snap_order[next_snap]] = sys;
      ++next_snap;
    }
    bool sampled = false;
    while (next_sample < o.samples && after >= sample_at(next_sample) - tol) {
      if (!sampled) record(sys.measure(), true);
      sampled = true;
      ++next_sample;
    }
    if (progress && it % 256 == 0) progress(after / o.eps_dev_max);
    if (after >= o.eps_dev_max - tol && next_sample >= o.samples && next_snap >= snap_order.size())
      break;
  }
  s.snapshots = std::move(snaps);
  s.servo_held = s.servo_error <= o.servo_tolerance;
  s.time = sys.time() - t0;
  if (progress) progress(1.0);
  return s;
}

WindowMean window_mean(const std::vector<double>& x, const std::vector<double>& y, double x_lo,
                       double x_hi, int batches) {
  WindowMean w;
  std::vector<double> in;
  for (std::size_t i = 0; i < x.size() && i < y.size(); ++i)
    if (x[i] >= x_lo && x[i] <= x_hi) in.push_back(y[i]);
  w.samples = static_cast<int>(in.size());
  if (in.empty()) return w;
  w.mean = std::accumulate(in.begin(), in.end(), 0.0) / static_cast<double>(in.size());
  if (batches < 2 || w.samples < 2 * batches) return w;
  // Batch b holds samples [b n / B, (b + 1) n / B): equal counts up to one sample.
  std::vector<double> means(static_cast<std::size_t>(batches));
  for (int b = 0; b < batches; ++b) {
    const std::size_t lo = static_cast<std::size_t>(b) * in.size() / batches;
    const std::size_t hi = static_cast<std::size_t>(b + 1) * in.size() / batches;
    means[static_cast<std::size_t>(b)] =
        std::accumulate(in.begin() + lo, in.begin() + hi, 0.0) / static_cast<double>(hi - lo);
  }
  const double m = std::accumulate(means.begin(), means.end(), 0.0) / batches;
  double ss = 0.0;
  for (double v : means) ss += (v - m) * (v - m);
  w.standard_error = std::sqrt(ss / (batches - 1) / batches);
  w.ok = true;
  return w;
}

std::int64_t step_count(double steps, const std::string& what) {
  if (!(steps <= kMaxSteps)) {
    throw InputError(what + " needs " + decimal_g(steps, 3) + " time steps, more than " +
                     decimal_g(kMaxSteps, 1));
  }
  return static_cast<std::int64_t>(steps);
}

std::int64_t impose_strain_increment(DemSystem& sys, const Eigen::Vector3d& d_eps, double rate,
                                     const std::string& rate_name) {
  if (!(rate > 0 && std::isfinite(rate))) throw InputError("strain increment: rate must be > 0");
  if (!d_eps.allFinite()) throw InputError("strain increment: non-finite component");
  const double largest = d_eps.cwiseAbs().maxCoeff();
  if (largest == 0) return 0;
  const std::int64_t n = std::max<std::int64_t>(
      1, step_count(std::ceil(largest / (rate * sys.dt())), "strain increment at " + rate_name));
  // epsilon = -E: a compressive increment is a negative D.
  const Eigen::Vector3d D = -d_eps / (static_cast<double>(n) * sys.dt());
  sys.advance(n, D);
  return n;
}

DemSystem system_from_positions(const Eigen::MatrixXd& positions, const std::vector<double>& radii,
                                const Eigen::Vector3d& lengths, const SystemOptions& options) {
  if (positions.cols() != 3 || static_cast<std::size_t>(positions.rows()) != radii.size())
    throw InputError("stored state: positions must be [N,3] with N = number of radii");
  Particles p;
  p.resize(radii.size());
  for (std::size_t i = 0; i < radii.size(); ++i) {
    if (!(radii[i] > 0)) throw InputError("stored state: radius " + std::to_string(i) + " <= 0");
    p.radius[i] = radii[i];
    p.inv_mass[i] = 1.0 / options.material.sphere_mass(radii[i]);
    p.x[i] = positions(i, 0);
    p.y[i] = positions(i, 1);
    p.z[i] = positions(i, 2);
  }
  return DemSystem(std::move(p), PeriodicCell::orthorhombic(lengths), options);
}

}  // namespace rendulic::dem
