// The effects of the vocabulary (model-format.md "Effects") as transformations of a Model.
#include "ema/model/effects.hpp"

#include <cmath>
#include <set>
#include <sstream>

#include "ema/core/error.hpp"
#include "ema/model/solve.hpp"

namespace ema::model {
namespace {

std::string Where(const Model& model, const Effect& e) {
  return model.Where(e.line) + ": effect " + e.kind + " '" + e.target + "'";
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

std::vector<Spring*> GroupSprings(Model& model, const Effect& e) {
  std::vector<Spring*> out;
  std::set<std::string> groups;
  for (Spring& s : model.springs) {
    groups.insert(s.group);
    if (s.group == e.target) out.push_back(&s);
  }
  if (out.empty()) {
    std::string known;
    for (const auto& g : groups) known += (known.empty() ? "" : ", ") + g;
    throw InputError(Where(model, e), "no spring group '" + e.target + "' (groups: " + (known.empty() ? "none" : known) + ")");
  }
  return out;
}

Body& TargetBody(Model& model, const Effect& e) {
  Body* b = model.FindBody(e.target);
  if (!b) {
    std::string known;
    for (const Body& x : model.bodies) known += (known.empty() ? "" : ", ") + x.name;
    throw InputError(Where(model, e), "no body '" + e.target + "' (bodies: " + (known.empty() ? "none" : known) + ")");
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

}  // namespace

const std::vector<std::string>& EffectKinds() {
  static const std::vector<std::string> kKinds = {"series_compliance", "stiffness_scale", "operating_point",
                                                  "added_mass",        "mass_scale",      "ground_spring"};
  return kKinds;
}

Model ApplyEffect(const Model& input, const Effect& e) {
  Model model = input;
  if (e.kind == "series_compliance") {
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
  } else if (e.kind == "stiffness_scale") {
    const double f = Param(model, e, "factor", true);
    for (Spring* s : GroupSprings(model, e)) s->stiffness_factor *= f;
  } else if (e.kind == "operating_point") {
    auto it = e.parameters.find("value");
    if (it == e.parameters.end() || !std::isfinite(it->second)) throw InputError(Where(model, e), "missing parameter 'value'");
    bool any = false;
    for (Spring* s : GroupSprings(model, e)) any |= SetOperatingValue(s->law, it->second);
    if (!any) throw InputError(Where(model, e), "group '" + e.target + "' has only linear laws; no operating point to change");
  } else if (e.kind == "added_mass") {
    const double m = Param(model, e, "mass", false);
    std::vector<const TestPoint*> targets;
    if (e.target == "all_points") {
      for (const TestPoint& p : model.points) targets.push_back(&p);
      if (targets.empty()) throw InputError(Where(model, e), "the model has no [[point]]");
    } else if (e.target.rfind("points:", 0) == 0) {
      std::stringstream list(e.target.substr(7));
      std::string item;
      while (std::getline(list, item, ',')) {
        int id = 0;
        try {
          std::size_t used = 0;
          id = std::stoi(item, &used);
          if (item.find_first_not_of(" ", used) != std::string::npos) throw std::invalid_argument(item);
        } catch (const std::exception&) {
          throw InputError(Where(model, e), "bad point id '" + item + "' (expected points:101,102)");
        }
        const TestPoint* found = nullptr;
        for (const TestPoint& p : model.points)
          if (p.id == id) found = &p;
        if (!found) throw InputError(Where(model, e), "no test point " + std::to_string(id));
        targets.push_back(found);
      }
    } else {
      throw InputError(Where(model, e), "target must be 'all_points' or 'points:101,102'");
    }
    std::vector<PointMass> added;
    for (const TestPoint* p : targets) added.push_back({"added_mass@" + std::to_string(p->id), p->where, m, e.line});
    model.masses.insert(model.masses.end(), added.begin(), added.end());
  } else if (e.kind == "mass_scale") {
    const double f = Param(model, e, "factor", true);
    Body& b = TargetBody(model, e);
    b.mass *= f;
    b.inertia *= f;
    b.products *= f;
  } else if (e.kind == "ground_spring") {
    const double k = Param(model, e, "k", false);
    const Body& b = TargetBody(model, e);
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
  } else {
    std::string kinds;
    for (const auto& k : EffectKinds()) kinds += (kinds.empty() ? "" : ", ") + k;
    throw InputError(Where(model, e), "unknown effect kind (allowed: " + kinds + ")");
  }
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
    Effect sc{"series_compliance", g, {}, Law(LinearLaw{k_mean > 0.0 ? k_mean : 1.0e6}), 0};
    out.push_back(sc);
    out.push_back(Effect{"stiffness_scale", g, {{"factor", 1.0}}, std::nullopt, 0});
    if (op_value.count(g)) out.push_back(Effect{"operating_point", g, {{"value", op_value[g]}}, std::nullopt, 0});
  }
  if (!model.points.empty()) out.push_back(Effect{"added_mass", "all_points", {{"mass", 0.0}}, std::nullopt, 0});
  const double k_ground = all_n > 0 ? 1e-3 * all_k / all_n : 1.0e3;
  for (const Body& b : model.bodies) out.push_back(Effect{"mass_scale", b.name, {{"factor", 1.0}}, std::nullopt, 0});
  for (const Body& b : model.bodies) out.push_back(Effect{"ground_spring", b.name, {{"k", k_ground}}, std::nullopt, 0});
  return out;
}

std::string Describe(const Effect& e) {
  std::ostringstream s;
  s << e.kind << " " << e.target;
  for (const auto& [k, v] : e.parameters) s << " " << k << "=" << v;
  if (e.law) {
    s << " law=" << e.law->KindName();
    if (const auto* lin = std::get_if<LinearLaw>(&e.law->value)) s << "(k=" << lin->k << ")";
  }
  return s.str();
}

}  // namespace ema::model
