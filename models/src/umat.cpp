// The Abaqus UMAT adapter (umat.hpp; docs/umat.md): loading the library, the conversions between
// rendulic's compression-positive tensors and the UMAT's tension-positive Voigt vectors, one call,
// the increment driver with PNEWDT cuts and step doubling, and paths that carry STATEV whole.
#include "rendulic/models/umat.hpp"

#include <dlfcn.h>
#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <mutex>

#include "rendulic/core/errors.hpp"
#include "rendulic/core/option_table.hpp"
#include "rendulic/core/text_file.hpp"
#include "toml_input.hpp"

namespace rendulic::models {

// The standard argument list (every argument by reference), then the hidden length of CMNAME
// that Fortran compilers append; a C UMAT declared without it ignores it.
using UmatEntry = void (*)(double* stress, double* statev, double* ddsdde, double* sse, double* spd,
                           double* scd, double* rpl, double* ddsddt, double* drplde, double* drpldt,
                           const double* stran, const double* dstran, const double* time,
                           const double* dtime, const double* temp, const double* dtemp,
                           const double* predef, const double* dpred, const char* cmname,
                           const int* ndi, const int* nshr, const int* ntens, const int* nstatv,
                           const double* props, const int* nprops, const double* coords,
                           const double* drot, double* pnewdt, const double* celent,
                           const double* dfgrd0, const double* dfgrd1, const int* noel,
                           const int* npt, const int* layer, const int* kspt, const int* kstep,
                           const int* kinc, std::size_t cmname_length);

class UmatLibrary {
 public:
  explicit UmatLibrary(const std::string& path) {
    // Checked before dlopen, which would block on a FIFO and call a folder "cannot read file
    // data"; in the words of every input file (docs/usage.md, the paragraph on text inputs).
    // Named by its path alone: it comes from --umat, calibration.umat or Python's umat=.
    refuse_unless_regular_file(path, path, "UMAT library", "a .so file");
    // RTLD_LOCAL: two UMAT libraries in one process keep their own symbols.
    const std::string absolute = std::filesystem::absolute(path).string();
    handle_ = ::dlopen(absolute.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle_) {
      const char* e = ::dlerror();
      std::string why = e ? e : "unknown error";
      // dlerror names the file again, absolute: "/abs/x.so: invalid ELF header".
      if (why.starts_with(absolute + ": ")) why.erase(0, absolute.size() + 2);
      throw InputError(path + ": cannot load the UMAT library: " + printable(why));
    }
    for (const char* s : {"umat_", "umat", "UMAT"}) {
      if (void* f = ::dlsym(handle_, s)) {
        entry_ = reinterpret_cast<UmatEntry>(f);
        symbol_ = s;
        break;
      }
    }
    if (!entry_) {
      ::dlclose(handle_);
      throw InputError(path +
                       ": exports no UMAT entry (looked for umat_ (Fortran), umat and UMAT (C))");
    }
  }
  ~UmatLibrary() { ::dlclose(handle_); }
  UmatLibrary(const UmatLibrary&) = delete;
  UmatLibrary& operator=(const UmatLibrary&) = delete;
  UmatEntry entry() const { return entry_; }
  const std::string& symbol() const { return symbol_; }

