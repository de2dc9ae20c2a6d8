// The common yardstick, the likelihood and the selection rule (selection.hpp;
// docs/calibration.md "One yardstick" and "Likelihood and model selection").
#include "rendulic/calibration/selection.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>

#include "rendulic/calibration/data.hpp"

namespace rendulic::calibration {

std::string yardstick_kind(const ResidualBlock& b) {
  if (b.kind == "path_stress" || b.kind == "path_fabric") return b.kind;
  const bool elastic = is_elastic_amplitude(b.amplitude);
  if (b.kind == "stress") return elastic ? "stress_elastic" : "stress_plastic";
  if (b.kind == "fabric") return elastic ? "fabric_elastic" : "fabric_plastic";
  return b.kind;
}

const std::vector<std::string>& yardstick_kinds() {
  static const std::vector<std::string> k = {"stress_elastic", "stress_plastic", "fabric_elastic",
                                             "fabric_plastic", "path_stress",    "path_fabric"};
  return k;
}

bool is_stress_kind(const std::string& kind) {
  return kind == "stress_elastic" || kind == "stress_plastic" || kind == "path_stress";
}

ObjectiveOptions yardstick_options(const models::StepOptions& step, bool path) {
  ObjectiveOptions o;
  o.envelope_points = true;
  o.envelope_features = false;
  o.path = path;
  o.elastic_envelopes = true;
  o.plastic_envelopes = true;
  o.linear_response_elastic_only = true;
  o.prediction = Prediction::kAuto;
  o.step = step;
  // The fit fails a probe that needs more than the objective's substep budget fast (an
  // infinite cost steers the optimiser away); the yardstick measures the law where the fit
  // ended, so it takes the driver's own budget: a law merely stiff there is scored, not lost.
  o.step.max_substeps = std::max(step.max_substeps, models::StepOptions{}.max_substeps);
  return o;
}

double block_deviance(const BlockScore& b) {
  const double sigma = std::max(b.misfit, b.noise);
  if (!(sigma > 0.0) || !std::isfinite(b.misfit)) return std::numeric_limits<double>::infinity();
  return b.components * (std::log(M_PI * sigma * sigma) + b.misfit * b.misfit / (sigma * sigma));
}

SetScore score_set(const ModelScore& m, BlockSet set) {
  SetScore s;
  double fit2 = 0.0, ho2 = 0.0, ho_log = 0.0;
  int nfit = 0, nho = 0, ho_components = 0;
  std::map<std::string, std::pair<double, int>> fk, hk;
  double dev = 0.0;
  for (const auto& b : m.blocks) {
    if (set == BlockSet::kStress && !is_stress_kind(b.kind)) continue;
    s.ids.push_back(b.id);
    const double m2 = b.misfit * b.misfit;
    if (b.held_out) {
      ho2 += m2;
      ++nho;
      ho_log += b.components * std::log(std::max(b.misfit, b.noise));
      ho_components += b.components;
      hk[b.kind].first += m2;
      ++hk[b.kind].second;
    } else {
      fit2 += m2;
      ++nfit;
      fk[b.kind].first += m2;
      ++fk[b.kind].second;
      s.n += b.components;
      dev += block_deviance(b);
    }
  }
  if (nfit > 0) {
    s.deviance = dev;
    s.bic = dev + m.n_free * std::log(static_cast<double>(s.n));
    s.fitted_misfit = std::sqrt(fit2 / nfit);
  }
  if (nho > 0) s.held_out_misfit = std::sqrt(ho2 / nho);
  if (ho_components > 0) s.held_out_score = std::exp(ho_log / ho_components);
  for (const auto& [k, v] : fk) s.fitted_by_kind[k] = std::sqrt(v.first / v.second);
  for (const auto& [k, v] : hk) s.held_out_by_kind[k] = std::sqrt(v.first / v.second);
  return s;
}

bool SelectionRule::IsValid(std::string* why) const {
  if (!(bic_tolerance >= 0.0) || !(held_out_tolerance >= 0.0)) {
    if (why) *why = "selection tolerances must be >= 0";
    return false;
  }
  return true;
}

namespace {

std::string fmt(double x, int prec = 3) {
  std::ostringstream o;
  o.precision(prec);
  o << x;
  return o.str();
}

std::string join(const std::vector<std::string>& v, const std::string& last = " and ") {
  std::string s;
  for (std::size_t i = 0; i < v.size(); ++i)
    s += (i == 0 ? "" : (i + 1 == v.size() ? last : ", ")) + v[i];
  return s;
}

std::string signature(const ModelScore& m) {
  std::string s;
  for (const auto& l : m.fitted_states) s += l + ",";
  s += "|";
  for (const auto& l : m.held_out_states) s += l + ",";
  return s;
}

// The kinds where `a` misfits clearly more than `b` (by 20 % or more), worst first.
std::vector<std::string> worse_kinds(const SetScore& a, const SetScore& b) {
  std::vector<std::pair<double, std::string>> r;
  for (const auto& [k, ma] : a.fitted_by_kind) {
    const auto it = b.fitted_by_kind.find(k);
    if (it == b.fitted_by_kind.end() || !(it->second > 0.0)) continue;
    if (ma > 1.2 * it->second) r.push_back({ma / it->second, k});
  }
  std::sort(r.rbegin(), r.rend());
  std::vector<std::string> out;
  for (std::size_t i = 0; i < r.size() && i < 2; ++i)
    out.push_back(r[i].second + " " + fmt(a.fitted_by_kind.at(r[i].second)) + " against " +
                  fmt(b.fitted_by_kind.at(r[i].second)));
  return out;
}

// The rule on one block set; returns the index into rows, or -1.
int pick(const std::vector<SelectionRow>& rows, const std::vector<bool>& candidate, bool stress,
         const SelectionRule& rule) {
  auto score = [&](int i) -> const SetScore& { return stress ? rows[i].stress : rows[i].all; };
  double best_ho = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < rows.size(); ++i)
    if (candidate[i] && std::isfinite(score(i).held_out_score))
      best_ho = std::min(best_ho, score(i).held_out_score);
  std::vector<int> c;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!candidate[i] || !std::isfinite(score(i).bic)) continue;
    if (std::isfinite(best_ho) &&
        !(score(i).held_out_score <= (1.0 + rule.held_out_tolerance) * best_ho))
      continue;
    c.push_back(static_cast<int>(i));
  }
  if (c.empty()) return -1;
  double best_bic = std::numeric_limits<double>::infinity();
  for (int i : c) best_bic = std::min(best_bic, score(i).bic);
  int sel = -1;
  for (int i : c) {
    if (score(i).bic > best_bic + rule.bic_tolerance) continue;
    if (sel < 0 || rows[i].n_free < rows[sel].n_free ||
        (rows[i].n_free == rows[sel].n_free && score(i).bic < score(sel).bic))
      sel = i;
  }
  return sel;
}

