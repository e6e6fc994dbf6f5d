#include "ema/curvefit/fit.hpp"

#include "ema/core/error.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace ema::curvefit {

std::vector<SelectedPole> SelectPolesNarrowBand(const StabilisationDiagram& diagram, const FitOptions& options,
                                                std::string* note) {
  // A band of few lines supports few orders (the normal equations turn singular early), so a
  // physical pole is seen at only a handful of orders, and at those low orders its damping
  // still moves by more than the 5 % of the default criterion between orders. Relax both to
  // what such a band can show: damping stable to 20 %, a cluster over 3 orders.
  const int orders = static_cast<int>(diagram.orders.size());
  const int lines = static_cast<int>(diagram.frequency_hz.size());
  if (orders < 2 || lines > options.narrow_band_max_lines) return {};
  StabilisationDiagram relaxed = diagram;
  StabilityOptions stability = options.stability;
  stability.damping_tol = std::max(stability.damping_tol, 0.2);
  ClassifyStability(&relaxed, stability);
  AutoSelectOptions select = options.auto_select;
  select.min_orders = std::min(select.min_orders, 3);
  std::vector<SelectedPole> selected = SelectPolesAuto(relaxed, select);
  if (note && !selected.empty())
    *note = "narrow band (" + std::to_string(diagram.frequency_hz.size()) + " lines, orders " +
            std::to_string(diagram.order_min) + ".." + std::to_string(diagram.order_max) +
            "): poles selected with relaxed stability (damping within 20 %, clusters over 3 orders)";
  return selected;
}

namespace {

// Fewer orders than this in the diagram: the narrow-band retry of automatic selection may replace
// a strict selection that found some modes (see Fit).
constexpr int kFewOrders = 20;

// Smallest Wald statistic of a pole's residues that counts as a mode, whatever its degrees of
// freedom (2 per FRF): chi2 with 2 dof exceeds 25 with probability 4e-6.
constexpr double kNoisePoleChi2Floor = 25.0;

// ML refinement of the selected poles (or, for --refine none, only their uncertainty). Updates the
// poles (and, from the refined residues, the participation vectors) when the refinement is usable.
bool RefineSelected(const FitData& data, const FitOptions& options, const std::string& source, FitResult* result,
                    MlRefineResult* ml, const ProgressCallback& progress) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  MlRefineOptions mo = options.ml;
  mo.estimate_only = options.refine == RefineMethod::kNone;
  mo.lower_residual = options.lsfd.lower_residual;
  mo.upper_residual = options.lsfd.upper_residual;
  try {
    *ml = RefineModalModel(data, result->selected, mo, progress);
  } catch (const InputError& e) {
    result->warnings.push_back(source + ": no ML refinement or uncertainty: " + e.what());
    return false;
  }
  result->refine = ml->summary;
  result->timing.refine_wall = std::chrono::duration<double>(Clock::now() - t0).count();
  if (!ml->summary.IsSolutionUsable()) {
    result->warnings.push_back(source + ": " + ml->summary.BriefReport() + "; PolyMAX poles kept");
    return std::isfinite(ml->summary.final_cost);  // sigma at the PolyMAX poles when computed
  }
  if (mo.estimate_only) return true;
  const int m = data.ReferenceCount(), l = data.OutputCount();
  for (size_t r = 0; r < result->selected.size(); ++r) {
    Pole& p = result->selected[r].pole;
    const RefinedPole& rp = ml->poles[r];
    p.lambda_fitted = rp.lambda_fitted;
    p.lambda = rp.lambda;
    p.frequency_hz = rp.frequency_hz;
    p.damping_ratio = rp.damping_ratio;
    if (m >= 2) {
      // R_r = phi l^T over (output, reference): rank-one part by SVD, l = conj(first right vector).
      Eigen::MatrixXcd rr(l, m);
      for (int o = 0; o < l; ++o)
        for (int i = 0; i < m; ++i) rr(o, i) = ml->residues(o * m + i, static_cast<int>(r));
      Eigen::JacobiSVD<Eigen::MatrixXcd> svd(rr, Eigen::ComputeThinV);
      if (svd.singularValues()[0] > 0.0) p.participation = svd.matrixV().col(0).conjugate();
    }
  }
  return true;
}

