// Report of a run: the seed's claims C1-C8 checked on the run's own numbers (see report.hpp).
// Thresholds are stated in each claim's text so a reader can judge the verdicts; they are
// deliberately loose where the seed's own data fluctuate (plastic envelopes, Fig. 7).
#include "report.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>

#include "commands.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/version.hpp"

namespace rendulic::app {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// physics.md section 5: elastic probes below 1e-4, elasto-plastic above 1e-3.
constexpr double kElasticMax = 1e-4, kPlasticMin = 1e-3;

struct FitInfo {
  bool present = false;
  std::string shape;
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double a = kNaN, b = kNaN, incl = kNaN;
};

struct EnvInfo {
  std::string name, method;
  double amplitude = kNaN;
  FitInfo stress, fabric;
  std::vector<double> theta;
  std::vector<Eigen::Vector2d> stress_pairs, fabric_pairs;
};

struct StateInfo {
  std::string label;
  double eps_dev = kNaN;
  std::vector<EnvInfo> envs;
};

FitInfo read_fit(const ResultsReader& r, const std::string& g) {
  FitInfo f;
  if (!r.exists(g)) return f;
  f.present = true;
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
  return f;
}

std::vector<StateInfo> read_states(const ResultsReader& r) {
  std::vector<StateInfo> out;
  for (const auto& label : r.children("/states")) {
    const std::string g = "/states/" + label;
    StateInfo s;
    s.label = label;
    if (r.has_attr(g, "eps_dev")) s.eps_dev = r.attr_double(g, "eps_dev");
    for (const auto& name : r.children(g + "/envelopes")) {
      const std::string e = g + "/envelopes/" + name;
      EnvInfo env;
      env.name = name;
      if (r.has_attr(e, "method")) env.method = r.attr_string(e, "method");
      if (r.has_attr(e, "amplitude")) env.amplitude = r.attr_double(e, "amplitude");
      if (r.exists(e + "/theta_deg")) env.theta = r.read_vector(e + "/theta_deg");
      if (r.exists(e + "/stress_star")) env.stress_pairs = r.read_pairs(e + "/stress_star");
      if (r.exists(e + "/fabric")) env.fabric_pairs = r.read_pairs(e + "/fabric");
      env.stress = read_fit(r, e + "/fit_stress");
      env.fabric = read_fit(r, e + "/fit_fabric");
      s.envs.push_back(std::move(env));
    }
    out.push_back(std::move(s));
  }
  // Along the path: -eps_dev increasing (the path is an extension, eps_dev < 0).
  std::sort(out.begin(), out.end(),
            [](const StateInfo& a, const StateInfo& b) { return -a.eps_dev < -b.eps_dev; });
  return out;
}

// The envelope of a state used for the claims: dynamic probes first (what the seed did),
// then minimisation, then linear response (elastic only).
const EnvInfo* pick(const StateInfo& s, bool elastic) {
  for (const char* method : {"dynamic", "minimisation", "linear_response"}) {
    for (const auto& e : s.envs) {
      const bool kind = elastic ? e.amplitude < kElasticMax : e.amplitude > kPlasticMin;
      // A linear response at a plastic amplitude is the elastic one scaled: never plastic data.
      const bool usable = elastic || std::string(method) != "linear_response";
      if (kind && usable && e.method == method && e.stress.present) return &e;
    }
  }
  return nullptr;
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

// Ratio of the deviatoric to the isotropic extent of a set of Rendulic response pairs.
double dev_to_iso_extent(const std::vector<Eigen::Vector2d>& pairs) {
  double iso = 0, dev = 0;
  for (const auto& p : pairs) {
    const Eigen::Vector2d q = iso_dev_from_rendulic(p);
    iso = std::max(iso, std::abs(q.x()));
    dev = std::max(dev, std::abs(q.y()));
  }
  return iso > 0 ? dev / iso : kNaN;
}

double angle_between_axes_deg(double a_deg, double b_deg) {
  double d = std::fmod(std::abs(a_deg - b_deg), 180.0);
  return std::min(d, 180.0 - d);
}

}  // namespace

std::vector<Claim> evaluate_claims(const ResultsReader& r) {
  std::vector<Claim> claims;
  const auto states = read_states(r);
  std::vector<const EnvInfo*> el, pl;
  std::vector<double> x;  // -eps_dev of each state
  for (const auto& s : states) {
    el.push_back(pick(s, true));
    pl.push_back(pick(s, false));
    x.push_back(-s.eps_dev);
  }
  auto all = [](const std::vector<const EnvInfo*>& v) {
    return !v.empty() && std::all_of(v.begin(), v.end(), [](auto* e) { return e != nullptr; });
  };

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
  {  // C2
    Claim c{"C2",
            "Elastic fabric envelope: a line, no deviatoric fabric change (dev/iso extent < 0.1)",
            "", ""};
    std::vector<double> ratio;
    if (all(el))
      for (auto* e : el) ratio.push_back(dev_to_iso_extent(e->fabric_pairs));
    const bool ok = !ratio.empty() && *std::max_element(ratio.begin(), ratio.end()) < 0.1;
    c.measured = ratio.empty() ? "" : "dev/iso extent of dF per state: " + series(ratio);
    c.verdict = verdict(!ratio.empty(), ok);
    claims.push_back(c);
  }
  {  // C3
    Claim c{"C3",
            "Near isotropy the isotropic probe (35.26 deg) maps onto the major axis (< 5 deg)", "",
            ""};
    bool measured = false, ok = false;
    // One stress pair per direction, or the envelope is damaged and C3 cannot be measured.
    if (!el.empty() && el[0] && !el[0]->theta.empty() &&
        el[0]->stress_pairs.size() == el[0]->theta.size() && std::isfinite(el[0]->stress.incl)) {
      const auto& e = *el[0];
      std::size_t best = 0;
      for (std::size_t i = 0; i < e.theta.size(); ++i)
        if (angle_between_axes_deg(e.theta[i], kIsoCompressionDeg) <
            angle_between_axes_deg(e.theta[best], kIsoCompressionDeg))
          best = i;
      if (angle_between_axes_deg(e.theta[best], kIsoCompressionDeg) < 0.01) {
        const Eigen::Vector2d v = e.stress_pairs[best] - e.stress.center;
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
            "Plastic stress envelope shifted from the origin (|centre|/a above the elastic one) "
            "and collapsing to a line at steady state (b/a < 0.1 at the last state)",
            "", ""};
    std::vector<double> shift, thin;
    if (all(pl))
      for (auto* e : pl)
        shift.push_back(e->stress.center.norm() / e->stress.a),
            thin.push_back(e->stress.b / e->stress.a);
    bool ok = false;
    if (!shift.empty() && all(el)) {
      ok = thin.back() < 0.1;
      for (std::size_t i = 0; i < pl.size(); ++i)
        ok = ok && shift[i] > el[i]->stress.center.norm() / el[i]->stress.a;
    }
    c.measured = shift.empty() ? "" : "|centre|/a: " + series(shift) + "; b/a: " + series(thin);
    // Why it fails when it does: axes per unit strain, plastic over elastic. Near 1 means the
    // larger probes still responded elastically (no rearrangement softened them).
    if (!shift.empty() && all(el)) {
      std::vector<double> a_ratio, b_ratio;
      for (std::size_t i = 0; i < pl.size(); ++i) {
        const double s = el[i]->amplitude / pl[i]->amplitude;
        a_ratio.push_back(pl[i]->stress.a * s / el[i]->stress.a);
        b_ratio.push_back(pl[i]->stress.b * s / el[i]->stress.b);
      }
      c.measured += "; stiffness plastic/elastic, major axis: " + series(a_ratio) +
                    ", minor axis: " + series(b_ratio);
    }
    c.verdict = verdict(!shift.empty() && all(el), ok);
    claims.push_back(c);
  }
  {  // C7
    Claim c{"C7",
            "Plastic fabric envelope: finite deviatoric change (dev/iso extent above the elastic "
            "one), inclination near 35 deg (within 10) at steady state",
            "", ""};
    std::vector<double> ratio, inc;
    if (all(pl))
      for (auto* e : pl)
        ratio.push_back(dev_to_iso_extent(e->fabric_pairs)), inc.push_back(e->fabric.incl);
    bool ok = false;
    if (!ratio.empty() && all(el)) {
      ok = std::abs(inc.back() - kIsoCompressionDeg) < 10.0;
      for (std::size_t i = 0; i < pl.size(); ++i)
        ok = ok && ratio[i] > dev_to_iso_extent(el[i]->fabric_pairs);
    }
    c.measured =
        ratio.empty() ? "" : "dev/iso extent: " + series(ratio) + "; inclination: " + series(inc);
    c.verdict = verdict(!ratio.empty() && all(el), ok);
    claims.push_back(c);
  }
  {  // C8
    Claim c{"C8",
            "Fig. 1 trends: sigma_xx first decreases then slightly increases; sigma_yy, sigma_zz "
            "rise towards an asymptote; F_xx decreases, F_yy and F_zz increase",
            "", ""};
    bool measured = false, ok = false;
    if (r.exists("/path/stress_star") && r.exists("/path/fabric")) {
      const auto s = r.read_tensors("/path/stress_star");
      const auto f = r.read_tensors("/path/fabric");
      if (s.size() >= 10 && f.size() == s.size()) {
        measured = true;
        const std::size_t n = s.size(), q = n / 5;
        std::size_t imin = 0;
        for (std::size_t i = 0; i < n; ++i)
          if (s[i](0, 0) < s[imin](0, 0)) imin = i;
        const bool xx_dip = imin > 0 && imin < n - 1 && s.back()(0, 0) > s[imin](0, 0);
        const double lat0 = 0.5 * (s[0](1, 1) + s[0](2, 2));
        const double latq = 0.5 * (s[q](1, 1) + s[q](2, 2));
        const double latn = 0.5 * (s[n - 1](1, 1) + s[n - 1](2, 2));
        const double latm = 0.5 * (s[n - 1 - q](1, 1) + s[n - 1 - q](2, 2));
        const bool lat_rise = latn > lat0;
        const bool asymptote = std::abs(latn - latm) < std::abs(latq - lat0);
        const bool fxx = f.back()(0, 0) < f[0](0, 0);
        const bool flat = f.back()(1, 1) > f[0](1, 1) && f.back()(2, 2) > f[0](2, 2);
        ok = xx_dip && lat_rise && asymptote && fxx && flat;
        c.measured = "sigma*_xx: " + fmt(s[0](0, 0)) + " -> min " + fmt(s[imin](0, 0)) + " -> " +
                     fmt(s.back()(0, 0)) + "; sigma*_lat: " + fmt(lat0) + " -> " + fmt(latn) +
                     " (first/last fifth rise " + fmt(latq - lat0) + " / " + fmt(latn - latm) +
                     "); F_xx " + fmt(f[0](0, 0)) + " -> " + fmt(f.back()(0, 0)) + ", F_yy " +
                     fmt(f[0](1, 1)) + " -> " + fmt(f.back()(1, 1));
      }
    }
    c.verdict = verdict(measured, ok);
    claims.push_back(c);
  }
  return claims;
}

std::string report_markdown(const ResultsReader& r, const std::vector<Claim>& claims,
                            const std::vector<std::string>& figures) {
  std::ostringstream md;
  md << "# rendulic run report\n\n";
  md << "- results: `" << r.path().filename().string() << "` (schema "
     << r.attr_string("/", "schema") << ", rendulic " << r.attr_string("/", "version") << ", git "
     << r.attr_string("/", "git_sha") << ")\n";
  if (r.has_attr("/", "scenario_file"))
    md << "- scenario: `" << r.attr_string("/", "scenario_file") << "`, seed "
       << r.attr_int("/", "seed") << "\n";
  if (r.has_attr("/material", "n_particles"))
    md << "- particles: " << r.attr_int("/material", "n_particles") << "\n";
  if (r.exists("/timings")) {
    md << "\n## Wall time per stage\n\n| stage | seconds |\n|---|---|\n";
    for (const char* st : {"prepare", "isotropic", "path", "states", "probes", "linear_response",
                           "fits", "calibration"})
      if (r.has_attr("/timings", st))
        md << "| " << st << " | " << fmt(r.attr_double("/timings", st), 4) << " |\n";
  }
  md << "\n## The seed's claims (physics.md section 5)\n\n"
     << "| claim | statement | measured | verdict |\n|---|---|---|---|\n";
  for (const auto& c : claims)
    md << "| " << c.id << " | " << c.claim << " | " << (c.measured.empty() ? "-" : c.measured)
       << " | **" << c.verdict << "** |\n";
  md << "\nVerdicts use the dynamic-probe envelopes where present (the seed's method), else "
        "minimisation, else linear response (elastic only).\n";
  if (r.exists("/calibration")) {
    md << "\n## Calibration (models.md)\n\n"
       << "| model | converged | objective | fitted misfit | held-out misfit | parameters "
          "(+- standard error) |\n|---|---|---|---|---|---|\n";
    for (const std::string& m : r.children("/calibration")) {
      const std::string g = "/calibration/" + m;
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
      const std::vector<double> p = r.read_vector(g + "/params");
      const std::vector<double> se = r.read_vector(g + "/stderr");
      std::stringstream names(r.attr_string(g, "param_names"));
      std::string name;
      for (std::size_t i = 0; i < p.size() && std::getline(names, name, ','); ++i)
        md << (i ? ", " : "") << name << " = " << fmt(p[i])
           << (i < se.size() && se[i] > 0 ? " +- " + fmt(se[i]) : "");
      md << " |\n";
    }
    md << "\nA standard error of inf marks a parameter the data do not determine; fixed "
          "parameters show none. Warnings per model are in the results file "
          "(/calibration/<model> attribute `warnings`).\n";
  }
  if (!figures.empty()) {
    md << "\n## Figures\n\n";
    for (const auto& f : figures)
      if (f.ends_with(".png"))
        md << "![" << std::filesystem::path(f).stem().string() << "](figures/"
           << std::filesystem::path(f).filename().string() << ")\n\n";
  } else {
    md << "\n(No figures: run `rendulic plot` with python3-matplotlib and python3-h5py.)\n";
  }
  return md.str();
}

std::filesystem::path write_report(const std::filesystem::path& results_file, bool with_figures) {
  namespace fs = std::filesystem;
  const ResultsReader r(results_file);
  const auto claims = evaluate_claims(r);
  std::vector<std::string> figures;
  const fs::path dir = results_file.parent_path();
  if (with_figures) {
    plot_results(results_file, dir / "figures");
    for (const auto& e : fs::directory_iterator(dir / "figures"))
      figures.push_back(e.path().string());
    std::sort(figures.begin(), figures.end());
  }
  const fs::path out = dir / "report.md", tmp = dir / ".report.md.tmp";
  // Made before the temporary file is: a damaged results file fails here and leaves nothing.
  const std::string text = report_markdown(r, claims, figures);
  {
    std::ofstream f(tmp);
    f << text;
    if (!f) {
      std::error_code ec;
      fs::remove(tmp, ec);
      throw InputError(tmp.string() + ": cannot write report");
    }
  }
  fs::rename(tmp, out);
  return out;
}

}  // namespace rendulic::app
