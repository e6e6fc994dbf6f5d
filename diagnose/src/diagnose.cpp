// Diagnose(): the stages in order (docs/diagnose.md). Each stage lives in its own file:
// candidates.cpp → search.cpp (screening, fits, combinations) with fit.cpp → explain.cpp.
#include "ema/diagnose/diagnose.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "ema/core/error.hpp"
#include "ema/model/solve.hpp"
#include "internal.hpp"

namespace ema::diagnose {

bool DiagnoseOptions::IsValid(std::string* error) const {
  std::string why;
  if (!(frequency_floor > 0.0)) why = "frequency_floor must be > 0, got " + std::to_string(frequency_floor);
  else if (!(shape_sigma > 0.0)) why = "shape_sigma must be > 0, got " + std::to_string(shape_sigma);
  else if (!(shape_dof_sigma > 0.0) || !std::isfinite(shape_dof_sigma))
    why = "shape_dof_sigma must be > 0, got " + std::to_string(shape_dof_sigma);
  else if (!(robust_threshold > 0.0)) why = "robust_threshold must be > 0, got " + std::to_string(robust_threshold);
  else if (scan_points < 3) why = "scan_points must be >= 3, got " + std::to_string(scan_points);
  else if (max_effects < 1 || max_effects > 3) why = "max_effects must be 1, 2 or 3, got " + std::to_string(max_effects);
  else if (beam < 1 || additions < 1) why = "beam and additions must be >= 1";
  else if (max_fitted_singles < 0) why = "max_fitted_singles must be >= 0";
  else if (reduced_model_min_dofs < 0) why = "reduced_model_min_dofs must be >= 0 (0: always full solves)";
  else if (kept_centres < 1) why = "kept_centres must be >= 1";
  else if (exact_candidates < 1) why = "exact_candidates must be >= 1";
  else if (polish_swaps < 0) why = "polish_swaps must be >= 0";
  else if (!(exact_margin >= 0.0)) why = "exact_margin must be >= 0 (nats; infinity: no margin)";
  else if (!(stiffness_fault_share >= 0.0 && stiffness_fault_share < 1.0))
    why = "stiffness_fault_share must be in [0, 1), got " + std::to_string(stiffness_fault_share);
  else if (!(stiffness_fault_sigma > 0.0)) why = "stiffness_fault_sigma must be > 0";
  else if (!(effect_prior_odds > 0.0 && effect_prior_odds <= 1.0))
    why = "effect_prior_odds must be in (0, 1], got " + std::to_string(effect_prior_odds);
  else if (!(model_error_frequency_min > 0.0 && model_error_frequency_max > model_error_frequency_min))
    why = "model_error_frequency_min must be > 0 and below model_error_frequency_max";
  else if (!(model_error_shape_min > 0.0 && model_error_shape_max > model_error_shape_min))
    why = "model_error_shape_min must be > 0 and below model_error_shape_max";
  if (error) *error = why;
  return why.empty();
}

std::string CriterionToString(Criterion criterion) { return NameOf(kCriterionNames, criterion); }

bool StringToCriterion(const std::string& name, Criterion* criterion) {
  return FromName(kCriterionNames, name, criterion);
}

std::string ShapeResidualToString(ShapeResidual shape_residual) { return NameOf(kShapeResidualNames, shape_residual); }

bool StringToShapeResidual(const std::string& name, ShapeResidual* shape_residual) {
  return FromName(kShapeResidualNames, name, shape_residual);
}

namespace {

using detail::Join;

// Readings re-fitted under the model error they inferred (the best by the ranking's evidence).
constexpr size_t kModelErrorRefits = 12;

// Setups must exist; test nodes must be test points of the model.
void CheckTests(const model::Model& base, const std::vector<SetupModes>& tests, const std::string& where) {
  if (tests.empty()) throw InputError(where, "no test given; expected at least one set of test modes");
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
}

// Baseline solve per setup (kept in *nominal for the evaluator: the one full solve of the base):
// DOF matching is done once (the observed DOFs do not move); each test frequency's σ is its
// measured spread or the floor.
std::vector<detail::SetupData> PrepareSetups(const model::Model& base, const std::vector<SetupModes>& tests,
                                             const DiagnoseOptions& options, int max_modes,
                                             std::vector<detail::NominalSolve>* nominal) {
  int test_modes = 0;
  for (const SetupModes& t : tests) test_modes += static_cast<int>(t.modes.modes.size());
  std::vector<detail::SetupData> setups;
  for (const SetupModes& t : tests) {
    nominal->push_back(detail::SolveNominal(base, t.setup, options, max_modes, test_modes));
    const model::Solution& sol = nominal->back().solution;
    detail::SetupData s;
    s.name = t.setup;
    s.match = correlation::MatchDofs(t.modes, sol.modes, options.dofs);
    if (s.match.Count() == 0)
      throw InputError(t.modes.source.empty() ? "test" : t.modes.source,
                       "no test DOF is observed by the model (the model gives +X/+Y/+Z at its test points)");
    s.test_shapes = s.match.TestShapes(t.modes);
    const auto n = static_cast<Eigen::Index>(t.modes.modes.size());
    s.test_hz.resize(n);
    s.sigma_hz.resize(n);
    s.sigma_shape.resize(n);
    s.half_power_hz.resize(n);
    const Eigen::Index measured_dofs = s.test_shapes.rows();
    s.real_shapes.resize(measured_dofs, n);
    s.sigma_dof.resize(measured_dofs, n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const Mode& m = t.modes.modes[static_cast<size_t>(i)];
      s.test_hz(i) = m.frequency_hz;
      // How well the mode was measured: its ML σ (ema fit), else the stabilisation spread.
      const double measured = std::isfinite(m.frequency_std_hz)      ? m.frequency_std_hz
                              : std::isfinite(m.frequency_spread_hz) ? m.frequency_spread_hz
                                                                     : 0.0;
      s.sigma_hz(i) = std::max(measured, options.frequency_floor * m.frequency_hz);
      // How well its shape was measured: the model's modes are real (modal damping), so a test
      // shape that is not (MPC < 1: two close modes fitted as one, a pole polluted by noise)
      // differs from any model mode by 1 − MAC of the order of 1 − MPC. Without this, a blended
      // shape at 1 − MAC = 0.26 weighs as 26 σ and spurious effects are "found" to reshape it.
      const double complexity = 1.0 - detail::PhaseCollinearity(s.test_shapes.col(i));
      s.sigma_shape(i) = std::hypot(options.shape_sigma, std::max(0.0, complexity));
      // The same per DOF (ShapeResidual::kPerDof), in units of the unit-norm shape: the floor
      // relative to its rms amplitude, the fit's σ of |φ| there, and the out-of-phase part.
      Eigen::VectorXd out_of_phase;
      const Eigen::VectorXd real = detail::RealShape(s.test_shapes.col(i), &out_of_phase);
      const double norm = s.test_shapes.col(i).norm();
      const double floor = options.shape_dof_sigma / std::sqrt(static_cast<double>(std::max<Eigen::Index>(1, measured_dofs)));
      for (Eigen::Index d = 0; d < measured_dofs; ++d) {
        const int test_index = s.match.shared[static_cast<size_t>(d)].test_index;
        const double fitted = m.shape_std.size() == m.shape.size() && test_index >= 0 && test_index < m.shape_std.size() &&
                                      std::isfinite(m.shape_std(test_index))
                                  ? m.shape_std(test_index)
                                  : 0.0;
        s.real_shapes(d, i) = norm > 0.0 ? real(d) / norm : 0.0;
        s.sigma_dof(d, i) = norm > 0.0 ? std::hypot(floor, std::hypot(fitted, out_of_phase(d)) / norm) : 1.0;
      }
      // Two model modes closer than the half-power bandwidth 2ζf (modal overlap > 1) are one
      // subspace to a hammer test: which basis of it the test returns depends on asymmetries no
      // model holds, so the fitted shape is judged against their span (BlendMac).
      const double zeta = std::isfinite(m.damping_ratio) ? std::max(m.damping_ratio, 1e-3) : 1e-3;
      s.half_power_hz(i) = 2.0 * zeta * m.frequency_hz;
    }
    s.model_dof_count = sol.modes.dofs.size();
    // The test's own sensors: one set of point masses per roving set (all measured nodes at once
    // when the sets are not known).
    if (t.sensor_mass > 0.0) {
      std::vector<std::vector<int>> sets = t.roving_sets;
      if (sets.empty()) {
        std::set<int> nodes;
        for (const Dof& d : t.modes.dofs) nodes.insert(d.node);
        sets.push_back({nodes.begin(), nodes.end()});
      }
      std::map<int, const model::TestPoint*> points;
      for (const auto& p : base.points) points[p.id] = &p;
      s.set_of_dof.assign(sol.modes.dofs.size(), -1);
      for (size_t k = 0; k < sets.size(); ++k) {
        std::vector<model::PointMass> sensors;
        std::set<int> in_set;
        for (int node : sets[k]) {
          const auto it = points.find(node);
          if (it == points.end() || !in_set.insert(node).second) continue;
          sensors.push_back({"sensor@" + std::to_string(node), it->second->where, t.sensor_mass, it->second->line});
        }
        int measured = 0;
        for (size_t d = 0; d < sol.modes.dofs.size(); ++d)
          if (in_set.count(sol.modes.dofs[d].node) && s.set_of_dof[d] < 0) s.set_of_dof[d] = static_cast<int>(k), ++measured;
        s.sensors.push_back(std::move(sensors));
        s.set_weight.push_back(std::max(1, measured));
      }
      s.equal_set_weights = true;
      for (const Mode& m : t.modes.modes)
        if (m.set_frequency_hz.size() != sets.size()) s.equal_set_weights = false;
      for (size_t d = 0; d < sol.modes.dofs.size(); ++d)
        if (t.reference.node > 0 && sol.modes.dofs[d].node == t.reference.node &&
            sol.modes.dofs[d].direction == std::abs(t.reference.direction))
          s.reference_row = static_cast<int>(d);
    }
    setups.push_back(std::move(s));
  }
  return setups;
}

// Whether a fit is more than `margin` (in −2 ln Z) behind the best judged by full solves, less the
// reduced models' measured overstatement — by the search's evidence and by the ranking's both: the
// ranking marginalises the model error, which brings poor fits closer together (a fit 1 200 behind
// by the search's score can be 70 behind by the ranking's), so a set far behind by one may still
// be in contention by the other.
bool Behind(const detail::Fit& f, double overstated, double best, double best_ranked, double margin) {
  return f.search_score - overstated > best + margin && f.score - overstated > best_ranked + margin;
}

// How far (in nats of the MAP objective, by the reduced model) a re-fit may improve on its centre
// for the centre's exact evaluation to stand for it: a score (−2 ln Z) then changes by at most
// 0.02 and a probability by about 1 %. A check is centred on the values the search fitted, and
// the re-fit on that basis moves them little (a loosened joint 0.302406 → 0.3025, 10⁻⁴ σ² of
// objective): one full solve instead of two, a minute at 220 941 DOFs (docs/diagnose.md).
constexpr double kCentreStandsNats = 0.01;

// How much a reported probability may move because a set is scored at its centre instead of at its
// re-fit: half a percentage point. A set's weight is exp(−(score − best)/2) of the best's, so
// scoring it at a worse point changes its probability, and the others' by as much in all, by at
// most the weight it loses — e^(−6) of the best's for one 12 behind even if the re-fit would have
// gained 5 nats (a look-alike pair on the 220 941-DOF bar: a full solve of 40 s for 0.2 %).
constexpr double kProbabilityTolerance = 0.005;

// A set re-centred at `centre` and re-fitted there (`refit`, on the new reduced model), judged by
// full solves: at the re-fitted values — or at the centre, whose full solve the reduced model's
// factory has made already (Evaluator::Evaluate takes it), when the reduced model puts the centre
// within kCentreStandsNats of the re-fit; when the re-fit's reduced score and the exact score at
// the centre both lie more than `limit` behind (out of contention: at 50 000 DOFs one full solve
// fewer for each such set); or when the re-fit's weight by its reduced score, exp(−(score −
// `best_ranked`)/2), exceeds the centre's exact one by no more than kProbabilityTolerance (a set
// far enough behind that the best its re-fit could do moves no probability by more than that).
// The centre's exact evaluation is the factory's solve, made already — where the test's sensors
// are on the model it is one more solve, which a set near the top then pays for nothing.
// Either way the reported score is an exact evaluation at one point of the set, never better than
// the set's best; the reduced model decides only whether the second solve is made.
detail::Fit AssessAtBest(detail::Problem* p, const std::vector<int>& set, const std::vector<double>& centre,
                         const detail::Fit& refit, double limit, double best_ranked, const DiagnoseOptions& options) {
  const bool same_set = refit.atoms == set;
  const bool centre_stands = same_set && p->Objective(set, centre) - p->Objective(set, refit.theta) <= kCentreStandsNats;
  const bool weights_known = same_set && std::isfinite(best_ranked) && std::isfinite(refit.score);
  if (centre_stands || refit.search_score > limit || weights_known) {
    detail::Fit at_centre = detail::Assess(p, set, centre, options, true);
    auto weight = [&](double score) { return std::exp(-0.5 * (score - best_ranked)); };
    const bool little_to_gain = weights_known && weight(refit.score) - weight(at_centre.score) <= kProbabilityTolerance;
    if (at_centre.ok && (centre_stands || at_centre.search_score > limit || little_to_gain)) return at_centre;
  }
  return detail::Assess(p, refit.atoms, refit.theta, options, true);
}

// The search's swap move (search.cpp) judges a look-alike through reduced models and from the
// search's own best sets; on an FE model a part factor can stand in for another part's at a value
// that part itself does not fit (benchmark case 43: a deck plate ×1.36 for one cross-beam zone
// ×2.47, so the true pair was never fitted and three effects won at 92 %). So the best polished
// fit of each size ≥ 2 (as the search's swap) has each effect replaced by each look-alike of the
// same kind, screened for its own value with the rest held; the 3·`polish_swaps` best starts are
// ranked again on the leader's own reduced model and the `polish_swaps` best of those re-fitted
// there, then on a basis centred where the fit went, and judged by full solves. Single effects are
// left alone, as in the search: on a 50 000-DOF model each full solve is a second or more.
void PolishSwaps(detail::Problem* p, std::vector<detail::Fit>* fits, const DiagnoseOptions& options) {
  if (options.polish_swaps == 0) return;
  std::map<size_t, detail::Fit> leaders;  // copies: *fits grows below
  double best = detail::kInf, best_ranked = detail::kInf;
  for (const detail::Fit& f : *fits)
    if (f.ok && f.exact) best = std::min(best, f.search_score), best_ranked = std::min(best_ranked, f.score);
  for (const detail::Fit& f : *fits) {
    // Swaps search near a set in contention: one more than `exact_margin` behind the best is not
    // worth the full solves (each seconds on a 50 000-DOF model).
    if (!f.ok || !f.exact || f.atoms.size() < 2 || Behind(f, 0.0, best, best_ranked, 2.0 * options.exact_margin)) continue;
    auto it = leaders.find(f.atoms.size());
    if (it == leaders.end() || f.search_score < it->second.search_score) leaders[f.atoms.size()] = f;
  }
  const std::vector<detail::Atom>& atoms = p->Atoms();
  using Start = std::pair<double, std::pair<std::vector<int>, std::vector<double>>>;
  for (const auto& [size, leader] : leaders) {
    std::vector<Start> starts;
    for (size_t k = 0; k < leader.atoms.size(); ++k) {
      const detail::Atom& a = atoms[leader.atoms[k]];
      for (int c = 0; c < static_cast<int>(atoms.size()); ++c) {
        if (atoms[c].effect.kind != a.effect.kind || !detail::LookAlike(a, atoms[c])) continue;
        if (std::find(leader.atoms.begin(), leader.atoms.end(), c) != leader.atoms.end()) continue;
        // The look-alike's own best value with the rest held (a factor on one cross-beam zone
        // must change twice as much as one on the deck that spans them all: benchmark case 43).
        const auto [rest, rest_theta] = detail::WithoutOne(leader, k);
        const auto [reduced, value] = detail::Screen(p, rest, rest_theta, c, std::max(5, options.scan_points - 2));
        if (!std::isfinite(reduced)) continue;
        std::vector<int> set = rest;
        std::vector<double> theta = rest_theta;
        set.push_back(c);
        theta.push_back(value);
        starts.push_back({reduced, detail::Sorted(set, theta)});
      }
    }
    auto by_objective = [](const Start& x, const Start& y) { return x.first < y.first; };
    std::sort(starts.begin(), starts.end(), by_objective);
    if (static_cast<int>(starts.size()) > 3 * options.polish_swaps) starts.resize(3 * options.polish_swaps);
    // Ranked on the leader's own reduced model (its centre was made when it was checked): each
    // start is the leader with one effect swapped for a look-alike, near that centre — nine full
    // solves at 50 000 DOFs saved; the best are judged by full solves below.
    for (Start& s : starts) {
      const auto eval = p->AtCentreOf(leader.atoms, s.second.first, s.second.second);
      s.first = eval->ok ? 0.5 * eval->cost - p->LogPrior(s.second.first, s.second.second) : detail::kInf;
    }
    std::sort(starts.begin(), starts.end(), by_objective);
    if (static_cast<int>(starts.size()) > options.polish_swaps) starts.resize(options.polish_swaps);
    for (const auto& [objective, start] : starts) {
      if (!std::isfinite(objective)) continue;
      ReportProgress(options.progress, 0.97, "checking a look-alike with full solves");
      // Fitted first on the leader's centre, where it was ranked (a full solve at the start
      // itself bought no better direction: the fit is centred again where it goes, below).
      p->RecentreOn(start.first, leader.atoms);
      detail::Fit refit = detail::FitSet(p, start.first, start.second, options);
      if (!refit.ok) continue;
      // A swap can land on a set the polish judged by full solves already (the 220 941-DOF bar:
      // J3+J5, re-found 0.002 better for two solves of 40 s). Only a better fit than that one's,
      // compared on this same reduced model, is worth the solves.
      auto judged = std::find_if(fits->begin(), fits->end(),
                                 [&](const detail::Fit& f) { return f.ok && f.exact && f.atoms == refit.atoms; });
      if (judged != fits->end() && refit.objective >= p->Objective(judged->atoms, judged->theta) - kCentreStandsNats) continue;
      // Centred again where it went (a swapped factor can move from 0.2 to 0.9): the Laplace
      // Hessian comes from the reduced model's Jacobian, and one centred at the start was off by
      // e^12 in det H there (benchmark case 159: a spurious third effect at "99.9 %").
      const std::vector<double> centre = refit.theta;
      p->Recentre(refit.atoms, centre);
      refit = detail::FitSet(p, refit.atoms, centre, options);
      if (!refit.ok) continue;
      refit = AssessAtBest(p, refit.atoms, centre, refit, best + 2.0 * options.exact_margin, best_ranked, options);
      if (!refit.ok) continue;
      auto same = std::find_if(fits->begin(), fits->end(), [&](const detail::Fit& f) { return f.atoms == refit.atoms; });
      if (same == fits->end()) fits->push_back(std::move(refit));
      else if (!same->ok || !same->exact || refit.search_score < same->search_score) *same = std::move(refit);
    }
  }
}

// θ at which an atom's effect is absent: its "no effect" end, else θ = 0 (the reference value: a
// factor of 1, the nominal operating point).
double AbsentTheta(const detail::ParamSpec& s) { return s.absent_end < 0 ? s.lo : (s.absent_end > 0 ? s.hi : 0.0); }

// Whether an effect pays for itself is decided against the same set without it — and that set must
// have had the same chance: the search fitted it on reduced models centred elsewhere, where it can
// stay stuck (a joint at ×0.10 for a truth of ×0.30 on the nominal centre: 6.5 % frequency error)
// while the set with one more effect, re-centred, reaches the truth plus milligrams at a point that
// move nothing — then "J3 + 28 mg at point 103" outranks J3 alone, which was never judged there
// (fe-import/loosened-joint-small). So after a set is checked, each set one effect smaller that has
// not been judged by full solves is screened on the checked set's own reduced model with that effect
// absent (the misfit it would add), and when that leaves it within `limit` it is checked from the
// checked set's values.
template <class Check>
void BackwardFromChecked(detail::Problem* p, std::vector<detail::Fit>* fits, size_t checked, double limit,
                         const Check& check) {
  const detail::Fit big = (*fits)[checked];  // a copy: the elements of *fits are replaced below
  if (big.atoms.size() < 2) return;
  const auto at_fit = p->At(big.atoms, big.theta);
  if (!at_fit->ok) return;
  for (size_t k = 0; k < big.atoms.size(); ++k) {
    // Not a structured binding: clang 14 (the sanitizer tree's) does not capture one in a lambda.
    const std::pair<std::vector<int>, std::vector<double>> without_one = detail::WithoutOne(big, k);
    const std::vector<int>& rest = without_one.first;
    const std::vector<double>& rest_theta = without_one.second;
    auto small = std::find_if(fits->begin(), fits->end(), [&](const detail::Fit& f) { return f.atoms == rest; });
    if (small == fits->end() || (small->ok && small->exact)) continue;
    std::vector<double> without = big.theta;
    without[k] = AbsentTheta(p->Atoms()[big.atoms[k]].spec);
    const auto at_without = p->At(big.atoms, without);
    if (!at_without->ok || big.search_score + (at_without->cost - at_fit->cost) > limit) continue;
    detail::Fit refit = check(rest, rest_theta);
    if (!refit.ok) continue;
    *small = std::move(refit);  // `small` stays valid: *fits does not grow here
  }
}

// FE-sized models are searched through reduced models: the best fits are re-fitted on a basis
// centred at their values (a full solve there) and their misfit, what is reported and ranked,
// comes from full solves.
void Polish(detail::Problem* p, std::vector<detail::Fit>* fits, const DiagnoseOptions& options) {
  if (!p->Reduced()) return;
  std::vector<size_t> order;
  for (size_t i = 0; i < fits->size(); ++i)
    if ((*fits)[i].ok && !(*fits)[i].atoms.empty()) order.push_back(i);
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return (*fits)[a].search_score < (*fits)[b].search_score; });
  if (static_cast<int>(order.size()) > options.exact_candidates) order.resize(options.exact_candidates);
  // Every fitted subset of those too: whether an effect pays for itself is decided against the
  // same set without it, and both must be judged by full solves (a reduced model far from its
  // centre can make the smaller set look worse than it is).
  for (size_t k = 0, top = order.size(); k < top; ++k) {
    const std::vector<int>& big = (*fits)[order[k]].atoms;
    for (size_t i = 0; i < fits->size(); ++i) {
      const std::vector<int>& small = (*fits)[i].atoms;
      if (!(*fits)[i].ok || small.empty() || small.size() >= big.size() ||
          std::find(order.begin(), order.end(), i) != order.end())
        continue;
      if (std::includes(big.begin(), big.end(), small.begin(), small.end())) order.push_back(i);
    }
  }
  // Full solves go where they can change the answer: a set whose reduced-model score, less the
  // most by which a reduced score has overstated a full one so far, is still more than
  // `exact_margin` nats behind the best full score — by the search's score and the ranking's both
  // (Behind) — keeps its reduced-model misfit. Where the reduced models are good (the 12 000-DOF
  // frame: within 3 nats) that spares the sets far behind; where they are poor the first check
  // shows it (the allowance grows by as much) and the sets behind are checked as before.
  double best_full = detail::kInf, best_full_ranked = detail::kInf, overstated = 0.0;
  const double margin = 2.0 * options.exact_margin;  // scores are −2 ln Z
  // A set re-centred at `start`, re-fitted there and judged by full solves (not ok: it failed).
  auto check = [&](const std::vector<int>& set, const std::vector<double>& start) {
    ReportProgress(options.progress, 0.95, "checking " + std::to_string(set.size()) + " effect(s) with full solves");
    p->Recentre(set, start);
    detail::Fit refit = detail::FitSet(p, set, start, options);
    if (!refit.ok) return refit;
    return AssessAtBest(p, set, start, refit, best_full + margin, best_full_ranked, options);
  };
  for (size_t i : order) {
    detail::Fit& f = (*fits)[i];
    if (f.exact) continue;  // checked already, from a larger set's values (below)
    if (Behind(f, overstated, best_full, best_full_ranked, margin)) continue;
    const double reduced_score = f.search_score;
    detail::Fit refit = check(f.atoms, f.theta);
    if (!refit.ok) continue;
    overstated = std::max(overstated, reduced_score - refit.search_score);
    best_full = std::min(best_full, refit.search_score);
    best_full_ranked = std::min(best_full_ranked, refit.score);
    f = std::move(refit);
    BackwardFromChecked(p, fits, i, best_full + overstated + margin, check);
  }
  PolishSwaps(p, fits, options);
}