// Roving-sensor tests: each roving set's FRFs refined with poles of their own, from the common
// PolyMAX poles. Usable when every set's refinement is; the selection's poles become the mean
// over the sets.
struct PerSetRefinement {
  bool ok = false;
  /// Every set's refined poles stayed in place (MlRefineSummary::poles_plausible), whether or not
  /// the misfit test accepted them.
  bool poles_plausible = false;
  std::vector<MlRefineResult> sets;
  SetPoles poles;
  std::string why;  ///< when not usable: the first set that was not
};

// `accept_misfit`: no misfit test (every set's poles kept where they settle, their σ scaled by the
// misfit), for a band whose misfit rejects every refinement whatever the poles.
PerSetRefinement RefinePerSet(const FitData& data, const FitOptions& options, const std::vector<SelectedPole>& selected,
                              const ProgressCallback& progress, bool accept_misfit = false) {
  PerSetRefinement out;
  const std::vector<std::vector<int>> sets = data.SetOutputs();
  if (sets.size() < 2 || options.refine != RefineMethod::kMl || !options.per_set_poles) return out;
  MlRefineOptions mo = options.ml;
  if (accept_misfit) mo.max_reduced_chi2 = std::numeric_limits<double>::infinity();
  mo.lower_residual = options.lsfd.lower_residual;
  mo.upper_residual = options.lsfd.upper_residual;
  // A set rejected only for its misfit does not end the loop: whether the other sets' poles stay in
  // place is what FindSetSplitPoles asks.
  out.poles_plausible = true;
  for (size_t k = 0; k < sets.size(); ++k) {
    MlRefineResult r;
    ProgressCallback set_progress;  // set k of K: (k + its share) / K
    if (progress)
      set_progress = [&progress, k, count = static_cast<double>(sets.size())](double f, std::string_view stage) {
        progress((static_cast<double>(k) + f) / count, stage);
      };
    try {
      r = RefineModalModel(SubsetOutputs(data, sets[k]), selected, mo, set_progress);
    } catch (const InputError& e) {
      if (out.why.empty()) out.why = "roving set " + std::to_string(k + 1) + ": " + e.what();
      out.poles_plausible = false;
      return out;
    }
    if (!r.summary.IsSolutionUsable()) {
      if (out.why.empty()) out.why = "roving set " + std::to_string(k + 1) + ": " + r.summary.BriefReport();
      if (!r.summary.poles_plausible) {
        out.poles_plausible = false;
        return out;
      }
    }
    out.poles.outputs.push_back(sets[k]);
    out.poles.lambda_fitted.emplace_back();
    for (const RefinedPole& p : r.poles) out.poles.lambda_fitted.back().push_back(p.lambda_fitted);
    out.sets.push_back(std::move(r));
  }
  out.ok = out.why.empty();
  return out;
}