 private:
  void* handle_ = nullptr;
  UmatEntry entry_ = nullptr;
  std::string symbol_;
};

namespace {

// Voigt order of Abaqus (11, 22, 33, 12, 13, 23) as (row, column) of the tensor.
constexpr std::array<std::array<int, 2>, 6> kVoigt = {
    {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}}};

// Compression-positive stress -> the UMAT's tension-positive STRESS.
void to_umat_stress(const Eigen::Matrix3d& s, double* v) {
  for (int i = 0; i < 6; ++i) v[i] = -s(kVoigt[i][0], kVoigt[i][1]);
}
Eigen::Matrix3d from_umat_stress(const double* v) {
  Eigen::Matrix3d s;
  for (int i = 0; i < 6; ++i) {
    s(kVoigt[i][0], kVoigt[i][1]) = -v[i];
    s(kVoigt[i][1], kVoigt[i][0]) = -v[i];
  }
  return s;
}
// Compression-positive strain -> tension-positive Voigt strain with engineering shears.
void to_umat_strain(const Eigen::Matrix3d& e, double* v) {
  for (int i = 0; i < 6; ++i) v[i] = -(i < 3 ? 1.0 : 2.0) * e(kVoigt[i][0], kVoigt[i][1]);
}

// DDSDDE (Fortran column-major, d STRESS_i / d DSTRAN_j) in rendulic's Mandel form. Both signs
// flip (sigma = -STRESS, eps = -STRAN), so the matrix keeps its sign; only the shear scalings
// and the order change: column j of the Mandel tangent is the stress of the unit Mandel strain j.
Matrix6d mandel_tangent(const double* ddsdde) {
  Matrix6d t;
  for (int j = 0; j < 6; ++j) {
    double e[6], s[6];
    to_umat_strain(from_mandel(Vector6d(Vector6d::Unit(j))), e);
    for (int i = 0; i < 6; ++i) {
      s[i] = 0.0;
      for (int k = 0; k < 6; ++k) s[i] += ddsdde[i + 6 * k] * e[k];
    }
    t.col(j) = to_mandel(from_umat_stress(s));
  }
  return t;
}

std::string fmt(double v) { return format_g(v); }

std::vector<double> numbers(const toml::node& node, const std::string& key,
                            const std::string& path) {
  const toml::array* a = node.as_array();
  if (!a) throw InputError(path + ": key '" + key + "' must be an array of numbers");
  std::vector<double> v;
  for (const auto& x : *a) {
    const std::optional<double> d = x.value<double>();
    if (!d || !std::isfinite(*d))
      throw InputError(path + ": key '" + key + "' must hold finite numbers only");
    v.push_back(*d);
  }
  return v;
}

}  // namespace

