// Stages 5–6: ranking (posterior probabilities, plausibility, ties) and the explanation.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <boost/math/distributions/chi_squared.hpp>
#include <set>
#include <sstream>

#include "internal.hpp"

namespace ema::diagnose {
namespace detail {
namespace {

// "series_compliance (hertz) of 'bearings'", several joined by " + ".
std::string CandidateLabel(const Candidate& c) {
  if (c.effects.empty()) return c.kind;
  std::vector<std::string> parts;
  for (const model::Effect& e : c.effects) {
    std::string label = model::KindName(e.kind);
    if (e.kind == model::EffectKind::kSeriesCompliance && e.law) label += " (" + e.law->KindName() + ")";
    parts.push_back(label + " of '" + model::TargetText(e.target) + "'");
  }
  return Join(parts, " + ");
}

// "group 'joints'", "member 'J3' of group 'joints'".
std::string Where(const model::EffectTarget& target) {
  if (target.form == model::EffectTarget::Form::kMember)
    return "member '" + target.member + "' of group '" + target.name + "'";
  return "group '" + model::TargetText(target) + "'";
}

// "101" or "101,102": the ids of a points target ("all_points" for all of them).
std::string PointWords(const model::EffectTarget& target) {
  if (target.form != model::EffectTarget::Form::kPoints) return model::TargetText(target);
  std::string ids;
  for (int id : target.points) ids += (ids.empty() ? "" : ",") + std::to_string(id);
  return "point " + ids;
}

// True when one candidate's effects (kind and target) all appear in the other's.
bool Nested(const Candidate& a, const Candidate& b) {
  auto contains = [](const Candidate& big, const Candidate& small) {
    for (const auto& e : small.effects) {
      bool found = false;
      for (const auto& f : big.effects) found |= e.kind == f.kind && e.target == f.target;
      if (!found) return false;
    }
    return true;
  };
  return contains(a, b) || contains(b, a);
}

// True when two candidates hold the same effects (kind and target, in order), whatever their
// values or laws: variants of one reading.
bool SameReading(const Candidate& a, const Candidate& b) {
  if (a.effects.size() != b.effects.size()) return false;
  for (size_t i = 0; i < a.effects.size(); ++i)
    if (a.effects[i].kind != b.effects[i].kind || a.effects[i].target != b.effects[i].target) return false;
  return true;
}

// "the stiffness of member 'J3' of group 'joints' is 50× lower than modelled (7.8σ of its stated
// uncertainty of 50 %): check it".
std::string OutsidePriorWords(const Atom& atom, const FittedParameter& p);

}  // namespace

std::string FormatNumber(double v, int significant) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*g", significant, v);
  return buffer;
}

std::string Join(const std::vector<std::string>& parts, const std::string& sep) {
  std::string out;
  for (size_t i = 0; i < parts.size(); ++i) out += (i ? sep : "") + parts[i];
  return out;
}

namespace {

std::string OutsidePriorWords(const Atom& atom, const FittedParameter& p) {
  const std::string& what = atom.words;
  auto times = [](double ratio) {
    return ratio >= 1.0 ? FormatNumber(ratio, 2) + "× higher" : FormatNumber(1.0 / ratio, 2) + "× lower";
  };
  std::string sentence;
  switch (atom.info->kind) {
    case model::EffectKind::kStiffnessScale:
      sentence = "the stiffness of " + what + " is " + times(p.value) + " than modelled";
      break;
    case model::EffectKind::kMassScale:
      sentence = "the mass of " + what + " is " + times(p.value) + " than modelled";
      break;
    case model::EffectKind::kSeriesCompliance:
      sentence = "a compliance of " + FormatNumber(p.value / 1e6, 3) + " N/µm in series with " + what + " is " +
                 times(p.value / atom.spec.ref) + " than the interface itself";
      break;
    case model::EffectKind::kOperatingPoint:
      sentence = "the operating point of " + what + " is " + times(p.value / atom.spec.ref) + " than the nominal one";
      break;
    case model::EffectKind::kAddedMass:
      sentence = "an unmodelled mass of " + FormatNumber(p.value * 1e3, 3) + " g per point at " + what +
                 " is far more than expected";
      break;
    case model::EffectKind::kGroundSpring:
      sentence = "the support of " + what + " (" + FormatNumber(p.value / 1e6, 3) +
                 " N/µm to ground) is far from fixed or free as modelled";
      break;
  }
  return sentence + " (" + FormatNumber(std::abs(p.prior_z), 2) + "σ of its stated uncertainty of " +
         FormatNumber(100.0 * p.prior_sigma, 2) + " %): check it";
}

}  // namespace

Candidate MakeCandidate(Problem* p, const Fit& f, double baseline_cost) {
  Candidate c;
  const auto& atoms = p->Atoms();
  std::vector<std::string> kinds, targets;
  for (int a : f.atoms) {
    kinds.push_back(model::KindName(atoms[a].effect.kind));
    targets.push_back(model::TargetText(atoms[a].effect.target));
  }
  c.kind = f.atoms.empty() ? "none" : Join(kinds, "+");
  c.target = Join(targets, "+");
  if (!f.ok) {
    c.error = f.error.empty() ? "could not be evaluated" : f.error;
    c.plausible = false;
    for (int a : f.atoms) c.effects.push_back(atoms[a].effect);
    return c;
  }
  c.effects = p->Effects(f.atoms, f.theta);
  const Evaluation& e = *f.eval;
  c.modes = e.modes;
  c.mean_abs_frequency_error_pct = e.mean_abs_frequency_error_pct;
  c.mean_mac = e.mean_mac;
  c.mean_agreement_pct = e.mean_agreement_pct;
  c.paired_modes = e.paired;
  c.residuals = e.r;
  c.cost = e.cost;
  c.log_prior = f.log_prior;
  c.log_evidence = f.log_evidence;
  c.score = f.score;
  c.explained_pct = baseline_cost > 0.0 ? 100.0 * (1.0 - c.cost / baseline_cost) : 0.0;
  c.reduced_model = !f.exact;
  c.model_error = f.model_error;
  {
    // Reduced χ² of the frequencies (cli.md): each test mode's frequency error in σ.
    double chi2 = 0.0;
    int modes = 0;
    for (const ModeComparison& m : e.modes) chi2 += m.frequency_misfit_sigma * m.frequency_misfit_sigma, ++modes;
    const int dof = std::max(1, modes - static_cast<int>(f.atoms.size()));
    c.reduced_chi2 = chi2 / dof;
    c.noise_consistent =
        std::isfinite(chi2) && chi2 <= boost::math::quantile(boost::math::chi_squared(static_cast<double>(dof)), 0.99);
  }
  for (size_t i = 0; i < f.atoms.size(); ++i) {
    const Atom& atom = atoms[f.atoms[i]];
    const ParamSpec& s = atom.spec;
    FittedParameter fp;
    fp.effect_kind = atom.effect.kind;
    fp.target = atom.effect.target;
    fp.name = s.name;
    fp.value = s.Value(f.theta[i]);
    fp.sigma = std::abs(s.Derivative(f.theta[i])) * (f.sigma_theta.size() > static_cast<Eigen::Index>(i)
                                                          ? f.sigma_theta(static_cast<Eigen::Index>(i))
                                                          : kNaN);
    fp.prior_sigma = atom.prior.relative_sigma;
    fp.lower = s.Value(s.lo);
    fp.upper = s.Value(s.hi);
    const int end = BoundEnd(s, f.theta[i]);
    fp.at_bound = end != 0;
    fp.prior_z = atom.prior.shape == model::PriorShape::kLogNormal ? (f.theta[i] - atom.prior.centre) / atom.prior.sigma
                                                                     : fp.value / atom.prior.sigma;
    fp.outside_prior = std::abs(fp.prior_z) > 3.0;
    if (fp.outside_prior) c.flags.push_back(OutsidePriorWords(atom, fp));
    // Sitting on the "absent" end just means the effect is not wanted; the other end means the
    // fit wants an unphysical value.
    if (end != 0 && end != s.absent_end) c.plausible = false;
    c.parameters.push_back(fp);
  }
  return c;
}

void Rank(std::vector<Candidate>* all, const Candidate& none) {
  // Posterior probabilities over every evaluated candidate (uniform prior over candidates).
  double best = kInf;
  for (const Candidate& c : *all)
    if (c.error.empty() && std::isfinite(c.score)) best = std::min(best, c.score);
  double sum = 0.0;
  for (Candidate& c : *all) {
    c.probability = c.error.empty() && std::isfinite(c.score) ? std::exp(-0.5 * (c.score - best)) : 0.0;
    sum += c.probability;
  }
  for (Candidate& c : *all) c.probability = sum > 0.0 ? c.probability / sum : 0.0;
  // By the posterior (with "none"), failures last. A value far outside its prior stays a
  // candidate ranked by its evidence (the prior already weighs it) and is flagged in words.
  std::stable_sort(all->begin(), all->end(), [](const Candidate& a, const Candidate& b) {
    const bool fa = !a.error.empty() || !std::isfinite(a.score), fb = !b.error.empty() || !std::isfinite(b.score);
    if (fa != fb) return fb;
    if (fa) return false;
    return a.score < b.score;
  });
  // A reading that needs a value far outside the engineer's stated uncertainty *and* still
  // leaves the model inadequate is a poor bet when a plausible reading fits about as well: its
  // evidence came from absorbing part of the model's own error. It is listed right below the
  // plausible reading, flagged with what it would take (docs/diagnose.md "Model error"). "About
  // as well" by the frequencies' misfit *and* by the evidence, which weighs the shapes and the
  // model's own error too: a plausible reading the evidence puts more than 20× behind (the first
  // screen's look-alike rule) fits worse where the frequencies cannot show it — a support nearly
  // gone on a beam whose modes also drift with its shear flexibility (form-rich benchmark cases
  // 6, 7, 61: the far reading the truth, the plausible one 10⁻⁹–10⁻³⁸ as likely, put at rank 1).
  const double kSimilarFitScore = 2.0 * std::log(20.0);
  auto outside = [](const Candidate& c) {
    for (const FittedParameter& p : c.parameters)
      if (p.outside_prior) return true;
    return false;
  };
  for (int guard = 0; guard < 4 && !all->empty(); ++guard) {
    Candidate& first = all->front();
    if (!first.error.empty() || !outside(first) || first.noise_consistent) break;
    auto plausible = std::find_if(all->begin() + 1, all->end(), [&](const Candidate& c) {
      // Similar fit: the frequency misfit's rms within 2× of the far reading's, the evidence within 20×.
      return c.error.empty() && std::isfinite(c.score) && !outside(c) && c.reduced_chi2 <= 4.0 * first.reduced_chi2 &&
             c.score - first.score <= kSimilarFitScore;
    });
    if (plausible == all->end()) break;
    first.flags.push_back("it needs a value far outside its stated uncertainty and still leaves the model inadequate: "
                          "listed below " +
                          (plausible->IsNone() ? std::string("the model as given") : CandidateLabel(*plausible)) +
                          ", a plausible reading that fits about as well");
    std::rotate(all->begin(), plausible, plausible + 1);
  }
  for (size_t i = 0; i < all->size(); ++i) (*all)[i].rank = static_cast<int>(i) + 1;
  // Ties in the data: residual changes that point the same way with misfits within 2 cannot be
  // told apart by these data; only the priors then order them.
  const int top = std::min<int>(6, all->size());
  for (int a = 0; a < top; ++a) {
    Candidate& ca = (*all)[a];
    if (ca.IsNone() || !ca.error.empty()) continue;
    const Eigen::VectorXd da = ca.residuals - none.residuals;
    for (int b = 0; b < top; ++b) {
      const Candidate& cb = (*all)[b];
      if (a == b || cb.IsNone() || !cb.error.empty()) continue;
      // A set and its own extension (one more effect at a neutral value) are not rival readings.
      if (Nested(ca, cb)) continue;
      const Eigen::VectorXd db = cb.residuals - none.residuals;
      const double na = da.norm(), nb = db.norm();
      if (na <= 0.0 || nb <= 0.0) continue;
      const double cosine = da.dot(db) / (na * nb);
      if (std::abs(cosine) > 0.95 && std::abs(ca.cost - cb.cost) < 2.0) ca.tied_with.push_back(CandidateLabel(cb));
    }
  }
}

std::string Explain(const std::vector<Candidate>& all, const Candidate& none) {
  std::ostringstream words;
  const Candidate& first = all.front();
  auto pct = [](double v) { return FormatNumber(v, v < 10.0 ? 2 : 3) + " %"; };
  auto prob = [](double p) { return FormatNumber(100.0 * p, p > 0.999 ? 4 : 3) + " %"; };
  if (first.IsNone()) {
    words << "No candidate effect explains the mismatch by more than its prior and parameter cost (probability "
          << prob(first.probability) << "): the model as given agrees to a mean frequency error of "
          << pct(none.mean_abs_frequency_error_pct) << " (mean MAC " << FormatNumber(none.mean_mac, 3) << ").";
    // The effect that fits best (lowest misfit), whatever its probability.
    const Candidate* closest = nullptr;
    for (const Candidate& c : all)
      if (!c.IsNone() && c.error.empty() && c.plausible && (!closest || c.cost < closest->cost)) closest = &c;
    if (closest && closest->cost < none.cost)
      words << " The effect that fits best, " << DescribeCandidate(*closest) << ", brings the misfit from "
            << FormatNumber(none.cost, 3) << " to " << FormatNumber(closest->cost, 3) << " σ² over "
            << none.modes.size() << " test modes (mean frequency error " << pct(closest->mean_abs_frequency_error_pct)
            << "): not enough to pay for its parameters.";
    return words.str();
  }
  words << DescribeCandidate(first) << " (probability " << prob(first.probability)
        << ") brings the mean frequency error from " << pct(none.mean_abs_frequency_error_pct) << " to "
        << pct(first.mean_abs_frequency_error_pct) << " (mean MAC " << FormatNumber(none.mean_mac, 3) << " → "
        << FormatNumber(first.mean_mac, 3) << ", " << FormatNumber(first.explained_pct, 3)
        << " % of the residual explained)";
  for (size_t i = 1; i < all.size(); ++i) {
    const Candidate& c = all[i];
    // The next best *other* explanation: not a variant (another law) of the same one.
    if (c.IsNone() || !c.error.empty() || SameReading(c, first)) continue;
    words << "; the next best, " << CandidateLabel(c) << " (probability " << prob(c.probability) << "), leaves "
          << pct(c.mean_abs_frequency_error_pct);
    break;
  }
  words << ".";
  if (!first.tied_with.empty())
    words << " The data alone cannot tell it apart from " << Join(first.tied_with, ", ")
          << " (the priors order them): more modes, shapes or another setup would.";
  if (first.probability < 0.9) {
    // Near-equal candidates share the probability: say how sure each effect is, whichever holds it.
    std::vector<std::string> parts;
    for (const EffectProbability& e : EffectProbabilities(all)) {
      if (parts.size() == 3) break;
      parts.push_back(model::KindName(e.kind) + " on " + model::TargetText(e.target) + " " + prob(e.probability));
    }
    if (!parts.empty()) words << " Summed over the candidates that hold it: " << Join(parts, ", ") << ".";
  }
  return words.str();
}

}  // namespace detail