// The selection's poles as the mean of the sets' (frequency and damping averaged with equal
// weights: what the diagnosis compares with the model's mean over the same sets), and the
// refinement summary over the sets.
void ApplyPerSet(const PerSetRefinement& per, FitResult* result) {
  const double k = static_cast<double>(per.sets.size());
  double chi2 = 0.0, initial = 0.0, final = 0.0;
  int iterations = 0;
  for (const auto& s : per.sets) {
    chi2 = std::max(chi2, s.summary.reduced_chi2);
    initial += s.summary.initial_cost;
    final += s.summary.final_cost;
    iterations = std::max(iterations, s.summary.iterations);
  }
  for (size_t r = 0; r < result->selected.size(); ++r) {
    double f = 0.0, z = 0.0;
    std::complex<double> fitted = 0.0;
    for (const auto& s : per.sets) {
      f += s.poles[r].frequency_hz / k;
      z += s.poles[r].damping_ratio / k;
      fitted += s.poles[r].lambda_fitted - s.poles[r].lambda;  // the window's damping
    }
    Pole& p = result->selected[r].pole;
    p.frequency_hz = f;
    p.damping_ratio = z;
    p.lambda = FrequencyAndDampingToPole(f, z);
    p.lambda_fitted = p.lambda + fitted / k;
    // Participation: the rank-one part of the refined residues of every set (outputs × references),
    // as the one-pole refinement does (RefineSelected).
    const int m = static_cast<int>(p.participation.size());
    if (m >= 2) {
      Eigen::Index rows = 0;
      for (const auto& s : per.sets) rows += s.residues.rows() / m;
      Eigen::MatrixXcd rr(rows, m);
      Eigen::Index row = 0;
      for (const auto& s : per.sets)
        for (Eigen::Index o = 0; o < s.residues.rows() / m; ++o, ++row)
          for (int i = 0; i < m; ++i) rr(row, i) = s.residues(o * m + i, static_cast<Eigen::Index>(r));
      Eigen::JacobiSVD<Eigen::MatrixXcd> svd(rr, Eigen::ComputeThinV);
      if (svd.singularValues()[0] > 0.0) p.participation = svd.matrixV().col(0).conjugate();
    }
  }
  MlRefineSummary& sum = result->refine;
  sum = per.sets.front().summary;
  sum.termination = RefineTermination::kConverged;
  for (const auto& s : per.sets)
    if (s.summary.termination == RefineTermination::kNoConvergence) sum.termination = RefineTermination::kNoConvergence;
  sum.iterations = iterations;
  sum.initial_cost = initial;
  sum.final_cost = final;
  sum.reduced_chi2 = chi2;
  std::ostringstream msg;
  msg.precision(3);
  msg << "each of " << per.sets.size() << " roving sets fitted with its own poles (largest reduced chi2 " << chi2 << ")";
  sum.message = msg.str();
}

// Each mode's frequency and damping as every set saw it, and σ of their mean.
void AttachSetFrequencies(const PerSetRefinement& per, LsfdResult& lsfd) {
  const double k = static_cast<double>(per.sets.size());
  for (size_t r = 0; r < lsfd.modes.modes.size(); ++r) {
    Mode& mode = lsfd.modes.modes[r];
    double var_f = 0.0, var_z = 0.0;
    for (const auto& s : per.sets) {
      const RefinedPole& p = s.poles[r];
      mode.set_frequency_hz.push_back(p.frequency_hz);
      mode.set_damping_ratio.push_back(p.damping_ratio);
      mode.set_frequency_std_hz.push_back(p.frequency_std_hz);
      var_f += p.frequency_std_hz * p.frequency_std_hz;
      var_z += p.damping_ratio_std * p.damping_ratio_std;
    }
    mode.frequency_std_hz = std::sqrt(var_f) / k;
    mode.damping_ratio_std = std::sqrt(var_z) / k;
  }
}

// Frequency/damping sigma per mode; sigma of |shape| from the residues' sigma at the strongest
// reference, scaled like the shape (first order; the scaling factor's own uncertainty neglected).
void AttachUncertainty(const MlRefineResult& ml, LsfdResult& lsfd) {
  const int n_frf = static_cast<int>(ml.residues.rows());
  for (size_t r = 0; r < lsfd.modes.modes.size() && r < ml.poles.size(); ++r) {
    Mode& mode = lsfd.modes.modes[r];
    mode.frequency_std_hz = ml.poles[r].frequency_std_hz;
    mode.damping_ratio_std = ml.poles[r].damping_ratio_std;
    const int m = static_cast<int>(mode.participation.size());
    const int l = static_cast<int>(mode.shape.size());
    if (m == 0 || l * m != n_frf) continue;
    int imax = 0;
    mode.participation.cwiseAbs().maxCoeff(&imax);
    double res_norm = 0.0;
    for (int o = 0; o < l; ++o) res_norm += std::norm(lsfd.residues(o * m + imax, static_cast<int>(r)));
    res_norm = std::sqrt(res_norm);
    if (!(res_norm > 0.0)) continue;
    const double kappa = mode.shape.norm() / res_norm;
    mode.shape_std.resize(l);
    for (int o = 0; o < l; ++o) mode.shape_std[o] = kappa * ml.residue_std(o * m + imax, static_cast<int>(r));
  }
}