UmatSpec load_umat_parameters_toml(const std::string& path) {
  const toml::table tbl = parse_toml_input(path, "parameter file");
  UmatSpec s;
  bool have_props = false, have_statev = false, have_names = false;
  const toml::table* bounds = nullptr;
  for (const auto& [k, node] : tbl) {
    const std::string key(k.str());
    if (key == "props") {
      s.props = numbers(node, key, path);
      have_props = true;
    } else if (key == "prop_names") {
      const toml::array* a = node.as_array();
      if (!a) throw InputError(path + ": key 'prop_names' must be an array of strings");
      have_names = true;
      for (const auto& x : *a) {
        const std::optional<std::string> n = x.value<std::string>();
        if (!n || n->empty())
          throw InputError(path + ": key 'prop_names' must hold non-empty strings");
        // Names are given back on the command line (--free K,G; --value K=1): a comma, a space
        // or an '=' split them there, and digits alone read as a PROPS index.
        const bool letter =
            std::isalpha(static_cast<unsigned char>(n->front())) || n->front() == '_';
        if (!letter || !std::all_of(n->begin(), n->end(),
                                    [](unsigned char c) { return std::isalnum(c) || c == '_'; }))
          throw InputError(path + ": prop name '" + printable(*n) +
                           "' must be letters, digits and '_', starting with a letter or '_'");
        s.prop_names.push_back(*n);
      }
    } else if (key == "nstatv") {
      const std::optional<int64_t> n = node.value<int64_t>();
      if (!n || *n < 0 || *n > 100000)
        throw InputError(path + ": key 'nstatv' must be an integer in [0, 100000]");
      s.nstatv = static_cast<int>(*n);
    } else if (key == "statev") {
      s.statev = numbers(node, key, path);
      have_statev = true;
    } else if (key == "cmname") {
      const std::optional<std::string> n = node.value<std::string>();
      if (!n || n->size() > 80) throw InputError(path + ": key 'cmname' must be <= 80 characters");
      s.cmname = *n;
    } else if (key == "bounds") {
      bounds = node.as_table();
      if (!bounds)
        throw InputError(path + ": key 'bounds' must be a table of name = [lower, upper]");
    } else {
      throw InputError(path + ": unknown key '" + key +
                       "' (a UMAT's parameters file has props, prop_names, nstatv, statev, "
                       "cmname, bounds)");
    }
  }
  if (!have_props || s.props.empty())
    throw InputError(path + ": missing key 'props' (the UMAT's PROPS, at least one)");
  const std::size_t n = s.props.size();
  if (!have_names)  // an empty list given is refused below, as any other count that is wrong
    for (std::size_t i = 0; i < n; ++i) s.prop_names.push_back("prop" + std::to_string(i + 1));
  if (s.prop_names.size() != n)
    throw InputError(path + ": 'prop_names' has " + std::to_string(s.prop_names.size()) +
                     " names for " + std::to_string(n) + " props");
  if (const std::string* again = first_repeat(s.prop_names))
    throw InputError(path + ": prop name '" + *again + "' given twice");
  if (!have_statev) s.statev.assign(s.nstatv, 0.0);
  if (static_cast<int>(s.statev.size()) != s.nstatv)
    throw InputError(path + ": 'statev' has " + std::to_string(s.statev.size()) +
                     " values, nstatv is " + std::to_string(s.nstatv));
  constexpr double inf = std::numeric_limits<double>::infinity();
  s.lower.assign(n, -inf);
  s.upper.assign(n, inf);
  if (bounds)
    for (const auto& [k, node] : *bounds) {
      const std::string key(k.str());
      const auto it = std::find(s.prop_names.begin(), s.prop_names.end(), key);
      if (it == s.prop_names.end())
        throw InputError(path + ": bounds given for '" + key + "', which is not a prop name");
      const std::vector<double> b = numbers(node, "bounds." + key, path);
      const std::size_t i = it - s.prop_names.begin();
      if (b.size() != 2 || !(b[0] < b[1]) || s.props[i] < b[0] || s.props[i] > b[1])
        throw InputError(path + ": bounds." + key +
                         " must be [lower, upper] with lower < upper around the prop's value " +
                         fmt(s.props[i]));
      s.lower[i] = b[0];
      s.upper[i] = b[1];
    }
  return s;
}

UmatLaw::UmatLaw(const std::string& library, UmatSpec spec)
    : library_path_(library), lib_(std::make_shared<UmatLibrary>(library)), spec_(std::move(spec)) {
  for (std::size_t i = 0; i < spec_.props.size(); ++i)
    info_.push_back({spec_.prop_names[i], "-", spec_.props[i], spec_.lower[i], spec_.upper[i],
                     "PROPS(" + std::to_string(i + 1) + ") of the UMAT"});
  for (int i = 0; i < std::min(spec_.nstatv, kMaxInternal); ++i)
    internal_names_.push_back("statev" + std::to_string(i + 1));
  params_ = spec_.props;
}

UmatLaw::~UmatLaw() = default;

const std::string& UmatLaw::symbol() const { return lib_->symbol(); }

Vector6d UmatLaw::initial_internal(const Eigen::Matrix3d&, const Eigen::Matrix3d&) const {
  Vector6d q = Vector6d::Zero();
  for (int i = 0; i < std::min(spec_.nstatv, kMaxInternal); ++i) q(i) = spec_.statev[i];
  return q;
}

double UmatLaw::yield_function(const MaterialState&) const {
  return -std::numeric_limits<double>::infinity();
}

UmatState UmatLaw::umat_state(const MaterialState& point) const {
  UmatState s;
  s.point = point;
  s.statev = spec_.statev;
  for (int i = 0; i < std::min(spec_.nstatv, kMaxInternal); ++i) s.statev[i] = point.internal(i);
  return s;
}

