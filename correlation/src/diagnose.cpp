#include "ema/correlation/diagnose.hpp"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <map>
#include <memory>
#include <set>
#include <sstream>

#include "ema/core/error.hpp"
#include "ema/correlation/mac.hpp"
#include "ema/model/effects.hpp"
#include "ema/model/solve.hpp"

namespace ema::correlation {
namespace {

// Ceres' numeric step is relative to |x|; parameters are stored as x = θ + kOffset so that the
// step (1e-4 |x| ≈ 1e-3 in θ, a 0.1 % change of the physical parameter) stays well above the
// noise of the model's own root finders, whatever θ is.
constexpr double kOffset = 10.0;
constexpr double kRelativeStep = 1e-4;

// How one effect's single free parameter maps to θ: value = ref·e^θ (log) or ref + scale·θ.
struct ParamSpec {
  std::string name;
  double ref = 1.0;
  double scale = 1.0;
  bool log = true;
  double lo = -1.0, hi = 1.0;  // θ bounds
  int absent_end = 0;          // -1: the lower bound means "no effect", +1: the upper, 0: none

  double Value(double theta) const { return log ? ref * std::exp(theta) : ref + scale * theta; }
  double Derivative(double theta) const { return log ? ref * std::exp(theta) : scale; }
  double Theta(double value) const { return log ? std::log(value / ref) : (value - ref) / scale; }
};

struct EffectTemplate {
  model::Effect effect;
  ParamSpec spec;
  bool hertz = false;  // series_compliance fitted as a Hertz contact (modulus free, radius fixed)
};

// Radius of the Hertz series element: only E'·sqrt(R') is identifiable from stiffness, so R'
// is fixed (1 mm, a ball-joint scale) and the modulus is fitted.
constexpr double kHertzRadius = 1e-3;

model::Effect WithParameter(const EffectTemplate& t, double theta) {
  model::Effect e = t.effect;
  const double v = t.spec.Value(theta);
  if (e.kind == "series_compliance" && t.hertz) {
    model::HertzLaw hertz;
    hertz.modulus = v;
    hertz.radius = kHertzRadius;
    e.law = model::Law(hertz);
  } else if (e.kind == "series_compliance") {
    e.law = model::Law(model::LinearLaw{v});
  } else {
    e.parameters[t.spec.name] = v;
  }
  return e;
}

double TotalMass(const model::Model& m) {
  double total = 0.0;
  for (const auto& b : m.bodies) total += b.mass;
  for (const auto& p : m.masses) total += p.mass;
  return total > 0.0 ? total : 1.0;
}

// Parameter ranges per kind (wide, so that a true effect never sits on a bound).
std::optional<EffectTemplate> MakeTemplate(const model::Effect& e, const model::Model& m) {
  EffectTemplate t{e, {}, false};
  ParamSpec& s = t.spec;
  if (e.kind == "series_compliance") {
    double k0 = 1e6;
    if (e.law)
      if (const auto* lin = std::get_if<model::LinearLaw>(&e.law->value)) k0 = lin->k;
    s = {"k", k0, 1.0, true, std::log(1e-3), std::log(1e3), +1};
  } else if (e.kind == "stiffness_scale") {
    s = {"factor", 1.0, 1.0, true, std::log(0.02), std::log(50.0), 0};
  } else if (e.kind == "operating_point") {
    const auto it = e.parameters.find("value");
    const double v0 = it == e.parameters.end() ? kNaN : it->second;
    if (!std::isfinite(v0)) return std::nullopt;
    if (v0 > 0.0) {
      s = {"value", v0, 1.0, true, std::log(0.1), std::log(10.0), 0};
    } else {
      const double scale = std::max(std::abs(v0), 1e-6);
      s = {"value", v0, scale, false, -10.0, 10.0, 0};
    }
  } else if (e.kind == "added_mass") {
    // Per point, relative to the model's mass per test point.
    const double per_point = TotalMass(m) / std::max<size_t>(1, m.points.size());
    s = {"mass", per_point, 1.0, true, std::log(1e-5), std::log(1.0), -1};
  } else if (e.kind == "mass_scale") {
    s = {"factor", 1.0, 1.0, true, std::log(0.1), std::log(10.0), 0};
  } else if (e.kind == "ground_spring") {
    const auto it = e.parameters.find("k");
    const double k0 = it == e.parameters.end() || it->second <= 0.0 ? 1e3 : it->second;
    s = {"k", k0, 1.0, true, std::log(1e-3), std::log(1e6), -1};
  } else {
    return std::nullopt;
  }
  return t;
}

// True when every spring of the group carries an air film's load (a lone film or a chain with
// one), so that an added series element has a defined force at its operating point.
bool GroupCarriesFilmLoad(const model::Model& m, const std::string& group) {
  bool any = false;
  for (const auto& spring : m.springs) {
    if (spring.group != group) continue;
    bool film = std::holds_alternative<model::AirFilmLaw>(spring.law.value);
    if (const auto* chain = std::get_if<model::SeriesLaw>(&spring.law.value))
      for (const auto& el : chain->elements) film |= std::holds_alternative<model::AirFilmLaw>(el.value);
    if (!film) return false;
    any = true;
  }
  return any;
}

// Per setup: the test data restricted to the DOFs the model observes.
struct SetupData {
  std::string name;
  DofMatch match;
  Eigen::MatrixXcd test_shapes;
  Eigen::VectorXd test_hz;
  size_t model_dof_count = 0;
};

struct Evaluation {
  bool ok = false;
  std::string error;
  Eigen::VectorXd r;  // 2 per test mode (frequency, shape), setups in order
  std::vector<ModeComparison> modes;
  double mean_abs_frequency_error_pct = kNaN;
  double mean_mac = kNaN;
  int paired = 0;
};

class Evaluator {
 public:
  Evaluator(const model::Model& base, std::vector<SetupData> setups, const DiagnoseOptions& options, int max_modes)
      : base_(base), setups_(std::move(setups)), options_(options), max_modes_(max_modes) {
    for (const auto& s : setups_) residual_count_ += 2 * static_cast<int>(s.test_hz.size());
  }

