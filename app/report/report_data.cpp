// Data preparation of the HTML report: the stabilisation points of `ema fit --stabilisation`, and
// the diagnosis as the page shows it (first screen, look-alikes folded, evidence per test mode).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <regex>
#include <set>

#include "report.hpp"

namespace ema::report {

namespace {

using json = nlohmann::json;

double Number(const json& j, const char* key, double fallback = kNaN) {
  if (!j.is_object()) return fallback;
  auto it = j.find(key);
  if (it == j.end() || !it->is_number()) return fallback;
  return it->get<double>();
}

std::complex<double> ComplexOf(const json& j) {
  if (j.is_array() && j.size() == 2 && j[0].is_number() && j[1].is_number())
    return {j[0].get<double>(), j[1].get<double>()};
  if (j.is_number()) return {j.get<double>(), 0.0};
  return {kNaN, kNaN};
}

std::string Text(const json& j, const char* key) {
  if (!j.is_object()) return "";
  auto it = j.find(key);
  return it != j.end() && it->is_string() ? it->get<std::string>() : "";
}

json NumberOrNull(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

// printf "%.*g": the significant digits a reader needs.
std::string Sig(double v, int digits) {
  char b[48];
  std::snprintf(b, sizeof b, "%.*g", digits, v);
  return b;
}

// 3.28e+04 → "3.28 × 10⁴": a large reduced χ² read as a number, not as C's exponent notation.
std::string Readable(double v) {
  if (!std::isfinite(v)) return "–";
  if (v == 0.0 || (std::abs(v) < 1e4 && std::abs(v) >= 1e-3)) return Sig(v, 3);
  static const char* const kSuperscript[] = {"⁰", "¹", "²", "³", "⁴", "⁵", "⁶", "⁷", "⁸", "⁹"};
  const int exponent = static_cast<int>(std::floor(std::log10(std::abs(v))));
  std::string power;
  for (char c : std::to_string(exponent)) power += c == '-' ? "⁻" : kSuperscript[c - '0'];
  return Sig(v / std::pow(10.0, exponent), 3) + " × 10" + power;
}

// '*' matches any run of characters ("points:*" holds "points:111").
bool GlobMatch(const std::string& pattern, const std::string& text) {
  size_t p = 0, t = 0, star = std::string::npos, mark = 0;
  while (t < text.size()) {
    if (p < pattern.size() && pattern[p] == '*') {
      star = p++;
      mark = t;
    } else if (p < pattern.size() && pattern[p] == text[t]) {
      ++p, ++t;
    } else if (star != std::string::npos) {
      p = star + 1;
      t = ++mark;
    } else {
      return false;
    }
  }
  while (p < pattern.size() && pattern[p] == '*') ++p;
  return p == pattern.size();
}

// "series_compliance+added_mass" → "series compliance + added mass".
std::string KindWords(const std::string& kind) {
  std::string out;
  for (char c : kind) {
    if (c == '_') out += ' ';
    else if (c == '+') out += " + ";
    else out += c;
  }
  return out;
}

// What the members of a group of look-alikes are: other points, other members, or other readings.
std::string MemberNoun(const std::string& pattern, int count) {
  const bool points = pattern.find("points:*") != std::string::npos;
  const bool members = pattern.find("/*") != std::string::npos;
  const std::string noun = points && !members ? "point" : members && !points ? "member" : "reading";
  return noun + (count == 1 ? "" : "s");
}

// A parameter key of DIAG.json: "name" (one effect), "kind.name", or "kind.name[target]".
struct ParameterKey {
  std::string kind, name, target;
};
ParameterKey SplitKey(const std::string& key, const std::string& candidate_kind) {
  ParameterKey k;
  std::string rest = key;
  const size_t bracket = rest.find('[');
  if (bracket != std::string::npos && rest.back() == ']') {
    k.target = rest.substr(bracket + 1, rest.size() - bracket - 2);
    rest = rest.substr(0, bracket);
  }
  const size_t dot = rest.rfind('.');
  if (dot == std::string::npos) {
    k.kind = candidate_kind;
    k.name = rest;
  } else {
    k.kind = rest.substr(0, dot);
    k.name = rest.substr(dot + 1);
  }
  return k;
}

// The contact radius of a Hertz law as DIAG.json writes it ("{ hertz = { modulus = .., radius = 0.001 } }").
double HertzRadius(const std::string& law) {
  std::smatch m;
  static const std::regex radius("hertz[^}]*radius\\s*=\\s*([-+0-9.eE]+)");
  return std::regex_search(law, m, radius) ? std::strtod(m[1].str().c_str(), nullptr) : kNaN;
}

struct ParameterView {
  std::string kind, target, text;
};

// Every fitted parameter of a candidate in engineering units with its 1σ, tied to its effect.
std::vector<ParameterView> CandidateParameters(const json& c) {
  std::vector<ParameterView> out;
  const json& parameters = c.contains("parameters") ? c["parameters"] : json();
  if (!parameters.is_object()) return out;
  const json& sigmas = c.contains("uncertainty") && c["uncertainty"].is_object() ? c["uncertainty"] : json::object();
  const json& effects = c.contains("effects") && c["effects"].is_array() ? c["effects"] : json::array();
  const std::string kind = Text(c, "kind");
  for (auto it = parameters.begin(); it != parameters.end(); ++it) {
    if (!it.value().is_number()) continue;
    ParameterKey key = SplitKey(it.key(), kind);
    // The effect the parameter belongs to: the only one, the one of its kind, or of its kind and target.
    const json* effect = nullptr;
    for (const json& e : effects) {
      if (Text(e, "kind") != key.kind && effects.size() > 1) continue;
      if (!key.target.empty() && Text(e, "target") != key.target) continue;
      effect = &e;
      break;
    }
    if (key.target.empty()) key.target = effect ? Text(*effect, "target") : Text(c, "target");
    const double radius = effect ? HertzRadius(Text(*effect, "law")) : kNaN;
    const double sigma = sigmas.contains(it.key()) && sigmas[it.key()].is_number() ? sigmas[it.key()].get<double>() : kNaN;
    out.push_back({key.kind, key.target, ParameterText(key.kind, key.name, it.value().get<double>(), sigma, radius)});
  }
  return out;
}

std::string JoinParameters(const std::vector<ParameterView>& parameters, const std::string& kind = "",
                           const std::string& target = "") {
  std::string out;
  for (const ParameterView& p : parameters) {
    if (!kind.empty() && (p.kind != kind || p.target != target)) continue;
    out += (out.empty() ? "" : "; ") + p.text;
  }
  return out;
}

const json* RankOne(const json& candidates) {
  const json* best = nullptr;
  for (const json& c : candidates)
    if (c.is_object() && c.contains("rank") && c["rank"].is_number() &&
        (!best || c["rank"].get<int>() < (*best)["rank"].get<int>()))
      best = &c;
  return best;
}

}  // namespace

std::string ParameterText(const std::string& kind, const std::string& name, double value, double sigma,
                          double radius_m) {
  const bool with_sigma = std::isfinite(sigma);
  auto words = [&](const std::string& label, double scale, const std::string& unit) {
    return label + Sig(value * scale, 3) + (with_sigma ? " ± " + Sig(std::abs(sigma * scale), 2) : "") + unit;
  };
  if (name == "modulus")
    return words("E' = ", 1e-9, " GPa") + (std::isfinite(radius_m) ? " (R' = " + Sig(radius_m * 1e3, 3) + " mm)" : "");
  if (name == "k") return words("k = ", 1e-6, " N/µm");
  if (name == "mass") return words("m = ", 1e3, " g");
  if (name == "factor")
    return words(kind == "stiffness_scale" ? "stiffness × " : kind == "mass_scale" ? "mass × " : "× ", 1.0, "");
  if (kind == "operating_point" && std::abs(value) < 1e-3) return words("value = ", 1e6, " µm");
  return words(name + " = ", 1.0, "");
}

json DiagnosisView(const json& diagnosis) {
  json view = json::object();
  if (!diagnosis.is_object() || !diagnosis.contains("candidates") || !diagnosis["candidates"].is_array()) return view;
  const json& candidates = diagnosis["candidates"];
  const json* first_ptr = RankOne(candidates);
  if (!first_ptr) return view;
  const json& first = *first_ptr;
  const double p_first = Number(first, "probability");
  std::map<int, const json*> by_rank;
  for (const json& c : candidates)
    if (c.is_object() && c.contains("rank") && c["rank"].is_number()) by_rank[c["rank"].get<int>()] = &c;

  // ---- the first screen ----
  json story = {{"rank", first["rank"]},
                {"kind", Text(first, "kind")},
                {"target", Text(first, "target")},
                {"description", Text(first, "description")},
                {"probability", NumberOrNull(p_first)}};
  const json& effects = first.contains("effects") && first["effects"].is_array() ? first["effects"] : json::array();
  // Rank 1's effects in words and numbers as `ema diagnose` made them (DIAG.json "findings",
  // in rank 1's effect order); a DIAG.json written before them: the words made here from the
  // candidate's own fields.
  const json& findings = diagnosis.contains("findings") && diagnosis["findings"].is_array() ? diagnosis["findings"] : json::array();
  const std::vector<ParameterView> first_parameters = CandidateParameters(first);
  const json& effect_probabilities =
      diagnosis.contains("effect_probabilities") && diagnosis["effect_probabilities"].is_array()
          ? diagnosis["effect_probabilities"] : json::array();
  json story_effects = json::array();
  for (size_t i = 0; i < effects.size(); ++i) {
    const std::string kind = Text(effects[i], "kind"), target = Text(effects[i], "target");
    double p_exact = kNaN, p_any = kNaN;
    std::string pattern;
    for (const json& ep : effect_probabilities) {
      if (Text(ep, "kind") != kind) continue;
      const std::string t = Text(ep, "target");
      const double p = Number(ep, "probability");
      if (t == target) p_exact = p;
      else if (t.find('*') != std::string::npos && GlobMatch(t, target) && !(p <= p_any)) p_any = p, pattern = t;
    }
    const json* finding = nullptr;
    for (const json& f : findings)
      if (f.is_object() && Text(f, "kind") == kind && Text(f, "target") == target) finding = &f;
    std::string description = finding ? Text(*finding, "description") : "";
    if (description.empty()) description = KindWords(kind) + (target.empty() ? "" : " on '" + target + "'");
    std::string values = finding ? Text(*finding, "values") : "";
    if (values.empty()) values = JoinParameters(first_parameters, kind, target);
    if (values.empty() && effects.size() == 1) values = JoinParameters(first_parameters);
    json e = {{"kind", kind}, {"target", target}, {"description", description}, {"values", values},
              {"probability", NumberOrNull(p_exact)}};
    if (!pattern.empty()) e["any"] = {{"target", pattern}, {"probability", NumberOrNull(p_any)}};
    story_effects.push_back(std::move(e));
  }
  story["effects"] = story_effects;
  const json& baseline = diagnosis.contains("baseline") ? diagnosis["baseline"] : json::object();
  story["error_before_pct"] = NumberOrNull(Number(baseline, "mean_abs_frequency_error_pct"));
  story["error_after_pct"] = NumberOrNull(Number(first, "mean_abs_frequency_error_pct"));
  story["mac_before"] = NumberOrNull(Number(baseline, "mean_mac"));
  story["mac_after"] = NumberOrNull(Number(first, "mean_mac"));
  // Adequacy to the test's noise, in words.
  const double chi2 = Number(first, "reduced_chi2");
  const double test_modes = Number(diagnosis, "test_modes");
  const std::string over = std::isfinite(test_modes) ? " over " + Sig(test_modes, 6) + " test modes" : "";
  if (first.contains("noise_consistent") && first["noise_consistent"].is_boolean()) {
    const bool ok = first["noise_consistent"].get<bool>();
    story["noise_consistent"] = ok;
    // Far below 1 the number itself says little: the misfit sits well inside the test's σ, which
    // the frequency floor (0.1 % of f by default) may dominate.
    story["adequacy"] = ok ? (chi2 < 0.01 ? "Adequate to the test's noise: yes — reduced χ² below 0.01" + over +
                                                ": the updated model sits well inside the test's σ (each σ at least "
                                                "the frequency floor, 0.1 % of f by default)."
                                          : "Adequate to the test's noise: yes — reduced χ² " + Readable(chi2) + over +
                                                ": what is left is what the measurement noise explains.")
                           : "Adequate to the test's noise: NO — reduced χ² " + Readable(chi2) + over +
                                 " (1 would be noise alone): the model still misses something these data can see" +
                                 (effects.empty() ? "" : "; rank 1 is not the whole answer") + ".";
  } else {
    story["noise_consistent"] = nullptr;
    story["adequacy"] = "Adequacy to the test's noise: not computed by this diagnosis.";
  }
  story["reduced_chi2"] = NumberOrNull(chi2);
  // The model's own error the diagnosis inferred (DIAG.json model_error, cli.md turn 4), in words
  // where it dominates the test's σ: the probabilities then compare the readings tried only.
  story["model_error_note"] = nullptr;
  if (first.contains("model_error") && first["model_error"].is_object() && first["model_error"].value("dominates", false)) {
    const double rel = Number(first["model_error"], "frequency_rel");
    const double common = first["model_error"].contains("frequency_common_rel") ? Number(first["model_error"], "frequency_common_rel") : 0.0;
    story["model_error_note"] = "The model's own error (about " + Readable(100.0 * rel) + " % of each frequency" +
                                (common >= rel ? " and " + Readable(100.0 * common) + " % shared by all of them" : std::string()) +
                                ") is larger than the test's σ: no reading of the vocabulary makes the "
                                "model exact, and the probabilities compare the readings tried with each other only.";
  }
  // Look-alikes: the other readings within a factor 20 of rank 1's probability, one per group (the
  // rule of the summary, app/cmd_diagnose.cpp).
  json alike = json::array();
  const json& groups = diagnosis.contains("groups") && diagnosis["groups"].is_array() ? diagnosis["groups"] : json::array();
  for (const json& g : groups) {
    const json& ranks = g.contains("ranks") && g["ranks"].is_array() ? g["ranks"] : json::array();
    const bool holds_first = std::find(ranks.begin(), ranks.end(), first["rank"]) != ranks.end();
    const double p = holds_first ? Number(g, "probability") - p_first : Number(g, "probability");
    const int others = static_cast<int>(ranks.size()) - (holds_first ? 1 : 0);
    if (others <= 0 || Text(g, "kind") == "none" || !(p >= 0.05 * p_first) || !(p >= 0.001)) continue;
    const std::string pattern = Text(g, "target");
    std::string text = holds_first ? "rank 1's reading on " + std::to_string(others) + " other " + MemberNoun(pattern, others)
                                   : KindWords(Text(g, "kind")) + (pattern.empty() ? "" : " on " + pattern) +
                                         (others > 1 ? " (" + std::to_string(others) + " " + MemberNoun(pattern, others) + ")" : "");
    if (holds_first) text += " (" + pattern + ")";
    alike.push_back({{"text", text}, {"probability", p}, {"same_reading", holds_first}, {"count", others}});
    if (alike.size() == 4) break;
  }
  story["lookalikes"] = alike;
  story["checks"] = first.contains("flags") && first["flags"].is_array() ? first["flags"] : json::array();

  // ---- evidence per test mode: as given (before) and with rank 1 (after), in σ of the test ----
  json modes = json::array();
  json failing = json::array();
  double total_drop = 0.0;
  const json& mode_rows = diagnosis.contains("modes") && diagnosis["modes"].is_array() ? diagnosis["modes"] : json::array();
  std::vector<double> drops;
  for (const json& m : mode_rows) {
    const double fb = Number(m, "frequency_misfit_sigma_before"), fa = Number(m, "frequency_misfit_sigma_after");
    const double sb = Number(m, "shape_misfit_sigma_before"), sa = Number(m, "shape_misfit_sigma_after");
    auto square = [](double v) { return std::isfinite(v) ? v * v : 0.0; };
    const double drop = std::max(0.0, square(fb) + square(sb) - square(fa) - square(sa));
    drops.push_back(drop);
    total_drop += drop;
  }
  for (size_t i = 0; i < mode_rows.size(); ++i) {
    const json& m = mode_rows[i];
    const bool paired_before = m.contains("mac_before") && m["mac_before"].is_number();
    const bool paired_after = m.contains("mac_after") && m["mac_after"].is_number();
    const double fa = Number(m, "frequency_misfit_sigma_after"), sa = Number(m, "shape_misfit_sigma_after");
    std::string verdict = !paired_after ? "unpaired"
                          : (std::abs(fa) > 3.0 || sa > 3.0) ? "misfit"
                          : (std::abs(fa) > 2.0 || sa > 2.0) ? "marginal" : "within noise";
    json row = {{"setup", Text(m, "setup")},
                {"test_mode", m.contains("test_mode") ? m["test_mode"] : json(nullptr)},
                {"test_frequency_hz", NumberOrNull(Number(m, "test_frequency_hz"))},
                {"sigma_hz", NumberOrNull(Number(m, "sigma_hz"))},
                {"model_frequency_hz_before", NumberOrNull(Number(m, "model_frequency_hz_before"))},
                {"model_frequency_hz_after", NumberOrNull(Number(m, "model_frequency_hz_after"))},
                {"frequency_misfit_sigma_before", paired_before ? NumberOrNull(Number(m, "frequency_misfit_sigma_before")) : json(nullptr)},
                {"frequency_misfit_sigma_after", paired_after ? NumberOrNull(fa) : json(nullptr)},
                {"mac_before", NumberOrNull(Number(m, "mac_before"))},
                {"mac_after", NumberOrNull(Number(m, "mac_after"))},
                {"shape_misfit_sigma_before", paired_before ? NumberOrNull(Number(m, "shape_misfit_sigma_before")) : json(nullptr)},
                {"shape_misfit_sigma_after", paired_after ? NumberOrNull(sa) : json(nullptr)},
                {"paired_before", paired_before},
                {"paired_after", paired_after},
                {"share_pct", total_drop > 0.0 ? json(100.0 * drops[i] / total_drop) : json(nullptr)},
                {"verdict", verdict}};
    if (verdict == "unpaired" || verdict == "misfit") {
      const std::string where = Text(m, "setup") + (Text(m, "setup").empty() ? "" : " ") + "mode " +
                                (m.contains("test_mode") ? m["test_mode"].dump() : "?") + " (" +
                                Sig(Number(m, "test_frequency_hz"), 4) + " Hz)";
      failing.push_back(where + (verdict == "unpaired" ? ": no model mode pairs with it"
                                                       : ": " + Sig(fa, 2) + " σ in frequency, " + Sig(sa, 2) + " σ in shape"));
    }
    modes.push_back(std::move(row));
  }
  story["failing_modes"] = failing;
  view["story"] = std::move(story);
  view["modes"] = std::move(modes);

  // ---- the candidates, look-alikes folded: one row per group, its best member first ----
  json rows = json::array();
  std::set<int> grouped;
  auto candidate_row = [&](const json& c) {
    const std::vector<ParameterView> parameters = CandidateParameters(c);
    return json{{"rank", c["rank"]},
                {"kind", Text(c, "kind")},
                {"target", Text(c, "target")},
                {"parameters", JoinParameters(parameters)},
                {"probability", NumberOrNull(Number(c, "probability"))},
                {"mean_abs_frequency_error_pct", NumberOrNull(Number(c, "mean_abs_frequency_error_pct"))},
                {"mean_mac", NumberOrNull(Number(c, "mean_mac"))},
                {"reduced_chi2", NumberOrNull(Number(c, "reduced_chi2"))},
                {"noise_consistent", c.contains("noise_consistent") ? c["noise_consistent"] : json(nullptr)},
                {"flags", c.contains("flags") && c["flags"].is_array() ? c["flags"] : json::array()}};
  };
  for (const json& g : groups) {
    std::vector<int> ranks;
    if (g.contains("ranks") && g["ranks"].is_array())
      for (const json& r : g["ranks"])
        if (r.is_number() && by_rank.count(r.get<int>())) ranks.push_back(r.get<int>());
    if (ranks.empty()) continue;
    std::sort(ranks.begin(), ranks.end());
    json row = candidate_row(*by_rank[ranks.front()]);
    row["pattern"] = Text(g, "target");
    row["probability_best"] = row["probability"];
    row["probability"] = NumberOrNull(Number(g, "probability"));
    row["ranks"] = ranks;
    row["more"] = static_cast<int>(ranks.size()) - 1;
    row["more_noun"] = MemberNoun(Text(g, "target"), static_cast<int>(ranks.size()) - 1);
    json members = json::array();
    for (size_t i = 1; i < ranks.size(); ++i) members.push_back(candidate_row(*by_rank[ranks[i]]));
    row["members"] = std::move(members);
    for (int r : ranks) grouped.insert(r);
    rows.push_back(std::move(row));
  }
  // Candidates no group holds (or a DIAG.json without "groups"): a row each.
  for (const auto& [rank, c] : by_rank) {
    if (grouped.count(rank)) continue;
    json row = candidate_row(*c);
    row["ranks"] = json::array({rank});
    row["more"] = 0;
    row["members"] = json::array();
    rows.push_back(std::move(row));
  }
  std::stable_sort(rows.begin(), rows.end(), [](const json& a, const json& b) {
    return a["rank"].get<int>() < b["rank"].get<int>();
  });
  view["groups"] = std::move(rows);
  view["candidate_count"] = by_rank.size();
  return view;
}

StabilisationPoints ReadStabilisation(const json& stabilisation) {
  StabilisationPoints points;
  auto add_pole = [&](const json& pole, int order) {
    if (!pole.is_object()) return;
    double f = Number(pole, "frequency_hz");
    double zeta = Number(pole, "damping_ratio");
    if (!std::isfinite(f) && pole.contains("pole")) {
      const std::complex<double> lambda = ComplexOf(pole["pole"]);
      PoleToFrequencyAndDamping(lambda, &f, &zeta);
    }
    if (!std::isfinite(f)) return;
    const int pole_order = pole.contains("order") && pole["order"].is_number() ? pole["order"].get<int>() : order;
    std::string status;
    if (pole.contains("label") && pole["label"].is_string()) {
      // ema fit's letters: s = stable in frequency, damping and vector; f, d, v = partly; o = new.
      const std::string label = pole["label"].get<std::string>();
      status = label == "s" ? "stable" : label == "o" ? "unstable" : label;
    } else if (pole.contains("status") && pole["status"].is_string()) {
      status = pole["status"].get<std::string>();
    } else if (pole.contains("stable") && pole["stable"].is_boolean()) {
      status = pole["stable"].get<bool>() ? "stable" : "unstable";
    } else {
      // Per-criterion flags: stable only when every criterion given holds.
      bool any = false, all = true;
      for (const char* key : {"stable_frequency", "stable_damping", "stable_vector", "stable_mac"}) {
        if (pole.contains(key) && pole[key].is_boolean()) {
          any = true;
          all = all && pole[key].get<bool>();
        }
      }
      status = any && all ? "stable" : "unstable";
    }
    if (pole.contains("physical") && pole["physical"].is_boolean() && !pole["physical"].get<bool>())
      status = "non-physical";
    points.order.push_back(pole_order);
    points.frequency_hz.push_back(f);
    points.damping_ratio.push_back(zeta);
    points.status.push_back(status);
  };
  if (!stabilisation.is_object()) return points;
  if (stabilisation.contains("orders") && stabilisation["orders"].is_array()) {
    for (const json& level : stabilisation["orders"]) {
      const int order = level.is_object() && level.contains("order") && level["order"].is_number() ? level["order"].get<int>() : 0;
      if (level.is_object() && level.contains("poles") && level["poles"].is_array())
        for (const json& pole : level["poles"]) add_pole(pole, order);
    }
  } else if (stabilisation.contains("poles") && stabilisation["poles"].is_array()) {
    for (const json& pole : stabilisation["poles"]) add_pole(pole, 0);
  }
  return points;
}

}  // namespace ema::report