using detail::FormatNumber;
using detail::Join;

std::optional<model::EffectTarget> EffectWildcard(const model::EffectTarget& target) {
  if (target.form == model::EffectTarget::Form::kMember) return model::EffectTarget::EveryMemberOf(target.name);
  if (target.form == model::EffectTarget::Form::kPoints && target.points.size() == 1)
    return model::EffectTarget::EveryPoint();
  return std::nullopt;
}

namespace {

// An effect's kind and target, ordered by the kind's name and then the target's text: effects of
// equal probability keep the order they have always had in DIAG.json.
struct EffectKey {
  model::EffectKind kind;
  model::EffectTarget target;
  std::string text;  ///< TargetText(target), for the order only
  EffectKey(model::EffectKind k, model::EffectTarget t)
      : kind(k), target(std::move(t)), text(model::TargetText(target)) {}
  bool operator<(const EffectKey& other) const {
    const int by_name = std::strcmp(model::Info(kind).name, model::Info(other.kind).name);
    if (by_name != 0) return by_name < 0;
    return text != other.text ? text < other.text : target < other.target;
  }
};

}  // namespace

std::vector<EffectProbability> EffectProbabilities(const std::vector<Candidate>& ranked) {
  std::map<EffectKey, double> sums;
  for (const Candidate& c : ranked) {
    if (!c.error.empty() || !(c.probability > 0.0)) continue;
    // Each key counts a candidate once, even when it holds two members of one group.
    std::set<EffectKey> keys;
    for (const model::Effect& e : c.effects) {
      keys.insert({e.kind, e.target});
      if (const auto wildcard = EffectWildcard(e.target)) keys.insert({e.kind, *wildcard});
    }
    for (const auto& k : keys) sums[k] += c.probability;
  }
  std::vector<EffectProbability> out;
  for (const auto& [key, p] : sums)
    if (p >= 0.01) out.push_back({key.kind, key.target, std::min(1.0, p)});
  std::stable_sort(out.begin(), out.end(), [](const EffectProbability& a, const EffectProbability& b) {
    return a.probability > b.probability;
  });
  return out;
}

