// The effects of the vocabulary (model-format.md "Effects") as transformations of a Model.
#include "ema/model/effects.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <set>
#include <sstream>

#include "ema/core/error.hpp"
#include "ema/model/solve.hpp"

namespace ema::model {
namespace {

std::string Where(const Model& model, const Effect& e) {
  return model.Where(e.line) + ": effect " + KindName(e.kind) + " '" + TargetText(e.target) + "'";
}

double Param(const Model& model, const Effect& e, const std::string& key, bool positive) {
  auto it = e.parameters.find(key);
  if (it == e.parameters.end()) throw InputError(Where(model, e), "missing parameter '" + key + "'");
  const double v = it->second;
  if (!std::isfinite(v) || v < 0.0 || (positive && v == 0.0))
    throw InputError(Where(model, e), "parameter '" + key + "' must be " + (positive ? "> 0" : ">= 0") + ", got " +
                                          std::to_string(v));
  return v;
}

// The names a stiffness or mass target may take, for messages: spring groups, part groups, parts
// in no group (and bodies for mass_scale).
std::string KnownTargets(const Model& model, bool bodies) {
  std::set<std::string> names;
  for (const Spring& s : model.springs) names.insert(s.group);
  for (const FePart& p : model.fe.parts) names.insert(p.group.empty() ? p.name : p.group);
  if (bodies)
    for (const Body& b : model.bodies) names.insert(b.name);
  std::string known;
  for (const auto& n : names) known += (known.empty() ? "" : ", ") + n;
  return known.empty() ? "none" : known;
}

std::vector<Spring*> GroupSprings(Model& model, const Effect& e) {
  std::vector<Spring*> out;
  for (int i : TargetSprings(model, e.target)) out.push_back(&model.springs[i]);
  if (out.empty()) {
    std::set<std::string> groups;
    for (const Spring& s : model.springs) groups.insert(s.group);
    std::string known;
    for (const auto& g : groups) known += (known.empty() ? "" : ", ") + g;
    const EffectTarget& t = e.target;
    if (t.form == EffectTarget::Form::kMember && groups.count(t.name)) {
      std::string members;
      for (const Member& m : Members(model))
        if (m.group == t.name) members += (members.empty() ? "" : ", ") + m.name;
      throw InputError(Where(model, e),
                       "no member '" + t.member + "' in group '" + t.name + "' (members: " + members + ")");
    }
    if (!model.fe.parts.empty())
      throw InputError(Where(model, e), "no spring group, part group or part '" + TargetText(t) +
                                            "' (targets: " + KnownTargets(model, false) + ")");
    throw InputError(Where(model, e),
                     "no spring group '" + TargetText(t) + "' (groups: " + (known.empty() ? "none" : known) + ")");
  }
  return out;
}

Body& EffectBody(Model& model, const Effect& e) {
  Body* b = e.target.form == EffectTarget::Form::kName ? model.FindBody(e.target.name) : nullptr;
  if (!b) {
    std::string known;
    for (const Body& x : model.bodies) known += (known.empty() ? "" : ", ") + x.name;
    if (!model.fe.parts.empty() && e.kind == EffectKind::kMassScale)
      throw InputError(Where(model, e), "no body, part group or part '" + TargetText(e.target) +
                                            "' (targets: " + KnownTargets(model, true) + ")");
    throw InputError(Where(model, e),
                     "no body '" + TargetText(e.target) + "' (bodies: " + (known.empty() ? "none" : known) + ")");
  }
  return *b;
}

/// Replaces the operating value of a non-linear law; false when the law is linear.
bool SetOperatingValue(Law& law, double value) {
  if (auto* t = std::get_if<TableLaw>(&law.value)) {
    if (!t->operating_deflection && t->operating_force) t->operating_force = value;
    else t->operating_deflection = value;
    return true;
  }
  if (auto* a = std::get_if<AirFilmLaw>(&law.value)) {
    a->operating_gap = value;
    return true;
  }
  if (auto* h = std::get_if<HertzLaw>(&law.value)) {
    if (!h->operating_deflection && h->operating_force) h->operating_force = value;
    else h->operating_deflection = value;
    return true;
  }
  if (auto* s = std::get_if<SeriesLaw>(&law.value)) {
    if (!law.IsNonlinear()) return false;
    bool film = false;
    for (const Law& el : s->elements) film |= std::holds_alternative<AirFilmLaw>(el.value);
    if (film) s->setting = value;
    else s->force = value;
    return true;
  }
  return false;
}

void ApplySeriesCompliance(Model& model, const Effect& e) {
  std::optional<Law> law = e.law;
  if (!law && e.parameters.count("k")) law = Law(LinearLaw{Param(model, e, "k", true)});
  if (!law) throw InputError(Where(model, e), "missing 'law' (e.g. law = { linear = { k = 6.5e6 } })");
  for (Spring* s : GroupSprings(model, e)) {
    if (auto* chain = std::get_if<SeriesLaw>(&s->law.value)) {
      chain->elements.push_back(*law);  // the chain re-solves its equilibrium with the new element
    } else {
      SeriesLaw series;
      series.elements = {s->law, *law};
      // A lone air film keeps its gap as the chain's setting; otherwise the chain keeps the
      // element's own operating point.
      if (const auto* film = std::get_if<AirFilmLaw>(&s->law.value)) series.setting = film->operating_gap;
      s->law = Law(std::move(series));
    }
  }
}

// The parts a target names; throws naming the target when it names none (and no spring group).
std::vector<FePart*> Parts(Model& model, const Effect& e, bool bodies) {
  std::vector<FePart*> out;
  for (int i : TargetParts(model, e.target)) out.push_back(&model.fe.parts[static_cast<std::size_t>(i)]);
  if (out.empty()) {
    if (e.target.form == EffectTarget::Form::kMember) {
      std::string members;
      for (const FePart& p : model.fe.parts)
        if (p.group == e.target.name) members += (members.empty() ? "" : ", ") + p.name;
      if (!members.empty())
        throw InputError(Where(model, e), "no part '" + e.target.member + "' in part group '" + e.target.name +
                                              "' (members: " + members + ")");
    }
    throw InputError(Where(model, e), "no spring group, part group or part '" + TargetText(e.target) +
                                          "' (targets: " + KnownTargets(model, bodies) + ")");
  }
  return out;
}

void ApplyStiffnessScale(Model& model, const Effect& e) {
  const double f = Param(model, e, "factor", true);
  if (!TargetSprings(model, e.target).empty() || model.fe.parts.empty()) {
    for (Spring* s : GroupSprings(model, e)) s->stiffness_factor *= f;
    return;
  }
  for (FePart* p : Parts(model, e, false)) {
    if (!p->HasStiffness())
      throw InputError(Where(model, e), "part '" + p->name + "' has no stiffness matrix to scale");
    p->stiffness_factor *= f;
  }
}

void ApplyOperatingPoint(Model& model, const Effect& e) {
  auto it = e.parameters.find("value");
  if (it == e.parameters.end() || !std::isfinite(it->second)) throw InputError(Where(model, e), "missing parameter 'value'");
  bool any = false;
  for (Spring* s : GroupSprings(model, e)) any |= SetOperatingValue(s->law, it->second);
  if (!any)
    throw InputError(Where(model, e),
                     "'" + TargetText(e.target) + "' has only linear laws; no operating point to change");
}

void ApplyAddedMass(Model& model, const Effect& e) {
  const double m = Param(model, e, "mass", false);
  std::vector<PointMass> added;
  for (int i : TargetPoints(model, e)) {
    const TestPoint& p = model.points[static_cast<std::size_t>(i)];
    added.push_back({"added_mass@" + std::to_string(p.id), p.where, m, e.line});
  }
  model.masses.insert(model.masses.end(), added.begin(), added.end());
}

void ApplyMassScale(Model& model, const Effect& e) {
  const double f = Param(model, e, "factor", true);
  if (!TargetBody(model, e.target) && !model.fe.parts.empty()) {
    for (FePart* p : Parts(model, e, true)) {
      if (!p->HasMass()) throw InputError(Where(model, e), "part '" + p->name + "' has no mass matrix to scale");
      p->mass_factor *= f;
    }
    return;
  }
  Body& b = EffectBody(model, e);
  b.mass *= f;
  b.inertia *= f;
  b.products *= f;
}

void ApplyGroundSpring(Model& model, const Effect& e) {
  const double k = Param(model, e, "k", false);
  const Body& b = EffectBody(model, e);
  static const char* kAxis[] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) {
    Spring s;
    s.name = "ground_spring:" + b.name + ":" + kAxis[i];
    s.group = "ground_spring";
    s.a.body = b.name;
    s.b.body = kGround;
    s.direction = Eigen::Vector3d::Unit(i);
    s.law = LinearLaw{k};
    s.line = e.line;
    model.springs.push_back(std::move(s));
  }
}

}  // namespace