  int ResidualCount() const { return residual_count_; }
  int Solves() const { return solves_; }

  Evaluation Evaluate(const std::vector<model::Effect>& effects) {
    Evaluation out;
    out.r.resize(residual_count_);
    try {
      model::Model m = base_;
      for (const auto& e : effects) m = model::ApplyEffect(m, e);
      int row = 0;
      double sum_err = 0.0, sum_mac = 0.0;
      for (const SetupData& s : setups_) {
        model::SolveOptions so;
        so.setup = s.name;
        so.max_modes = max_modes_;
        const model::Solution sol = model::Solve(m, so);
        ++solves_;
        if (sol.modes.dofs.size() != s.model_dof_count)
          throw InputError(base_.origin, "the model's observed DOFs changed while fitting");
        if (sol.modes.modes.empty()) throw InputError(base_.origin, "the model has no elastic mode");
        const Eigen::MatrixXcd model_shapes = s.match.ModelShapes(sol.modes);
        Eigen::VectorXd model_hz(sol.modes.modes.size());
        for (size_t j = 0; j < sol.modes.modes.size(); ++j) model_hz(j) = sol.modes.modes[j].frequency_hz;
        const Eigen::MatrixXd mac = MacMatrix(s.test_shapes, model_shapes);
        const Pairing pairing = PairModes(mac, s.test_hz, model_hz, options_.pairing);
        std::vector<int> partner(s.test_hz.size(), -1);
        for (const ModePair& p : pairing.pairs) partner[p.test] = p.model;
        for (Eigen::Index i = 0; i < s.test_hz.size(); ++i) {
          ModeComparison c;
          c.setup = s.name;
          c.test_mode = static_cast<int>(i);
          c.test_frequency_hz = s.test_hz(i);
          const int j = partner[i];
          if (j >= 0) {
            c.model_mode = j;
            c.model_frequency_hz = model_hz(j);
            c.agreement_pct = AgreementPct(model_hz(j), s.test_hz(i));
            c.mac = mac(i, j);
            out.r(row) = options_.frequency_weight * (model_hz(j) - s.test_hz(i)) / s.test_hz(i);
            out.r(row + 1) = options_.shape_weight * (1.0 - mac(i, j));
            sum_err += 100.0 * std::abs(model_hz(j) - s.test_hz(i)) / s.test_hz(i);
            sum_mac += mac(i, j);
            ++out.paired;
          } else {
            out.r(row) = options_.frequency_weight * options_.unpaired_frequency_residual;
            out.r(row + 1) = options_.shape_weight;
          }
          row += 2;
          out.modes.push_back(c);
        }
      }
      if (out.paired > 0) {
        out.mean_abs_frequency_error_pct = sum_err / out.paired;
        out.mean_mac = sum_mac / out.paired;
      }
      out.ok = true;
    } catch (const std::exception& e) {
      out.ok = false;
      out.error = e.what();
    }
    return out;
  }