void FillModel(const FitData& data, const std::vector<SelectedPole>& selected, const LsfdResult& lsfd, ModalModel* model) {
  model->outputs = data.outputs;
  model->references = data.references;
  model->transposed = data.transposed;
  model->frf_type = data.frf_type;
  model->band_lo_hz = data.frequency_hz.size() ? data.frequency_hz[0] : 0.0;
  model->band_hi_hz = data.frequency_hz.size() ? data.frequency_hz[data.frequency_hz.size() - 1] : 0.0;
  model->poles_fitted.clear();
  for (const auto& s : selected) model->poles_fitted.push_back(s.pole.lambda_fitted);
  model->residues = lsfd.residues;
  model->lower_residual = lsfd.lower_residual;
  model->upper_residual = lsfd.upper_residual;
}

// The note of a pole dropped as the same mode as `kept`: "same mode as the one at 485.35 Hz" and
// then `why`. Two decimals, as the note gives the dropped pole's own frequency: "473 Hz" and
// "1.05e+03 Hz" beside "1059.42 Hz" read as another mode.
DroppedPole MergedPole(const Pole& dropped, const Pole& kept, const std::string& why) {
  std::ostringstream reason;
  reason << std::fixed << std::setprecision(2) << "same mode as the one at " << kept.frequency_hz << " Hz" << why;
  DroppedPole d;
  d.frequency_hz = dropped.frequency_hz;
  d.damping_ratio = dropped.damping_ratio;
  d.merged_into_hz = kept.frequency_hz;
  d.reason = reason.str();
  return d;
}

// Two poles whose half-power bands overlap, with the same participation vector (the references
// excite them alike: m >= 2) but living on different outputs (little overlap of |shape|^2) are one
// mode measured with different frequencies by different roving sets (sensor mass loading) or
// records: the weaker (smaller residue energy) is returned for dropping, -1 when there is none.
int FindSplitPole(const FitData& data, const std::vector<SelectedPole>& selected, const LsfdResult& lsfd,
                  const SplitPoleOptions& options, DroppedPole* dropped) {
  const int n = static_cast<int>(selected.size());
  const int m = data.ReferenceCount();
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      const Pole& pa = selected[a].pole;
      const Pole& pb = selected[b].pole;
      if (std::abs(pa.frequency_hz - pb.frequency_hz) >=
          pa.damping_ratio * pa.frequency_hz + pb.damping_ratio * pb.frequency_hz)
        continue;  // half-power bands apart: resolvable modes
      double part_mac = kNaN;
      if (m >= 2) {
        part_mac = Mac(pa.participation, pb.participation);
        if (!(part_mac >= options.participation_mac_min)) continue;
      }
      const Eigen::VectorXcd& sa = lsfd.modes.modes[a].shape;
      const Eigen::VectorXcd& sb = lsfd.modes.modes[b].shape;
      if (sa.size() != sb.size() || sa.size() == 0 || !(sa.squaredNorm() > 0.0) || !(sb.squaredNorm() > 0.0)) continue;
      const Eigen::VectorXd ea = sa.cwiseAbs2() / sa.squaredNorm(), eb = sb.cwiseAbs2() / sb.squaredNorm();
      const double overlap = ea.cwiseMin(eb).sum();
      if (!(overlap <= options.support_overlap_max)) continue;
      const double energy_a = lsfd.residues.col(a).squaredNorm(), energy_b = lsfd.residues.col(b).squaredNorm();
      const int weak = energy_a < energy_b ? a : b, strong = weak == a ? b : a;
      std::ostringstream why;
      why.precision(3);
      why << " seen on other outputs (" << (m >= 2 ? "participation MAC " : "");
      if (m >= 2) why << part_mac << ", ";
      why << "shape overlap " << overlap
          << "): roving sets or records disagree on its frequency; the mode is fitted as one pole";
      *dropped = MergedPole(selected[weak].pole, selected[strong].pole, why.str());
      return weak;
    }
  return -1;
}

// A tenth of a half-power bandwidth: sets that see a mode this far apart are not one pole's.
constexpr double kSetsApartBandwidths = 0.1;

