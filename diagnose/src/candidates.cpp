// Stage 1, candidates: every kind of the vocabulary (model::EffectKindTable) on every target it
// applies to — spring groups and their members, all points and single points, bodies — each
// with its parameter's mapping, range and prior.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>

#include "ema/core/error.hpp"
#include "ema/model/solve.hpp"
#include "internal.hpp"

namespace ema::diagnose::detail {
namespace {

using model::EffectKind;

// Radius of the Hertz series element: only E'·sqrt(R') is identifiable from stiffness, so R' is
// fixed (1 mm, a ball-joint scale) and the modulus is fitted.
constexpr double kHertzRadius = 1e-3;
constexpr double kHertzModulus = 1e10;  // reference (prior centre) of the fitted modulus, Pa

double TotalMass(const model::Model& m) {
  double total = 0.0;
  for (const auto& b : m.bodies) total += b.mass;
  for (const auto& p : m.masses) total += p.mass;
  if (!m.fe.Empty()) {
    // FE: the kinetic energy of a unit rigid translation, rᵀ M r with r = 1 on every DOF of one
    // direction — the mass exactly, for lumped and consistent matrices alike ([fe] and parts),
    // from the direction that carries the most.
    double per_direction[3] = {0.0, 0.0, 0.0};
    auto add = [&](const Eigen::SparseMatrix<double>& a, double factor) {
      for (int c = 0; c < a.outerSize(); ++c)
        for (Eigen::SparseMatrix<double>::InnerIterator it(a, c); it; ++it) {
          const int dr = m.fe.dofs[static_cast<size_t>(it.row())].dof, dc = m.fe.dofs[static_cast<size_t>(it.col())].dof;
          if (dr == dc && dr <= 3) per_direction[dr - 1] += factor * it.value();
        }
    };
    add(m.fe.mass, 1.0);
    for (const auto& part : m.fe.parts)
      if (part.mass) add(*part.mass, part.mass_factor);
    total += std::max({per_direction[0], per_direction[1], per_direction[2]});
  }
  return total > 0.0 ? total : 1.0;
}

// True when every spring of the set carries an air film's load (a lone film or a chain with
// one), so that an added series element has a defined force at its operating point.
bool CarriesFilmLoad(const model::Model& m, const std::vector<int>& springs) {
  bool any = false;
  for (int i : springs) {
    const auto& spring = m.springs[i];
    bool film = std::holds_alternative<model::AirFilmLaw>(spring.law.value);
    if (const auto* chain = std::get_if<model::SeriesLaw>(&spring.law.value))
      for (const auto& el : chain->elements) film |= std::holds_alternative<model::AirFilmLaw>(el.value);
    if (!film) return false;
    any = true;
  }
  return any;
}

struct SpringSet {
  model::EffectTarget target;
  std::string group;
  std::vector<int> springs;
  bool member = false;
};

double PriorSigma(const model::Model& m, EffectKind kind, double item_sigma) {
  if (std::isfinite(item_sigma)) return item_sigma;
  const auto it = m.priors.find(kind);
  return it != m.priors.end() ? it->second : model::Info(kind).prior_sigma;
}

Atom MakeAtom(const model::Model& m, EffectKind kind, const model::EffectTarget& target, double ref,
              double item_sigma) {
  using Form = model::EffectTarget::Form;
  const model::EffectKindInfo& info = model::Info(kind);
  Atom a;
  a.info = &info;
  a.effect = model::Effect{kind, target, {}, std::nullopt, 0};
  if (target.form == Form::kAllPoints) {
    a.words = "all points";
  } else if (target.form == Form::kPoints) {
    a.words = "point";
    for (size_t i = 0; i < target.points.size(); ++i) a.words += (i ? "," : " ") + std::to_string(target.points[i]);
  } else if (info.acts_on == model::ActsOn::kBody) {
    a.words = "body '" + model::TargetText(target) + "'";
  } else if (target.form == Form::kMember) {
    a.words = "member '" + target.member + "' of group '" + target.name + "'";
  } else {
    a.words = "group '" + model::TargetText(target) + "'";
  }
  a.spec = {info.parameter, ref, 1.0, true, std::log(info.range_low), std::log(info.range_high), info.absent_end};
  a.prior.shape = info.prior_shape;
  a.prior.sigma = PriorSigma(m, kind, item_sigma);
  a.prior.relative_sigma = a.prior.sigma;
  if (info.prior_shape == model::PriorShape::kHalfNormal) a.prior.sigma *= TotalMass(m);
  return a;
}

}  // namespace

double ParamSpec::Value(double theta) const { return log ? ref * std::exp(theta) : ref + scale * theta; }
double ParamSpec::Derivative(double theta) const { return log ? ref * std::exp(theta) : scale; }
double ParamSpec::Theta(double value) const { return log ? std::log(value / ref) : (value - ref) / scale; }

namespace {
constexpr double kLogSqrt2Pi = 0.91893853320467274;

// log of (1 − ε)·N(d; 0, σ²) + ε·N(d; 0, σ_t²), and the core's share of it at d.
std::pair<double, double> MixtureLogDensity(double d, double sigma, double share, double tail_sigma) {
  const double core = std::log1p(-share) - 0.5 * (d / sigma) * (d / sigma) - std::log(sigma) - kLogSqrt2Pi;
  if (!(share > 0.0)) return {core, 1.0};
  const double tail = std::log(share) - 0.5 * (d / tail_sigma) * (d / tail_sigma) - std::log(tail_sigma) - kLogSqrt2Pi;
  const double top = std::max(core, tail);
  const double total = top + std::log(std::exp(core - top) + std::exp(tail - top));
  return {total, std::exp(core - total)};
}
}  // namespace

double Prior::LogDensity(double theta, const ParamSpec& spec) const {
  if (shape == model::PriorShape::kLogNormal) return MixtureLogDensity(theta - centre, sigma, tail_share, tail_sigma).first;
  const double v = spec.Value(theta);
  return std::log(2.0) - 0.5 * (v / sigma) * (v / sigma) - std::log(sigma) - kLogSqrt2Pi +
         std::log(std::abs(spec.Derivative(theta)));
}

double Prior::Curvature(double theta, const ParamSpec& spec) const {
  if (shape == model::PriorShape::kLogNormal) {
    if (!(tail_share > 0.0)) return 1.0 / (sigma * sigma);
    // −d²/dθ² of the mixture's log: w/σ² + (1−w)/σ_t² − w(1−w)(d/σ² − d/σ_t²)², w the core's
    // share at d. Between the two components it is negative, and a Laplace evidence taken there
    // with a Hessian the data leave flat in some direction is unbounded (a spurious third member
    // at "99.9 %", benchmark case 159): it is floored at the tail's own 1/σ_t², the evidence of
    // the tail component alone, which never counts more than the tail's share ε of the prior.
    const double d = theta - centre;
    const double w = MixtureLogDensity(d, sigma, tail_share, tail_sigma).second;
    const double a = 1.0 / (sigma * sigma), b = 1.0 / (tail_sigma * tail_sigma);
    return std::max(b, w * a + (1.0 - w) * b - w * (1.0 - w) * (d * a - d * b) * (d * a - d * b));
  }
  const double v = spec.Value(theta);
  // −d²/dθ² of −½ v²/σ² (+ θ, the log Jacobian): 2v²/σ² for v = ref·e^θ, scale²/σ² for linear.
  return spec.log ? 2.0 * v * v / (sigma * sigma) : spec.scale * spec.scale / (sigma * sigma);
}

double Prior::Residual(double theta, const ParamSpec& spec) const {
  if (shape == model::PriorShape::kLogNormal) {
    if (!(tail_share > 0.0)) return (theta - centre) / sigma;
    // ½ r² = log p(centre) − log p(θ): the MAP fit minimises the same objective.
    const double d = theta - centre;
    const double drop = MixtureLogDensity(0.0, sigma, tail_share, tail_sigma).first -
                        MixtureLogDensity(d, sigma, tail_share, tail_sigma).first;
    return std::copysign(std::sqrt(2.0 * std::max(0.0, drop)), d);
  }
  return spec.Value(theta) / sigma;
}

model::Effect Atom::With(double theta) const {
  model::Effect e = effect;
  const double v = spec.Value(theta);
  if (info->kind == EffectKind::kSeriesCompliance && hertz) {
    model::HertzLaw law;
    law.modulus = v;
    law.radius = kHertzRadius;
    e.law = model::Law(law);
  } else if (info->kind == EffectKind::kSeriesCompliance) {
    e.law = model::Law(model::LinearLaw{v});
  } else {
    e.parameters[spec.name] = v;
  }
  return e;
}

std::string Atom::Label() const {
  return model::KindName(effect.kind) + (hertz ? " (hertz)" : "") + " of '" + model::TargetText(effect.target) + "'";
}

std::vector<Atom> BuildAtoms(const model::Model& base, const DiagnoseOptions& options) {
  std::vector<Atom> atoms;
  // Linearised stiffness of every spring at the nominal operating point.
  std::vector<double> k(base.springs.size());
  double k_all = 0.0;
  for (size_t i = 0; i < base.springs.size(); ++i) {
    const auto& s = base.springs[i];
    k[i] = model::LinearizeLaw(s.law, base.Where(s.line) + ": spring '" + s.name + "'").stiffness * s.stiffness_factor;
    k_all += k[i];
  }
  const double k_mean_all = base.springs.empty() ? 1e6 : k_all / base.springs.size();

  // Spring targets: each group, then (with members) each member of a group with ≥ 2 members.
  std::vector<SpringSet> sets;
  std::vector<std::string> groups;
  for (const auto& s : base.springs)
    if (std::find(groups.begin(), groups.end(), s.group) == groups.end()) groups.push_back(s.group);
  const std::vector<model::Member> members = model::Members(base);
  for (const std::string& g : groups) {
    const model::EffectTarget group = model::EffectTarget::Named(g);
    sets.push_back({group, g, model::TargetSprings(base, group), false});
    std::vector<const model::Member*> of_group;
    for (const auto& mem : members)
      if (mem.group == g) of_group.push_back(&mem);
    if (options.members && of_group.size() >= 2)
      for (const model::Member* mem : of_group) sets.push_back({mem->Target(), g, mem->springs, true});
  }
  for (const SpringSet& set : sets) {
    double k_sum = 0.0, sigma = kNaN;
    bool nonlinear = false, all_linear_equal = true;
    double op = kNaN;
    for (int i : set.springs) {
      const auto& s = base.springs[i];
      k_sum += k[i];
      if (std::isfinite(s.uncertainty)) sigma = std::isfinite(sigma) ? std::max(sigma, s.uncertainty) : s.uncertainty;
      if (s.law.IsNonlinear()) {
        nonlinear = true;
        if (!std::isfinite(op)) op = model::OperatingValue(s);
      }
      const auto* lin = std::get_if<model::LinearLaw>(&s.law.value);
      if (!lin || std::abs(k[i] - k[set.springs.front()]) > 1e-9 * std::abs(k[i])) all_linear_equal = false;
    }
    const double k_mean = k_sum > 0.0 ? k_sum / set.springs.size() : 1e6;
    // A series element on linear springs of one stiffness is exactly a stiffness factor < 1:
    // the simpler reading (stiffness_scale) stands for both.
    if (!all_linear_equal) {
      Atom a = MakeAtom(base, EffectKind::kSeriesCompliance, set.target, k_mean, kNaN);
      a.member = set.member;
      a.group = set.group;
      atoms.push_back(a);
      // A series element in an air-film chain carries the film's load, so it may as well be a
      // non-linear contact (a ball joint, thesis §7.2.4): its stiffness then differs between
      // stud settings in a way no linear element reproduces.
      if (!set.member && CarriesFilmLoad(base, set.springs)) {
        Atom h = a;
        h.hertz = true;
        h.spec = {"modulus", kHertzModulus, 1.0, true, std::log(1e-3), std::log(1e3), +1};
        h.prior.sigma = 3.0;
        h.prior.relative_sigma = 3.0;
        atoms.push_back(h);
      }
    }
    Atom sc = MakeAtom(base, EffectKind::kStiffnessScale, set.target, 1.0, sigma);
    sc.member = set.member;
    sc.group = set.group;
    atoms.push_back(sc);
    if (nonlinear && std::isfinite(op)) {
      Atom o = MakeAtom(base, EffectKind::kOperatingPoint, set.target, op, kNaN);
      if (!(op > 0.0)) {
        o.spec.log = false;
        o.spec.scale = std::max(std::abs(op), 1e-6);
        o.spec.lo = -10.0;
        o.spec.hi = 10.0;
      }
      o.member = set.member;
      o.group = set.group;
      atoms.push_back(o);
    }
  }
  // FE parts (model-format.md "FE models built from parts"): each part group and each part in no
  // group, then (with members) each member of a group of ≥ 2: stiffness_scale, and mass_scale
  // where the parts carry mass (groups and lone parts only).
  {
    const auto& parts = base.fe.parts;
    std::vector<std::string> part_targets;
    for (const auto& p : parts) {
      const std::string t = p.group.empty() ? p.name : p.group;
      if (std::find(part_targets.begin(), part_targets.end(), t) == part_targets.end()) part_targets.push_back(t);
    }
    auto add_part_atoms = [&](const model::EffectTarget& target, const std::string& group, bool member) {
      double sigma = kNaN;
      bool stiffness = false, mass = false;
      for (int i : model::TargetParts(base, target)) {
        const auto& p = parts[static_cast<size_t>(i)];
        if (std::isfinite(p.uncertainty)) sigma = std::isfinite(sigma) ? std::max(sigma, p.uncertainty) : p.uncertainty;
        stiffness |= p.HasStiffness();
        mass |= p.HasMass();
      }
      const std::string words =
          target.form == model::EffectTarget::Form::kMember
              ? "member '" + target.member + "' of part group '" + group + "'"
              : (parts[static_cast<size_t>(model::TargetParts(base, target).front())].group.empty()
                     ? "part '" + target.name + "'"
                     : "part group '" + target.name + "'");
      if (stiffness) {
        Atom a = MakeAtom(base, EffectKind::kStiffnessScale, target, 1.0, sigma);
        a.words = words;
        a.member = member;
        a.group = group;
        a.part = true;
        atoms.push_back(a);
      }
      if (mass && !member) {
        Atom a = MakeAtom(base, EffectKind::kMassScale, target, 1.0, kNaN);
        a.words = words;
        a.group = group;
        a.part = true;
        atoms.push_back(a);
      }
    };
    for (const std::string& t : part_targets) {
      add_part_atoms(model::EffectTarget::Named(t), t, false);
      const std::vector<int> of_group = model::TargetParts(base, model::EffectTarget::Named(t));
      if (options.members && of_group.size() >= 2 && !parts[static_cast<size_t>(of_group.front())].group.empty())
        for (int i : of_group) add_part_atoms(parts[static_cast<size_t>(i)].Target(), t, true);
    }
  }
  // Points: all together, then (with members) one by one.
  if (!base.points.empty()) {
    const double per_point = TotalMass(base) / base.points.size();
    atoms.push_back(MakeAtom(base, EffectKind::kAddedMass, model::EffectTarget::AllPoints(), per_point, kNaN));
    if (options.members && base.points.size() >= 2)
      for (const auto& p : base.points) {
        Atom a = MakeAtom(base, EffectKind::kAddedMass, model::EffectTarget::Points({p.id}), per_point, kNaN);
        a.member = true;
        atoms.push_back(a);
      }
  }
  // Bodies.
  for (const auto& b : base.bodies)
    atoms.push_back(MakeAtom(base, EffectKind::kMassScale, model::EffectTarget::Named(b.name), 1.0, b.uncertainty));
  for (const auto& b : base.bodies)
    atoms.push_back(
        MakeAtom(base, EffectKind::kGroundSpring, model::EffectTarget::Named(b.name), 0.1 * k_mean_all, kNaN));
  // Stiffnesses fail grossly (a loose bolt, a cracked weld, rubber for a rated mount); masses are
  // weighed. Only stiffness factors carry the fault tail.
  for (Atom& a : atoms)
    if (a.info->kind == EffectKind::kStiffnessScale) {
      // The model file's [priors] states the tail where the engineer knows better than the default.
      a.prior.tail_share = base.stiffness_fault_share.value_or(options.stiffness_fault_share);
      a.prior.tail_sigma = base.stiffness_fault_width.value_or(options.stiffness_fault_sigma);
    }
  return atoms;
}

}  // namespace ema::diagnose::detail
