// Contact law, time scales and the time step of the DEM engine (docs/physics.md section 1, seed
// paper section 2.1). NormalContact is the one statement of the contact law: a pure kernel of
// the overlap and its rate; the callers own minimum image, the relative velocity and the sums.
// The closed forms here (contact duration, restitution) are what the two-particle tests compare
// the integrator against.
#pragma once

#include <cmath>
#include <numbers>
#include <string>

namespace rendulic::dem {

// Linear spring-dashpot normal contact: f = k delta + gamma d(delta)/dt, positive = repulsive,
// along the branch vector l = x_i - x_j, with delta = r_i + r_j - |l| > 0 the overlap. The force
// is not clipped at zero: the closed forms of t_c and e below assume exactly this law (the
// dashpot may pull slightly just before separation).
//
// Evaluated per pair, in the manner of HOOMD-blue's pair evaluators: a small value made once
// outside a loop whose inline methods every user of the law calls per pair (the engine's force
// loop and measures, dem_system.cpp; the energy minimiser, probe_minimise.cpp; the static
// stress of the probe tools, probe_geometry.cpp; the Hessian of the linear response,
// linear_response.cpp; the force balance at rest, rest.cpp). It inlines into the engine's
// vectorised force loop, where it costs nothing (docs/performance.md). The static tools work
// at rest: they use the spring alone (elastic_force, energy, stiffness).
//
// Friction is TangentialContact below: the engine adds its force to this normal force.
struct NormalContact {
  double k = 1e8;     // kg/s^2
  double gamma = 1.;  // kg/s
  double force(double delta, double delta_dot) const { return k * delta + gamma * delta_dot; }
  // The force loop's form: the force on i as a multiple s of l (F = s l), from delta, 1 / |l|
  // and l . v_rel, v_rel = v_i - v_j the true relative velocity (peculiar plus affine part), so
  // that d(delta)/dt = -l . v_rel / |l|. One scale factor instead of the normal's three
  // components.
  double force_over_distance(double delta, double inv_distance, double l_dot_v) const {
    return (k * delta - gamma * l_dot_v * inv_distance) * inv_distance;
  }
  // At rest (no relative velocity): the spring's force, its energy k delta^2 / 2, and its
  // stiffness df / d(delta), the normal part of the contact's block of the Hessian.
  double elastic_force(double delta) const { return k * delta; }
  double energy(double delta) const { return 0.5 * k * delta * delta; }
  double stiffness() const { return k; }
};

// Tangential contact with Coulomb friction (docs/physics.md section 1b; Luding 2008, Granular
// Matter 10:235; Cundall & Strack 1979): a linear spring on the tangential displacement xi
// that the contact has accumulated since it formed, a dashpot on the tangential relative
// velocity, and the Coulomb limit |f_t| <= mu |f_n| (f_n the whole normal force, dashpot
// included). The caller keeps xi per contact, turns it with the contact each step (it stays in
// the tangent plane with its length kept) and passes the relative tangential velocity of the
// contact point twice: at mid-step, the displacement's increment over the step (the positions
// of velocity Verlet advance with it), and predicted at the step's end, the dashpot's (as the
// normal dashpot, dem_system.hpp).
// The arithmetic TangentialContact is written in: plain doubles for its scalar callers. The
// engine's force loop passes its own, whose values are vectors of contacts (one per lane) and
// whose select is a blend (dem_system.cpp), so that the same law runs across contacts.
struct ScalarMath {
  static double sqrt(double x) { return std::sqrt(x); }
  static double abs(double x) { return std::abs(x); }
  static double select(bool c, double a, double b) { return c ? a : b; }
  // a where c holds, else rare(x, y) (a function of M's values): for a value that is costly
  // and rarely needed, which the engine's lanes then compute only when a lane needs it.
  template <class F>
  static double unless(bool c, double a, F rare, double x, double y) {
    return c ? a : rare(x, y);
  }
};

// With the engine's four-lane arithmetic the law passes 32-byte vectors between functions
// that are all inlined into one file (dem_system.cpp): without AVX (the sanitizer build, no
// -march=native) GCC would warn at each that such a vector has another ABI than with AVX, and
// -Werror makes that an error; no ABI is involved, so the warning is off for the law alone.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"
#endif
struct TangentialContact {
  double k_t = 0;      // kg/s^2
  double gamma_t = 0;  // kg/s
  double mu = 0;       // Coulomb coefficient
  // Turns the spring with the contact: xi back into the plane normal to the unit vector n,
  // its length kept (Luding 2008, eq. 17). Exact when the contact turned by a rotation.
  // Without branches (selects only, M above), so that it runs across contacts: a spring
  // without history (xi = 0), already in the plane (xi . n = 0) or along n is only projected.
  template <class V, class M = ScalarMath>
  static void turn(V& xi, const V& n) {
    const auto xn = xi[0] * n[0] + xi[1] * n[1] + xi[2] * n[2];
    const auto len2 = xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2];
    for (int a = 0; a < 3; ++a) xi[a] -= xn * n[a];
    // The projection shortened xi by the factor sqrt(1 - e), e = xn^2 / |xi|^2 (the contact's
    // turn per step, squared: tiny). The inverse, (1 - e)^(-1/2) = 1 + e/2 + 3e^2/8 + ..., to
    // round-off for e < 1e-5 (the next term is below 1e-15), saves a square root.
    // Beyond, the exact factor (a division and a square root) for the few contacts that
    // need it alone (M::unless).
    const auto e = M::select(len2 > 0.0, xn * xn / len2, 0.0);
    const auto p2 = xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2];
    const auto s = M::unless(
        e < 1e-5, 1.0 + e * (0.5 + 0.375 * e),
        [](auto len2_, auto p2_) { return M::select(p2_ > 0.0, M::sqrt(len2_ / p2_), 1.0); }, len2,
        p2);
    for (int a = 0; a < 3; ++a) xi[a] *= s;
  }
  // Advances xi by v_mid dt and sets f to the tangential force on i, f_t = -k_t xi - gamma_t
  // v_end, held at the Coulomb limit mu |f_n|: there the contact slides and xi is reset to
  // the spring that gives the limit force. The slip's work is added to *dissipated: the spring
  // force averaged over the step, k_t (xi_0 + xi) / 2 (xi_0 the spring the step started from,
  // xi the reset one), times the slip xi_trial - xi. Velocity Verlet moves the particles by
  // that average too, so the work done on the contact equals the spring's energy plus the
  // dashpot's and the slip's dissipation to second order in dt, also while f_n, and with it the
  // limit, changes. (The end's force alone, k_t xi . (xi_trial - xi), is exact only for a
  // steady slide: where the limit falls, it missed about k_t |xi_0 - xi|^2 / 2 a step, a
  // first-order error, 18 % of the slip's work at mu = 10; docs/dem.md "Friction".) Vectors are
  // anything with three components indexed [0..2] (Eigen vectors, the engine's packed records,
  // arrays of lanes); the force is an out parameter because a returned 32-byte vector record would
  // change the ABI with the build's instruction set (GCC's -Wpsabi, an error where AVX is off).
  template <class V, class S, class M = ScalarMath>
  void force(V& xi, const V& v_mid, const V& v_end, double dt, S f_n, S* dissipated, V& f) const {
    const V start = xi;
    for (int a = 0; a < 3; ++a) xi[a] += v_mid[a] * dt;
    for (int a = 0; a < 3; ++a) f[a] = -k_t * xi[a] - gamma_t * v_end[a];
    const auto limit = mu * M::abs(f_n);
    const auto f2 = f[0] * f[0] + f[1] * f[1] + f[2] * f[2];
    // Selects instead of a branch, as in turn(): a sticking contact keeps f and xi (s = 1, no
    // slip work). The reset spring is multiplied by 1 / k_t, not divided by k_t: three
    // divisions fewer per contact, a change in the last bit.
    const auto slides = f2 > limit * limit;
    // A division and a square root only where the contact slides (M::unless, as in turn()):
    // in the engine's lanes most contacts stick (docs/performance.md "Friction").
    const auto s = M::unless(
        f2 <= limit * limit, 1.0, [](auto limit_, auto f2_) { return limit_ / M::sqrt(f2_); },
        limit, f2);
    const double inv_k_t = 1.0 / k_t;
    S slip_work{};
    for (int a = 0; a < 3; ++a) {
      const auto held = f[a] * s;
      const auto spring = held + gamma_t * v_end[a];  // -k_t xi after the slip
      const auto trial = xi[a];
      const auto reset = M::select(slides, -spring * inv_k_t, trial);
      slip_work += 0.5 * (k_t * start[a] - spring) * (trial - reset);
      f[a] = M::select(slides, held, f[a]);
      xi[a] = reset;
    }
    *dissipated += slip_work;
  }
  // The spring's energy k_t |xi|^2 / 2, from |xi|^2.
  double energy(double xi2) const { return 0.5 * k_t * xi2; }
};
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