std::vector<CandidateGroup> GroupCandidates(const std::vector<Candidate>& ranked) {
  std::vector<CandidateGroup> groups;
  // One group per sequence of kinds on the same wildcard targets.
  std::map<std::pair<std::vector<model::EffectKind>, std::vector<model::EffectTarget>>, size_t> index;
  for (const Candidate& c : ranked) {
    if (!c.error.empty()) continue;
    std::vector<model::EffectKind> kinds;
    std::vector<model::EffectTarget> targets;
    std::vector<std::string> texts;
    for (const model::Effect& e : c.effects) {
      kinds.push_back(e.kind);
      targets.push_back(EffectWildcard(e.target).value_or(e.target));
      texts.push_back(model::TargetText(targets.back()));
    }
    auto [it, fresh] = index.emplace(std::make_pair(kinds, targets), groups.size());
    if (fresh) groups.push_back({c.kind, Join(texts, "+"), {}, 0.0});
    CandidateGroup& g = groups[it->second];
    g.ranks.push_back(c.rank);
    g.probability += std::isfinite(c.probability) ? c.probability : 0.0;
  }
  return groups;
}

std::string DescribeCandidate(const Candidate& c, bool with_law_values) {
  if (c.effects.empty()) return "no missing effect";
  std::vector<std::string> parts;
  for (const model::Effect& e : c.effects) {
    auto param = [&](const char* key) {
      auto it = e.parameters.find(key);
      return it == e.parameters.end() ? kNaN : it->second;
    };
    const model::HertzLaw* hertz = e.law ? std::get_if<model::HertzLaw>(&e.law->value) : nullptr;
    const model::EffectKind kind = e.kind;
    if (kind == model::EffectKind::kSeriesCompliance && hertz) {
      parts.push_back(with_law_values ? "a Hertz contact (E' = " + FormatNumber(hertz->modulus, 3) + " Pa, R' = " +
                                            FormatNumber(hertz->radius * 1e3, 3) + " mm) in series with " +
                                            detail::Where(e.target)
                                      : "a Hertz contact in series with " + detail::Where(e.target));
    } else if (kind == model::EffectKind::kSeriesCompliance) {
      double k = kNaN;
      if (e.law)
        if (const auto* lin = std::get_if<model::LinearLaw>(&e.law->value)) k = lin->k;
      parts.push_back("a compliance of " + FormatNumber(k / 1e6, 3) + " N/µm in series with " + detail::Where(e.target));
    } else if (kind == model::EffectKind::kStiffnessScale) {
      parts.push_back("the stiffness of " + detail::Where(e.target) + " scaled by " + FormatNumber(param("factor"), 3));
    } else if (kind == model::EffectKind::kOperatingPoint) {
      const double v = param("value");
      const std::string shown = std::abs(v) < 1e-3 ? FormatNumber(v * 1e6, 3) + " µm" : FormatNumber(v, 4);
      parts.push_back("an operating point (setting/gap/preload) of " + shown + " for " + detail::Where(e.target));
    } else if (kind == model::EffectKind::kAddedMass) {
      parts.push_back("an added mass of " + FormatNumber(param("mass") * 1e3, 3) + " g per point at " +
                      detail::PointWords(e.target));
    } else if (kind == model::EffectKind::kMassScale) {
      parts.push_back("the mass and inertia of body '" + model::TargetText(e.target) + "' scaled by " +
                      FormatNumber(param("factor"), 3));
    } else {
      parts.push_back("a spring to ground of " + FormatNumber(param("k") / 1e6, 3) + " N/µm on body '" +
                      model::TargetText(e.target) + "'");
    }
  }
  return Join(parts, " together with ");
}

std::vector<std::string> ParameterKeys(const Candidate& c) {
  std::map<std::string, int> count;
  for (const auto& p : c.parameters) ++count[model::KindName(p.effect_kind) + "." + p.name];
  std::vector<std::string> keys;
  for (const auto& p : c.parameters) {
    const std::string key = model::KindName(p.effect_kind) + "." + p.name;
    if (c.effects.size() <= 1) keys.push_back(p.name);
    else if (count[key] == 1) keys.push_back(key);
    else keys.push_back(key + "[" + model::TargetText(p.target) + "]");
  }
  return keys;
}

std::string PriorDefaultsText() {
  std::ostringstream s;
  for (const model::EffectKindInfo& info : model::EffectKindTable())
    s << "  " << info.name << " = " << info.prior_sigma << "  (" << info.prior_meaning << ")\n";
  const DiagnoseOptions defaults;
  s << "  stiffness_fault_share = " << defaults.stiffness_fault_share
    << "  (prior weight of a grossly-off stiffness: loose, cracked; 0: the plain log-normal)\n"
    << "  stiffness_fault_width = " << defaults.stiffness_fault_sigma << "  (1σ of ln(factor) of that fault tail)\n";
  return s.str();
}

}  // namespace ema::diagnose
