// Stages 2–4: screening, fits of the promising singles, combinations.
//
// Screening scans each candidate's parameter over its (log) range on a coarse grid and keeps
// the best point of the MAP objective: cheap (scan_points model solves), global in the one
// parameter, and it needs no derivative at the "absent" end, where a series stiffness → ∞ or an
// added mass → 0 has none. Group, body and all-points candidates are all fitted; of the many
// member and single-point candidates only the best screened ones are.
//
// Combinations: forward selection with a beam. The `beam` best sets of each size grow by every
// compatible candidate, screened with the set's parameters held at their optimum; the
// `additions` best of those are re-fitted jointly. Every new set is then checked backward: each
// of its effects is dropped in turn and the rest re-fitted, so a confounder picked first (a
// body mass standing in for a joint compliance) leaves the set when the true pair is in. Growth
// stops at `max_effects` or when no larger set beats the best smaller one.
//
// Swap: the backward check only drops effects, so a set that holds a look-alike of a true effect
// (a series layer for a stiffness factor on the same mount, a mass on all points for one at a
// single point, the other body's mass) plus a third effect patching the difference is never
// turned into the true pair. The best set of each size ≥ 2 therefore has each effect replaced in
// turn by its look-alikes (any kind on the same spring group or its members; the same kind on any
// FE part; any mass effect for a mass effect; the same kind on another body), screened with the
// rest held, the best `additions` / 2 re-fitted and checked backward. Found by the diagnosis
// benchmark (docs/diagnosis-benchmark.md).
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include "internal.hpp"

namespace ema::diagnose::detail {
namespace {

bool Plausible(const Problem& problem, const Fit& f) {
  if (!f.ok) return false;
  for (size_t i = 0; i < f.atoms.size(); ++i) {
    const ParamSpec& s = problem.Atoms()[f.atoms[i]].spec;
    const int end = BoundEnd(s, f.theta[i]);
    if (end != 0) return false;  // at the far end: implausible; at the absent end: not wanted
  }
  return true;
}

bool Compatible(const std::vector<Atom>& atoms, const std::vector<int>& set, int candidate) {
  const Atom& c = atoms[candidate];
  for (int i : set) {
    if (i == candidate) return false;
    const Atom& a = atoms[i];
    if (a.effect.kind == c.effect.kind && a.effect.target == c.effect.target) return false;
  }
  return true;
}

std::vector<double> Grid(const ParamSpec& s, int points) {
  std::vector<double> g;
  for (int i = 0; i < points; ++i) g.push_back(s.lo + (s.hi - s.lo) * i / (points - 1));
  // The prior's neighbourhood of "no change" is where most true effects are: θ = 0 joins the grid.
  if (s.lo < 0.0 && s.hi > 0.0) g.push_back(0.0);
  return g;
}

}  // namespace

std::pair<std::vector<int>, std::vector<double>> Sorted(const std::vector<int>& set, const std::vector<double>& theta) {
  std::vector<size_t> order(set.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return set[a] < set[b]; });
  std::pair<std::vector<int>, std::vector<double>> out;
  for (size_t i : order) {
    out.first.push_back(set[i]);
    out.second.push_back(theta[i]);
  }
  return out;
}

std::pair<std::vector<int>, std::vector<double>> WithoutOne(const Fit& f, size_t k) {
  std::pair<std::vector<int>, std::vector<double>> out;
  for (size_t i = 0; i < f.atoms.size(); ++i)
    if (i != k) {
      out.first.push_back(f.atoms[i]);
      out.second.push_back(f.theta[i]);
    }
  return out;
}

// Best point of `candidate` added to `base` (θ of base fixed): the best of a coarse grid, then
// a golden-section search between its neighbours (the valley of a well-determined parameter is
// narrower than the grid). Returns (objective, θ).
std::pair<double, double> Screen(Problem* p, const std::vector<int>& base_set, const std::vector<double>& base_theta,
                                 int candidate, int points) {
  std::vector<int> set = base_set;
  set.push_back(candidate);
  std::vector<double> theta = base_theta;
  theta.push_back(0.0);
  auto objective = [&](double t) {
    theta.back() = t;
    return p->Objective(set, theta);
  };
  const ParamSpec& spec = p->Atoms()[candidate].spec;
  double best = kInf, best_theta = 0.0;
  for (double t : Grid(spec, points)) {
    const double obj = objective(t);
    if (obj < best) {
      best = obj;
      best_theta = t;
    }
  }
  if (!std::isfinite(best)) return {best, best_theta};
  const double spacing = (spec.hi - spec.lo) / (points - 1);
  double a = std::max(spec.lo, best_theta - spacing), b = std::min(spec.hi, best_theta + spacing);
  constexpr double kGolden = 0.6180339887498949;
  double c = b - kGolden * (b - a), d = a + kGolden * (b - a);
  double fc = objective(c), fd = objective(d);
  for (int it = 0; it < 8; ++it) {
    if (fc < fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - kGolden * (b - a);
      fc = objective(c);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + kGolden * (b - a);
      fd = objective(d);
    }
  }
  if (fc < best) {
    best = fc;
    best_theta = c;
  }
  if (fd < best) {
    best = fd;
    best_theta = d;
  }
  return {best, best_theta};
}