 private:
  const model::Model& base_;
  std::vector<SetupData> setups_;
  const DiagnoseOptions& options_;
  int max_modes_ = 0;
  int residual_count_ = 0;
  int solves_ = 0;
};

// Huber cost of one mode's residual pair (s = squared norm), as Ceres' HuberLoss(a):
// s for s ≤ a², 2a√s − a² beyond.
double Huber(double s, double a) { return s <= a * a ? s : 2.0 * a * std::sqrt(s) - a * a; }

double RobustCost(const Eigen::VectorXd& r, double a) {
  double cost = 0.0;
  for (Eigen::Index i = 0; i + 1 < r.size(); i += 2) cost += Huber(r(i) * r(i) + r(i + 1) * r(i + 1), a);
  return cost;
}

// Evaluations of one candidate, cached by parameter vector: Ceres evaluates every mode's
// residual block at the same points, and each point costs one model solve per setup.
class CandidateFunction {
 public:
  CandidateFunction(Evaluator* evaluator, std::vector<EffectTemplate> templates)
      : evaluator_(evaluator), templates_(std::move(templates)) {}

  int Size() const { return static_cast<int>(templates_.size()); }
  const std::vector<EffectTemplate>& Templates() const { return templates_; }

  std::vector<model::Effect> Effects(const std::vector<double>& theta) const {
    std::vector<model::Effect> effects;
    for (size_t k = 0; k < templates_.size(); ++k) effects.push_back(WithParameter(templates_[k], theta[k]));
    return effects;
  }

  std::shared_ptr<const Evaluation> At(const std::vector<double>& theta) {
    for (const auto& [key, value] : cache_)
      if (key == theta) return value;
    auto value = std::make_shared<const Evaluation>(evaluator_->Evaluate(Effects(theta)));
    cache_.emplace_back(theta, value);
    if (cache_.size() > 16) cache_.pop_front();
    return value;
  }

 private:
  Evaluator* evaluator_;
  std::vector<EffectTemplate> templates_;
  std::deque<std::pair<std::vector<double>, std::shared_ptr<const Evaluation>>> cache_;
};

struct ModeBlock {
  CandidateFunction* function;
  int index;
  bool operator()(double const* const* parameters, double* residuals) const {
    std::vector<double> theta(function->Size());
    for (int k = 0; k < function->Size(); ++k) theta[k] = parameters[0][k] - kOffset;
    const auto e = function->At(theta);
    if (!e->ok) return false;
    residuals[0] = e->r(2 * index);
    residuals[1] = e->r(2 * index + 1);
    return true;
  }
};

// Least-squares refinement of θ from `start` with Ceres (bounded, Huber loss, central numeric
// differences). Returns the best θ found (never worse than `start`).
std::vector<double> Refine(CandidateFunction* function, std::vector<double> start, int residual_count,
                           const DiagnoseOptions& options) {
  const int k = function->Size();
  std::vector<double> x(k);
  for (int i = 0; i < k; ++i) x[i] = start[i] + kOffset;
  ceres::Problem problem;
  ceres::NumericDiffOptions nd;
  nd.relative_step_size = kRelativeStep;
  for (int m = 0; m < residual_count / 2; ++m) {
    auto* cost = new ceres::DynamicNumericDiffCostFunction<ModeBlock, ceres::CENTRAL>(
        new ModeBlock{function, m}, ceres::TAKE_OWNERSHIP, nd);
    cost->AddParameterBlock(k);
    cost->SetNumResiduals(2);
    problem.AddResidualBlock(cost, new ceres::HuberLoss(options.robust_threshold), x.data());
  }
  for (int i = 0; i < k; ++i) {
    const ParamSpec& s = function->Templates()[i].spec;
    problem.SetParameterLowerBound(x.data(), i, s.lo + kOffset);
    problem.SetParameterUpperBound(x.data(), i, s.hi + kOffset);
  }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = options.max_iterations;
  so.function_tolerance = 1e-9;
  so.parameter_tolerance = 1e-7;
  so.gradient_tolerance = 1e-12;
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  so.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  std::vector<double> theta(k);
  for (int i = 0; i < k; ++i) theta[i] = x[i] - kOffset;
  const auto a = function->At(theta);
  const auto b = function->At(start);
  if (!a->ok) return start;
  if (b->ok && RobustCost(b->r, options.robust_threshold) < RobustCost(a->r, options.robust_threshold)) return start;
  return theta;
}

std::string FormatNumber(double v, int significant = 3) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*g", significant, v);
  return buffer;
}

std::string EffectLabel(const model::Effect& e) { return e.kind + " of '" + e.target + "'"; }

// "series_compliance (hertz) of 'bearings'", "mass_scale of 'carriage'", pairs joined by " + ".
std::string CandidateLabel(const Candidate& c) {
  if (c.effects.empty()) return c.kind;
  std::vector<std::string> parts;
  for (const model::Effect& e : c.effects) {
    std::string label = e.kind;
    if (e.kind == "series_compliance" && e.law) label += " (" + e.law->KindName() + ")";
    parts.push_back(label + " of '" + e.target + "'");
  }
  std::string out;
  for (size_t i = 0; i < parts.size(); ++i) out += (i ? " + " : "") + parts[i];
  return out;
}

std::string Join(const std::vector<std::string>& parts, const std::string& sep) {
  std::string out;
  for (size_t i = 0; i < parts.size(); ++i) out += (i ? sep : "") + parts[i];
  return out;
}

}  // namespace