// Whether the sets' refined poles put some mode apart by at least `bandwidths` half-power
// bandwidths (2ζf at the sets' mean): what one pole for every set cannot hold.
bool SetsSeeModesApart(const PerSetRefinement& per, double bandwidths) {
  if (per.sets.size() < 2) return false;
  for (size_t r = 0; r < per.sets.front().poles.size(); ++r) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo, f = 0.0, z = 0.0;
    for (const auto& s : per.sets) {
      if (r >= s.poles.size()) return false;
      lo = std::min(lo, s.poles[r].frequency_hz);
      hi = std::max(hi, s.poles[r].frequency_hz);
      f += s.poles[r].frequency_hz / static_cast<double>(per.sets.size());
      z += s.poles[r].damping_ratio / static_cast<double>(per.sets.size());
    }
    if (hi - lo >= bandwidths * 2.0 * z * f) return true;
  }
  return false;
}

// The poles FitPreparedData drops when a roving test's sets could not be refined with poles of
// their own. The pairs of poles closer than a set's refined pole can move (|Δf| < 2 (ζa fa + ζb fb):
// the refinement keeps a pole within 2 half-power bandwidths of its start), closest first and each
// pole in one pair at most, are candidates: the weaker of
// each pair (smaller residue energy) dropped — all of them, else all but the farthest pair, ... (at
// most kMaxSetSplitTries refinements of every set) — when every set's refinement is then usable,
// or when every set's refined poles then stay in place where with all poles (`with_all`) one did
// not (a band whose misfit rejects every refinement, the one-set test's as well).
// Indices into `selected`, highest first (erase in that order); empty when no such drop works.
std::vector<int> FindSetSplitPoles(const FitData& data, const FitOptions& options,
                                   const std::vector<SelectedPole>& selected, const LsfdResult& lsfd,
                                   const PerSetRefinement& with_all, std::vector<DroppedPole>* dropped,
                                   const ProgressCallback& progress) {
  constexpr int kMaxSetSplitTries = 4;
  constexpr double kReach = 2.0;  // |Δf| / (ζa fa + ζb fb) a set's pole can bridge
  struct Pair {
    double closeness;  // |Δf| over ζa fa + ζb fb
    int a, b;
  };
  std::vector<Pair> pairs;
  const int n = static_cast<int>(selected.size());
  // Twins pull each other's refined poles away; sets whose poles all stayed in place failed for
  // something no drop repairs.
  if (lsfd.residues.cols() < n || with_all.poles_plausible) return {};
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      const Pole& pa = selected[a].pole;
      const Pole& pb = selected[b].pole;
      const double band = pa.damping_ratio * pa.frequency_hz + pb.damping_ratio * pb.frequency_hz;
      if (!(band > 0.0)) continue;
      const double closeness = std::abs(pa.frequency_hz - pb.frequency_hz) / band;
      if (closeness < kReach) pairs.push_back({closeness, a, b});
    }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& x, const Pair& y) { return x.closeness < y.closeness; });
  std::vector<char> used(static_cast<size_t>(n), 0);
  std::vector<Pair> disjoint;
  for (const Pair& pr : pairs)
    if (!used[pr.a] && !used[pr.b]) used[pr.a] = used[pr.b] = 1, disjoint.push_back(pr);
  for (int tries = 0; tries < kMaxSetSplitTries && !disjoint.empty(); ++tries, disjoint.pop_back()) {
    std::vector<int> weak, strong;
    for (const Pair& pr : disjoint) {
      const bool a_weaker = lsfd.residues.col(pr.a).squaredNorm() < lsfd.residues.col(pr.b).squaredNorm();
      weak.push_back(a_weaker ? pr.a : pr.b);
      strong.push_back(a_weaker ? pr.b : pr.a);
    }
    std::vector<SelectedPole> fewer;
    for (int k = 0; k < n; ++k)
      if (std::find(weak.begin(), weak.end(), k) == weak.end()) fewer.push_back(selected[k]);
    const PerSetRefinement per = RefinePerSet(data, options, fewer, progress);
    // Usable; or — where a band's misfit rejects every refinement, the one-set test's too (leakage
    // of a long decay) — every set's poles now stay in place where with the twins one was pulled.
    if (!per.ok && !per.poles_plausible) continue;
    double chi2 = 0.0;
    for (const auto& r : per.sets) chi2 = std::max(chi2, r.summary.reduced_chi2);
    std::ostringstream why;
    why.precision(3);
    why << ", within two half-power bandwidths of it: the roving sets see it at slightly different frequencies; ";
    if (per.ok)
      why << "with one pole for both every set's own refinement fits (largest reduced chi2 " << chi2
          << "), with two it did not";
    else
      why << "with one pole for both every set's refined poles stay in place (largest reduced chi2 " << chi2
          << ", the band's misfit), with two one was pulled towards its twin";
    for (size_t k = 0; k < weak.size(); ++k)
      dropped->push_back(MergedPole(selected[weak[k]].pole, selected[strong[k]].pole, why.str()));
    std::sort(weak.rbegin(), weak.rend());
    return weak;
  }
  return {};
}

}  // namespace

