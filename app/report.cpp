// Report of a run: the seed's claims C1-C8 checked on the run's own numbers (see report.hpp).
// Thresholds are stated in each claim's text so a reader can judge the verdicts; they are
// deliberately loose where the seed's own data fluctuate (plastic envelopes, Fig. 7).
#include "report.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>

#include "commands.hpp"
#include "rendulic/calibration/report.hpp"
#include "rendulic/core/comma_list.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/core/envelope_io.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/core/text_file.hpp"
#include "rendulic/core/version.hpp"
#include "rendulic/dem/probe_envelope.hpp"
#include "rendulic/dem/protocols.hpp"

namespace rendulic::app {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct FitInfo {
  bool present = false;
  std::string shape;
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double a = kNaN, b = kNaN, incl = kNaN;
  // The fit's own verdict: a fit that did not converge can sit anywhere (an ellipse of huge
  // axes whose arc passes the points), and a claim read from it would be an artefact.
  bool converged = true;
};

struct EnvInfo {
  std::string name, method;
  double amplitude = kNaN;
  FitInfo stress, fabric;
  EnvelopeRecord data;       // as stored (core/envelope_record.hpp): pairs, fabric split, ...
  double mean_flips = kNaN;  // contacts opened + closed per probe (all contacts), if stored
  // The fabric split and the stress pairs of every direction (what C2 compares probe by probe).
  bool has_split() const {
    const std::size_t n = data.theta_deg.size();
    return n > 0 && data.d_fabric_contacts.size() == n && data.d_fabric_volume.size() == n &&
           data.d_fabric_rotation.size() == n && data.stress_star.size() == n;
  }
};

struct StateInfo {
  std::string label;
  double eps_dev = kNaN, volume_fraction = kNaN;
  std::vector<EnvInfo> envs;
  // Envelopes of other probe planes than the Rendulic one (docs/probes.md "Probe planes"): the
  // claims read Rendulic pairs, so these are only listed with their fits.
  std::vector<EnvInfo> other_planes;
  bool has_range = false;
  double yield_strain = kNaN;
  bool yielded = false;
};

FitInfo read_fit(const ResultsReader& r, const std::string& g) {
  FitInfo f;
  if (!r.exists(g)) return f;
  if (r.has_attr(g, "shape")) f.shape = r.attr_string(g, "shape");
  if (r.has_attr(g, "center")) {
    const auto c = r.attr_doubles(g, "center");
    if (c.size() == 2) f.center = {c[0], c[1]};
  }
  if (r.has_attr(g, "semi_axes")) {
    const auto s = r.attr_doubles(g, "semi_axes");
    if (s.size() == 2) f.a = s[0], f.b = s[1];
  }
  if (r.has_attr(g, "inclination_deg")) f.incl = r.attr_double(g, "inclination_deg");
  if (r.has_attr(g, "converged")) f.converged = r.attr_int(g, "converged") != 0;
  // A group that says the envelope could not be fitted (shape "none", an `error`) holds no
  // fit: read as one, its NaN axes turned claims C1, C4 and C5 into "does not hold" where
  // nothing was measured.
  f.present = !f.shape.empty() && f.shape != "none" && std::isfinite(f.a);
  return f;
}

std::vector<StateInfo> read_states(const ResultsReader& r) {
  std::vector<StateInfo> out;
  for (const auto& label : r.children(paths::kStates)) {
    const std::string g = paths::state(label);
    StateInfo s;
    s.label = label;
    if (r.has_attr(g, "eps_dev")) s.eps_dev = r.attr_double(g, "eps_dev");
    if (r.has_attr(g, "volume_fraction")) s.volume_fraction = r.attr_double(g, "volume_fraction");
    const std::string er = paths::elastic_range(g);
    if (r.exists(er) && r.has_attr(er, "yield_strain")) {
      s.has_range = true;
      s.yield_strain = r.attr_double(er, "yield_strain");
      s.yielded = r.has_attr(er, "yielded") && r.attr_int(er, "yielded") != 0;
    }
    for (const auto& name : r.children(paths::envelopes(g))) {
      const std::string e = paths::envelope(g, name);
      EnvInfo env;
      env.name = name;
      env.data = read_envelope(r, e);
      env.method = env.data.method;
      env.amplitude = env.data.amplitude;
      const auto opened = env.data.diagnostics.find("contacts_opened");
      const auto closed = env.data.diagnostics.find("contacts_closed");
      if (opened != env.data.diagnostics.end() && closed != env.data.diagnostics.end()) {
        double sum = 0;
        for (std::size_t p = 0; p < opened->second.size() && p < closed->second.size(); ++p)
          sum += opened->second[p] + closed->second[p];
        if (!opened->second.empty())
          env.mean_flips = sum / static_cast<double>(opened->second.size());
      }
      env.stress = read_fit(r, e + paths::kFitStress);
      env.fabric = read_fit(r, e + paths::kFitFabric);
      (env.data.plane.rendulic() ? s.envs : s.other_planes).push_back(std::move(env));
    }
    out.push_back(std::move(s));
  }
  // Along the path: -eps_dev increasing (the path is an extension, eps_dev < 0).
  std::sort(out.begin(), out.end(),
            [](const StateInfo& a, const StateInfo& b) { return -a.eps_dev < -b.eps_dev; });
  return out;
}

bool same_amplitude(double a, double b) { return std::abs(a - b) <= 1e-9 * std::abs(b); }

// The elastic envelope of a state used for the claims: dynamic probes first (what the seed
// did), then minimisation, then linear response.
const EnvInfo* pick_elastic(const StateInfo& s) {
  for (const char* method : {"dynamic", "minimisation", "linear_response"})
    for (const auto& e : s.envs)
      if (is_elastic_amplitude(e.amplitude) && e.method == method && e.stress.present) return &e;
  return nullptr;
}
const EnvInfo* find_env(const StateInfo& s, const std::string& method, double amplitude) {
  for (const auto& e : s.envs)
    if (e.method == method && same_amplitude(e.amplitude, amplitude)) return &e;
  return nullptr;
}
// The plastic envelope at amplitude A: dynamic first, then minimisation. A linear response
// at a plastic amplitude is the elastic one scaled: never plastic data.
const EnvInfo* pick_plastic(const StateInfo& s, double amplitude) {
  for (const char* method : {"dynamic", "minimisation"})
    if (const EnvInfo* e = find_env(s, method, amplitude); e && e->stress.present) return e;
  return nullptr;
}

// The plastic amplitude of the claims (docs/claims.md): among the probe amplitudes above
// 1e-3 that every state has, the smallest at least twice the largest yield strain of the
// elastic ranges; without elastic ranges, the largest; NaN if none. `note` says how.
double plastic_amplitude(const std::vector<StateInfo>& states, std::string* note) {
  std::vector<double> common;
  if (!states.empty())
    for (const auto& e : states[0].envs)
      if (is_plastic_amplitude(e.amplitude) && pick_plastic(states[0], e.amplitude))
        common.push_back(e.amplitude);
  std::erase_if(common, [&](double a) {
    return !std::all_of(states.begin(), states.end(),
                        [&](const StateInfo& s) { return pick_plastic(s, a) != nullptr; });
  });
  std::sort(common.begin(), common.end());
  common.erase(std::unique(common.begin(), common.end(), same_amplitude), common.end());
  if (common.empty()) return kNaN;
  double largest_yield = kNaN;
  bool all_ranges = true;
  for (const auto& s : states) {
    all_ranges = all_ranges && s.has_range;
    if (s.has_range && !(s.yield_strain <= largest_yield)) largest_yield = s.yield_strain;
  }
  if (!all_ranges) {
    *note = "plastic amplitude " + decimal_g(common.back()) +
            " (no elastic range measured: not checked against the yield strain)";
    return common.back();
  }
  for (double a : common)
    if (a >= 2.0 * largest_yield) {
      std::ostringstream o;
      o << "plastic amplitude " << a << " (>= 2 x the largest yield strain " << std::setprecision(3)
        << largest_yield << ")";
      *note = o.str();
      return a;
    }
  std::ostringstream o;
  o << "plastic amplitude " << common.back() << " is below 2 x the largest yield strain "
    << std::setprecision(3) << largest_yield << ": the probes are not beyond the elastic range";
  *note = o.str();
  return -common.back();  // negative: present, but inside the elastic range
}

std::string fmt(double x, int prec = 3) {
  if (!std::isfinite(x)) return "n/a";
  std::ostringstream o;
  o << std::setprecision(prec) << x;
  return o.str();
}

std::string series(const std::vector<double>& xs, int prec = 3) {
  std::string out;
  for (std::size_t i = 0; i < xs.size(); ++i) out += (i ? ", " : "") + fmt(xs[i], prec);
  return out;
}

std::string verdict(bool measured, bool holds) {
  return !measured ? "not measured" : holds ? "holds" : "does not hold";
}

double angle_between_axes_deg(double a_deg, double b_deg) {
  double d = std::fmod(std::abs(a_deg - b_deg), 180.0);
  return std::min(d, 180.0 - d);
}

// The index of the probe in direction `deg` (modulo 360), or -1.
int probe_at(const EnvInfo& e, double deg) {
  for (std::size_t i = 0; i < e.data.theta_deg.size(); ++i)
    if (std::abs(std::fmod(e.data.theta_deg[i] - deg + 540.0, 360.0) - 180.0) < 0.01)
      return static_cast<int>(i);
  return -1;
}

// Directional stiffness (d_sigma* : d_eps) / |d_eps|^2 of the probe in direction deg
// (stress_star units), NaN if absent.
double directional_stiffness(const EnvInfo& e, double deg) {
  const int i = probe_at(e, deg);
  if (i < 0 || static_cast<std::size_t>(i) >= e.data.stress_star.size()) return kNaN;
  const Eigen::Vector2d u(std::cos(deg_to_rad(deg)), std::sin(deg_to_rad(deg)));
  return e.data.stress_star[static_cast<std::size_t>(i)].dot(u) / e.amplitude;
}

// The fabric change of one contact flip (docs/claims.md): the largest contribution one contact
// makes to eq. 2, (V_i + V_j) / V between two of the largest particles, = 2 nu r_max^3 / (N
// <r^3>) for radii uniform in [r_min, r_max].
double one_contact_flip(const ResultsReader& r, double nu) {
  if (!r.has_attr(paths::kMaterial, "n_particles") || !r.has_attr(paths::kMaterial, "w") ||
      !r.has_attr(paths::kMaterial, "r_mean") || !std::isfinite(nu))
    return kNaN;
  const double n = static_cast<double>(r.attr_int(paths::kMaterial, "n_particles"));
  const double w = r.attr_double(paths::kMaterial, "w"),
               rm = r.attr_double(paths::kMaterial, "r_mean");
  // A damaged file's n_particles = -5 made every flip ratio of C2 negative, without a word.
  const auto refuse = [&](const char* key, double v, const char* wanted) {
    std::ostringstream why;
    why << r.path().string() << ":" << paths::kMaterial << "@" << key << " is " << v << ", not "
        << wanted;
    throw InputError(why.str());
  };
  if (!(n >= 1.0)) refuse("n_particles", n, "a positive count");
  if (!(w >= 1.0 && std::isfinite(w))) refuse("w", w, "a finite ratio >= 1");
  if (!(rm > 0.0 && std::isfinite(rm))) refuse("r_mean", rm, "a positive finite radius");
  const double r_min = 2.0 * rm / (1.0 + w), r_max = w * r_min;
  const double r3 = w > 1.0 ? (std::pow(r_max, 4) - std::pow(r_min, 4)) / (4.0 * (r_max - r_min))
                            : std::pow(rm, 3);
  return 2.0 * nu * std::pow(r_max, 3) / (n * r3);
}

double frobenius_max(const std::vector<Eigen::Matrix3d>& ts) {
  double m = 0.0;
  for (const auto& t : ts) m = std::max(m, t.norm());
  return m;
}
double frobenius_mean(const std::vector<Eigen::Matrix3d>& ts) {
  double m = 0.0;
  for (const auto& t : ts) m += t.norm();
  return ts.empty() ? kNaN : m / static_cast<double>(ts.size());
}

// The plateau windows of C8 (docs/claims.md), as fractions of the path's final -eps_dev:
// the start (the first sample, at rest), the trough of sigma_xx, and the steady state.
constexpr double kTroughFrom = 0.125, kTroughTo = 0.375;  // -eps_dev 0.04-0.12 of 0.32
// C2: the kinematic fabric envelope agrees with the linear response "within its noise" when
// its relative difference is at most this many times that of the stress envelope of the same
// probes (the same relaxation error acts on both).
constexpr double kKinematicNoiseFactor = 3.0;

// "Model selection" (docs/calibration.md "Likelihood and model selection"): the common yardstick
// per law, the held-out score, the information criterion, how each fit stopped, and the sentence of
// /calibration `selection`; parameters at a bound or undetermined are named.
std::string model_selection_markdown(const ResultsReader& r) {
  if (!r.has_attr(paths::kCalibration, "selection")) return "";
  std::ostringstream md;
  const std::string sel = r.attr_string(paths::kCalibration, "selected_model");
  md << "\n## Model selection (docs/calibration.md)\n\n"
     << r.attr_string(paths::kCalibration, "selection") << "\n\n";
  static const char* kinds[] = {"stress_elastic", "stress_plastic", "fabric_elastic",
                                "fabric_plastic", "path_stress",    "path_fabric"};
  md << "| law | free | stress el. | stress pl. | fabric el. | fabric pl. | path stress | path "
        "fabric | held-out score (all / stress) | BIC (all / stress) | Δ BIC (all / stress) | "
        "stopped by | global start | s |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  double best = kNaN, best_stress = kNaN;
  const std::string sel_s = r.has_attr(paths::kCalibration, "selected_model_stress")
                                ? r.attr_string(paths::kCalibration, "selected_model_stress")
                                : "";
  if (!sel.empty() && r.has_attr(paths::calibration(sel), "information_criterion"))
    best = r.attr_double(paths::calibration(sel), "information_criterion");
  if (!sel_s.empty() && r.has_attr(paths::calibration(sel_s), "information_criterion_stress"))
    best_stress = r.attr_double(paths::calibration(sel_s), "information_criterion_stress");
  std::vector<std::string> flags;
  std::string noise_row;
  for (const std::string& m : r.children(paths::kCalibration)) {
    const std::string g = paths::calibration(m);
    if (r.has_attr(g, "error") || !r.has_attr(g, "information_criterion")) continue;
    auto num = [&](const std::string& a, int prec = 3) {
      return r.has_attr(g, a) ? fmt(r.attr_double(g, a), prec) : std::string("-");
    };
    md << "| " << (m == sel ? "**" + m + "**" : m) << " | " << r.attr_int(g, "n_free");
    for (const char* k : kinds) md << " | " << num(std::string("misfit_") + k);
    const double ic = r.attr_double(g, "information_criterion");
    const double ics = r.attr_double(g, "information_criterion_stress");
    bool fabric = false;
    for (const std::string& kind : r.attr_strings(g, "blocks_covered"))
      fabric = fabric || kind.find("fabric") != std::string::npos;
    md << " | " << (fabric ? num("held_out_score") : "-") << " / " << num("held_out_score_stress")
       << " | " << (fabric ? fmt(ic, 6) : "-") << " / " << fmt(ics, 6) << " | "
       << (fabric && std::isfinite(best) ? fmt(ic - best, 4) : "-") << " / "
       << (std::isfinite(best_stress) ? fmt(ics - best_stress, 4) : "-") << " | "
       << (r.has_attr(g, "termination") ? r.attr_string(g, "termination") : "-") << " | "
       << (r.has_attr(g, "global_start") && r.attr_string(g, "global_start").rfind("used", 0) == 0
               ? "used"
               : "no")
       << " | " << num("seconds", 2) << " |\n";
    const auto listed = [&](const char* name) {
      std::string s;
      if (r.has_attr(g, name))
        for (const std::string& n : r.attr_strings(g, name)) s += (s.empty() ? "" : ",") + n;
      return s;
    };
    const std::string at = listed("at_bound");
    const std::string und = listed("undetermined");
    if (!at.empty()) flags.push_back(m + ": at a bound of its range: " + at);
    if (!und.empty())
      flags.push_back(m +
                      ": not determined by the data (standard error above half the value): " + und);
    if (r.has_attr(g, "global_start") && r.attr_string(g, "global_start").rfind("used", 0) == 0)
      flags.push_back(m + ": global start " + r.attr_string(g, "global_start"));
    if (noise_row.empty() && fabric) {
      // The data's own noise per kind (rms over the fitted blocks; any law's yardstick has it).
      const std::vector<std::string> ids = r.attr_strings(g, "yardstick_blocks");
      const auto noise = r.attr_doubles(g, "yardstick_noise");
      const auto held = r.attr_doubles(g, "yardstick_held_out");
      std::map<std::string, std::pair<double, int>> acc;
      for (std::size_t i = 0; i < ids.size() && i < noise.size(); ++i) {
        const std::string& id = ids[i];
        if (i < held.size() && held[i] != 0.0) continue;
        const std::string kind = id.substr(id.rfind('/') + 1);
        acc[kind].first += noise[i] * noise[i];
        ++acc[kind].second;
      }
      noise_row = "| *DEM noise* | ";
      for (const char* k : kinds)
        noise_row += " | " + (acc.count(k) ? fmt(std::sqrt(acc[k].first / acc[k].second))
                                           : std::string("-"));
      noise_row += " | | | | | | |\n";
    }
  }
  md << noise_row;
  md << "\nMisfits: relative rms of (law - DEM) per block over the fitted states, each block "
        "normalised by its data scale only; the DEM noise row is the data's own roughness on "
        "the same scale. Held-out score: geometric mean of max(misfit, noise) over the held-out "
        "states' blocks. BIC: -2 ln L + k ln N with the block variances profiled "
        "(docs/calibration.md \"Likelihood and model selection\"); laws without fabric are "
        "compared on the "
        "stress blocks only. Rule: "
     << r.attr_string(paths::kCalibration, "selection_rule") << ".\n";
  if (!flags.empty()) {
    md << "\nParameters to read with care:\n\n";
    for (const auto& f : flags) md << "- " << f << "\n";
  }
  return md.str();
}

}  // namespace