std::string DescribeCandidate(const Candidate& c) {
  if (c.effects.empty()) return "no missing effect";
  std::vector<std::string> parts;
  for (const model::Effect& e : c.effects) {
    auto param = [&](const char* key) {
      auto it = e.parameters.find(key);
      return it == e.parameters.end() ? kNaN : it->second;
    };
    const model::HertzLaw* hertz = e.law ? std::get_if<model::HertzLaw>(&e.law->value) : nullptr;
    if (e.kind == "series_compliance" && hertz) {
      parts.push_back("a Hertz contact (E' = " + FormatNumber(hertz->modulus, 3) + " Pa, R' = " +
                      FormatNumber(hertz->radius * 1e3, 3) + " mm) in series with group '" + e.target + "'");
    } else if (e.kind == "series_compliance") {
      double k = kNaN;
      if (e.law)
        if (const auto* lin = std::get_if<model::LinearLaw>(&e.law->value)) k = lin->k;
      parts.push_back("a compliance of " + FormatNumber(k / 1e6, 3) + " N/µm in series with group '" + e.target + "'");
    } else if (e.kind == "stiffness_scale") {
      parts.push_back("the stiffness of group '" + e.target + "' scaled by " + FormatNumber(param("factor"), 3));
    } else if (e.kind == "operating_point") {
      const double v = param("value");
      const std::string shown = std::abs(v) < 1e-3 ? FormatNumber(v * 1e6, 3) + " µm" : FormatNumber(v, 4);
      parts.push_back("an operating point (setting/gap/preload) of " + shown + " for group '" + e.target + "'");
    } else if (e.kind == "added_mass") {
      parts.push_back("an added mass of " + FormatNumber(param("mass") * 1e3, 3) + " g per point at " + e.target);
    } else if (e.kind == "mass_scale") {
      parts.push_back("the mass and inertia of body '" + e.target + "' scaled by " + FormatNumber(param("factor"), 3));
    } else if (e.kind == "ground_spring") {
      parts.push_back("a spring to ground of " + FormatNumber(param("k") / 1e6, 3) + " N/µm on body '" + e.target + "'");
    } else {
      parts.push_back(model::Describe(e));
    }
  }
  return Join(parts, " together with ");
}