const std::vector<EffectKindInfo>& EffectKindTable() {
  // Ranges: wide enough that physics does not reach them (a fit that reaches a far end is re-fitted
  // with the range widened there, diagnose/search.cpp); the priors, not the ranges, say what is
  // plausible. Priors: docs/diagnose.md.
  static const std::vector<EffectKindInfo> kTable = {
      {EffectKind::kSeriesCompliance, "series_compliance", "k", ActsOn::kSprings, true, 1e-4, 1e4, +1,
       PriorShape::kLogNormal, 1.5, "1σ of ln(k / the target's mean stiffness)",
       "a mount, joint or adhesive layer in series with the interface", ApplySeriesCompliance},
      {EffectKind::kStiffnessScale, "stiffness_scale", "factor", ActsOn::kSprings, true, 1e-3, 1e3, 0,
       PriorShape::kLogNormal, 0.5,
       "1σ of ln(factor); a spring's or part's `uncertainty` overrides it; beyond it a 2 % fault tail (1σ 3 in ln) "
       "keeps a part or joint grossly off in play",
       "the interface stiffness itself is mis-estimated", ApplyStiffnessScale},
      {EffectKind::kOperatingPoint, "operating_point", "value", ActsOn::kSprings, true, 0.05, 20.0, 0,
       PriorShape::kLogNormal, 0.5, "1σ of ln(value / nominal value)",
       "the gap, preload or setting differs from the nominal one", ApplyOperatingPoint},
      {EffectKind::kAddedMass, "added_mass", "mass", ActsOn::kPoints, false, 1e-5, 10.0, -1, PriorShape::kHalfNormal,
       0.02, "1σ of the mass per point, as a share of the model's mass", "sensor mass loading, cables, payload",
       ApplyAddedMass},
      {EffectKind::kMassScale, "mass_scale", "factor", ActsOn::kBody, false, 0.01, 100.0, 0, PriorShape::kLogNormal,
       0.05, "1σ of ln(factor); a body's `uncertainty` overrides it", "body mass or inertia mis-estimated",
       ApplyMassScale},
      {EffectKind::kGroundSpring, "ground_spring", "k", ActsOn::kBody, false, 1e-5, 1e4, -1, PriorShape::kLogNormal,
       3.0, "1σ of ln(k / 0.1 x the mean spring stiffness)", "the \"fixed\" support is flexible", ApplyGroundSpring},
  };
  return kTable;
}

