// PlanTest (docs/plan.md): the target modes, sensors by effective independence and exchange,
// references by driving-point participation, acquisition settings from band and damping, and the
// separation of competing readings.
#include "ema/planning/plan.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "ema/core/error.hpp"
#include "ema/core/text.hpp"
#include "ema/correlation/mac.hpp"
#include "ema/model/effects.hpp"
#include "ema/model/solve.hpp"

namespace ema::planning {

bool PlanOptions::IsValid(std::string* why) const {
  std::string bad;
  const bool band_unset = band_lo_hz == 0.0 && band_hi_hz == 0.0;
  if (!band_unset && !(band_lo_hz >= 0.0 && std::isfinite(band_hi_hz) && band_hi_hz > band_lo_hz))
    bad = "the band (--band) must be 0 <= LO < HI (Hz), or unset";
  else if (default_modes < 1) bad = "default_modes must be >= 1";
  else if (sensors_per_set < 1) bad = "sensors (--sensors) must be >= 1";
  else if (sets < 1) bad = "sets (--sets) must be >= 1";
  else if (references < 1) bad = "references (--references) must be >= 1";
  else if (!(min_reference_participation > 0.0 && min_reference_participation < 1.0))
    bad = "min_reference_participation must be in (0, 1)";
  else if (!(automac_limit > 0.0 && automac_limit < 1.0)) bad = "automac_limit must be in (0, 1)";
  else if (!(frequency_sigma_rel > 0.0) || !(shape_dof_sigma > 0.0))
    bad = "frequency_sigma_rel and shape_dof_sigma must be > 0";
  else if (!(frequency_model_error_rel >= 0.0) || !std::isfinite(frequency_model_error_rel) ||
           !(shape_model_error >= 0.0) || !std::isfinite(shape_model_error))
    bad = "frequency_model_error_rel and shape_model_error must be >= 0";
  else if (!(sensor_mass_kg >= 0.0) || !std::isfinite(sensor_mass_kg)) bad = "sensor mass (--sensor-mass) must be >= 0 kg";
  else if (impacts < 1) bad = "impacts must be >= 1";
  if (why) *why = bad;
  return bad.empty();
}

std::vector<Dof> TestPlan::Sensors() const {
  std::vector<Dof> out;
  for (const auto& s : sets) out.insert(out.end(), s.begin(), s.end());
  return out;
}

namespace {

// The Fisher information ΦᵀΦ regularised by a trace share, so that a set with fewer rows than
// modes still orders (it is singular: every such set scores about alike).
Eigen::MatrixXd Regularised(const Eigen::MatrixXd& info) {
  const double ridge = 1e-10 * std::max(info.trace(), 1e-300) / std::max<Eigen::Index>(1, info.rows());
  return info + ridge * Eigen::MatrixXd::Identity(info.rows(), info.cols());
}

// log det of the regularised information.
double LogDetInformation(const Eigen::MatrixXd& info) {
  Eigen::LLT<Eigen::MatrixXd> llt(Regularised(info));
  if (llt.info() != Eigen::Success) return -std::numeric_limits<double>::infinity();
  return 2.0 * llt.matrixL().toDenseMatrix().diagonal().array().log().sum();
}

Eigen::MatrixXd GroupInformation(const Eigen::MatrixXd& shapes, const std::vector<int>& rows) {
  Eigen::MatrixXd info = Eigen::MatrixXd::Zero(shapes.cols(), shapes.cols());
  for (int r : rows) info.noalias() += shapes.row(r).transpose() * shapes.row(r);
  return info;
}

std::vector<int> RowsOf(const std::vector<std::vector<int>>& groups, const std::vector<int>& chosen) {
  std::vector<int> rows;
  for (int g : chosen) rows.insert(rows.end(), groups[g].begin(), groups[g].end());
  return rows;
}

Eigen::MatrixXcd ShapesAt(const Eigen::MatrixXd& shapes, const std::vector<int>& rows) {
  Eigen::MatrixXcd out(static_cast<Eigen::Index>(rows.size()), shapes.cols());
  for (size_t k = 0; k < rows.size(); ++k) out.row(static_cast<Eigen::Index>(k)) = shapes.row(rows[k]).cast<std::complex<double>>();
  return out;
}

double MaxOffDiagonal(const Eigen::MatrixXd& automac) {
  double worst = 0.0;
  for (Eigen::Index i = 0; i < automac.rows(); ++i)
    for (Eigen::Index j = 0; j < automac.cols(); ++j)
      if (i != j) worst = std::max(worst, automac(i, j));
  return worst;
}

double AutoMacMax(const Eigen::MatrixXd& shapes, const std::vector<std::vector<int>>& groups, const std::vector<int>& chosen) {
  const std::vector<int> rows = RowsOf(groups, chosen);
  if (rows.empty()) return 1.0;
  return MaxOffDiagonal(correlation::AutoMac(ShapesAt(shapes, rows)));
}

// The model's modes in the setup, with enough of them for any band of interest.
model::Solution SolveFor(const model::Model& m, const std::string& setup, int fe_modes = 40) {
  model::SolveOptions so;
  so.setup = setup;
  so.max_modes = m.fe.Empty() ? 0 : fe_modes;
  return model::Solve(m, so);
}

std::string Hz(double f) { return FixedPoint(f, f < 100.0 ? 2 : 1); }

}  // namespace

std::vector<int> ChooseSensorGroups(const Eigen::MatrixXd& shapes, const std::vector<std::vector<int>>& groups, int count,
                                    const std::vector<int>& fixed) {
  const int n = static_cast<int>(groups.size());
  if (count > n) throw std::invalid_argument("ChooseSensorGroups: more groups asked than there are");
  std::vector<char> is_fixed(n, 0);
  for (int g : fixed) is_fixed[g] = 1;
  std::vector<int> chosen(n);
  for (int g = 0; g < n; ++g) chosen[g] = g;
  // Effective independence: the share each row holds of the information, E = diag(Φ (ΦᵀΦ)⁻¹ Φᵀ),
  // summed per group; the group holding least goes, until `count` are left.
  while (static_cast<int>(chosen.size()) > count) {
    const Eigen::MatrixXd info = GroupInformation(shapes, RowsOf(groups, chosen));
    const Eigen::MatrixXd inverse = Regularised(info).ldlt().solve(Eigen::MatrixXd::Identity(info.rows(), info.cols()));
    int worst = -1;
    double worst_share = std::numeric_limits<double>::infinity();
    for (size_t k = 0; k < chosen.size(); ++k) {
      if (is_fixed[chosen[k]]) continue;
      double share = 0.0;
      for (int r : groups[chosen[k]]) share += shapes.row(r) * inverse * shapes.row(r).transpose();
      if (share < worst_share) worst_share = share, worst = static_cast<int>(k);
    }
    if (worst < 0) break;  // only fixed groups left
    chosen.erase(chosen.begin() + worst);
  }
  // Exchange: deletion is greedy and can leave a better set one swap away.
  std::vector<char> in(n, 0);
  for (int g : chosen) in[g] = 1;
  Eigen::MatrixXd info = GroupInformation(shapes, RowsOf(groups, chosen));
  double best = LogDetInformation(info);
  for (int pass = 0; pass < 4 * n; ++pass) {
    int out_group = -1, in_group = -1;
    double gain = 1e-9;
    for (int g : chosen) {
      if (is_fixed[g]) continue;
      const Eigen::MatrixXd without = info - GroupInformation(shapes, groups[g]);
      for (int u = 0; u < n; ++u) {
        if (in[u]) continue;
        const double value = LogDetInformation(without + GroupInformation(shapes, groups[u]));
        if (value - best > gain) gain = value - best, out_group = g, in_group = u;
      }
    }
    if (out_group < 0) break;
    std::replace(chosen.begin(), chosen.end(), out_group, in_group);
    in[out_group] = 0, in[in_group] = 1;
    info = GroupInformation(shapes, RowsOf(groups, chosen));
    best = LogDetInformation(info);
  }
  std::sort(chosen.begin(), chosen.end());
  return chosen;
}

TestPlan PlanTest(const model::Model& input, const PlanOptions& options, const std::vector<Reading>& readings,
                  const std::vector<std::vector<Dof>>& keep, const std::vector<Dof>& kept_references) {
  if (std::string why; !options.IsValid(&why)) throw UsageError("plan options: " + why);
  const std::string where = input.origin.empty() ? "model" : input.origin;
  const model::Model base = model::ApplyEffects(input);
  const model::Solution nominal = SolveFor(base, options.setup);
  const ModeSet& modes = nominal.modes;
  if (modes.modes.empty()) throw InputError(where, "the model has no elastic mode to plan a test for");
  if (modes.dofs.empty()) throw InputError(where, "the model has no [[point]]: a test plan places sensors on its test points");

  TestPlan plan;
  // Target modes: those in the band (by default up to 1.25 × the default_modes-th mode).
  plan.band_lo_hz = options.band_lo_hz;
  plan.band_hi_hz = options.band_hi_hz;
  if (!(options.band_hi_hz > options.band_lo_hz)) {
    // The lowest default_modes modes, stopping at a gap of more than 3× (what lies beyond is of
    // another regime: a machine's modes on its mounts, then its body's own far above).
    size_t last = 0;
    while (last + 1 < std::min<size_t>(static_cast<size_t>(options.default_modes), modes.modes.size()) &&
           modes.modes[last + 1].frequency_hz <= 3.0 * modes.modes[last].frequency_hz)
      ++last;
    plan.band_lo_hz = 0.0;
    plan.band_hi_hz = 1.25 * modes.modes[last].frequency_hz;
  }
  std::vector<int> target;
  for (size_t i = 0; i < modes.modes.size(); ++i)
    if (modes.modes[i].frequency_hz >= plan.band_lo_hz && modes.modes[i].frequency_hz <= plan.band_hi_hz)
      target.push_back(static_cast<int>(i));
  if (target.empty()) {
    std::string found;
    for (size_t i = 0; i < modes.modes.size() && i < 8; ++i) found += (i ? ", " : "") + Hz(modes.modes[i].frequency_hz);
    throw InputError(where, "no model mode in the band " + Hz(plan.band_lo_hz) + "–" + Hz(plan.band_hi_hz) + " Hz" +
                                (options.setup.empty() ? "" : " (setup '" + options.setup + "')") +
                                "; expected a band holding at least one mode (the model's modes: " + found + (modes.modes.size() > 8 ? ", ..." : "") + " Hz)");
  }
  // Candidates: the test DOFs that move in some mode of the model (a model without, say, lateral
  // DOFs gives zero rows there: nothing a sensor could see).
  std::vector<Eigen::Index> rows_kept;
  {
    double largest = 0.0;
    for (const Mode& mode : modes.modes) largest = std::max(largest, mode.shape.cwiseAbs().maxCoeff());
    for (Eigen::Index r = 0; r < static_cast<Eigen::Index>(modes.dofs.size()); ++r) {
      double row = 0.0;
      for (const Mode& mode : modes.modes) row = std::max(row, std::abs(mode.shape(r)));
      if (row > 1e-9 * largest) rows_kept.push_back(r);
    }
  }
  plan.candidates.clear();
  for (Eigen::Index r : rows_kept) plan.candidates.push_back(modes.dofs[static_cast<size_t>(r)]);
  const auto c = static_cast<Eigen::Index>(rows_kept.size());
  const auto m = static_cast<Eigen::Index>(target.size());
  Eigen::MatrixXd shapes(c, m);
  for (Eigen::Index j = 0; j < m; ++j)
    for (Eigen::Index r = 0; r < c; ++r) shapes(r, j) = modes.modes[target[j]].shape(rows_kept[static_cast<size_t>(r)]).real();
  const std::vector<Dof>& candidates = plan.candidates;

  // Candidate groups: a point's X, Y, Z together with triaxial sensors, else each DOF.
  std::vector<std::vector<int>> groups;
  std::map<Dof, int> group_of_dof;
  if (options.triaxial) {
    std::map<int, int> group_of_node;
    for (Eigen::Index r = 0; r < c; ++r) {
      const int node = candidates[static_cast<size_t>(r)].node;
      auto [it, fresh] = group_of_node.emplace(node, static_cast<int>(groups.size()));
      if (fresh) groups.emplace_back();
      groups[it->second].push_back(static_cast<int>(r));
      group_of_dof[candidates[static_cast<size_t>(r)]] = it->second;
    }
  } else {
    for (Eigen::Index r = 0; r < c; ++r)
      group_of_dof[candidates[static_cast<size_t>(r)]] = static_cast<int>(groups.size()), groups.push_back({static_cast<int>(r)});
  }
  std::vector<int> fixed;
  for (const auto& set : keep)
    for (const Dof& d : set) {
      const auto it = group_of_dof.find(Dof{d.node, std::abs(d.direction)});
      if (it == group_of_dof.end())
        throw InputError(where, "the kept plan's sensor " + DofName(d) + " is not a test point DOF of the model");
      if (std::find(fixed.begin(), fixed.end(), it->second) == fixed.end()) fixed.push_back(it->second);
    }
  const int wanted = options.sensors_per_set * options.sets;
  const int available = static_cast<int>(groups.size()) - static_cast<int>(fixed.size());
  const std::string unit = options.triaxial ? "test points" : "test DOFs";
  if (wanted > available) {
    std::ostringstream msg;
    msg << options.sensors_per_set << " sensors x " << options.sets << " sets = " << wanted << " " << unit
        << " asked, but the model has " << available << " " << unit << (fixed.empty() ? "" : " not already in the kept plan")
        << "; expected at most " << available << " (fewer --sensors or --sets" << (options.triaxial ? "" : ", or --triaxial") << ")";
    throw InputError(where, msg.str());
  }

  // Sensors for the modes alone, then — with readings — exchanged for separation.
  const int total = static_cast<int>(fixed.size()) + wanted;
  std::vector<int> chosen = ChooseSensorGroups(shapes, groups, total, fixed);
  std::vector<char> is_fixed(groups.size(), 0);
  for (int g : fixed) is_fixed[g] = 1;
  // The AutoMAC exchange: while two modes look alike at the sensors, swap a sensor for the
  // candidate that lowers the largest off-diagonal most (the information criterion does not bound it).
  {
    double worst = AutoMacMax(shapes, groups, chosen);
    for (int pass = 0; pass < 2 * total && worst > options.automac_limit; ++pass) {
      int out_group = -1, in_group = -1;
      double best = worst;
      for (size_t k = 0; k < chosen.size(); ++k) {
        if (is_fixed[chosen[k]]) continue;
        for (int u = 0; u < static_cast<int>(groups.size()); ++u) {
          if (std::find(chosen.begin(), chosen.end(), u) != chosen.end()) continue;
          std::vector<int> trial = chosen;
          trial[k] = u;
          const double value = AutoMacMax(shapes, groups, trial);
          if (value < best - 1e-6) best = value, out_group = chosen[k], in_group = u;
        }
      }
      if (out_group < 0) break;
      std::replace(chosen.begin(), chosen.end(), out_group, in_group);
      worst = best;
    }
  }

  // References: those of a kept plan as they were; else the candidate DOF whose smallest
  // normalised participation over the target modes is largest, then each next one raising the
  // smallest of the best participations most.
  Eigen::MatrixXd participation(c, m);
  for (Eigen::Index j = 0; j < m; ++j) {
    const double peak = shapes.col(j).cwiseAbs2().maxCoeff();
    participation.col(j) = peak > 0.0 ? Eigen::VectorXd(shapes.col(j).cwiseAbs2() / peak) : Eigen::VectorXd::Zero(c);
  }
  Eigen::VectorXd covered = Eigen::VectorXd::Zero(m);
  std::vector<Eigen::Index> picked;
  for (const Dof& d : kept_references) {
    const auto it = std::find(candidates.begin(), candidates.end(), Dof{d.node, std::abs(d.direction)});
    if (it == candidates.end())
      throw InputError(where, "the kept plan's reference " + DofName(d) + " is not a test point DOF of the model");
    const auto r = static_cast<Eigen::Index>(it - candidates.begin());
    picked.push_back(r);
    covered = covered.cwiseMax(participation.row(r).transpose());
  }
  for (int k = 0; kept_references.empty() && k < options.references && static_cast<Eigen::Index>(picked.size()) < c; ++k) {
    Eigen::Index best = -1;
    double best_min = -1.0, best_sum = -1.0;
    for (Eigen::Index r = 0; r < c; ++r) {
      if (std::find(picked.begin(), picked.end(), r) != picked.end()) continue;
      const Eigen::VectorXd with = covered.cwiseMax(participation.row(r).transpose());
      const double lo = with.minCoeff(), sum = with.sum();
      if (lo > best_min + 1e-12 || (std::abs(lo - best_min) <= 1e-12 && sum > best_sum)) best = r, best_min = lo, best_sum = sum;
    }
    picked.push_back(best);
    covered = covered.cwiseMax(participation.row(best).transpose());
  }
  if (!kept_references.empty()) plan.references = kept_references;
  else
    for (Eigen::Index r : picked) plan.references.push_back(candidates[static_cast<size_t>(r)]);
  // A mode the references do not excite is not measured: it separates no readings either.
  const auto excited = [&](Eigen::Index j) { return covered(j) >= options.min_reference_participation; };


  // Readings: small changes of the model, so mode k of one is mode k of another (by frequency
  // order) — pairing each to the nominal modes by MAC instead mixed up the close pairs of a
  // symmetric structure (a mass on one girder localises its two twin modes differently). A mode
  // that crossed its neighbour is followed by MAC over the neighbours (k − 1, k, k + 1).
  struct Predicted {
    Eigen::VectorXd hz;
    Eigen::MatrixXd shapes;  // candidates × modes, by frequency
  };
  std::vector<Predicted> predicted;
  for (const Reading& reading : readings) {
    model::Model changed = base;
    try {
      for (const model::Effect& e : reading.effects) changed = model::ApplyEffect(changed, e);
    } catch (const InputError& e) {
      throw InputError(reading.origin.empty() ? where : reading.origin,
                       "the reading '" + reading.label + "' does not apply to the model " + where + " (" + e.what() +
                           "); expected a diagnosis of this model");
    }
    // Modes up to the band's last and its neighbour (the counterpart search looks one further).
    const model::Solution s = SolveFor(changed, options.setup, target.back() + 3);
    if (s.modes.dofs != modes.dofs)
      throw InputError(reading.origin.empty() ? where : reading.origin,
                       "the reading '" + reading.label + "' changes the test DOFs of the model " + where + "; expected a diagnosis of this model");
    const auto count = static_cast<Eigen::Index>(s.modes.modes.size());
    Predicted p{Eigen::VectorXd(count), Eigen::MatrixXd(c, count)};
    for (Eigen::Index k = 0; k < count; ++k) {
      p.hz(k) = s.modes.modes[static_cast<size_t>(k)].frequency_hz;
      for (Eigen::Index r = 0; r < c; ++r) p.shapes(r, k) = s.modes.modes[static_cast<size_t>(k)].shape(rows_kept[static_cast<size_t>(r)]).real();
    }
    predicted.push_back(std::move(p));
  }
  // Reading b's mode that is reading a's k-th: k itself, or a neighbour it crossed (largest MAC).
  auto counterpart = [&](const Predicted& a, const Predicted& b, Eigen::Index k) {
    Eigen::Index best = std::min<Eigen::Index>(k, b.hz.size() - 1);
    double best_mac = -1.0;
    for (Eigen::Index q = std::max<Eigen::Index>(0, k - 1); q <= std::min<Eigen::Index>(b.hz.size() - 1, k + 1); ++q) {
      const double mac = correlation::Mac(a.shapes.col(k).cast<std::complex<double>>(), b.shapes.col(q).cast<std::complex<double>>());
      if (mac > best_mac + 1e-9 || (q == k && mac >= best_mac - 1e-9)) best_mac = mac, best = q;
    }
    return best;
  };
  const Eigen::VectorXd target_hz = [&] {
    Eigen::VectorXd f(m);
    for (Eigen::Index j = 0; j < m; ++j) f(j) = modes.modes[target[j]].frequency_hz;
    return f;
  }();
  const size_t n_readings = predicted.size();
  std::vector<std::vector<Eigen::Index>> partner(n_readings * n_readings);  // [a·n + b][j]: b's mode for a's target j
  for (size_t a = 0; a < n_readings; ++a)
    for (size_t b = 0; b < n_readings; ++b)
      for (Eigen::Index j = 0; j < m; ++j)
        partner[a * n_readings + b].push_back(target[j] < predicted[a].hz.size() ? counterpart(predicted[a], predicted[b], target[j]) : -1);
  // A mode the sensors barely see is not measured at all (the fit does not find it, or its shape
  // at the sensors is noise): it separates nothing. Seen = observability ≥ kSeen (RMS at the
  // sensors over RMS at every candidate, PlannedMode::observability).
  constexpr double kSeen = 0.3;
  const Eigen::VectorXd mean_square = shapes.colwise().squaredNorm().transpose() / static_cast<double>(c);
  const std::vector<int> for_modes = chosen;
  if (predicted.size() >= 2) {
    // The exchange judges thousands of sets: per pair of readings and target mode, the sums Σx²,
    // Σy², Σxy over a set's rows (real shapes: MAC = (Σxy)² / (Σx² Σy²)) and the nominal Σφ²
    // (is the mode seen) are kept per candidate group, so a swap costs pairs × modes additions.
    struct Sums {
      double xx = 0.0, yy = 0.0, xy = 0.0;
    };
    const auto n_groups = groups.size();
    // The σ a test result lies off each reading's prediction by: the noise and the model's own
    // error combined (PlanOptions::frequency_model_error_rel, shape_model_error).
    const double frequency_sigma = std::hypot(options.frequency_sigma_rel, options.frequency_model_error_rel);
    const double shape_sigma = std::hypot(options.shape_dof_sigma, options.shape_model_error);
    std::vector<std::pair<size_t, size_t>> pairs;
    for (size_t a = 0; a < n_readings; ++a)
      for (size_t b = a + 1; b < n_readings; ++b) pairs.emplace_back(a, b);
    const size_t slots = pairs.size() * static_cast<size_t>(m);
    std::vector<Sums> contribution(slots * n_groups);
    std::vector<double> seen_contribution(static_cast<size_t>(m) * n_groups, 0.0), frequency_term(slots, 0.0);
    std::vector<char> usable(slots, 0);
    for (size_t q = 0; q < pairs.size(); ++q) {
      const auto [a, b] = pairs[q];
      for (Eigen::Index j = 0; j < m; ++j) {
        const size_t slot = q * static_cast<size_t>(m) + static_cast<size_t>(j);
        const Eigen::Index ka = target[j], kb = partner[a * n_readings + b][static_cast<size_t>(j)];
        if (kb < 0 || !excited(j)) continue;
        usable[slot] = 1;
        const double df = (predicted[a].hz(ka) - predicted[b].hz(kb)) / (frequency_sigma * target_hz(j));
        frequency_term[slot] = df * df;
        for (size_t g = 0; g < n_groups; ++g)
          for (int r : groups[g]) {
            const double x = predicted[a].shapes(r, ka), y = predicted[b].shapes(r, kb);
            Sums& c = contribution[slot * n_groups + g];
            c.xx += x * x, c.yy += y * y, c.xy += x * y;
          }
      }
    }
    for (Eigen::Index j = 0; j < m; ++j)
      for (size_t g = 0; g < n_groups; ++g)
        for (int r : groups[g]) seen_contribution[static_cast<size_t>(j) * n_groups + g] += shapes(r, j) * shapes(r, j);
    struct State {
      std::vector<Sums> sums;
      std::vector<double> seen;
      size_t rows = 0;
    };
    auto add = [&](State* st, int g, double sign) {
      for (size_t slot = 0; slot < slots; ++slot) {
        const Sums& c = contribution[slot * n_groups + static_cast<size_t>(g)];
        st->sums[slot].xx += sign * c.xx, st->sums[slot].yy += sign * c.yy, st->sums[slot].xy += sign * c.xy;
      }
      for (Eigen::Index j = 0; j < m; ++j) st->seen[static_cast<size_t>(j)] += sign * seen_contribution[static_cast<size_t>(j) * n_groups + g];
      st->rows = sign > 0 ? st->rows + groups[g].size() : st->rows - groups[g].size();
    };
    auto state_of = [&](const std::vector<int>& set) {
      State st{std::vector<Sums>(slots), std::vector<double>(static_cast<size_t>(m), 0.0), 0};
      for (int g : set) add(&st, g, 1.0);
      return st;
    };
    // The separation of pair q at a set (its sums): frequencies and shapes in σ over the target
    // modes the references excite and the set sees — the figure reported and the exchange's. The
    // shapes as the diagnosis weighs them (docs/diagnose.md "Shapes in the likelihood"): per DOF,
    // in units of shape_dof_sigma × the rms amplitude, so a mode's shape term is Σ_d r_d² =
    // rows · (1 − MAC) / shape_dof_sigma² over the set's rows.
    auto separation_of = [&](const State& st, size_t q) {
      double sum = 0.0;
      for (Eigen::Index j = 0; j < m; ++j) {
        const size_t slot = q * static_cast<size_t>(m) + static_cast<size_t>(j);
        if (!usable[slot] || st.rows == 0 || st.seen[static_cast<size_t>(j)] / static_cast<double>(st.rows) < kSeen * kSeen * mean_square(j))
          continue;
        const Sums& t = st.sums[slot];
        const double mac = t.xx > 0.0 && t.yy > 0.0 ? t.xy * t.xy / (t.xx * t.yy) : 1.0;
        sum += frequency_term[slot] +
               static_cast<double>(st.rows) * std::max(0.0, 1.0 - mac) / (shape_sigma * shape_sigma);
      }
      return std::sqrt(sum);
    };
    auto smallest_of = [&](const State& st) {
      double worst = std::numeric_limits<double>::infinity();
      for (size_t q = 0; q < pairs.size(); ++q) worst = std::min(worst, separation_of(st, q));
      return worst;
    };
    // Exchange for the smallest separation, keeping the AutoMAC within its limit (or no worse
    // than the modes-only plan's when that already exceeds it).
    const double automac_bound = std::max(options.automac_limit, AutoMacMax(shapes, groups, chosen));
    State current = state_of(chosen);
    double value = smallest_of(current);
    std::vector<char> in_set(n_groups, 0);
    for (int g : chosen) in_set[static_cast<size_t>(g)] = 1;
    for (int pass = 0; pass < 4 * total; ++pass) {
      int out_group = -1, in_group = -1;
      double best = value;
      for (size_t k = 0; k < chosen.size(); ++k) {
        if (is_fixed[chosen[k]]) continue;
        State without = current;
        add(&without, chosen[k], -1.0);
        for (int u = 0; u < static_cast<int>(n_groups); ++u) {
          if (in_set[static_cast<size_t>(u)]) continue;
          State trial = without;
          add(&trial, u, 1.0);
          const double v = smallest_of(trial);
          if (!(v > best * (1.0 + 1e-6) + 1e-9)) continue;
          std::vector<int> set = chosen;
          set[k] = u;
          if (AutoMacMax(shapes, groups, set) <= automac_bound + 1e-9) best = v, out_group = chosen[k], in_group = u;
        }
      }
      if (out_group < 0) break;
      std::replace(chosen.begin(), chosen.end(), out_group, in_group);
      in_set[static_cast<size_t>(out_group)] = 0, in_set[static_cast<size_t>(in_group)] = 1;
      current = state_of(chosen);
      value = best;
    }
    const State before = state_of(keep.empty() ? for_modes : fixed);
    plan.separation_frequency_sigma_rel = frequency_sigma, plan.separation_shape_sigma = shape_sigma;
    plan.separations_include_model_error = options.frequency_model_error_rel > 0.0 || options.shape_model_error > 0.0;
    for (size_t q = 0; q < pairs.size(); ++q)
      plan.separations.push_back({readings[pairs[q].first].label, readings[pairs[q].second].label, separation_of(before, q),
                                  separation_of(current, q)});
  }

  // Roving sets: the kept sets as they were, then the new groups by test point, in sets.
  plan.sets = keep;
  std::vector<int> fresh;
  for (int g : chosen)
    if (!is_fixed[g]) fresh.push_back(g);
  std::sort(fresh.begin(), fresh.end(), [&](int a, int b) { return candidates[groups[a][0]] < candidates[groups[b][0]]; });
  for (int s = 0; s < options.sets; ++s) {
    std::vector<Dof> set;
    for (int k = s * options.sensors_per_set; k < (s + 1) * options.sensors_per_set && k < static_cast<int>(fresh.size()); ++k)
      for (int r : groups[fresh[k]]) set.push_back(candidates[r]);
    plan.sets.push_back(std::move(set));
  }
  const std::vector<int> rows = RowsOf(groups, chosen);
  plan.automac = correlation::AutoMac(ShapesAt(shapes, rows));
  plan.automac_max_offdiagonal = MaxOffDiagonal(plan.automac);
  if (plan.automac_max_offdiagonal > options.automac_limit)
    plan.notes.push_back("two target modes still look alike at these sensors (AutoMAC " + FixedPoint(plan.automac_max_offdiagonal, 2) +
                         " > " + FixedPoint(options.automac_limit, 2) + "): more sensors, sets or --triaxial would separate them");

  // Per mode: how the sensors see it and the references excite it.
  for (Eigen::Index j = 0; j < m; ++j) {
    const Mode& mode = modes.modes[target[j]];
    PlannedMode pm;
    pm.frequency_hz = mode.frequency_hz;
    pm.damping_ratio = mode.damping_ratio;
    double at_sensors = 0.0;
    for (int r : rows) at_sensors += shapes(r, j) * shapes(r, j);
    const double everywhere = shapes.col(j).squaredNorm() / static_cast<double>(c);
    pm.observability = everywhere > 0.0 && !rows.empty() ? std::sqrt(at_sensors / static_cast<double>(rows.size()) / everywhere) : 0.0;
    pm.reference_participation = covered(j);
    pm.excited = excited(j);
    if (!pm.excited)
      plan.notes.push_back("the mode at " + Hz(pm.frequency_hz) + " Hz is barely excited by the references (participation " +
                           FixedPoint(covered(j), 3) + "): add a reference (--references)");
    plan.modes.push_back(pm);
  }

  // Acquisition: 2.56 × the band's top (the anti-alias filter's usual margin); a record that holds
  // five spectral lines per half-power bandwidth 2ζf and lets the response decay to 0.1 % (no
  // window needed); a tip whose half-sine pulse loses at most 2 dB at the band's top (τ = 0.5/f).
  const double top = std::max(plan.band_hi_hz, target_hz.maxCoeff());
  plan.sample_rate_hz = 10.0 * std::ceil(2.56 * top / 10.0);
  double record_s = 0.0;
  for (const PlannedMode& pm : plan.modes) {
    const double zeta = std::max(pm.damping_ratio, 2e-3);
    record_s = std::max({record_s, 5.0 / (2.0 * zeta * pm.frequency_hz), std::log(1000.0) / (zeta * kTwoPi * pm.frequency_hz)});
  }
  int samples = 256;
  while (samples < record_s * plan.sample_rate_hz && samples < (1 << 22)) samples *= 2;
  plan.samples = samples;
  plan.pulse_duration_s = 0.5 / top;
  plan.impacts = options.impacts;
  plan.sensor_mass_kg = options.sensor_mass_kg;
  bool undamped = false;
  for (const PlannedMode& pm : plan.modes) undamped = undamped || !(pm.damping_ratio > 0.0);
  if (undamped)
    plan.notes.push_back("the model has undamped target modes ([damping] not set): the record length assumes 0.2 % damping");
  return plan;
}

}  // namespace ema::planning