std::vector<Claim> evaluate_claims(const ResultsReader& r) {
  std::vector<Claim> claims;
  const auto states = read_states(r);
  std::vector<const EnvInfo*> el;
  for (const auto& s : states) el.push_back(pick_elastic(s));
  auto all = [](const std::vector<const EnvInfo*>& v) {
    return !v.empty() && std::all_of(v.begin(), v.end(), [](auto* e) { return e != nullptr; });
  };
  std::string amplitude_note;
  const double signed_plastic = plastic_amplitude(states, &amplitude_note);
  const bool beyond_elastic = signed_plastic > 0;
  const double plastic = std::abs(signed_plastic);
  std::vector<const EnvInfo*> pl;
  for (const auto& s : states)
    pl.push_back(std::isfinite(plastic) ? pick_plastic(s, plastic) : nullptr);

  {  // C1
    Claim c{"C1", "Elastic stress envelope: an ellipse centred at the origin (|centre|/a < 0.05)",
            "", ""};
    std::vector<double> shift;
    if (all(el))
      for (auto* e : el) shift.push_back(e->stress.center.norm() / e->stress.a);
    const bool ok = !shift.empty() && *std::max_element(shift.begin(), shift.end()) < 0.05;
    c.measured = shift.empty() ? "" : "|centre|/a per state: " + series(shift);
    c.verdict = verdict(!shift.empty(), ok);
    claims.push_back(c);
  }
  {  // C2: on the contact-set part of dF, and the kinematic parts against the linear response
    Claim c{"C2",
            "Elastic probes leave the structure unchanged: the contact-set part of dF within one "
            "contact flip in every probe, and the kinematic (volume + rotation) fabric envelope "
            "equal to the linear response's within its noise",
            "", ""};
    std::vector<double> flips, kin_err, noise;
    bool measured = all(el) && !states.empty();
    bool ok = measured;
    for (std::size_t i = 0; measured && i < states.size(); ++i) {
      const EnvInfo* e = el[i];
      const EnvInfo* lr = find_env(states[i], "linear_response", e->amplitude);
      const double flip = one_contact_flip(r, states[i].volume_fraction);
      if (!e->has_split() || !lr || !lr->has_split() || !std::isfinite(flip) ||
          lr->data.theta_deg.size() != e->data.theta_deg.size()) {
        measured = false;
        break;
      }
      flips.push_back(frobenius_max(e->data.d_fabric_contacts) / flip);
      // Kinematic parts of the probes against the linear response, relative to its largest
      // fabric change; the noise is the same comparison of the stress responses.
      double d_kin = 0, f_max = 0, d_s = 0, s_max = 0;
      for (std::size_t p = 0; p < e->data.theta_deg.size(); ++p) {
        const Eigen::Matrix3d kin = e->data.d_fabric_volume[p] + e->data.d_fabric_rotation[p];
        const Eigen::Matrix3d kin_lr = lr->data.d_fabric_volume[p] + lr->data.d_fabric_rotation[p];
        d_kin = std::max(d_kin, (kin - kin_lr).norm());
        f_max = std::max(f_max, kin_lr.norm());
        d_s = std::max(d_s, (e->data.stress_star[p] - lr->data.stress_star[p]).norm());
        s_max = std::max(s_max, lr->data.stress_star[p].norm());
      }
      kin_err.push_back(d_kin / f_max);
      noise.push_back(d_s / s_max);
      ok = ok && flips.back() <= 1.0 && kin_err.back() <= kKinematicNoiseFactor * noise.back();
    }
    if (measured)
      c.measured = "largest contact-set |dF| per state / one flip: " + series(flips) +
                   "; kinematic fabric against the linear response: " + series(kin_err) +
                   " (stress: " + series(noise) + ")";
    c.verdict = verdict(measured, ok);
    claims.push_back(c);
  }
  {  // C3
    Claim c{"C3",
            "Near isotropy the isotropic probe (35.26 deg) maps onto the major axis (< 5 deg)", "",
            ""};
    bool measured = false, ok = false;
    // One stress pair per direction, or the envelope is damaged and C3 cannot be measured.
    if (!el.empty() && el[0] && !el[0]->data.theta_deg.empty() &&
        el[0]->data.stress_star.size() == el[0]->data.theta_deg.size() &&
        std::isfinite(el[0]->stress.incl)) {
      const auto& e = *el[0];
      std::size_t best = 0;
      for (std::size_t i = 0; i < e.data.theta_deg.size(); ++i)
        if (angle_between_axes_deg(e.data.theta_deg[i], kIsoCompressionDeg) <
            angle_between_axes_deg(e.data.theta_deg[best], kIsoCompressionDeg))
          best = i;
      if (angle_between_axes_deg(e.data.theta_deg[best], kIsoCompressionDeg) < 0.01) {
        const Eigen::Vector2d v = e.data.stress_star[best] - e.stress.center;
        const double dir = rad_to_deg(std::atan2(v.y(), v.x()));
        const double off = angle_between_axes_deg(dir, e.stress.incl);
        measured = true;
        ok = off < 5.0;
        c.measured = "state " + states[0].label + ": response at " + fmt(dir, 4) +
                     " deg, major axis at " + fmt(e.stress.incl, 4) + " deg (off by " +
                     fmt(off, 2) + " deg)";
      }
    }
    c.verdict = verdict(measured, ok);
    claims.push_back(c);
  }
  {  // C4
    Claim c{"C4",
            "Along the path the elastic major axis stays about constant (within 25%) while the "
            "minor axis shrinks",
            "", ""};
    std::vector<double> ra, rb;
    if (all(el))
      for (auto* e : el)
        ra.push_back(e->stress.a / el[0]->stress.a), rb.push_back(e->stress.b / el[0]->stress.b);
    bool ok = false;
    if (ra.size() >= 2) {
      double dev = 0;
      for (double v : ra) dev = std::max(dev, std::abs(v - 1));
      ok = dev < 0.25 && rb.back() < 1.0;
    }
    c.measured = ra.empty() ? "" : "a/a0: " + series(ra) + "; b/b0: " + series(rb);
    c.verdict = verdict(ra.size() >= 2, ok);
    claims.push_back(c);
  }
  {  // C5
    Claim c{"C5", "The elastic stress inclination decreases with anisotropy (first to last)", "",
            ""};
    std::vector<double> inc;
    if (all(el))
      for (auto* e : el) inc.push_back(e->stress.incl);
    const bool ok = inc.size() >= 2 && inc.back() < inc.front();
    c.measured = inc.empty() ? "" : "inclination [deg] per state: " + series(inc, 4);
    c.verdict = verdict(inc.size() >= 2, ok);
    claims.push_back(c);
  }
  {  // C6
    Claim c{"C6",
            "At the plastic amplitude the stress envelope is shifted (|centre|/a above the "
            "elastic one per state) and at steady state collapses onto a shifted line (b/a < "
            "0.1, stiffness continuing the path < 0.2 of reversing it)",
            "", ""};
    std::vector<double> shift, thin, k_ratio;
    std::vector<std::string> unconverged_labels;
    for (std::size_t i = 0; i < pl.size() && all(pl); ++i)
      if (!pl[i]->stress.converged) unconverged_labels.push_back(states[i].label);
    const std::string unconverged = comma_list(unconverged_labels);
    const bool measured = all(pl) && all(el) && beyond_elastic && unconverged.empty();
    bool ok = measured;
    if (all(pl) && all(el)) {
      for (std::size_t i = 0; i < pl.size(); ++i) {
        shift.push_back(pl[i]->stress.center.norm() / pl[i]->stress.a);
        thin.push_back(pl[i]->stress.b / pl[i]->stress.a);
        k_ratio.push_back(directional_stiffness(*pl[i], kDevExtensionDeg) /
                          directional_stiffness(*pl[i], kDevCompressionDeg));
        ok = ok && shift.back() > el[i]->stress.center.norm() / el[i]->stress.a;
      }
      ok = ok && thin.back() < 0.1 && k_ratio.back() < 0.2;
      c.measured = amplitude_note + "; |centre|/a: " + series(shift) + "; b/a: " + series(thin) +
                   "; k_continue/k_reverse: " + series(k_ratio);
      if (!unconverged.empty())
        c.measured += "; the plastic stress fit did not converge at state " + unconverged +
                      ", so its axes and centre are not a measurement";
    } else {
      c.measured = amplitude_note;
    }
    c.verdict = verdict(measured, ok);
    claims.push_back(c);
  }
  {  // C7
    Claim c{"C7",
            "At the plastic amplitude the fabric changes structurally (contact-set part of dF "
            "per unit strain above 5x its elastic value) and at steady state its envelope is a "
            "line (b/a < 0.15) inclined within 10 deg of 35.26",
            "", ""};
    std::vector<double> gain, inc;
    double thin = kNaN;
    bool measured = all(pl) && all(el) && beyond_elastic;
    bool ok = measured;
    for (std::size_t i = 0; measured && i < pl.size(); ++i) {
      if (!pl[i]->has_split() || !el[i]->has_split()) {
        measured = false;
        break;
      }
      // A contact-set part at round-off (no contact changed) is zero.
      auto structural = [](const EnvInfo& env) {
        const double m = frobenius_mean(env.data.d_fabric_contacts);
        return m > 1e-12 ? m / env.amplitude : 0.0;
      };
      const double p = structural(*pl[i]), e = structural(*el[i]);
      gain.push_back(e > 0 ? p / e : (p > 0 ? std::numeric_limits<double>::infinity() : kNaN));
      ok = ok && (e > 0 ? p > 5.0 * e : p > 0);
      // The fit's inclination (line or ellipse, as the shape test chose), else the map's.
      inc.push_back(pl[i]->fabric.incl);
    }
    if (measured) {
      const EnvInfo& last = *pl.back();
      const dem::RendulicMap m = dem::fit_rendulic_map(last.data.strain, last.data.fabric);
      thin = m.semi_minor / m.semi_major;
      if (!std::isfinite(inc.back())) inc.back() = m.inclination_deg;
      ok = ok && thin < 0.15 && angle_between_axes_deg(inc.back(), kIsoCompressionDeg) < 10.0;
      c.measured = amplitude_note +
                   "; contact-set |dF| per unit strain, plastic / elastic: " + series(gain) +
                   "; steady-state fabric b/a " + fmt(thin) + "; inclination: " + series(inc, 4);
      // Why the gain can be small: contacts made and lost per probe (a flip's fabric change
      // does not shrink with the amplitude, and the many flips of a large probe partly cancel).
      std::vector<double> el_flips, pl_flips;
      for (std::size_t i = 0; i < pl.size(); ++i) {
        el_flips.push_back(el[i]->mean_flips);
        pl_flips.push_back(pl[i]->mean_flips);
      }
      if (std::all_of(el_flips.begin(), el_flips.end(), [](double v) { return std::isfinite(v); }))
        c.measured += "; contacts made or lost per probe, elastic: " + series(el_flips) +
                      ", plastic: " + series(pl_flips);
    } else {
      c.measured = amplitude_note;
    }
    c.verdict = verdict(measured, ok);
    claims.push_back(c);
  }
  {  // C8: plateau means with standard errors (docs/claims.md)
    Claim c{"C8",
            "Fig. 1: sigma_xx falls then rises slightly; sigma_yy, sigma_zz rise to an "
            "asymptote; F_xx falls, F_yy and F_zz rise (plateau means, differences beyond 2 "
            "standard errors)",
            "", ""};
    bool measured = false, ok = false;
    const std::string p = paths::kPath;
    const std::string type =
        r.exists(p) && r.has_attr(p, "type") ? r.attr_string(p, "type") : "undrained_extension";
    if (type != "undrained_extension")
      c.measured = "the run's path is " + type + ", not the seed's undrained extension";
    else if (r.exists(p + datasets::kStressStar) && r.exists(p + datasets::kFabric) &&
             r.exists(p + datasets::kEpsDev)) {
      const auto s = r.read_tensors(p + datasets::kStressStar);
      const auto f = r.read_tensors(p + datasets::kFabric);
      const auto e = r.read_vector(p + datasets::kEpsDev);
      if (s.size() >= 10 && f.size() == s.size() && e.size() == s.size()) {
        std::vector<double> x, sxx, slat, fxx, flat;
        for (std::size_t i = 0; i < s.size(); ++i) {
          x.push_back(-e[i]);
          sxx.push_back(s[i](0, 0));
          slat.push_back(0.5 * (s[i](1, 1) + s[i](2, 2)));
          fxx.push_back(f[i](0, 0));
          flat.push_back(0.5 * (f[i](1, 1) + f[i](2, 2)));
        }
        const double end = *std::max_element(x.begin(), x.end());
        auto trough = [&](const std::vector<double>& y) {
          return dem::window_mean(x, y, kTroughFrom * end, kTroughTo * end);
        };
        auto steady = [&](const std::vector<double>& y) {
          return dem::window_mean(x, y, dem::kSteadyStateFrom * end, end);
        };
        const dem::WindowMean sxx_t = trough(sxx), sxx_s = steady(sxx), slat_t = trough(slat),
                              slat_s = steady(slat), fxx_s = steady(fxx), flat_s = steady(flat);
        measured = sxx_t.ok && sxx_s.ok && slat_t.ok && slat_s.ok && fxx_s.ok && flat_s.ok;
        if (measured) {
          // Beyond 2 standard errors of the difference (the start is one sample at rest: its
          // own error is taken as 0).
          auto beyond = [](double d, double se) { return d > 2.0 * se; };
          auto se2 = [](const dem::WindowMean& a, const dem::WindowMean& b) {
            return std::hypot(a.standard_error, b.standard_error);
          };
          const bool xx_falls = beyond(sxx[0] - sxx_t.mean, sxx_t.standard_error);
          const bool xx_rises = beyond(sxx_s.mean - sxx_t.mean, se2(sxx_s, sxx_t));
          const bool lat_rises = beyond(slat_t.mean - slat[0], slat_t.standard_error);
          // An asymptote: the rise after the trough window is smaller than the rise up to it.
          const bool lat_flattens = slat_s.mean - slat_t.mean < slat_t.mean - slat[0];
          const bool f_xx = beyond(fxx[0] - fxx_s.mean, fxx_s.standard_error);
          const bool f_lat = beyond(flat_s.mean - flat[0], flat_s.standard_error);
          ok = xx_falls && xx_rises && lat_rises && lat_flattens && f_xx && f_lat;
          auto pm = [](const dem::WindowMean& w) {
            return fmt(w.mean, 4) + " +- " + fmt(w.standard_error, 2);
          };
          c.measured = "windows -eps_dev [" + fmt(kTroughFrom * end) + ", " + fmt(kTroughTo * end) +
                       "] and [" + fmt(dem::kSteadyStateFrom * end) + ", " + fmt(end) +
                       "]: sigma*_xx " + fmt(sxx[0], 4) + " -> " + pm(sxx_t) + " -> " + pm(sxx_s) +
                       "; sigma*_lat " + fmt(slat[0], 4) + " -> " + pm(slat_t) + " -> " +
                       pm(slat_s) + "; F_xx " + fmt(fxx[0], 4) + " -> " + pm(fxx_s) + "; F_lat " +
                       fmt(flat[0], 4) + " -> " + pm(flat_s);
          if (!xx_rises)
            c.measured += " (sigma_xx does not rise beyond 2 standard errors after its trough)";
        } else {
          c.measured = "too few path samples in the plateau windows (raise path.samples)";
        }
      }
    }
    c.verdict = verdict(measured, ok);
    claims.push_back(c);
  }
  return claims;
}