bool LookAlike(const Atom& a, const Atom& b) {
  // FE parts: a factor on one part stands in for one on another that strains in the same modes
  // (a deck plate and the cross beams it spans: benchmark case 43).
  if (a.part && b.part) return a.info->kind == b.info->kind || a.group == b.group;
  if (!a.group.empty() || !b.group.empty()) return a.group == b.group;
  const auto mass = [](const Atom& t) {
    return t.info->kind == model::EffectKind::kAddedMass || t.info->kind == model::EffectKind::kMassScale;
  };
  if (mass(a) || mass(b)) return mass(a) && mass(b);
  return a.info->kind == b.info->kind;
}

SearchResult Search(Problem* p, const DiagnoseOptions& options) {
  const std::vector<Atom>& atoms = p->Atoms();
  SearchResult result;
  std::map<std::vector<int>, Fit> fitted;
  auto fit = [&](const std::vector<int>& set, const std::vector<double>& theta) -> const Fit& {
    auto [s, t] = Sorted(set, theta);
    auto it = fitted.find(s);
    if (it != fitted.end()) {
      // Keep the better optimum when a set is reached from another start.
      const double obj = p->Objective(s, t);
      if (!(obj < it->second.objective - 1e-9)) return it->second;
    }
    Fit f = FitSet(p, s, t, options);
    // Priors, not cliffs: a fit that reaches the far end of a searched range (not the end that means
    // "no effect") is re-fitted with that side widened 1000-fold, twice at most, before it is ranked.
    for (int round = 0; round < 2 && f.ok; ++round) {
      bool widened = false;
      for (size_t k = 0; k < f.atoms.size(); ++k) {
        const ParamSpec& spec = p->Atoms()[f.atoms[k]].spec;
        const int end = BoundEnd(spec, f.theta[k]);
        if (end != 0 && end != spec.absent_end) {
          p->Widen(f.atoms[k], end);
          widened = true;
        }
      }
      if (!widened) break;
      f = FitSet(p, s, f.theta, options);
    }
    if (it != fitted.end() && !(f.objective < it->second.objective)) return it->second;
    return fitted[s] = std::move(f);
  };
  // Backward check of a fitted set: each effect dropped in turn, the rest re-fitted.
  auto fit_each_without_one = [&](const Fit& full) {
    for (size_t k = 0; k < full.atoms.size(); ++k) {
      const auto [rest, rest_theta] = WithoutOne(full, k);
      fit(rest, rest_theta);
    }
  };
  const int total = static_cast<int>(atoms.size());
  int step = 0;
  auto progress = [&](const std::string& what) {
    ReportProgress(options.progress, std::min(0.95, 0.9 * step / std::max(1, total * options.max_effects)), what);
  };

  // Screening of every single.
  std::vector<std::pair<double, double>> screened(atoms.size());
  for (size_t i = 0; i < atoms.size(); ++i) {
    ++step;
    progress("screening " + atoms[i].Label());
    screened[i] = Screen(p, {}, {}, static_cast<int>(i), options.scan_points);
  }
  result.screened = static_cast<int>(atoms.size());

  // Fits: every group/body/all-points single, and the best screened member/point singles.
  std::vector<int> member_order;
  for (size_t i = 0; i < atoms.size(); ++i)
    if (atoms[i].member && std::isfinite(screened[i].first)) member_order.push_back(static_cast<int>(i));
  std::sort(member_order.begin(), member_order.end(),
            [&](int a, int b) { return screened[a].first < screened[b].first; });
  if (static_cast<int>(member_order.size()) > options.max_fitted_singles) member_order.resize(options.max_fitted_singles);
  for (size_t i = 0; i < atoms.size(); ++i) {
    const bool take = !atoms[i].member ||
                      std::find(member_order.begin(), member_order.end(), static_cast<int>(i)) != member_order.end();
    if (!take) continue;
    progress("fitting " + atoms[i].Label());
    if (!std::isfinite(screened[i].first)) {
      // Could not be evaluated anywhere on the grid: recorded with its error.
      Fit f = Assess(p, {static_cast<int>(i)}, {0.0}, options);
      f.ok = false;
      if (f.error.empty()) f.error = "no parameter value could be evaluated";
      fitted[{static_cast<int>(i)}] = f;
      continue;
    }
    fit({static_cast<int>(i)}, {screened[i].second});
  }

  // Combinations.
  auto best_of_size = [&](size_t size, int count) {
    std::vector<const Fit*> out;
    for (const auto& [set, f] : fitted)
      if (set.size() == size && Plausible(*p, f)) out.push_back(&f);
    std::sort(out.begin(), out.end(), [](const Fit* a, const Fit* b) { return a->search_score < b->search_score; });
    if (static_cast<int>(out.size()) > count) out.resize(count);
    return out;
  };
  double best_so_far = kInf;
  for (const Fit* f : best_of_size(1, 1)) best_so_far = f->search_score;
  for (int size = 2; size <= options.max_effects; ++size) {
    std::vector<Fit> beam;
    for (const Fit* f : best_of_size(size - 1, options.beam)) beam.push_back(*f);
    if (beam.empty()) break;
    std::vector<std::vector<int>> grown;
    for (const Fit& base : beam) {
      std::vector<std::pair<double, std::pair<int, double>>> adds;
      for (int c = 0; c < total; ++c) {
        if (!Compatible(atoms, base.atoms, c)) continue;
        // Members need a promising screen of their own: the rest are not worth a joint scan.
        if (atoms[c].member &&
            std::find(member_order.begin(), member_order.end(), c) == member_order.end())
          continue;
        ++step;
        progress("screening additions to " + std::to_string(size - 1) + " effect(s)");
        const auto [obj, theta] = Screen(p, base.atoms, base.theta, c, std::max(5, options.scan_points - 2));
        if (std::isfinite(obj)) adds.push_back({obj, {c, theta}});
      }
      std::sort(adds.begin(), adds.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      if (static_cast<int>(adds.size()) > options.additions) adds.resize(options.additions);
      for (const auto& [obj, add] : adds) {
        std::vector<int> set = base.atoms;
        std::vector<double> theta = base.theta;
        set.push_back(add.first);
        theta.push_back(add.second);
        progress("fitting " + std::to_string(size) + " effects");
        grown.push_back(fit(set, theta).atoms);
      }
    }
    // Backward check: each effect of every new set dropped in turn, the rest re-fitted.
    for (const std::vector<int>& set : grown) {
      const Fit full = fitted.at(set);
      if (full.ok) fit_each_without_one(full);
    }
    const auto best = best_of_size(size, 1);
    if (best.empty() || !(best.front()->search_score < best_so_far)) break;
    best_so_far = best.front()->search_score;
  }
  // Swap (see the top of the file).
  std::vector<Fit> tops;
  for (int size = 2; options.swaps && size <= options.max_effects; ++size)
    for (const Fit* f : best_of_size(size, 1)) tops.push_back(*f);
  for (const Fit& top : tops) {
    for (size_t k = 0; k < top.atoms.size(); ++k) {
      const auto [rest, rest_theta] = WithoutOne(top, k);
      std::vector<std::pair<double, std::pair<int, double>>> swaps;
      for (int c = 0; c < total; ++c) {
        if (c == top.atoms[k] || !LookAlike(atoms[top.atoms[k]], atoms[c]) || !Compatible(atoms, top.atoms, c)) continue;
        progress("screening swaps");
        const auto [obj, theta] = Screen(p, rest, rest_theta, c, std::max(5, options.scan_points - 2));
        if (std::isfinite(obj)) swaps.push_back({obj, {c, theta}});
      }
      std::sort(swaps.begin(), swaps.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      if (static_cast<int>(swaps.size()) > std::max(1, options.additions / 2)) swaps.resize(std::max(1, options.additions / 2));
      for (const auto& [obj, swap] : swaps) {
        std::vector<int> set = rest;
        std::vector<double> theta = rest_theta;
        set.push_back(swap.first);
        theta.push_back(swap.second);
        const Fit swapped = fit(set, theta);
        if (swapped.ok) fit_each_without_one(swapped);
      }
    }
  }
  for (auto& [set, f] : fitted) result.fits.push_back(std::move(f));
  return result;
}

Fit FitSubset(Problem* p, const std::vector<Fit>& known, const std::vector<int>& set, const DiagnoseOptions& options) {
  for (const Fit& f : known)
    if (f.atoms == set) return f;
  // Start from the θ of the best known superset.
  const Fit* from = nullptr;
  for (const Fit& f : known) {
    if (!f.ok || f.atoms.size() <= set.size()) continue;
    if (!std::includes(f.atoms.begin(), f.atoms.end(), set.begin(), set.end())) continue;
    if (!from || f.search_score < from->search_score) from = &f;
  }
  std::vector<double> theta;
  for (int a : set) {
    double t = 0.0;
    if (from)
      for (size_t i = 0; i < from->atoms.size(); ++i)
        if (from->atoms[i] == a) t = from->theta[i];
    theta.push_back(t);
  }
  return FitSet(p, set, theta, options);
}

}  // namespace ema::diagnose::detail
