// Data preparation of the HTML report: the stabilisation points of `ema fit --stabilisation`, and
// the diagnosis as the page shows it (first screen, look-alikes folded, evidence per test mode).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "report.hpp"
#include "words.hpp"
#include "ema/model/effects.hpp"

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

json NumberOrNull(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

// 3.28e+04 → "3.28 × 10⁴": a large reduced χ² read as a number, not as C's exponent notation.
std::string Readable(double v) {
  if (!std::isfinite(v)) return "–";
  if (v == 0.0 || (std::abs(v) < 1e4 && std::abs(v) >= 1e-3)) return Significant(v, 3);
  static const char* const kSuperscript[] = {"⁰", "¹", "²", "³", "⁴", "⁵", "⁶", "⁷", "⁸", "⁹"};
  const int exponent = static_cast<int>(std::floor(std::log10(std::abs(v))));
  std::string power;
  for (char c : std::to_string(exponent)) power += c == '-' ? "⁻" : kSuperscript[c - '0'];
  return Significant(v / std::pow(10.0, exponent), 3) + " × 10" + power;
}

const char* VerdictName(pipeline::ModeVerdict verdict) {
  switch (verdict) {
    case pipeline::ModeVerdict::kWithinNoise: return "within noise";
    case pipeline::ModeVerdict::kMarginal: return "marginal";
    case pipeline::ModeVerdict::kMisfit: return "misfit";
    case pipeline::ModeVerdict::kUnpaired: return "unpaired";
  }
  return "";
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
std::string MemberNoun(pipeline::GroupSpan span, int count) {
  const std::string noun = span == pipeline::GroupSpan::kPoints    ? "point"
                           : span == pipeline::GroupSpan::kMembers ? "member"
                                                                   : "reading";
  return noun + (count == 1 ? "" : "s");
}

// Every fitted parameter of a candidate in engineering units with its 1σ, each with its own effect's words.
std::string CandidateParameters(const diagnose::Candidate& c) {
  std::string out;
  for (const diagnose::FittedParameter& p : c.parameters) {
    const model::Effect* effect = nullptr;
    for (const model::Effect& e : c.effects)
      if (e.kind == p.effect_kind && e.target == p.target) effect = &e;
    out += (out.empty() ? "" : "; ") + ParameterWords(p, effect);
  }
  return out;
}

json CandidateRow(const diagnose::Candidate& c) {
  return json{{"rank", c.rank},
              {"kind", c.kind},
              {"target", c.target},
              {"parameters", CandidateParameters(c)},
              {"probability", NumberOrNull(c.probability)},
              {"mean_abs_frequency_error_pct", NumberOrNull(c.mean_abs_frequency_error_pct)},
              {"mean_mac", NumberOrNull(c.mean_mac)},
              {"reduced_chi2", NumberOrNull(c.reduced_chi2)},
              {"noise_consistent", c.noise_consistent},
              {"flags", c.flags}};
}

// Global position of an anchor (body point, body centre, FE node); false when unknown.
bool Place(const model::Model& m, const model::Anchor& a, const model::Anchor* fallback, Eigen::Vector3d* p) {
  if (a.IsNode()) {
    auto it = m.fe.node_positions.find(a.node);
    if (it == m.fe.node_positions.end()) return false;
    *p = it->second;
    return true;
  }
  if (a.has_at) {
    *p = a.at;
    return true;
  }
  if (fallback && fallback->has_at) {
    *p = fallback->at;
    return true;
  }
  if (const model::Body* b = m.FindBody(a.body)) {
    *p = b->centre;
    return true;
  }
  return false;
}

}  // namespace

json DiagnosedPlaces(const model::Model& m, const std::vector<model::Effect>& effects) {
  json out = json::array();
  for (const model::Effect& e : effects) {
    const model::EffectKindInfo& info = model::Info(e.kind);
    json points = json::array();
    auto add = [&](const Eigen::Vector3d& p) { points.push_back({p.x(), p.y(), p.z()}); };
    Eigen::Vector3d p;
    if (info.acts_on == model::ActsOn::kSprings) {
      for (int i : model::TargetSprings(m, e.target)) {
        const model::Spring& s = m.springs[static_cast<std::size_t>(i)];
        if (Place(m, s.a, nullptr, &p)) add(p);
        if (!s.b.IsGround() && Place(m, s.b, &s.a, &p)) add(p);
      }
    } else if (info.acts_on == model::ActsOn::kPoints) {
      std::vector<int> named;
      try {
        named = model::TargetPoints(m, e);
      } catch (const std::exception&) {
        // A target this model does not hold: nothing to draw.
      }
      for (int i : named)
        if (Place(m, m.points[static_cast<std::size_t>(i)].where, nullptr, &p)) add(p);
    } else if (const model::Body* b = model::TargetBody(m, e.target)) {
      add(b->centre);
    }
    // A member is labelled by its own name ("J3" of "joints/J3").
    std::string label = model::TargetText(e.target);
    for (const model::Member& member : model::Members(m))
      if (member.Target() == e.target) label = member.name;
    for (const model::FePart& part : m.fe.parts)
      if (!part.group.empty() && part.Target() == e.target) label = part.name;
    out.push_back({{"target", model::TargetText(e.target)},
                   {"kind", model::KindName(e.kind)},
                   {"label", label},
                   {"points", points}});
  }
  return out;
}

json DiagnosisView(const pipeline::DiagnoseStage& stage) {
  json view = json::object();
  const diagnose::Diagnosis& d = stage.diagnosis;
  const pipeline::Findings& f = stage.findings;
  if (d.candidates.empty()) return view;
  const diagnose::Candidate& first = d.candidates.front();

  // ---- the first screen ----
  json story = {{"rank", first.rank},
                {"kind", first.kind},
                {"target", first.target},
                {"description", diagnose::DescribeCandidate(first)},
                {"probability", NumberOrNull(f.rank_one_probability)}};
  json story_effects = json::array();
  for (const pipeline::EffectFinding& e : f.effects) {
    diagnose::Candidate single;
    single.effects = {e.effect};
    json j = {{"kind", model::KindName(e.effect.kind)},
              {"target", model::TargetText(e.effect.target)},
              {"description", diagnose::DescribeCandidate(single, false)},
              {"values", EffectValuesWords(e)},
              {"probability", NumberOrNull(e.probability)}};
    if (e.wildcard)
      j["any"] = {{"target", model::TargetText(*e.wildcard)}, {"probability", NumberOrNull(e.wildcard_probability)}};
    story_effects.push_back(std::move(j));
  }
  story["effects"] = story_effects;
  story["error_before_pct"] = NumberOrNull(f.error_before_pct);
  story["error_after_pct"] = NumberOrNull(f.error_after_pct);
  story["mac_before"] = NumberOrNull(f.mac_before);
  story["mac_after"] = NumberOrNull(f.mac_after);
  // Adequacy to the test's noise, in words.
  const std::string over = " over " + std::to_string(f.test_modes) + " test modes";
  story["noise_consistent"] = f.adequate;
  // Far below 1 the number itself says little: the misfit sits well inside the test's σ, which
  // the frequency floor (0.1 % of f by default) may dominate.
  // The headline (bold on the page) and the rest as two fields, so that no reader has to find
  // where one ends in the sentence; `adequacy` is the whole sentence.
  const std::string headline = f.adequate ? "Adequate to the test's noise: yes" : "Adequate to the test's noise: NO";
  const std::string detail =
      f.well_inside_noise ? "reduced χ² below 0.01" + over +
                                ": the updated model sits well inside the test's σ (each σ at least the frequency "
                                "floor, 0.1 % of f by default)."
      : f.adequate
          ? "reduced χ² " + Readable(f.reduced_chi2) + over + ": what is left is what the measurement noise explains."
          : "reduced χ² " + Readable(f.reduced_chi2) + over +
                " (1 would be noise alone): the model still misses something these data can see" +
                (f.effects.empty() ? "" : "; rank 1 is not the whole answer") + ".";
  story["adequacy_headline"] = headline;
  story["adequacy_detail"] = detail;
  story["adequacy"] = headline + " — " + detail;
  story["reduced_chi2"] = NumberOrNull(f.reduced_chi2);
  // The model's own error the diagnosis inferred (DIAG.json model_error, cli.md turn 4), in words
  // where it dominates the test's σ: the probabilities then compare the readings tried only.
  story["model_error_note"] = nullptr;
  if (f.model_error.dominates) {
    const double rel = f.model_error.frequency_rel, common = f.model_error.frequency_common_rel;
    story["model_error_note"] = "The model's own error (about " + Readable(100.0 * rel) + " % of each frequency" +
                                (common >= rel ? " and " + Readable(100.0 * common) + " % shared by all of them" : std::string()) +
                                ") is larger than the test's σ: no reading of the vocabulary makes the "
                                "model exact, and the probabilities compare the readings tried with each other only.";
  }
  // Rank 1 the model as given, still inadequate, and a reading its own error also explains: the
  // lead says so instead of "no candidate explains the mismatch".
  story["model_error_lookalike"] = nullptr;
  if (f.model_inadequate && f.model_error_lookalike)
    story["model_error_lookalike"] = "The model as given ranks first (probability " + Percent(f.rank_one_probability) +
                                     ")" + ModelErrorLookAlikeWords(f);
  // Look-alikes: the readings the diagnosis found within a factor 20 of rank 1 (Findings::lookalikes).
  json alike = json::array();
  for (const pipeline::LookAlike& l : f.lookalikes) {
    std::string text = l.holds_rank_one
                           ? "rank 1's reading on " + std::to_string(l.readings) + " other " + MemberNoun(l.span, l.readings) +
                                 " (" + l.target + ")"
                           : KindWords(l.kind) + (l.target.empty() ? "" : " on " + l.target) +
                                 (l.readings > 1 ? " (" + std::to_string(l.readings) + " " + MemberNoun(l.span, l.readings) + ")" : "");
    alike.push_back({{"text", text}, {"probability", l.probability}, {"same_reading", l.holds_rank_one}, {"count", l.readings}});
  }
  story["lookalikes"] = alike;
  story["checks"] = f.checks;

  // ---- evidence per test mode: as given (before) and with rank 1 (after), in σ of the test ----
  json modes = json::array();
  json failing = json::array();
  const bool several = SeveralTestsOfOneSetup(stage.diagnosis.baseline.modes);  // f.modes' `before`
  for (const pipeline::ModeEvidence& m : f.modes) {
    const diagnose::ModeComparison &b = m.before, &a = m.after;
    json row = {{"setup", b.setup},
                {"test", b.test + 1},
                {"test_mode", b.test_mode + 1},
                {"test_frequency_hz", NumberOrNull(b.test_frequency_hz)},
                {"sigma_hz", NumberOrNull(b.sigma_hz)},
                {"model_frequency_hz_before", NumberOrNull(b.model_frequency_hz)},
                {"model_frequency_hz_after", NumberOrNull(a.model_frequency_hz)},
                {"frequency_misfit_sigma_before", m.paired_before ? NumberOrNull(b.frequency_misfit_sigma) : json(nullptr)},
                {"frequency_misfit_sigma_after", m.paired_after ? NumberOrNull(a.frequency_misfit_sigma) : json(nullptr)},
                {"mac_before", NumberOrNull(b.mac)},
                {"mac_after", NumberOrNull(a.mac)},
                {"shape_misfit_sigma_before", m.paired_before ? NumberOrNull(b.shape_misfit_sigma) : json(nullptr)},
                {"shape_misfit_sigma_after", m.paired_after ? NumberOrNull(a.shape_misfit_sigma) : json(nullptr)},
                {"paired_before", m.paired_before},
                {"paired_after", m.paired_after},
                {"share_pct", NumberOrNull(m.share_pct)},
                {"verdict", VerdictName(m.verdict)}};
    if (m.verdict == pipeline::ModeVerdict::kUnpaired || m.verdict == pipeline::ModeVerdict::kMisfit) {
      const std::string where = TestModeWords(b, several) + " (" + Significant(b.test_frequency_hz, 4) + " Hz)";
      failing.push_back(where + (m.verdict == pipeline::ModeVerdict::kUnpaired
                                     ? ": no model mode pairs with it"
                                     : ": " + Significant(a.frequency_misfit_sigma, 2) + " σ in frequency, " +
                                           Significant(a.shape_misfit_sigma, 2) + " σ in shape"));
    }
    modes.push_back(std::move(row));
  }
  story["failing_modes"] = failing;
  view["story"] = std::move(story);
  view["modes"] = std::move(modes);

  // ---- the candidates, look-alikes folded: one row per group, its best member first ----
  std::map<int, const diagnose::Candidate*> by_rank;
  for (const diagnose::Candidate& c : d.candidates) by_rank[c.rank] = &c;
  json rows = json::array();
  std::set<int> grouped;
  for (const diagnose::CandidateGroup& g : d.groups) {
    std::vector<int> ranks;
    for (int r : g.ranks)
      if (by_rank.count(r)) ranks.push_back(r);
    if (ranks.empty()) continue;
    std::sort(ranks.begin(), ranks.end());
    json row = CandidateRow(*by_rank[ranks.front()]);
    row["pattern"] = g.target;
    row["probability_best"] = row["probability"];
    row["probability"] = NumberOrNull(g.probability);
    row["ranks"] = ranks;
    row["more"] = static_cast<int>(ranks.size()) - 1;
    row["more_noun"] = MemberNoun(pipeline::SpanOf(d, g), static_cast<int>(ranks.size()) - 1);
    json members = json::array();
    for (size_t i = 1; i < ranks.size(); ++i) members.push_back(CandidateRow(*by_rank[ranks[i]]));
    row["members"] = std::move(members);
    for (int r : ranks) grouped.insert(r);
    rows.push_back(std::move(row));
  }
  // Candidates no group holds (failed ones): a row each.
  for (const auto& [rank, c] : by_rank) {
    if (grouped.count(rank)) continue;
    json row = CandidateRow(*c);
    row["ranks"] = json::array({rank});
    row["more"] = 0;
    row["members"] = json::array();
    rows.push_back(std::move(row));
  }
  std::stable_sort(rows.begin(), rows.end(), [](const json& a, const json& b) { return a["rank"].get<int>() < b["rank"].get<int>(); });
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