// The path (docs/dem.md "Paths"): its type and the stress ratio q/p = (sigma_xx - (sigma_yy +
// sigma_zz) / 2) / p along it, at its steady state (the window of dem::kSteadyStateFrom of its
// strain s to the end, batch-means standard error) and at a few points on the way.
namespace {
std::string path_section(const ResultsReader& r) {
  const std::string p = paths::kPath;
  if (!r.exists(p + datasets::kStress) || !r.exists(p + datasets::kStrain)) return "";
  const std::string type = r.has_attr(p, "type") ? r.attr_string(p, "type") : "undrained_extension";
  const auto stress = r.read_tensors(p + datasets::kStress);
  const auto strain = r.read_tensors(p + datasets::kStrain);
  if (stress.size() < 2 || strain.size() != stress.size()) return "";
  const dem::PathType t = dem::path_type(type);
  std::vector<double> s, q_over_p;
  for (std::size_t i = 0; i < stress.size(); ++i) {
    const Eigen::Matrix3d& g = stress[i];
    const double pm = g.trace() / 3.0;
    s.push_back(dem::path_strain(t, strain[i]));
    q_over_p.push_back(pm > 0 ? (g(0, 0) - 0.5 * (g(1, 1) + g(2, 2))) / pm : kNaN);
  }
  std::ostringstream md;
  md << "\n## Path (docs/dem.md \"Paths\")\n\n- type: `" << type << "`";
  if (r.has_attr(p, "rate")) md << ", rate " << fmt(r.attr_double(p, "rate")) << " 1/s";
  if (r.has_attr(p, "inertial_number"))
    md << " at most, holding I = " << fmt(r.attr_double(p, "inertial_number")) << " (at least "
       << fmt(r.attr_double(p, "rate_min")) << " 1/s)";
  md << ", to s = " << fmt(s.back(), 3) << "\n";
  const double end = s.back();
  const dem::WindowMean w = dem::window_mean(s, q_over_p, dem::kSteadyStateFrom * end, end);
  md << "- steady state (s in [" << fmt(dem::kSteadyStateFrom * end, 3) << ", " << fmt(end, 3)
     << "]): q/p = "
     << (w.ok ? fmt(w.mean, 4) + " +- " + fmt(w.standard_error, 2) : std::string("-")) << "\n";
  // Friction: the share of contacts at the Coulomb limit, the mechanism of the steady state.
  std::vector<double> sliding;
  if (r.exists(p + datasets::kSlidingFraction))
    sliding = r.read_vector(p + datasets::kSlidingFraction);
  if (sliding.size() != s.size()) sliding.clear();
  {
    if (!sliding.empty()) {
      const dem::WindowMean f = dem::window_mean(s, sliding, dem::kSteadyStateFrom * end, end);
      md << "- sliding contacts (at the Coulomb limit), steady state: "
         << (f.ok ? fmt(f.mean, 3) + " +- " + fmt(f.standard_error, 2) : std::string("-"))
         << " of the contacts\n";
    }
  }
  // Whether the steady state is quasi-static: I <= 1e-3 (docs/physics.md section 4).
  if (r.exists(p + datasets::kInertialNumber)) {
    const std::vector<double> inertial = r.read_vector(p + datasets::kInertialNumber);
    if (inertial.size() == s.size()) {
      const dem::WindowMean f = dem::window_mean(s, inertial, dem::kSteadyStateFrom * end, end);
      if (f.samples > 0) md << "- inertial number, steady state: " << fmt(f.mean, 3) << "\n";
    }
  }
  md << "- p at the end / p at the start: "
     << fmt(stress.back().trace() / std::max(stress.front().trace(), 1e-300), 4) << "\n";
  if (r.has_attr(p, "servo_error"))
    md << "- lateral servo: largest error " << fmt(r.attr_double(p, "servo_error"), 3)
       << " of p0 (tolerance " << fmt(r.attr_double(p, "servo_tolerance"), 3) << ")\n";
  md << (sliding.empty() ? "\n| s | q/p |\n|---|---|\n"
                         : "\n| s | q/p | sliding contacts |\n|---|---|---|\n");
  const std::size_t n = s.size();
  for (std::size_t k = 0; k <= 8; ++k) {
    const std::size_t i = std::min(n - 1, k * (n - 1) / 8);
    md << "| " << fmt(s[i], 3) << " | " << fmt(q_over_p[i], 4) << " |";
    if (!sliding.empty()) md << " " << fmt(sliding[i], 3) << " |";
    md << "\n";
  }
  return md.str();
}
}  // namespace