// Material of the seed study (docs/physics.md section 1), SI units.
// The smallest k_t / k and k_r / k: a slipping contact resets its spring to mu |f_n| / k_t,
// and with k_t / k = 1e-300 that length overflowed when squared (NaN springs, then an
// internal error). A spring a million times softer than the normal one is far below any
// material's; the floor leaves |xi|^2 finite by 290 decades.
inline constexpr double kMinSpringRatio = 1e-6;

struct Material {
  double k = 1e8;         // normal stiffness, kg/s^2
  double gamma = 1.0;     // contact viscosity, kg/s
  double gamma_b = 0.1;   // background damping on the peculiar velocity, kg/s
  double density = 2000;  // kg/m^3
  double r_mean = 1e-3;   // m
  double w = 3.0;         // r_max / r_min
  // Friction (TangentialContact; 0 = the seed's frictionless law, and the engine's
  // frictionless path). k_t and gamma_t are given relative to k and gamma: 2/7 makes the
  // tangential oscillation of a sticking pair of equal spheres (effective mass 2/7 of the
  // normal one, rolling included) as fast and as damped as the normal one.
  double mu = 0.0;
  double k_t_ratio = 2.0 / 7.0;
  double gamma_t_ratio = 2.0 / 7.0;
  // Rolling resistance (docs/physics.md section 1b; 0 = none, and the engine's frictional path
  // without it): the tangential law again, on the rolling displacement, with k_r, gamma_r and
  // mu_r. Rotations exist only with friction, so mu_r > 0 needs mu > 0. The defaults equal the
  // tangential ratios: the rolling spring's stiffness against a turn, a'^2 k_r, is then a
  // quarter of the tangential spring's, a^2 k_t, for equal spheres (a' = a / 2), so that
  // rolling does not set the time step.
  double mu_r = 0.0;
  double k_r_ratio = 2.0 / 7.0;
  double gamma_r_ratio = 2.0 / 7.0;
  bool frictional() const { return mu > 0; }
  bool rolling() const { return mu_r > 0; }
  TangentialContact tangential() const { return {k_t_ratio * k, gamma_t_ratio * gamma, mu}; }
  TangentialContact rolling_contact() const { return {k_r_ratio * k, gamma_r_ratio * gamma, mu_r}; }
  double r_min() const { return 2.0 * r_mean / (1.0 + w); }
  double r_max() const { return w * r_min(); }
  // k* = k / (2 <r>): the stress scale of sigma* (seed paper section 2.2).
  double k_star() const { return k / (2.0 * r_mean); }
  double sphere_mass(double r) const { return density * 4.0 / 3.0 * std::numbers::pi * r * r * r; }
  NormalContact contact() const { return {k, gamma}; }
  bool IsValid(std::string* why) const;
};