UmatCall UmatLaw::call(const UmatState& start, const Eigen::Matrix3d& d_eps, double dtime,
                       int kinc) const {
  UmatCall c;
  double stress[6], ddsdde[36] = {}, ddsddt[6] = {}, drplde[6] = {}, stran[6], dstran[6];
  to_umat_stress(start.point.stress, stress);
  to_umat_strain(start.strain, stran);
  to_umat_strain(d_eps, dstran);
  // A Fortran array of size zero still needs an address.
  std::vector<double> statev = start.statev;
  if (statev.empty()) statev.push_back(0.0);
  double sse = start.sse, spd = start.spd, scd = start.scd, rpl = 0.0, drpldt = 0.0;
  const double time[2] = {start.time, start.time};
  const double temp = 0.0, dtemp = 0.0, predef[1] = {0.0}, dpred[1] = {0.0};
  char cmname[80];
  std::fill(std::begin(cmname), std::end(cmname), ' ');
  std::copy(spec_.cmname.begin(), spec_.cmname.end(), cmname);
  const int ndi = 3, nshr = 3, ntens = 6, nstatv = spec_.nstatv;
  const int nprops = static_cast<int>(params_.size());
  const double coords[3] = {0.0, 0.0, 0.0};
  const double drot[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  // Abaqus starts PNEWDT at a large value; a UMAT lowers it to ask for a smaller increment.
  double pnewdt = 1e36;
  const double celent = 1.0;
  // Small strains without rotation: F = I + eps (tension positive), column-major.
  const Eigen::Matrix3d f0 = Eigen::Matrix3d::Identity() - start.strain;
  const Eigen::Matrix3d f1 = f0 - d_eps;
  const int noel = 1, npt = 1, layer = 1, kspt = 1;
  // KSTEP, or JSTEP(4) in the newer interface: step 1, general procedure, not perturbation.
  const int kstep[4] = {1, 1, 0, 0};
  {
    // A UMAT need not be thread-safe (Fortran SAVE and COMMON): two Python threads calling
    // model_envelope at once got envelopes off by 100x. One call at a time, in any library.
    static std::mutex one_call_at_a_time;
    const std::lock_guard<std::mutex> lock(one_call_at_a_time);
    lib_->entry()(stress, statev.data(), ddsdde, &sse, &spd, &scd, &rpl, ddsddt, drplde, &drpldt,
                  stran, dstran, time, &dtime, &temp, &dtemp, predef, dpred, cmname, &ndi, &nshr,
                  &ntens, &nstatv, params_.data(), &nprops, coords, drot, &pnewdt, &celent,
                  f0.data(), f1.data(), &noel, &npt, &layer, &kspt, kstep, &kinc, sizeof cmname);
  }
  c.pnewdt = pnewdt;
  const auto bad = [&](const char* what) {
    c.finite = false;
    c.reason = std::string("the UMAT returned NaN or inf in ") + what +
               " at increment KINC = " + std::to_string(kinc) + " (DSTRAN norm " +
               fmt(d_eps.norm()) + ")";
    return c;
  };
  if (!std::all_of(stress, stress + 6, [](double x) { return std::isfinite(x); }))
    return bad("STRESS");
  if (!std::all_of(statev.begin(), statev.end(), [](double x) { return std::isfinite(x); }))
    return bad("STATEV");
  if (!std::all_of(ddsdde, ddsdde + 36, [](double x) { return std::isfinite(x); }))
    return bad("DDSDDE");
  if (!std::isfinite(pnewdt)) return bad("PNEWDT");
  statev.resize(spec_.nstatv);
  c.end = start;
  c.end.point.stress = from_umat_stress(stress);
  c.end.point.volume_fraction = start.point.volume_fraction * std::exp(d_eps.trace());
  for (int i = 0; i < std::min(spec_.nstatv, kMaxInternal); ++i)
    c.end.point.internal(i) = statev[i];
  c.end.statev = std::move(statev);
  c.end.strain = start.strain + d_eps;
  c.end.sse = sse;
  c.end.spd = spd;
  c.end.scd = scd;
  c.end.time = start.time + dtime;
  c.tangent = mandel_tangent(ddsdde);
  return c;
}

namespace {

// The tangent call at a point: a tiny increment in the direction of d_eps (see umat.hpp).
UmatCall tangent_call(const UmatLaw& law, const MaterialState& state, const Eigen::Matrix3d& de) {
  const double n = de.norm();
  const Eigen::Matrix3d probe = n > 0.0 ? Eigen::Matrix3d(de * (kUmatTangentProbe / n)) : de;
  return law.call(law.umat_state(state), probe, kUmatTangentProbe, 1);
}

}  // namespace

bool UmatLaw::rate_checked(const MaterialState& state, const Eigen::Matrix3d& d_eps, LawRate* r,
                           std::string* why) const {
  const UmatCall c = tangent_call(*this, state, d_eps);
  if (!c.finite) {
    if (why) *why = c.reason;
    r->d_stress.setConstant(std::numeric_limits<double>::quiet_NaN());
    return false;
  }
  r->d_stress = from_mandel(Vector6d(c.tangent * to_mandel(d_eps)));
  return true;
}

LawRate UmatLaw::rate(const MaterialState& state, const Eigen::Matrix3d& d_eps) const {
  LawRate r;
  rate_checked(state, d_eps, &r, nullptr);
  return r;
}

Matrix6d UmatLaw::tangent(const MaterialState& state, const Eigen::Matrix3d& d_eps) const {
  const UmatCall c = tangent_call(*this, state, d_eps);
  return c.finite ? c.tangent : Matrix6d::Constant(std::numeric_limits<double>::quiet_NaN());
}

namespace {
// The Frobenius norm without overflow of its squares (up to the largest double). Eigen 3.4's
// stableNorm() of a 3x3 matrix fails its own block assertion in a build with assertions.
double scaled_norm(const Eigen::Matrix3d& m) {
  const double s = m.cwiseAbs().maxCoeff();
  return s > 0.0 && std::isfinite(s) ? s * (m / s).norm() : s;
}

// A step-doubling increment whose finite stresses overflow its arithmetic (norms of 1e160).
UmatCall overflowed(int kinc) {
  UmatCall c;
  c.finite = false;
  c.reason =
      "the UMAT's stresses are too large for the driver (its error estimate or the "
      "extrapolated STRESS is not finite) at increment KINC = " +
      std::to_string(kinc);
  return c;
}
}  // namespace

StepResult UmatLaw::integrate(const UmatState& start, const Eigen::Matrix3d& d_eps,
                              const StepOptions& o, UmatState* end_state,
                              UmatSchedule* schedule) const {
  StepResult res;
  res.end = start.point;
  std::string why;
  if (!o.IsValid(&why)) {
    res.reason = "invalid step options: " + why;
    return res;
  }
  if (!d_eps.allFinite()) {
    res.reason = "non-finite strain increment";
    return res;
  }
  // Step doubling (adaptive): one increment h against two of h/2; their difference in stress is
  // the error estimate, and the two halves are kept with their stress extrapolated. Otherwise
  // `fixed_substeps` increments, one call each.
  // A UMAT gives no rate to build stages from: every adaptive scheme is step doubling here.
  const bool doubling = o.adaptive && o.scheme != Scheme::kExplicitEuler;
  UmatState y = start;
  if (schedule && schedule->replay) {
    int kinc = 0;
    for (const double h : schedule->fractions) {
      const Eigen::Matrix3d de = h * d_eps;
      ++kinc;
      UmatCall c = doubling ? call(y, 0.5 * de, 0.5 * h, kinc) : call(y, de, h, kinc);
      if (doubling && c.finite) {
        const UmatCall full = call(y, de, h, kinc);
        c = full.finite ? call(c.end, 0.5 * de, 0.5 * h, kinc) : full;
        if (c.finite) c.end.point.stress += c.end.point.stress - full.end.point.stress;
        if (c.finite && !c.end.point.stress.allFinite()) c = overflowed(kinc);
      }
      res.rate_evaluations += doubling ? 3 : 1;
      if (!c.finite) {
        res.reason = c.reason;
        return res;
      }
      y = std::move(c.end);
      ++res.substeps;
    }
    res.end = y.point;
    if (end_state) *end_state = y;
    res.success = true;
    return res;
  }
  if (schedule) schedule->fractions.clear();
  double t = 0.0, dt = doubling ? 1.0 : 1.0 / o.fixed_substeps;
  int cuts = 0, kinc = 0;
  bool rejected_last = false;
  while (1.0 - t > 1e-14) {
    if (res.attempted() >= o.max_substeps) {
      res.on_substep_limit = true;
      res.reason = "UMAT driver: more than " + std::to_string(o.max_substeps) +
                   " increments (reached fraction " + fmt(t) + " of the strain increment)";
      break;
    }
    if (dt < o.min_fraction) {
      res.reason = "UMAT driver: increment below " + fmt(o.min_fraction) +
                   " of the strain increment at fraction " + fmt(t);
      break;
    }
    const double h = std::min(dt, 1.0 - t);
    const Eigen::Matrix3d de = h * d_eps;
    ++kinc;
    UmatCall full = call(y, de, h, kinc);
    ++res.rate_evaluations;
    if (!full.finite) {
      res.reason = full.reason + ", fraction " + fmt(t) + " of the strain increment";
      break;
    }
    double pnewdt = full.pnewdt, err = 0.0;
    UmatCall kept;
    if (doubling && pnewdt >= 1.0) {
      UmatCall a = call(y, 0.5 * de, 0.5 * h, kinc);
      UmatCall b = a.finite ? call(a.end, 0.5 * de, 0.5 * h, kinc) : a;
      res.rate_evaluations += a.finite ? 2 : 1;
      if (!b.finite) {
        res.reason = b.reason + ", fraction " + fmt(t) + " of the strain increment";
        break;
      }
      pnewdt = std::min({pnewdt, a.pnewdt, b.pnewdt});
      const Eigen::Matrix3d diff = b.end.point.stress - full.end.point.stress;
      // Scaled: finite stresses of 1e160 overflowed norm()'s sum of squares (err NaN).
      // Relative to the larger of the end's and the start's |sigma|, as the laws' driver
      // (driver_core.hpp, difference_error): no floor in Pa.
      err = scaled_norm(diff) /
            std::max({scaled_norm(b.end.point.stress), scaled_norm(y.point.stress),
                      std::numeric_limits<double>::min()});
      kept = std::move(b);
      // Local extrapolation of the stress (Richardson, for a first-order update: 2 halves - 1
      // full), as modified Euler keeps its second-order value over the Euler one it measures
      // the error by; an exact UMAT is unchanged. STATEV stay those of the two halves: they
      // may be discrete (flags, counters), where an extrapolation has no meaning.
      kept.end.point.stress += diff;
      // Stresses near the largest double overflow the difference itself: an error estimate of
      // NaN passed the tolerance test (NaN > tol is false) and the step was kept as exact.
      if (!std::isfinite(err) || !kept.end.point.stress.allFinite()) {
        res.reason = overflowed(kinc).reason + ", fraction " + fmt(t) + " of the strain increment";
        break;
      }
    } else {
      kept = std::move(full);
    }
    if (pnewdt < 1.0) {
      // Abaqus's rule: the increment is abandoned and retried PNEWDT times as long (a
      // non-positive PNEWDT gets Abaqus's default cutback, 0.25).
      if (++cuts > kUmatMaxCutbacks) {
        res.reason = "the UMAT asked for a smaller increment (PNEWDT = " + fmt(pnewdt) + ") " +
                     std::to_string(kUmatMaxCutbacks) + " times in a row at fraction " + fmt(t) +
                     " of the strain increment (last increment " + fmt(h) + " of it)";
        break;
      }
      dt = h * (pnewdt > 0.0 ? std::max(pnewdt, 0.01) : 0.25);
      ++res.rejected;
      rejected_last = true;
      continue;
    }
    if (err > o.tolerance) {
      dt = h * std::max(0.9 * std::sqrt(o.tolerance / err), 0.1);
      ++res.rejected;
      rejected_last = true;
      continue;
    }
    cuts = 0;
    if (schedule) schedule->fractions.push_back(h);
    y = std::move(kept.end);
    t += h;
    ++res.substeps;
    res.error_estimate = std::max(res.error_estimate, err);
    // Growth: by the error (step doubling), never beyond what PNEWDT allows, and not right after
    // a rejection.
    double q = doubling ? (err > 0.0 ? 0.9 * std::sqrt(o.tolerance / err) : 2.0) : 1.0;
    q = std::min({q, 2.0, pnewdt});
    if (rejected_last) q = std::min(q, 1.0);
    rejected_last = false;
    dt = h * q;
    if (!doubling) dt = std::max(dt, std::min(h, 1.0 / o.fixed_substeps));
  }
  res.end = y.point;
  if (end_state) *end_state = y;
  if (!res.reason.empty()) return res;
  res.success = true;
  return res;
}

PathSeries UmatLaw::run_path(const MaterialState& start, const Eigen::Matrix3d& total,
                             const PathOptions& o, UmatState* end_state) const {
  PathSeries s;
  std::string why;
  if (!o.IsValid(&why)) {
    s.reason = "invalid path options: " + why;
    return s;
  }
  const Eigen::Matrix3d de = total / o.steps;
  UmatState y = umat_state(start);
  const auto record = [&] {
    s.strain.push_back(y.strain);
    s.eps_v.push_back(volumetric_strain(y.strain));
    s.eps_dev.push_back(signed_deviator(y.strain));
    s.stress.push_back(y.point.stress);
    s.fabric.push_back(y.point.fabric);
    s.volume_fraction.push_back(y.point.volume_fraction);
    s.internal.push_back(y.point.internal);
  };
  record();
  for (int k = 0; k < o.steps; ++k) {
    UmatState next;
    const StepResult r = integrate(y, de, o.step, &next);
    if (!r.success) {
      s.reason =
          "step " + std::to_string(k + 1) + " of " + std::to_string(o.steps) + ": " + r.reason;
      return s;
    }
    y = std::move(next);
    if (const std::string bad = volume_fraction_problem(y.point.volume_fraction); !bad.empty()) {
      s.reason = "step " + std::to_string(k + 1) + " of " + std::to_string(o.steps) + ": " + bad;
      return s;
    }
    s.max_error_estimate = std::max(s.max_error_estimate, r.error_estimate);
    s.total_substeps += r.substeps;
    record();
    if (o.after_step) o.after_step(k + 1, o.steps);
  }
  if (end_state) *end_state = y;
  s.success = true;
  return s;
}

std::unique_ptr<UmatLaw> make_umat_law(const std::string& library, const std::string& params) {
  // The front ends name their own options first (app::law_for, calibration_plan).
  if (library.empty()) throw InputError("a UMAT needs its library (a .so file: docs/umat.md)");
  if (params.empty())
    throw InputError("a UMAT needs its parameters file (props, nstatv, ...: docs/umat.md)");
  return std::make_unique<UmatLaw>(library, load_umat_parameters_toml(params));
}

namespace {
std::shared_ptr<const UmatLaw>& session_slot() {
  static std::shared_ptr<const UmatLaw> law;
  return law;
}
}  // namespace

void set_session_umat(std::shared_ptr<const UmatLaw> law) { session_slot() = std::move(law); }
std::shared_ptr<const UmatLaw> session_umat() { return session_slot(); }

}  // namespace rendulic::models