// The envelopes of other probe planes than the Rendulic one, with their stress fits per unit
// strain (semi-axes in k*, inclination from the plane's first axis).
std::string other_planes_section(const ResultsReader& r) {
  std::ostringstream rows;
  for (const StateInfo& s : read_states(r))
    for (const EnvInfo& e : s.other_planes) {
      rows << "| " << s.label << " | " << e.name << " | " << e.data.plane.name << " | " << e.method
           << " | " << fmt(e.amplitude) << " | ";
      if (!e.stress.present || e.stress.shape.empty()) {
        rows << "- | - | - | - |\n";
        continue;
      }
      rows << e.stress.shape << " | " << fmt(e.stress.a / e.amplitude, 4) << " | "
           << fmt(e.stress.b / e.amplitude, 4) << " | " << fmt(e.stress.incl, 4) << " |\n";
    }
  if (rows.str().empty()) return "";
  return "\n## Envelopes in other probe planes (docs/probes.md \"Probe planes\")\n\nNot used "
         "by the claims, which read Rendulic pairs. Pairs are the coordinates in the plane; the "
         "stress fit's semi-axes per unit strain in k*, inclination from the plane's first "
         "axis.\n\n| state | envelope | plane | method | amplitude | shape | a/A [k*] | b/A [k*] "
         "| inclination [deg] |\n|---|---|---|---|---|---|---|---|---|\n" +
         rows.str();
}