const EffectKindInfo* FindEffectKind(const std::string& name) {
  for (const EffectKindInfo& info : EffectKindTable())
    if (name == info.name) return &info;
  return nullptr;
}

const EffectKindInfo& Info(EffectKind kind) {
  for (const EffectKindInfo& info : EffectKindTable())
    if (info.kind == kind) return info;
  throw std::logic_error("effect kind missing from EffectKindTable");
}

std::string KindName(EffectKind kind) { return Info(kind).name; }

const std::vector<std::string>& EffectKinds() {
  static const std::vector<std::string> kKinds = [] {
    std::vector<std::string> names;
    for (const EffectKindInfo& info : EffectKindTable()) names.push_back(info.name);
    return names;
  }();
  return kKinds;
}

Model ApplyEffect(const Model& input, const Effect& e) {
  Model model = input;
  Info(e.kind).apply(model, e);
  return model;
}

Model ApplyEffects(const Model& input) {
  Model model = input;
  model.effects.clear();
  for (const Effect& e : input.effects) model = ApplyEffect(model, e);
  return model;
}

std::vector<Effect> CandidateEffects(const Model& input) {
  const Model model = input.effects.empty() ? input : ApplyEffects(input);
  std::vector<Effect> out;
  // Nominal linearised stiffness per group, at the nominal operating point.
  std::vector<std::string> groups;
  std::map<std::string, std::pair<double, int>> k_sum;
  std::map<std::string, double> op_value;
  double all_k = 0.0;
  int all_n = 0;
  for (const Spring& s : model.springs) {
    if (!k_sum.count(s.group)) groups.push_back(s.group);
    const SpringState st = LinearizeLaw(s.law, model.Where(s.line) + ": spring '" + s.name + "'");
    auto& acc = k_sum[s.group];
    acc.first += st.stiffness * s.stiffness_factor;
    acc.second += 1;
    all_k += st.stiffness * s.stiffness_factor;
    ++all_n;
    if (s.law.IsNonlinear() && !op_value.count(s.group)) {
      double v = kNaN;
      if (const auto* ser = std::get_if<SeriesLaw>(&s.law.value)) {
        bool film = false;
        for (const Law& el : ser->elements) film |= std::holds_alternative<AirFilmLaw>(el.value);
        v = film ? ser->setting : ser->force.value_or(st.force);
      } else if (const auto* a = std::get_if<AirFilmLaw>(&s.law.value)) {
        v = a->operating_gap;
      } else if (const auto* t = std::get_if<TableLaw>(&s.law.value)) {
        v = (!t->operating_deflection && t->operating_force) ? *t->operating_force : st.deflection;
      } else if (const auto* h = std::get_if<HertzLaw>(&s.law.value)) {
        v = (!h->operating_deflection && h->operating_force) ? *h->operating_force : st.deflection;
      }
      op_value[s.group] = v;
    }
  }
  for (const std::string& g : groups) {
    const double k_mean = k_sum[g].second > 0 ? k_sum[g].first / k_sum[g].second : 0.0;
    const EffectTarget group = EffectTarget::Named(g);
    Effect sc{EffectKind::kSeriesCompliance, group, {}, Law(LinearLaw{k_mean > 0.0 ? k_mean : 1.0e6}), 0};
    out.push_back(sc);
    out.push_back(Effect{EffectKind::kStiffnessScale, group, {{"factor", 1.0}}, std::nullopt, 0});
    if (op_value.count(g))
      out.push_back(Effect{EffectKind::kOperatingPoint, group, {{"value", op_value[g]}}, std::nullopt, 0});
  }
  if (!model.points.empty())
    out.push_back(Effect{EffectKind::kAddedMass, EffectTarget::AllPoints(), {{"mass", 0.0}}, std::nullopt, 0});
  const double k_ground = all_n > 0 ? 1e-3 * all_k / all_n : 1.0e3;
  for (const Body& b : model.bodies)
    out.push_back(Effect{EffectKind::kMassScale, EffectTarget::Named(b.name), {{"factor", 1.0}}, std::nullopt, 0});
  for (const Body& b : model.bodies)
    out.push_back(Effect{EffectKind::kGroundSpring, EffectTarget::Named(b.name), {{"k", k_ground}}, std::nullopt, 0});
  return out;
}