// Duration of a binary collision, t_c = pi / sqrt(k/m_red - (gamma / (2 m_red))^2).
// Returns +inf for an overdamped pair (no rebound).
double contact_time(const NormalContact& c, double m_reduced);
// Coefficient of normal restitution, e = exp(-gamma t_c / (2 m_red)).
double restitution(const NormalContact& c, double m_reduced);

// The material's contact law as LAMMPS pair settings (pair_style granular, docs/interop.md): a
// Hookean normal spring with a velocity dashpot (damping velocity: eta_n = gamma); without
// friction no tangential force, with it linear_history k_t x_gamma_t mu, where LAMMPS's
// tangential damping is x_gamma_t times the normal one, so x_gamma_t = gamma_t / gamma.
std::string lammps_pair_lines(const Material& m);

// t_c of the two smallest particles: the unit of dem.dt_factor and of the servo's gains
// (docs/physics.md section 1, docs/dem.md "Paths").
double contact_duration(const Material& m);
// Time step: dt = factor * t_c of the two smallest particles (docs/physics.md section 1).
double time_step(const Material& m, double factor);
// A sufficient bound for the stability of the explicit scheme on any packing of this
// material. Springs: Gershgorin on the mass-weighted stiffness matrix bounds the highest
// frequency by omega_max^2 <= 2 z k / m_min with z = 12 contacts at most on the smallest
// particle; Verlet is stable for omega_max dt < 2. Dashpots, treated explicitly: the same
// bound with the damping rate (2 z gamma + gamma_b) / m_min in place of omega_max. With
// friction a tangential spring acts on the translation and, through the lever r, on the
// rotation (I = 2/5 m r^2): k_t (1/m + r^2/I) = 3.5 k_t / m, so max(k, 3.5 k_t) takes k's
// place (and max(gamma, 3.5 gamma_t) gamma's). A rolling spring acts on the rotation alone,
// through the lever a' <= r: a'^2 k_r / I <= 2.5 k_r / m, added to the tangential term
// (max(k, 3.5 k_t + 2.5 k_r); the same for the dashpots).
double stability_limit(const Material& m);
// Throws InputError (naming `key`) if factor gives a dt at or beyond stability_limit().
void check_time_step(const Material& m, double factor, const std::string& key);

}  // namespace rendulic::dem