// The error falling as rank 1's effects are added one at a time, in the order of their single
// evidence (each subset re-fitted).
std::vector<Step> Steps(detail::Problem* p, const std::vector<detail::Fit>& fits, const detail::Fit& first,
                        const Candidate& none, const DiagnoseOptions& options) {
  std::vector<Step> steps;
  steps.push_back({"", none.mean_abs_frequency_error_pct, none.mean_mac, none.mean_agreement_pct});
  std::vector<int> order = first.atoms;
  auto single_score = [&](int a) {
    for (const auto& f : fits)
      if (f.atoms.size() == 1 && f.atoms[0] == a && f.ok) return f.search_score;
    return detail::kInf;
  };
  std::sort(order.begin(), order.end(), [&](int a, int b) { return single_score(a) < single_score(b); });
  std::vector<int> set;
  for (int a : order) {
    set.push_back(a);
    std::vector<int> sorted = set;
    std::sort(sorted.begin(), sorted.end());
    detail::Fit f = detail::FitSubset(p, fits, sorted, options);
    if (f.ok && !f.exact) f = detail::Assess(p, f.atoms, f.theta, options, true);
    if (!f.ok) break;
    steps.push_back({p->Atoms()[a].Label(), f.eval->mean_abs_frequency_error_pct, f.eval->mean_mac,
                     f.eval->mean_agreement_pct});
  }
  return steps;
}

}  // namespace