std::string Describe(const Effect& e) {
  std::ostringstream s;
  s << KindName(e.kind) << " " << TargetText(e.target);
  for (const auto& [k, v] : e.parameters) s << " " << k << "=" << v;
  if (e.law) {
    s << " law=" << e.law->KindName();
    if (const auto* lin = std::get_if<LinearLaw>(&e.law->value)) s << "(k=" << lin->k << ")";
  }
  return s.str();
}


double OperatingValue(const Spring& s) {
  if (!s.law.IsNonlinear()) return std::numeric_limits<double>::quiet_NaN();
  const SpringState st = LinearizeLaw(s.law, "spring '" + s.name + "'");
  if (const auto* ser = std::get_if<SeriesLaw>(&s.law.value)) {
    bool film = false;
    for (const Law& el : ser->elements) film |= std::holds_alternative<AirFilmLaw>(el.value);
    return film ? ser->setting : ser->force.value_or(st.force);
  }
  if (const auto* a = std::get_if<AirFilmLaw>(&s.law.value)) return a->operating_gap;
  if (const auto* t = std::get_if<TableLaw>(&s.law.value))
    return (!t->operating_deflection && t->operating_force) ? *t->operating_force : st.deflection;
  if (const auto* h = std::get_if<HertzLaw>(&s.law.value))
    return (!h->operating_deflection && h->operating_force) ? *h->operating_force : st.deflection;
  return std::numeric_limits<double>::quiet_NaN();
}