std::string report_markdown(const ResultsReader& r, const std::vector<Claim>& claims,
                            const std::vector<std::string>& figures, bool plotted) {
  std::ostringstream md;
  md << "# rendulic run report\n\n";
  md << "- results: `" << r.path().filename().string() << "` (schema "
     << r.attr_string("/", "schema") << ", rendulic " << r.attr_string("/", "version") << ", git "
     << r.attr_string("/", "git_sha") << ")\n";
  if (r.has_attr("/", "scenario_file"))
    md << "- scenario: `" << r.attr_string("/", "scenario_file") << "`, seed "
       << r.attr_int("/", "seed") << "\n";
  if (r.has_attr(paths::kMaterial, "n_particles"))
    md << "- particles: " << r.attr_int(paths::kMaterial, "n_particles") << "\n";
  if (r.exists(paths::kTimings)) {
    md << "\n## Wall time per stage\n\n| stage | seconds |\n|---|---|\n";
    for (const char* st : {"prepare", "isotropic", "path", "states", "elastic_range", "probes",
                           "linear_response", "pressure", "fits", "calibration"})
      if (r.has_attr(paths::kTimings, st))
        md << "| " << st << " | " << fmt(r.attr_double(paths::kTimings, st), 4) << " |\n";
  }
  md << path_section(r);
  md << "\n## The seed's claims (docs/claims.md)\n\n"
     << "| claim | statement | measured | verdict |\n|---|---|---|---|\n";
  for (const auto& c : claims)
    md << "| " << c.id << " | " << c.claim << " | " << (c.measured.empty() ? "-" : c.measured)
       << " | **" << c.verdict << "** |\n";
  md << "\nVerdicts use the dynamic-probe envelopes where present (the seed's method), else "
        "minimisation, else linear response (elastic only).\n";
  md << other_planes_section(r);
  // The elastic range of every state, at nu_max and at the pressure branches.
  std::ostringstream range;
  for (const auto& root : state_roots(r)) {
    if (!r.exists(paths::states(root))) continue;
    for (const auto& label : r.children(paths::states(root))) {
      const std::string g = paths::state(label, root), e = paths::elastic_range(g);
      if (!r.exists(e) || !r.has_attr(e, "yield_strain")) continue;
      const bool yielded = r.has_attr(e, "yielded") && r.attr_int(e, "yielded") != 0;
      auto attr_or_nan = [&](const std::string& object, const char* name) {
        return r.has_attr(object, name) ? r.attr_double(object, name) : kNaN;
      };
      range << "| " << fmt(attr_or_nan(g, "volume_fraction"), 3) << " | "
            << fmt(attr_or_nan(g, "pressure_star"), 3) << " | " << label << " | "
            << fmt(-attr_or_nan(g, "eps_dev"), 3) << " | " << (yielded ? "" : ">= ")
            << fmt(r.attr_double(e, "yield_strain")) << " | "
            << (r.has_attr(e, "elastic_to") ? fmt(r.attr_double(e, "elastic_to")) : "-") << " |\n";
    }
  }
  if (!range.str().empty())
    md << "\n## Elastic range (docs/probes.md)\n\nThe yield strain is the first amplitude of the "
          "ladder whose response departs from the elastic one by the tolerance; the yield lies "
          "between the rung below (elastic to) and it.\n\n| nu | P* | state | -eps_dev | yield "
          "strain | elastic to |\n|---|---|---|---|---|---|\n"
       << range.str();
  if (r.exists(paths::kCalibration)) {
    md << "\n## Calibration (docs/calibration.md)\n\n"
       << "| model | converged | objective | fitted misfit | held-out misfit | parameters "
          "(+- standard error) |\n|---|---|---|---|---|---|\n";
    for (const std::string& m : r.children(paths::kCalibration)) {
      const std::string g = paths::calibration(m);
      md << "| " << m << " | ";
      if (r.has_attr(g, "error")) {
        md << "no | - | - | - | failed: " << r.attr_string(g, "error") << " |\n";
        continue;
      }
      md << (r.attr_int(g, "converged") ? "yes" : "no") << " | "
         << fmt(r.attr_double(g, "objective")) << " | " << fmt(r.attr_double(g, "fitted_misfit"))
         << " | "
         << (r.has_attr(g, "held_out_misfit") ? fmt(r.attr_double(g, "held_out_misfit")) : "-")
         << " | ";
      const calibration::StoredParameters p = calibration::read_parameters(r, g);
      for (std::size_t i = 0; i < p.names.size(); ++i)
        md << (i ? ", " : "") << p.names[i] << " = " << fmt(p.values[i])
           << (i < p.stderr_.size() && p.stderr_[i] > 0 ? " +- " + fmt(p.stderr_[i]) : "");
      md << " |\n";
    }
    md << "\nA standard error of inf marks a parameter the data do not determine; fixed "
          "parameters show none. Warnings per model are in the results file "
          "(/calibration/<model> attribute `warnings`).\n";
    md << model_selection_markdown(r);
  }
  if (!figures.empty()) {
    md << "\n## Figures\n\n";
    for (const auto& f : figures)
      if (f.ends_with(".png"))
        md << "![" << std::filesystem::path(f).stem().string() << "](figures/"
           << std::filesystem::path(f).filename().string() << ")\n\n";
  } else if (plotted) {
    md << "\n(No figures: this file holds none of their data; `rendulic plot` says what each "
          "one lacks.)\n";
  } else {
    md << "\n(No figures: run `rendulic plot` with python3-matplotlib and python3-h5py.)\n";
  }
  return md.str();
}