Diagnosis Diagnose(const model::Model& input_model, const std::vector<SetupModes>& tests,
                   const DiagnoseOptions& options) {
  if (std::string bad; !options.IsValid(&bad)) throw UsageError("diagnose options: " + bad);
  const std::string where = input_model.origin.empty() ? "model" : input_model.origin;
  const model::Model base = model::ApplyEffects(input_model);
  CheckTests(base, tests, where);
  int max_test_modes = 0;
  for (const SetupModes& t : tests) max_test_modes = std::max<int>(max_test_modes, t.modes.modes.size());
  const int max_modes = base.fe.Empty() ? 0 : std::max(20, 2 * max_test_modes + 4);

  std::vector<detail::NominalSolve> nominal;
  std::vector<detail::SetupData> setups = PrepareSetups(base, tests, options, max_modes, &nominal);
  detail::Evaluator evaluator(base, std::move(setups), options, max_modes, std::move(nominal));
  Diagnosis result;
  result.residual_count = evaluator.ResidualCount();
  result.test_mode_count = evaluator.TestModeCount();

  // Stage 1: candidates.
  std::vector<detail::Atom> atoms = detail::BuildAtoms(base, options);
  detail::Problem problem(&evaluator, &atoms);

  // Baseline ("none").
  const detail::Fit none_fit = detail::Assess(&problem, {}, {}, options);
  if (!none_fit.ok) throw InputError(where, "the model cannot be solved: " + none_fit.error);
  if (none_fit.eval->paired < 2) {
    std::ostringstream msg;
    msg << "only " << none_fit.eval->paired << " test mode(s) pair with a model mode (MAC ≥ " << options.pairing.mac_min
        << "); at least 2 paired modes are needed to fit any parameter";
    throw InputError(where, msg.str());
  }
  Candidate none = detail::MakeCandidate(&problem, none_fit, none_fit.eval->cost);
  none.explained_pct = 0.0;

  // Stages 2–4: screening, fits, combinations.
  detail::SearchResult search = detail::Search(&problem, options);
  result.candidates_screened = search.screened;
  Polish(&problem, &search.fits, options);

  // Stage 5: ranking.
  // The best readings by the ranking's evidence are fitted again where the model's own error
  // dominates the test's σ (their parameters then weigh each mode by both).
  {
    std::vector<size_t> order(search.fits.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return search.fits[a].score < search.fits[b].score; });
    for (size_t i = 0; i < order.size() && i < kModelErrorRefits; ++i)
      search.fits[order[i]] = detail::RefitUnderModelError(&problem, search.fits[order[i]], options);
  }
  std::vector<Candidate> all;
  all.push_back(none);
  for (const detail::Fit& f : search.fits) all.push_back(detail::MakeCandidate(&problem, f, none.cost));
  detail::Rank(&all, none);
  for (const Candidate& c : all)
    if (c.IsNone()) result.baseline = c;
  result.effect_probabilities = EffectProbabilities(all);
  result.groups = GroupCandidates(all);

  // Stage 6: explanation, and the error falling as rank 1's effects are added.
  result.explanation = detail::Explain(all, result.baseline);
  if (all.front().effects.empty()) {
    result.steps.push_back({"", none.mean_abs_frequency_error_pct, none.mean_mac, none.mean_agreement_pct});
  } else {
    for (const detail::Fit& f : search.fits)
      if (problem.Effects(f.atoms, f.theta).size() == all.front().effects.size() && f.ok &&
          std::abs(f.score - all.front().score) == 0.0) {
        result.steps = Steps(&problem, search.fits, f, none, options);
        break;
      }
  }
  result.candidates = std::move(all);
  result.model_solves = evaluator.Solves();
  ReportProgress(options.progress, 1.0, "done");
  return result;
}

}  // namespace ema::diagnose
