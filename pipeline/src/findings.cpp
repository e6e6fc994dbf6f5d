#include "ema/pipeline/findings.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ema/model/effects.hpp"
#include "ema/model/solve.hpp"

namespace ema::pipeline {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Per setup, the mean linearised stiffness of the target's springs with rank 1's effects, and of
// the series element the effect added: the numbers of a mount or joint an engineer compares with
// a catalogue.
std::vector<SpringStiffness> SpringStiffnessOf(const model::Model& model, const std::vector<model::Effect>& effects,
                                               const model::Effect& effect, const std::vector<std::string>& setups) {
  std::vector<SpringStiffness> out;
  if (model::TargetSprings(model, effect.target).empty()) return out;
  model::Model updated = model;
  for (const model::Effect& e : effects) updated = model::ApplyEffect(updated, e);
  const std::vector<int> springs = model::TargetSprings(updated, effect.target);
  const bool series = effect.kind == model::EffectKind::kSeriesCompliance;
  for (const std::string& setup : setups) {
    model::SolveOptions options;
    options.setup = setup;
    const model::Solution solution = model::Solve(updated, options);
    double k = 0.0, k_element = 0.0;
    int n = 0, n_element = 0;
    for (int i : springs) {
      const model::SpringState& state = solution.springs[static_cast<size_t>(i)];
      k += state.stiffness;
      ++n;
      if (series && !state.element_stiffnesses.empty()) k_element += state.element_stiffnesses.back(), ++n_element;
    }
    if (n == 0) continue;
    SpringStiffness s;
    s.setup = setup;
    s.per_spring_n_per_m = k / n;
    if (n_element) s.element_n_per_m = k_element / n_element;
    out.push_back(s);
  }
  return out;
}

double Square(double v) { return std::isfinite(v) ? v * v : 0.0; }

// True when the group's readings add no effect: the model as given.
bool IsNoneGroup(const diagnose::Diagnosis& d, const diagnose::CandidateGroup& group) {
  for (const diagnose::Candidate& c : d.candidates)
    if (!group.ranks.empty() && c.rank == group.ranks.front()) return c.IsNone();
  return false;
}

ModeVerdict VerdictOf(const ModeEvidence& m) {
  if (!m.paired_after) return ModeVerdict::kUnpaired;
  const double f = std::abs(m.after.frequency_misfit_sigma), s = m.after.shape_misfit_sigma;
  if (f > 3.0 || s > 3.0) return ModeVerdict::kMisfit;
  if (f > 2.0 || s > 2.0) return ModeVerdict::kMarginal;
  return ModeVerdict::kWithinNoise;
}

// True when `reading` moves the frequency of every test mode paired in both (at least two) the
// same way, by between ½ and 2× each other: a uniform shift — an added mass spread over every
// point, a material constant — which an error shared by all the model's frequencies also is. A
// point mass moves the modes by their amplitude at its point, tens of times apart.
bool MovesEveryModeAlike(const diagnose::Candidate& as_given, const diagnose::Candidate& reading) {
  double smallest = kInfinity, largest = 0.0;
  int up = 0, down = 0;
  for (const diagnose::ModeComparison& a : reading.modes)
    for (const diagnose::ModeComparison& b : as_given.modes) {
      if (a.setup != b.setup || a.test_mode != b.test_mode) continue;
      if (a.model_mode < 0 || b.model_mode < 0 || !(a.model_frequency_hz > 0.0) || !(b.model_frequency_hz > 0.0)) break;
      const double shift = a.model_frequency_hz / b.model_frequency_hz - 1.0;
      (shift > 0.0 ? up : down) += 1;
      smallest = std::min(smallest, std::abs(shift));
      largest = std::max(largest, std::abs(shift));
      break;
    }
  return up + down >= 2 && (up == 0 || down == 0) && smallest > 0.0 && largest <= 2.0 * smallest;
}

}  // namespace

GroupSpan SpanOf(const diagnose::Diagnosis& d, const diagnose::CandidateGroup& group) {
  const diagnose::Candidate* best = nullptr;
  std::vector<const diagnose::Candidate*> members;
  for (int rank : group.ranks)
    for (const diagnose::Candidate& c : d.candidates)
      if (c.rank == rank) {
        if (best) members.push_back(&c);
        else best = &c;
      }
  bool points = false, others = false;
  for (const diagnose::Candidate* c : members)
    for (std::size_t i = 0; i < c->effects.size(); ++i) {
      const model::Effect& e = c->effects[i];
      if (i < best->effects.size() && best->effects[i].target == e.target) continue;
      if (model::Info(e.kind).acts_on == model::ActsOn::kPoints) points = true;
      else others = true;
    }
  if (points && !others) return GroupSpan::kPoints;
  if (others && !points) return GroupSpan::kMembers;
  return GroupSpan::kReadings;
}