Eigen::VectorXcd SynthesiseFrf(const ModalModel& model, int output, int reference, const Eigen::VectorXd& frequency_hz) {
  const int m = static_cast<int>(model.references.size());
  const int c = output * m + reference;
  const int k_pow = model.frf_type == FrfType::kReceptance ? 0 : model.frf_type == FrfType::kMobility ? 1 : 2;
  Eigen::VectorXcd h(frequency_hz.size());
  for (Eigen::Index f = 0; f < frequency_hz.size(); ++f) {
    const std::complex<double> jw(0.0, kTwoPi * frequency_hz[f]);
    const std::complex<double> fac = std::pow(jw, k_pow);
    std::complex<double> v = 0.0;
    for (size_t r = 0; r < model.poles_fitted.size(); ++r) {
      const std::complex<double> res = model.residues(c, static_cast<int>(r)), lam = model.poles_fitted[r];
      v += res / (jw - lam) + std::conj(res) / (jw - std::conj(lam));
    }
    if (model.lower_residual.size() > c && frequency_hz[f] > 0.0) v += model.lower_residual[c] / (jw * jw);
    if (model.upper_residual.size() > c) v += model.upper_residual[c];
    h[f] = fac * v;
  }
  return h;
}

namespace {

// Fit after PrepareFitData: its stages throw InputErrors that name the stage ("polymax", "lsfd",
// "--select"), which Fit places at the input.
FitResult FitPreparedData(const FitData& data, const FitOptions& options, const std::string& source,
                          const ProgressCallback& progress, std::chrono::steady_clock::time_point t0) {
  using Clock = std::chrono::steady_clock;
  FitResult result;
  result.transposed = data.transposed;
  // After the poles ("poles", 0..1): the refinement's iterations and a step before each LSFD, below 1
  // until the fit is done (a bar ends its line at 1). Every step is also where a progress callback
  // that throws (a cancellation) stops the fit.
  ProgressCallback modes_progress;
  if (progress)
    modes_progress = [&progress](double f, std::string_view stage) { progress(std::min(f, 0.99), stage); };
  result.warnings = data.warnings;
  if (options.method == FitMethod::kPeak) {
    result.modes = PeakPick(data, options.peak);
  } else {
    result.diagram = EstimatePoles(data, options.polymax, progress, &result.timing.polymax);
    for (size_t k = data.warnings.size(); k < result.diagram.warnings.size(); ++k)
      result.warnings.push_back(result.diagram.warnings[k]);
    const double t1 = ThreadCpuSeconds();
    ClassifyStability(&result.diagram, options.stability);
    result.selected = options.select_frequencies_hz.empty()
                          ? SelectPolesAuto(result.diagram, options.auto_select)
                          : SelectPolesNear(result.diagram, options.select_frequencies_hz);
    result.selection_rule = options.select_frequencies_hz.empty() ? "automatic" : "given frequencies";
    // The relaxed retry is for bands whose normal equations support few orders; a band that
    // reached many orders (a zoom band spread over the circle) keeps the strict selection unless
    // that found nothing.
    const int orders_reached = result.diagram.order_max - result.diagram.order_min + 1;
    if (options.select_frequencies_hz.empty() && (result.selected.empty() || orders_reached < kFewOrders)) {
      std::string note;
      std::vector<SelectedPole> relaxed = SelectPolesNarrowBand(result.diagram, options, &note);
      if (relaxed.size() > result.selected.size()) {
        result.selection_rule = "automatic, narrow band";
        result.selected = std::move(relaxed);
        result.warnings.push_back(source + ": " + note);
      }
    }
    const double t2 = ThreadCpuSeconds();
    if (!result.selected.empty()) {
      for (;;) {
        const size_t warnings_before = result.warnings.size();
        MlRefineResult ml;
        PerSetRefinement per = RefinePerSet(data, options, result.selected, modes_progress);
        // Every set's poles stayed in place and only the misfit rejected them (a band whose misfit
        // no modal model removes: leakage of a long decay; the one-set test's refinement is
        // rejected too). Where the sets see some mode apart by at least a tenth of its half-power
        // bandwidth — which one pole at their mean misfits near resonance by ~20 % — one pole for
        // all cannot hold what they saw: each set keeps its poles, the misfit said and their σ
        // scaled by it. Automatic selection only: poles picked by hand keep what was picked.
        std::string misfit_why;
        if (!per.ok && per.poles_plausible && !per.why.empty() && options.select_frequencies_hz.empty()) {
          PerSetRefinement lenient = RefinePerSet(data, options, result.selected, modes_progress, true);
          if (lenient.ok && SetsSeeModesApart(lenient, kSetsApartBandwidths)) {
            misfit_why = per.why;
            per = std::move(lenient);
          }
        }
        bool have_ml = false;
        if (per.ok) {
          ApplyPerSet(per, &result);
          if (!misfit_why.empty()) {
            result.refine.message += ", above the noise: each set keeps the frequencies it saw";
            result.warnings.push_back(source + ": each roving set fitted with its own poles although the modal model "
                                               "misfits the data beyond their noise (" + misfit_why +
                                      "); their σ are scaled by that misfit");
          }
        } else {
          have_ml = RefineSelected(data, options, source, &result, &ml, modes_progress);
          // Why the sets did not get poles of their own, also when the one-pole refinement that
          // replaced it was not usable either (its own warning says that much, not this).
          if (!per.why.empty())
            result.warnings.push_back(source + ": one pole per mode for every roving set (" + per.why + ")");
        }
        const double t_lsfd = ThreadCpuSeconds();
        LsfdResult lsfd =
            EstimateModeShapes(data, result.selected, options.lsfd, per.ok ? &per.poles : nullptr, modes_progress);
        if (per.ok) AttachSetFrequencies(per, lsfd);
        result.timing.lsfd += ThreadCpuSeconds() - t_lsfd;
        // Automatic selection only: a pole that is the same mode as a neighbour seen on other
        // outputs (roving-set inconsistency) is dropped and the model fitted again without it.
        if (options.select_frequencies_hz.empty() && options.split_poles.enabled) {
          DroppedPole dropped;
          const int drop = FindSplitPole(data, result.selected, lsfd, options.split_poles, &dropped);
          if (drop >= 0) {
            result.warnings.resize(warnings_before);  // this round's refinement messages are moot
            // Handled here (the mode is fitted as one pole): a note in `dropped`, not a warning.
            result.dropped.push_back(dropped);
            result.selected.erase(result.selected.begin() + drop);
            continue;
          }
        }
        // Automatic selection, roving sets whose own refinement failed: two poles within reach of
        // each other's half-power band may be one mode the sets see at slightly different frequencies
        // (each set's sensors load it differently), too close for their shapes to fall apart by
        // outputs as above. The weaker of each such pair is dropped when, with one pole for both,
        // every set's own refinement becomes usable — or, where the band's misfit rejects every
        // refinement, every set's refined poles stay in place: the data then say it was one mode
        // (every such pair at once: a light structure's sets split each of its modes).
        if (options.select_frequencies_hz.empty() && options.split_poles.enabled && !per.ok && !per.why.empty()) {
          std::vector<DroppedPole> dropped;
          const std::vector<int> drops =
              FindSetSplitPoles(data, options, result.selected, lsfd, per, &dropped, modes_progress);
          if (!drops.empty()) {
            result.warnings.resize(warnings_before);
            result.dropped.insert(result.dropped.end(), dropped.begin(), dropped.end());
            for (int k : drops) result.selected.erase(result.selected.begin() + k);  // highest index first
            continue;
          }
        }
        // Automatic selection only: a pole whose residues, over all FRFs, stand no clearer above
        // their uncertainty than noise would (the Wald statistic of a pole fitted to noise is
        // ~ its degrees of freedom, a little more for the place it chose) models noise, not a mode.
        if (options.select_frequencies_hz.empty() && have_ml && result.selected.size() > 1) {
          int weakest = -1;
          double weakest_ratio = 1.0;
          for (size_t r = 0; r < ml.poles.size() && r < result.selected.size(); ++r) {
            const RefinedPole& p = ml.poles[r];
            if (p.residue_dof <= 0 || !(p.residue_chi2 > 0.0)) continue;
            const double threshold = std::max(kNoisePoleChi2Floor, p.residue_dof + 6.0 * std::sqrt(2.0 * p.residue_dof));
            const double ratio = p.residue_chi2 / threshold;
            if (ratio < weakest_ratio) weakest = static_cast<int>(r), weakest_ratio = ratio;
          }
          if (weakest >= 0) {
            const RefinedPole& p = ml.poles[weakest];
            DroppedPole dropped;
            dropped.frequency_hz = result.selected[weakest].pole.frequency_hz;
            std::ostringstream why;
            why.precision(3);
            why << "its residues stand no clearer above the noise than a pole fitted to noise would (Wald chi2 "
                << p.residue_chi2 << " on " << p.residue_dof << " degrees of freedom)";
            dropped.reason = why.str();
            result.warnings.resize(warnings_before);
            result.dropped.push_back(dropped);  // handled: a note, not a warning
            result.selected.erase(result.selected.begin() + weakest);
            continue;
          }
        }
        if (have_ml) AttachUncertainty(ml, lsfd);
        FillModel(data, result.selected, lsfd, &result.model);
        result.modes = std::move(lsfd.modes);
        // Modes come out sorted by frequency whatever the refinement did (two close poles may
        // cross): the modes and the selection they came from, permuted alike.
        std::vector<size_t> order(result.modes.modes.size());
        for (size_t k = 0; k < order.size(); ++k) order[k] = k;
        std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
          return result.modes.modes[a].frequency_hz < result.modes.modes[b].frequency_hz;
        });
        if (!std::is_sorted(order.begin(), order.end())) {
          std::vector<Mode> modes;
          std::vector<SelectedPole> selected;
          for (size_t k : order) {
            modes.push_back(result.modes.modes[k]);
            if (k < result.selected.size()) selected.push_back(result.selected[k]);
          }
          result.modes.modes = std::move(modes);
          if (selected.size() == result.selected.size()) result.selected = std::move(selected);
        }
        result.synthesis_error = lsfd.synthesis_error;
        for (const auto& w : lsfd.warnings) result.warnings.push_back(source + ": " + w);
        break;
      }
    } else {
      result.modes.dofs = data.outputs;
      result.warnings.push_back(source + ": no stable poles found; no modes selected");
    }
    const double t3 = ThreadCpuSeconds();
    result.timing.stabilisation_and_selection = t2 - t1;
    result.timing.refine = t3 - t2 - result.timing.lsfd;
    ReportProgress(progress, 1.0, "modes");
  }
  result.modes.source = source;
  result.timing.total = std::chrono::duration<double>(Clock::now() - t0).count();
  return result;
}

}  // namespace

FitResult Fit(const FrfSet& frfs, const FitOptions& options, const std::string& source,
              const ProgressCallback& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  const FitData data = PrepareFitData(frfs, options.data, source);  // its errors name `source` already
  try {
    return FitPreparedData(data, options, source, progress, t0);
  } catch (const InputError& e) {
    throw InputError(source, e.what());  // "FRF.unv: polymax: ...": every error of the fit names its input
  }
}

}  // namespace ema::curvefit