// One sentence per other law: what it adds over the selected one, or what it lacks. Only the
// laws with `describe` set are described (all candidates when empty).
std::string explain(const std::vector<SelectionRow>& rows, const std::vector<bool>& candidate,
                    int sel, bool stress, const SelectionRule& rule,
                    const std::vector<bool>& describe = {}) {
  auto score = [&](int i) -> const SetScore& { return stress ? rows[i].stress : rows[i].all; };
  const SetScore& s = score(sel);
  // The other laws by rising BIC (then name): the sentence reads the same whatever order the
  // laws were fitted in (a run's, or `rendulic calibrate --model` in the user's order).
  std::vector<std::size_t> order(rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) order[i] = i;
  auto bic = [&](std::size_t i) {  // an unscored law last, keeping the order strict
    const double b = score(static_cast<int>(i)).bic;
    return std::isfinite(b) ? b : std::numeric_limits<double>::infinity();
  };
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return bic(a) != bic(b) ? bic(a) < bic(b) : rows[a].model < rows[b].model;
  });
  std::vector<std::string> parts;
  for (const std::size_t i : order) {
    if (static_cast<int>(i) == sel || !candidate[i]) continue;
    if (!describe.empty() && !describe[i]) continue;
    const SetScore& m = score(static_cast<int>(i));
    const double d = m.bic - s.bic;
    const std::string& name = rows[i].model;
    const bool ho_worse = std::isfinite(m.held_out_score) && std::isfinite(s.held_out_score) &&
                          m.held_out_score > (1.0 + rule.held_out_tolerance) * s.held_out_score;
    std::ostringstream o;
    if (rows[i].n_free > rows[sel].n_free) {
      if (d >= 0.0) {
        o << name << " (" << rows[i].n_free << " free parameters) adds nothing: BIC +" << fmt(d);
      } else if (-d <= rule.bic_tolerance) {
        o << name << " (" << rows[i].n_free << " free parameters) lowers BIC by only " << fmt(-d)
          << ", less than " << fmt(rule.bic_tolerance);
      } else {
        o << name << " lowers BIC by " << fmt(-d)
          << " but predicts the held-out states worse (held-out score " << fmt(m.held_out_score)
          << " against " << fmt(s.held_out_score) << ")";
      }
      if (ho_worse && d >= -rule.bic_tolerance)
        o << " and predicts the held-out states worse (" << fmt(m.held_out_misfit) << " against "
          << fmt(s.held_out_misfit) << ")";
    } else {
      o << name << " (" << rows[i].n_free << " free parameters) is worse by BIC "
        << (d >= 0 ? "+" : "") << fmt(d);
      const auto w = worse_kinds(m, s);
      if (!w.empty()) o << ": misfit " << join(w);
      if (ho_worse)
        o << "; held-out score " << fmt(m.held_out_score) << " against " << fmt(s.held_out_score);
    }
    parts.push_back(o.str());
  }
  // Pairs of other laws where the richer adds nothing over the simpler (e.g. the anisotropy
  // term of the elastic laws when an elasto-plastic law is selected).
  if (describe.empty())
    for (const std::size_t a : order)
      for (const std::size_t b : order) {
        if (a == b || !candidate[a] || !candidate[b] || static_cast<int>(a) == sel ||
            static_cast<int>(b) == sel || rows[b].n_free <= rows[a].n_free)
          continue;
        const double d = score(static_cast<int>(b)).bic - score(static_cast<int>(a)).bic;
        if (d >= -rule.bic_tolerance && score(static_cast<int>(b)).fitted_misfit >=
                                            0.98 * score(static_cast<int>(a)).fitted_misfit)
          parts.push_back(rows[b].model + " adds nothing over " + rows[a].model + " (BIC " +
                          (d >= 0 ? "+" : "") + fmt(d) + ", misfit " +
                          fmt(score(static_cast<int>(b)).fitted_misfit) + " against " +
                          fmt(score(static_cast<int>(a)).fitted_misfit) + ")");
      }
  std::string out;
  for (const auto& p : parts) out += (out.empty() ? "" : "; ") + p;
  return out;
}