Diagnosis Diagnose(const model::Model& input_model, const std::vector<SetupModes>& tests,
                   const DiagnoseOptions& options) {
  const std::string where = input_model.origin.empty() ? "model" : input_model.origin;
  if (tests.empty()) throw InputError(where, "no test given; expected at least one set of test modes");
  const model::Model base = model::ApplyEffects(input_model);

  // Setups must exist; test nodes must be test points of the model.
  std::set<int> point_ids;
  for (const auto& p : base.points) point_ids.insert(p.id);
  std::set<std::string> setup_names;
  for (const auto& s : base.setups) setup_names.insert(s.name);
  for (const SetupModes& t : tests) {
    const std::string source = t.modes.source.empty() ? "test" : t.modes.source;
    if (!t.setup.empty() && !setup_names.count(t.setup)) {
      std::vector<std::string> names(setup_names.begin(), setup_names.end());
      throw InputError(where, "setup '" + t.setup + "' (for " + source + ") is not defined; the model's setups: " +
                                  (names.empty() ? std::string("none") : Join(names, ", ")));
    }
    if (t.modes.modes.empty()) throw InputError(source, "no modes found; expected the test's fitted modes");
    std::set<int> missing;
    for (const Dof& d : t.modes.dofs)
      if (!point_ids.count(d.node)) missing.insert(d.node);
    if (!missing.empty()) {
      std::vector<std::string> ids;
      for (int id : missing) ids.push_back(std::to_string(id));
      throw InputError(source, "test node(s) " + Join(ids, ", ") + " are not [[point]]s of the model " + where +
                                   "; expected every test node to be a model test point");
    }
  }

  int max_test_modes = 0;
  for (const SetupModes& t : tests) max_test_modes = std::max<int>(max_test_modes, t.modes.modes.size());
  const int max_modes = base.fe.Empty() ? 0 : std::max(20, 2 * max_test_modes + 4);

  // Baseline solve per setup: DOF matching is done once (the observed DOFs do not move).
  std::vector<SetupData> setups;
  for (const SetupModes& t : tests) {
    model::SolveOptions so;
    so.setup = t.setup;
    so.max_modes = max_modes;
    const model::Solution sol = model::Solve(base, so);
    SetupData s;
    s.name = t.setup;
    s.match = MatchDofs(t.modes, sol.modes, options.dofs);
    if (s.match.Count() == 0)
      throw InputError(t.modes.source.empty() ? "test" : t.modes.source,
                       "no test DOF is observed by the model (the model gives +X/+Y/+Z at its test points)");
    s.test_shapes = s.match.TestShapes(t.modes);
    s.test_hz.resize(t.modes.modes.size());
    for (size_t i = 0; i < t.modes.modes.size(); ++i) s.test_hz(i) = t.modes.modes[i].frequency_hz;
    s.model_dof_count = sol.modes.dofs.size();
    setups.push_back(std::move(s));
  }

  Evaluator evaluator(base, std::move(setups), options, max_modes);
  const int n = evaluator.ResidualCount();
  Diagnosis result;
  result.residual_count = n;
  result.test_mode_count = n / 2;

  auto score_of = [&](double cost, int k) {
    const double j = cost + n * options.residual_floor * options.residual_floor;
    double s = n * std::log(j / n);
    if (options.criterion == InformationCriterion::kBic) {
      s += k * std::log(static_cast<double>(n));
    } else {
      s += 2.0 * k + (n - k - 1 > 0 ? 2.0 * k * (k + 1) / (n - k - 1) : 1e9);
    }
    return s;
  };

  auto fill = [&](Candidate* c, const Evaluation& e) {
    c->modes = e.modes;
    c->mean_abs_frequency_error_pct = e.mean_abs_frequency_error_pct;
    c->mean_mac = e.mean_mac;
    c->paired_modes = e.paired;
    c->residuals = e.r;
    c->cost = RobustCost(e.r, options.robust_threshold);
  };

  // Baseline.
  const Evaluation e0 = evaluator.Evaluate({});
  if (!e0.ok) throw InputError(where, "the model cannot be solved: " + e0.error);
  if (e0.paired < 2) {
    std::ostringstream msg;
    msg << "only " << e0.paired << " test mode(s) pair with a model mode (MAC ≥ " << options.pairing.mac_min
        << "); at least 2 paired modes are needed to fit any parameter";
    throw InputError(where, msg.str());
  }
  Candidate none;
  none.kind = "none";
  fill(&none, e0);
  none.score = score_of(none.cost, 0);
  none.explained_pct = 0.0;
  result.baseline = none;
  const double j0 = none.cost;

  // The candidate effects.
  std::vector<EffectTemplate> templates;
  for (const model::Effect& e : model::CandidateEffects(base)) {
    auto t = MakeTemplate(e, base);
    if (!t) continue;
    templates.push_back(*t);
    // A series element in an air-film chain carries the film's load, so it may as well be a
    // non-linear contact (a ball joint, thesis §7.2.4): its stiffness then differs between stud
    // settings in a way no linear element reproduces. Tried as a second series_compliance.
    if (e.kind == "series_compliance" && GroupCarriesFilmLoad(base, e.target)) {
      EffectTemplate h = *t;
      h.hertz = true;
      h.spec = {"modulus", 1e10, 1.0, true, std::log(1e-3), std::log(1e3), +1};
      templates.push_back(h);
    }
  }
  const int total_steps = static_cast<int>(templates.size()) + options.pair_pool;
  int step = 0;

  auto finish = [&](Candidate* c, CandidateFunction* f, const std::vector<double>& theta) {
    const auto e = f->At(theta);
    fill(c, *e);
    c->effects = f->Effects(theta);
    std::vector<std::string> kinds, targets;
    for (const auto& ef : c->effects) {
      kinds.push_back(ef.kind);
      targets.push_back(ef.target);
    }
    c->kind = Join(kinds, "+");
    c->target = Join(targets, "+");
    const int k = f->Size();
    c->score = score_of(c->cost, k);
    c->explained_pct = j0 > 0.0 ? 100.0 * (1.0 - c->cost / j0) : 0.0;
    // Uncertainty: central-difference Jacobian of the residuals in θ, s² = r·r / (N − k).
    Eigen::MatrixXd jac(n, k);
    bool ok = true;
    const double h = 1e-3;
    for (int i = 0; i < k && ok; ++i) {
      std::vector<double> plus = theta, minus = theta;
      plus[i] += h;
      minus[i] -= h;
      const auto ep = f->At(plus);
      const auto em = f->At(minus);
      if (!ep->ok || !em->ok) ok = false;
      else jac.col(i) = (ep->r - em->r) / (2.0 * h);
    }
    Eigen::VectorXd sigma_theta = Eigen::VectorXd::Constant(k, kNaN);
    if (ok && n > k) {
      const Eigen::MatrixXd jtj = jac.transpose() * jac;
      Eigen::JacobiSVD<Eigen::MatrixXd> svd(jtj);
      const double cond = svd.singularValues()(0) / std::max(1e-300, svd.singularValues()(k - 1));
      if (svd.singularValues()(k - 1) > 0.0 && cond < 1e12) {
        const double s2 = e->r.squaredNorm() / (n - k);
        sigma_theta = (s2 * jtj.inverse()).diagonal().cwiseSqrt();
      }
    }
    for (int i = 0; i < k; ++i) {
      const ParamSpec& s = f->Templates()[i].spec;
      FittedParameter p;
      p.effect_kind = f->Templates()[i].effect.kind;
      p.name = s.name;
      p.value = s.Value(theta[i]);
      p.sigma = std::abs(s.Derivative(theta[i])) * sigma_theta(i);
      p.lower = s.Value(s.lo);
      p.upper = s.Value(s.hi);
      const double margin = 1e-3 * (s.hi - s.lo);
      const int end = theta[i] <= s.lo + margin ? -1 : (theta[i] >= s.hi - margin ? +1 : 0);
      p.at_bound = end != 0;
      // Sitting on the "absent" end just means the effect is not wanted; the other end means
      // the fit wants an unphysical value.
      if (end != 0 && end != s.absent_end) c->plausible = false;
      c->parameters.push_back(p);
    }
  };

  // Singles: scan the log-range, then refine with Ceres from the best grid point.
  std::vector<Candidate> singles;
  std::vector<std::vector<double>> single_theta;
  std::vector<int> single_template;
  for (size_t t = 0; t < templates.size(); ++t) {
    ReportProgress(options.progress, static_cast<double>(step++) / std::max(1, total_steps),
                   "fitting " + EffectLabel(templates[t].effect));
    CandidateFunction f(&evaluator, {templates[t]});
    const ParamSpec& s = templates[t].spec;
    double best_cost = std::numeric_limits<double>::infinity();
    std::vector<double> best;
    std::string error;
    const int points = std::max(3, options.scan_points);
    for (int g = 0; g < points; ++g) {
      const std::vector<double> theta{s.lo + (s.hi - s.lo) * g / (points - 1)};
      const auto e = f.At(theta);
      if (!e->ok) {
        error = e->error;
        continue;
      }
      const double cost = RobustCost(e->r, options.robust_threshold);
      if (cost < best_cost) {
        best_cost = cost;
        best = theta;
      }
    }
    Candidate c;
    if (best.empty() && templates[t].hertz) continue;  // an optional variant: no failure to report
    if (best.empty()) {
      c.effects = {templates[t].effect};
      c.kind = templates[t].effect.kind;
      c.target = templates[t].effect.target;
      c.error = error.empty() ? "no parameter value could be evaluated" : error;
      c.plausible = false;
      singles.push_back(c);
      single_theta.push_back({});
      single_template.push_back(static_cast<int>(t));
      continue;
    }
    const std::vector<double> theta = Refine(&f, best, n, options);
    finish(&c, &f, theta);
    singles.push_back(c);
    single_theta.push_back(theta);
    single_template.push_back(static_cast<int>(t));
  }

  // Pairs: each of the best `pair_pool` plausible singles combined with every other plausible
  // single (a forward step from the leaders: the second effect of a true pair is often a poor
  // single on its own, hidden behind a confounder of the first).
  std::vector<int> order;
  for (size_t i = 0; i < singles.size(); ++i)
    if (singles[i].error.empty() && singles[i].plausible) order.push_back(static_cast<int>(i));
  std::sort(order.begin(), order.end(), [&](int a, int b) { return singles[a].score < singles[b].score; });
  const double best_single_score =
      order.empty() ? std::numeric_limits<double>::infinity() : singles[order[0]].score;
  std::vector<Candidate> pairs;
  std::set<std::pair<int, int>> tried;
  const int pool = std::min<int>(options.pair_pool, order.size());
  for (int a = 0; a < pool; ++a) {
    ReportProgress(options.progress, static_cast<double>(step++) / std::max(1, total_steps), "fitting pairs");
    for (size_t b = 0; b < order.size(); ++b) {
      const int ia = order[a], ib = order[b];
      if (ia == ib || tried.count({std::min(ia, ib), std::max(ia, ib)})) continue;
      tried.insert({std::min(ia, ib), std::max(ia, ib)});
      const EffectTemplate& ta = templates[single_template[ia]];
      const EffectTemplate& tb = templates[single_template[ib]];
      if (ta.effect.kind == tb.effect.kind && ta.effect.target == tb.effect.target) continue;
      CandidateFunction f(&evaluator, {ta, tb});
      // Start from the best of: each single's optimum with the other effect near absent, and
      // both singles' optima together.
      const auto nominal = [](const EffectTemplate& t) {
        return t.spec.absent_end == 0 ? 0.0 : (t.spec.absent_end > 0 ? t.spec.hi : t.spec.lo);
      };
      const std::vector<std::vector<double>> starts = {{single_theta[ia][0], nominal(tb)},
                                                       {nominal(ta), single_theta[ib][0]},
                                                       {single_theta[ia][0], single_theta[ib][0]}};
      std::vector<double> start;
      double start_cost = std::numeric_limits<double>::infinity();
      for (const auto& candidate_start : starts) {
        const auto e = f.At(candidate_start);
        if (!e->ok) continue;
        const double cost = RobustCost(e->r, options.robust_threshold);
        if (cost < start_cost) {
          start_cost = cost;
          start = candidate_start;
        }
      }
      if (start.empty()) continue;
      const std::vector<double> theta = Refine(&f, start, n, options);
      Candidate c;
      finish(&c, &f, theta);
      // A pair is reported only when it beats the best single after its extra parameter's
      // penalty (the criterion already charges it) and neither parameter ends on a bound.
      bool on_bound = false;
      for (const auto& p : c.parameters) on_bound |= p.at_bound;
      if (c.plausible && !on_bound && c.score < best_single_score) pairs.push_back(c);
    }
  }
  // Keep the few best pairs: many pairs share their leading effect and say the same thing.
  std::sort(pairs.begin(), pairs.end(), [](const Candidate& a, const Candidate& b) { return a.score < b.score; });
  if (pairs.size() > 3) pairs.resize(3);

  // Rank: plausible candidates by score (with "none"), then implausible ones, then failures.
  std::vector<Candidate> all;
  all.push_back(none);
  for (auto& c : singles) all.push_back(c);
  for (auto& c : pairs) all.push_back(c);
  std::stable_sort(all.begin(), all.end(), [](const Candidate& a, const Candidate& b) {
    const int ca = !a.error.empty() ? 2 : (a.plausible ? 0 : 1);
    const int cb = !b.error.empty() ? 2 : (b.plausible ? 0 : 1);
    if (ca != cb) return ca < cb;
    if (ca == 2) return false;
    return a.score < b.score;
  });
  for (size_t i = 0; i < all.size(); ++i) all[i].rank = static_cast<int>(i) + 1;

  // Ties: residual changes that point the same way cannot be told apart by these data.
  const int top = std::min<int>(6, all.size());
  for (int a = 0; a < top; ++a) {
    if (all[a].kind == "none" || !all[a].error.empty()) continue;
    const Eigen::VectorXd da = all[a].residuals - none.residuals;
    for (int b = 0; b < top; ++b) {
      if (a == b || all[b].kind == "none" || !all[b].error.empty()) continue;
      const Eigen::VectorXd db = all[b].residuals - none.residuals;
      const double na = da.norm(), nb = db.norm();
      if (na <= 0.0 || nb <= 0.0) continue;
      const double cosine = da.dot(db) / (na * nb);
      if (std::abs(cosine) > 0.95 && std::abs(all[a].score - all[b].score) < 2.0)
        all[a].tied_with.push_back(CandidateLabel(all[b]));
    }
  }

  // Explanation in words.
  std::ostringstream words;
  const Candidate& first = all.front();
  auto pct = [](double v) { return FormatNumber(v, v < 10.0 ? 2 : 3) + " %"; };
  if (first.kind == "none") {
    words << "No candidate effect explains the mismatch by more than its parameter penalty: the model as given "
             "agrees to a mean frequency error of "
          << pct(none.mean_abs_frequency_error_pct) << " (mean MAC " << FormatNumber(none.mean_mac, 3) << ").";
    for (const Candidate& c : all)
      if (c.kind != "none" && c.error.empty()) {
        words << " The best effect, " << DescribeCandidate(c) << ", would bring it to "
              << pct(c.mean_abs_frequency_error_pct) << ", not enough to pay for its parameter.";
        break;
      }
  } else {
    words << DescribeCandidate(first) << " brings the mean frequency error from "
          << pct(none.mean_abs_frequency_error_pct) << " to " << pct(first.mean_abs_frequency_error_pct)
          << " (mean MAC " << FormatNumber(none.mean_mac, 3) << " → " << FormatNumber(first.mean_mac, 3) << ", "
          << FormatNumber(first.explained_pct, 3) << " % of the residual explained)";
    for (size_t i = 1; i < all.size(); ++i) {
      const Candidate& c = all[i];
      // The next best *other* explanation: not a variant (another law, a pair) of the same one.
      if (c.kind == "none" || !c.error.empty() || (c.kind == first.kind && c.target == first.target)) continue;
      words << "; the next best, " << CandidateLabel(c) << ", leaves "
            << pct(c.mean_abs_frequency_error_pct);
      break;
    }
    words << ".";
    if (!first.tied_with.empty())
      words << " The data cannot tell it apart from " << Join(first.tied_with, ", ")
            << ": more modes, shapes or another setup would.";
  }
  result.explanation = words.str();
  result.candidates = std::move(all);
  result.model_solves = evaluator.Solves();
  ReportProgress(options.progress, 1.0, "done");
  return result;
}