namespace {
std::filesystem::path report_file(const std::filesystem::path& dir) { return dir / "report.md"; }
std::filesystem::path figures_folder(const std::filesystem::path& dir) { return dir / "figures"; }
constexpr const char* kReportWhat = "the report";
}  // namespace

void check_report_destination(const std::filesystem::path& dir, bool with_figures) {
  if (with_figures) {  // the environment's settings of the figures, before the DEM
    plot_jobs_from_environment();
    plot_script_file();
  }
  // A file in the output folder's place is named as the results writer names it, not as the
  // place of the report or of the figures folder inside it.
  refuse_file_in_place_of_folder(dir, "output folder");
  AtomicTextFile::refuse_folder(report_file(dir), kReportWhat);
  refuse_read_only(link_target(report_file(dir)), report_file(dir), kReportWhat);
  if (with_figures) refuse_file_in_place_of_folder(figures_folder(dir), "figures folder");
}

std::filesystem::path write_report(const std::filesystem::path& results_file, bool with_figures) {
  namespace fs = std::filesystem;
  const ResultsReader r(results_file);
  const auto claims = evaluate_claims(r);
  std::vector<std::string> figures;
  const fs::path dir = results_file.parent_path();
  if (with_figures) {
    plot_results(results_file, figures_folder(dir));
    std::error_code ec;  // no folder: nothing was drawn (plot_results removes it again)
    for (fs::directory_iterator it(figures_folder(dir), ec), end; !ec && it != end;
         it.increment(ec))
      figures.push_back(it->path().string());
    std::sort(figures.begin(), figures.end());
  }
  // Made before the temporary file is: a damaged results file fails here and leaves nothing.
  const std::string text = report_markdown(r, claims, figures, with_figures);
  AtomicTextFile out(report_file(dir), kReportWhat);
  out.stream() << text;
  out.commit();
  return out.path();
}

}  // namespace rendulic::app