// The kinds the selected law predicts no better than no change at all (misfit >= 1: the
// yardstick's scale is the data's own size), with the best other candidate on each: a
// selection by BIC among laws that all miss a block must not read as "this law fits".
std::string misses(const std::vector<SelectionRow>& rows, const std::vector<bool>& candidate,
                   int sel, bool stress) {
  auto score = [&](std::size_t i) -> const SetScore& {
    return stress ? rows[i].stress : rows[i].all;
  };
  std::vector<std::string> parts;
  for (const auto& [kind, m] : score(static_cast<std::size_t>(sel)).fitted_by_kind) {
    if (!(m >= 1.0)) continue;
    std::ostringstream o;
    o << kind << " " << fmt(m);
    double best = std::numeric_limits<double>::infinity();
    std::string best_law;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      if (static_cast<int>(i) == sel || !candidate[i]) continue;
      const auto it = score(i).fitted_by_kind.find(kind);
      if (it != score(i).fitted_by_kind.end() && it->second < best)
        best = it->second, best_law = rows[i].model;
    }
    if (best < 1.0)
      o << " (" << best_law << ": " << fmt(best) << ")";
    else
      o << " (no other law below 1 either)";
    parts.push_back(o.str());
  }
  if (parts.empty()) return "";
  std::string list;
  for (const auto& p : parts) list += (list.empty() ? "" : "; ") + p;
  return " Read with care: " + rows[static_cast<std::size_t>(sel)].model +
         " predicts these blocks no better than no change at all (misfit 1): " + list + ".";
}

}  // namespace