Findings FindingsOf(const diagnose::Diagnosis& d, const model::Model& model) {
  Findings out;
  if (d.candidates.empty()) return out;
  const diagnose::Candidate& first = d.candidates.front();
  out.rank_one_probability = first.probability;
  out.certain_among_tried_only = !first.noise_consistent && first.probability >= 0.99;
  out.adequate = first.noise_consistent;
  out.reduced_chi2 = first.reduced_chi2;
  out.well_inside_noise = first.noise_consistent && first.reduced_chi2 < 0.01;
  out.test_modes = d.test_mode_count;
  out.model_error = first.model_error;
  out.model_inadequate = !first.noise_consistent && first.model_error.dominates;
  out.checks = first.flags;
  out.error_before_pct = d.baseline.mean_abs_frequency_error_pct;
  out.error_after_pct = first.mean_abs_frequency_error_pct;
  out.mac_before = d.baseline.mean_mac;
  out.mac_after = first.mean_mac;

  // Rank 1's effects with their numbers.
  std::vector<std::string> setups;
  for (const auto& m : first.modes)
    if (std::find(setups.begin(), setups.end(), m.setup) == setups.end()) setups.push_back(m.setup);
  for (const model::Effect& e : first.effects) {
    EffectFinding f;
    f.effect = e;
    const std::optional<model::EffectTarget> wildcard = diagnose::EffectWildcard(e.target);
    for (const diagnose::EffectProbability& ep : d.effect_probabilities) {
      if (ep.kind == e.kind && ep.target == e.target) f.probability = ep.probability;
      if (ep.kind == e.kind && wildcard && ep.target == *wildcard) {
        f.wildcard = wildcard;
        f.wildcard_probability = ep.probability;
      }
    }
    for (const diagnose::FittedParameter& p : first.parameters)
      if (p.effect_kind == e.kind && p.target == e.target) f.parameters.push_back(p);
    f.springs = SpringStiffnessOf(model, first.effects, e, setups);
    out.effects.push_back(std::move(f));
  }

  // Look-alikes: the other readings within a factor 20 of rank 1's probability, one per group of
  // the same reading on other members or points.
  for (const diagnose::CandidateGroup& g : d.groups) {
    const bool holds_first = std::find(g.ranks.begin(), g.ranks.end(), first.rank) != g.ranks.end();
    const double p = holds_first ? g.probability - first.probability : g.probability;
    const int others = static_cast<int>(g.ranks.size()) - (holds_first ? 1 : 0);
    if (others <= 0 || IsNoneGroup(d, g) || !diagnose::IsLookAlike(p, first.probability)) continue;
    out.lookalikes.push_back({g.kind, g.target, others, holds_first, SpanOf(d, g), p});
    if (out.lookalikes.size() == 4) break;
  }

  // Rank 1 the model as given, still inadequate: the next reading with effects, when the data
  // cannot tell it from the model's own error — a look-alike that halves the frequency error by
  // moving every mode alike, the pattern of an error all the modes share.
  if (out.model_inadequate && first.IsNone())
    for (const diagnose::Candidate& c : d.candidates) {
      if (c.IsNone()) continue;
      if (diagnose::IsLookAlike(c.probability, first.probability) &&
          c.mean_abs_frequency_error_pct <= 0.5 * first.mean_abs_frequency_error_pct && MovesEveryModeAlike(first, c))
        out.model_error_lookalike =
            ModelErrorLookAlike{c.rank, diagnose::DescribeCandidate(c, false), c.probability,
                                c.mean_abs_frequency_error_pct, c.model_error};
      break;  // the most probable reading with effects only: candidates are in rank order
    }

  // Evidence per test mode, as given and with rank 1, and each mode's share of the fall in χ².
  double total_drop = 0.0;
  std::vector<double> drops;
  for (std::size_t i = 0; i < d.baseline.modes.size() && i < first.modes.size(); ++i) {
    ModeEvidence m;
    m.before = d.baseline.modes[i];
    m.after = first.modes[i];
    m.paired_before = std::isfinite(m.before.mac);
    m.paired_after = std::isfinite(m.after.mac);
    m.verdict = VerdictOf(m);
    const double drop = std::max(0.0, Square(m.before.frequency_misfit_sigma) + Square(m.before.shape_misfit_sigma) -
                                          Square(m.after.frequency_misfit_sigma) - Square(m.after.shape_misfit_sigma));
    drops.push_back(drop);
    total_drop += drop;
    out.modes.push_back(m);
  }
  if (total_drop > 0.0)
    for (std::size_t i = 0; i < out.modes.size(); ++i) out.modes[i].share_pct = 100.0 * drops[i] / total_drop;

  // Where rank 1's misfit sits, and which kinds of missing physics fit its pattern.
  std::vector<int> order;
  for (std::size_t i = 0; i < first.modes.size(); ++i) order.push_back(static_cast<int>(i));
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    const auto& ma = first.modes[static_cast<size_t>(a)];
    const auto& mb = first.modes[static_cast<size_t>(b)];
    return std::hypot(ma.frequency_misfit_sigma, ma.shape_misfit_sigma) > std::hypot(mb.frequency_misfit_sigma, mb.shape_misfit_sigma);
  });
  for (std::size_t i = 0; i < order.size() && i < 3; ++i) out.worst_modes.push_back(order[i]);
  int above = 0, below = 0, paired = 0;
  double frequency2 = 0.0, shape2 = 0.0, frequency_sum = 0.0;
  for (const auto& m : first.modes) {
    if (m.model_mode < 0) continue;
    ++paired;
    if (m.frequency_misfit_sigma > 1.0) ++above;
    if (m.frequency_misfit_sigma < -1.0) ++below;
    frequency_sum += m.frequency_misfit_sigma;
    frequency2 += m.frequency_misfit_sigma * m.frequency_misfit_sigma;
    shape2 += m.shape_misfit_sigma * m.shape_misfit_sigma;
  }
  // Every mode off the same way, or the error the modes share at least as large as each one's:
  // a distributed error of the model.
  out.pattern.all_one_way = (paired > 0 && (above == paired || below == paired)) ||
                            (paired > 1 && first.model_error.frequency_common_rel >= first.model_error.frequency_rel);
  out.pattern.model_too_stiff = frequency_sum > 0.0;
  out.pattern.mixed = !out.pattern.all_one_way && above > 0 && below > 0;
  out.pattern.shapes_off_more = shape2 > frequency2;
  out.pattern.unpaired_modes = static_cast<int>(first.modes.size()) > paired;
  return out;
}

}  // namespace ema::pipeline