namespace {

// Where a spring end sits, for "the same two points": body (or node) and position.
struct EndKey {
  std::string body;
  int node = 0;
  Eigen::Vector3d at = Eigen::Vector3d::Zero();
  bool Same(const EndKey& o) const {
    return body == o.body && node == o.node && (at - o.at).norm() <= 1e-9 * std::max(1.0, at.norm());
  }
};

EndKey EndOf(const Model& m, const Anchor& a, const Anchor* fallback) {
  EndKey k;
  k.body = a.body;
  k.node = a.node;
  if (a.IsNode()) return k;
  if (a.has_at) {
    k.at = a.at;
  } else if (fallback && fallback->has_at) {
    k.at = fallback->at;  // b.at defaults to a.at
  } else if (const Body* b = m.FindBody(a.body)) {
    k.at = b->centre;
  }
  return k;
}

std::string CommonPrefix(const std::vector<std::string>& names) {
  if (names.empty()) return "";
  std::string p = names.front();
  for (const std::string& n : names) {
    size_t i = 0;
    while (i < p.size() && i < n.size() && p[i] == n[i]) ++i;
    p.resize(i);
  }
  return p;
}

}  // namespace

std::vector<Member> Members(const Model& model) {
  std::vector<Member> out;
  std::vector<std::string> groups;
  for (const Spring& s : model.springs)
    if (std::find(groups.begin(), groups.end(), s.group) == groups.end()) groups.push_back(s.group);
  for (const std::string& g : groups) {
    // Explicit members first by name, then implicit ones by their two ends.
    std::vector<Member> members;
    std::vector<std::pair<EndKey, EndKey>> keys;
    std::vector<bool> explicit_name;
    for (size_t i = 0; i < model.springs.size(); ++i) {
      const Spring& s = model.springs[i];
      if (s.group != g) continue;
      if (!s.member.empty()) {
        auto it = std::find_if(members.begin(), members.end(), [&](const Member& m) { return m.name == s.member; });
        size_t at = static_cast<size_t>(it - members.begin());
        for (size_t j = 0; j < members.size(); ++j)
          if (explicit_name[j] && members[j].name == s.member) at = j;
        if (at < members.size() && explicit_name[at]) {
          members[at].springs.push_back(static_cast<int>(i));
        } else {
          members.push_back({g, s.member, {static_cast<int>(i)}});
          keys.push_back({});
          explicit_name.push_back(true);
        }
        continue;
      }
      const EndKey a = EndOf(model, s.a, nullptr), b = EndOf(model, s.b, &s.a);
      size_t at = members.size();
      for (size_t j = 0; j < members.size(); ++j)
        if (!explicit_name[j] && keys[j].first.Same(a) && keys[j].second.Same(b)) at = j;
      if (at < members.size()) {
        members[at].springs.push_back(static_cast<int>(i));
      } else {
        members.push_back({g, "", {static_cast<int>(i)}});
        keys.push_back({a, b});
        explicit_name.push_back(false);
      }
    }
    // Names of implicit members: the longest common prefix, or the first spring's name when
    // they share none or the prefix is not unique in the group.
    std::vector<std::string> prefix(members.size());
    for (size_t j = 0; j < members.size(); ++j) {
      if (explicit_name[j]) continue;
      std::vector<std::string> names;
      for (int i : members[j].springs) names.push_back(model.springs[i].name);
      prefix[j] = names.size() > 1 ? CommonPrefix(names) : names.front();
    }
    for (size_t j = 0; j < members.size(); ++j) {
      if (explicit_name[j]) continue;
      bool unique = !prefix[j].empty();
      for (size_t o = 0; o < members.size() && unique; ++o)
        if (o != j && (explicit_name[o] ? members[o].name : prefix[o]) == prefix[j]) unique = false;
      members[j].name = unique ? prefix[j] : model.springs[members[j].springs.front()].name;
    }
    for (Member& m : members) out.push_back(std::move(m));
  }
  return out;
}