Selection select_model(const std::vector<ModelScore>& models, const SelectionRule& rule) {
  Selection out;
  std::ostringstream r;
  r << "among the laws that predict every block, those whose held-out score is within "
    << fmt(100 * rule.held_out_tolerance) << " % of the best; among those, the ones whose BIC "
    << "is within " << fmt(rule.bic_tolerance) << " of the lowest; of these, the one with the "
    << "fewest free parameters";
  out.rule = r.str();
  if (models.empty()) return out;
  // The states the most laws were fitted on: only those laws compare.
  std::map<std::string, int> count;
  for (const auto& m : models) ++count[signature(m)];
  std::string common;
  int most = 0;
  for (const auto& m : models)
    if (count[signature(m)] > most) most = count[signature(m)], common = signature(m);
  std::set<std::string> all_ids, stress_ids;
  for (const auto& m : models) {
    if (signature(m) != common) continue;
    for (const auto& b : m.blocks) {
      all_ids.insert(b.id);
      if (is_stress_kind(b.kind)) stress_ids.insert(b.id);
    }
  }
  std::vector<bool> cand_all, cand_stress;
  for (const auto& m : models) {
    SelectionRow row;
    row.model = m.model;
    row.n_free = m.n_free;
    row.all = score_set(m, BlockSet::kAll);
    row.stress = score_set(m, BlockSet::kStress);
    const std::set<std::string> ids(row.all.ids.begin(), row.all.ids.end());
    row.covers_all = std::includes(ids.begin(), ids.end(), all_ids.begin(), all_ids.end());
    const bool covers_stress =
        std::includes(ids.begin(), ids.end(), stress_ids.begin(), stress_ids.end());
    const bool same = signature(m) == common;
    if (!same) {
      row.note = "fitted or held out on other states than the others: not compared";
    } else if (!covers_stress) {
      row.note = "does not predict every stress block";
    } else if (!row.covers_all) {
      row.note = "predicts no fabric: compared on the stress blocks only";
    }
    cand_all.push_back(same && row.covers_all);
    cand_stress.push_back(same && covers_stress);
    out.rows.push_back(row);
  }
  const int sel = pick(out.rows, cand_all, false, rule);
  const int sel_s = pick(out.rows, cand_stress, true, rule);
  if (sel >= 0) out.selected = out.rows[sel].model;
  if (sel_s >= 0) out.selected_stress = out.rows[sel_s].model;
  std::ostringstream s;
  if (sel >= 0) {
    s << "This scene needs " << out.selected << " (" << out.rows[sel].n_free
      << " free parameters; BIC " << fmt(out.rows[sel].all.bic, 6) << ", fitted misfit "
      << fmt(out.rows[sel].all.fitted_misfit);
    if (std::isfinite(out.rows[sel].all.held_out_score))
      s << ", held-out score " << fmt(out.rows[sel].all.held_out_score);
    s << ").";
    const std::string e = explain(out.rows, cand_all, sel, false, rule);
    if (!e.empty()) s << " Against it: " << e << ".";
    s << misses(out.rows, cand_all, sel, false);
  } else {
    s << "No law predicts every block of this scene's data.";
  }
  if (sel_s >= 0 && out.selected_stress != out.selected) {
    s << " On the stress blocks alone (where the laws without fabric compete too) it needs "
      << out.selected_stress << " (BIC " << fmt(out.rows[sel_s].stress.bic, 6) << ")";
    const std::string e = explain(out.rows, cand_stress, sel_s, true, rule);
    if (!e.empty()) s << ": " << e;
    s << "." << misses(out.rows, cand_stress, sel_s, true);
  } else if (sel_s >= 0) {
    // The laws without fabric, compared with the selected one on the stress blocks.
    std::vector<bool> only_stress(out.rows.size());
    bool others = false;
    for (std::size_t i = 0; i < out.rows.size(); ++i) {
      only_stress[i] = cand_stress[i] && !cand_all[i];
      others = others || only_stress[i];
    }
    if (others) {
      s << " On the stress blocks alone, where the laws without fabric compete too, the choice "
           "is the same";
      const std::string e = explain(out.rows, cand_stress, sel_s, true, rule, only_stress);
      if (!e.empty()) s << ": " << e;
      s << ".";
    }
  }
  out.sentence = s.str();
  return out;
}

}  // namespace rendulic::calibration