NonlinearityReport DetectAmplitudeDependence(std::vector<ForceLevelModes> levels, const NonlinearityOptions& options) {
  if (levels.size() < 2)
    throw InputError("", "amplitude dependence needs modes from at least 2 force levels, found " +
                             std::to_string(levels.size()));
  for (const auto& l : levels) {
    if (!(l.force_n > 0.0)) throw InputError(l.modes.source, "force level must be a positive force in N");
    if (l.modes.modes.empty()) throw InputError(l.modes.source, "no modes found at force level " + FormatNumber(l.force_n));
  }
  std::sort(levels.begin(), levels.end(), [](const auto& a, const auto& b) { return a.force_n < b.force_n; });
  const ModeSet& ref = levels.front().modes;
  NonlinearityReport report;
  for (size_t m = 0; m < ref.modes.size(); ++m) {
    AmplitudeTrend t;
    t.reference_mode = static_cast<int>(m);
    t.force_n.push_back(levels.front().force_n);
    t.frequency_hz.push_back(ref.modes[m].frequency_hz);
    double spread = std::isfinite(ref.modes[m].frequency_spread_hz) ? ref.modes[m].frequency_spread_hz : 0.0;
    report.modes.push_back(t);
    report.modes.back().threshold_pct = spread;  // holds the largest spread (Hz) until the end
  }
  PairingOptions popt;
  popt.mac_min = options.mac_min;
  popt.frequency_weight = 0.2;
  for (size_t l = 1; l < levels.size(); ++l) {
    const ModeSet& set = levels[l].modes;
    const DofMatch match = MatchDofs(set, ref);
    if (match.Count() == 0)
      throw InputError(set.source, "shares no DOF with the lowest force level's modes " + ref.source);
    const Eigen::MatrixXd mac = MacMatrix(match.TestShapes(set), match.ModelShapes(ref));
    Eigen::VectorXd f_set(set.modes.size()), f_ref(ref.modes.size());
    for (size_t i = 0; i < set.modes.size(); ++i) f_set(i) = set.modes[i].frequency_hz;
    for (size_t j = 0; j < ref.modes.size(); ++j) f_ref(j) = ref.modes[j].frequency_hz;
    for (const ModePair& p : PairModes(mac, f_set, f_ref, popt).pairs) {
      AmplitudeTrend& t = report.modes[p.model];
      t.force_n.push_back(levels[l].force_n);
      t.frequency_hz.push_back(set.modes[p.test].frequency_hz);
      if (std::isfinite(set.modes[p.test].frequency_spread_hz))
        t.threshold_pct = std::max(t.threshold_pct, set.modes[p.test].frequency_spread_hz);
    }
  }
  std::vector<std::string> flagged;
  for (AmplitudeTrend& t : report.modes) {
    const double f0 = t.frequency_hz.front();
    const double spread_hz = t.threshold_pct;
    t.threshold_pct = 100.0 * std::max(options.repeatability_factor * spread_hz / f0, options.min_change);
    if (t.frequency_hz.size() < 2) {
      t.trend = "none";
      continue;
    }
    t.change_pct = 100.0 * (t.frequency_hz.back() - f0) / f0;
    // Least squares of f on log10 F.
    const size_t n = t.force_n.size();
    double mx = 0.0, my = 0.0;
    for (size_t i = 0; i < n; ++i) {
      mx += std::log10(t.force_n[i]) / n;
      my += t.frequency_hz[i] / n;
    }
    double sxx = 0.0, sxy = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const double dx = std::log10(t.force_n[i]) - mx;
      sxx += dx * dx;
      sxy += dx * (t.frequency_hz[i] - my);
    }
    t.slope_pct_per_decade = sxx > 0.0 ? 100.0 * (sxy / sxx) / f0 : 0.0;
    t.flagged = std::abs(t.change_pct) > t.threshold_pct;
    t.trend = !t.flagged ? "none" : (t.change_pct < 0.0 ? "softening" : "hardening");
    if (t.flagged)
      flagged.push_back("mode at " + FormatNumber(f0, 4) + " Hz " + t.trend + " by " +
                        FormatNumber(std::abs(t.change_pct), 2) + " % from " + FormatNumber(t.force_n.front(), 3) +
                        " N to " + FormatNumber(t.force_n.back(), 3) + " N (" +
                        FormatNumber(t.slope_pct_per_decade, 2) + " % per decade of force)");
  }
  report.any_flagged = !flagged.empty();
  report.summary = flagged.empty()
                       ? "No amplitude-dependent frequency: every mode stays within its repeatability across the "
                         "force levels, so a linear model is adequate."
                       : "Amplitude-dependent stiffness: " + Join(flagged, "; ") +
                             ". A linear model holds only at the amplitude it was fitted at.";
  return report;
}

}  // namespace ema::correlation