std::vector<int> TargetPoints(const Model& model, const Effect& e) {
  std::vector<int> targets;
  if (e.target.form == EffectTarget::Form::kAllPoints) {
    for (std::size_t i = 0; i < model.points.size(); ++i) targets.push_back(static_cast<int>(i));
    if (targets.empty()) throw InputError(Where(model, e), "the model has no [[point]]");
  } else if (e.target.form == EffectTarget::Form::kPoints) {
    for (int id : e.target.points) {
      int found = -1;
      for (std::size_t i = 0; i < model.points.size(); ++i)
        if (model.points[i].id == id) found = static_cast<int>(i);
      if (found < 0) throw InputError(Where(model, e), "no test point " + std::to_string(id));
      targets.push_back(found);
    }
  } else {
    throw InputError(Where(model, e), "target must be 'all_points' or 'points:101,102'");
  }
  return targets;
}

std::vector<int> TargetSprings(const Model& model, const EffectTarget& target) {
  std::vector<int> out;
  if (target.form == EffectTarget::Form::kName) {
    for (size_t i = 0; i < model.springs.size(); ++i)
      if (model.springs[i].group == target.name) out.push_back(static_cast<int>(i));
  } else if (target.form == EffectTarget::Form::kMember) {
    for (const Member& m : Members(model))
      if (m.group == target.name && m.name == target.member) return m.springs;
  }
  return out;
}

std::vector<int> TargetParts(const Model& model, const EffectTarget& target) {
  std::vector<int> out;
  const auto& parts = model.fe.parts;
  for (size_t i = 0; i < parts.size(); ++i) {
    const FePart& p = parts[i];
    const bool named = target.form == EffectTarget::Form::kName &&
                       (p.group == target.name || (p.group.empty() && p.name == target.name));
    if (named || (target.form == EffectTarget::Form::kMember && p.Target() == target))
      out.push_back(static_cast<int>(i));
  }
  return out;
}

const Body* TargetBody(const Model& model, const EffectTarget& target) {
  return target.form == EffectTarget::Form::kName ? model.FindBody(target.name) : nullptr;
}

}  // namespace ema::model
