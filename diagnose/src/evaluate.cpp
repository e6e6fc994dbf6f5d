// Residuals of one model variant against every setup's test modes: per test mode, the frequency
// error in units of that mode's σ and the shape's difference at each measured DOF in units of its
// σ there (or one (1 − MAC) in units of the shape σ). Pairing is redone at
// every evaluation, so mode swaps while the parameters move are followed.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>

#include "ema/core/error.hpp"
#include "ema/correlation/correlate.hpp"
#include "ema/correlation/mac.hpp"
#include "ema/model/reduced.hpp"
#include "ema/model/solve.hpp"
#include "internal.hpp"

namespace ema::diagnose::detail {

double PhaseCollinearity(const Eigen::VectorXcd& shape) {
  const double sxx = shape.real().squaredNorm(), syy = shape.imag().squaredNorm();
  const double sxy = shape.real().dot(shape.imag());
  const double total = sxx + syy;
  if (!(total > 0.0)) return 0.0;
  return ((sxx - syy) * (sxx - syy) + 4.0 * sxy * sxy) / (total * total);
}

// Model mode j and its neighbours within 3 half-power widths (j first), and in *weight the blend
// weight exp(−z²) of the closest, z its distance in half-power widths (0 without neighbours).
static std::vector<Eigen::Index> CloseModes(const Eigen::VectorXd& model_hz, int j, double half_power_hz, double* weight) {
  std::vector<Eigen::Index> cols{j};
  *weight = 0.0;
  for (Eigen::Index k = 0; k < model_hz.size(); ++k) {
    if (k == j) continue;
    const double z = (model_hz(k) - model_hz(j)) / half_power_hz;
    if (std::abs(z) > 3.0) continue;
    cols.push_back(k);
    *weight = std::max(*weight, std::exp(-z * z));
  }
  return cols;
}

double BlendMac(const Eigen::VectorXcd& test_shape, const Eigen::MatrixXcd& model_shapes, const Eigen::VectorXd& model_hz,
                int j, double plain_mac, double half_power_hz) {
  if (!(half_power_hz > 0.0)) return plain_mac;
  double weight = 0.0;
  const std::vector<Eigen::Index> cols = CloseModes(model_hz, j, half_power_hz, &weight);
  if (cols.size() == 1) return plain_mac;
  Eigen::MatrixXcd basis(model_shapes.rows(), static_cast<Eigen::Index>(cols.size()));
  for (size_t c = 0; c < cols.size(); ++c) basis.col(static_cast<Eigen::Index>(c)) = model_shapes.col(cols[c]);
  const double norm = test_shape.squaredNorm();
  if (!(norm > 0.0)) return plain_mac;
  // Share of the test shape inside the span of the close model modes: bᴴ G⁺ b / φᴴφ.
  const Eigen::VectorXcd b = basis.adjoint() * test_shape;
  const Eigen::MatrixXcd gram = basis.adjoint() * basis;
  const Eigen::VectorXcd x = gram.completeOrthogonalDecomposition().solve(b);
  const double subspace = std::clamp(std::real(b.dot(x)) / norm, 0.0, 1.0);
  return plain_mac + weight * std::max(0.0, subspace - plain_mac);
}

Eigen::VectorXd RealShape(const Eigen::VectorXcd& shape, Eigen::VectorXd* out_of_phase) {
  const std::complex<double> sum_squares = shape.cwiseProduct(shape).sum();
  const std::complex<double> turn = std::polar(1.0, -0.5 * std::arg(sum_squares));
  const Eigen::VectorXcd turned = shape * turn;
  if (out_of_phase) *out_of_phase = turned.imag();
  return turned.real();
}

Eigen::VectorXd ShapeDifference(const Eigen::VectorXd& test_real, const Eigen::MatrixXcd& model_shapes,
                                const Eigen::VectorXd& model_hz, int j, double half_power_hz) {
  // Least-squares fit of the test shape by the columns of `basis`.
  auto fitted_by = [&](const Eigen::MatrixXd& basis) -> Eigen::VectorXd {
    const Eigen::MatrixXd gram = basis.transpose() * basis;
    if (!(gram.trace() > 0.0)) return Eigen::VectorXd::Zero(test_real.size());
    return basis * gram.completeOrthogonalDecomposition().solve(basis.transpose() * test_real);
  };
  const Eigen::MatrixXd own = RealShape(model_shapes.col(j));
  const Eigen::VectorXd plain = test_real - fitted_by(own);
  if (!(half_power_hz > 0.0)) return plain;
  double weight = 0.0;
  const std::vector<Eigen::Index> cols = CloseModes(model_hz, j, half_power_hz, &weight);  // as BlendMac
  if (cols.size() == 1) return plain;
  Eigen::MatrixXd basis(model_shapes.rows(), static_cast<Eigen::Index>(cols.size()));
  for (size_t c = 0; c < cols.size(); ++c) basis.col(static_cast<Eigen::Index>(c)) = RealShape(model_shapes.col(cols[c]));
  const Eigen::VectorXd in_span = test_real - fitted_by(basis);
  return (1.0 - weight) * plain + weight * in_span;
}

double Huber(double s, double a) { return s <= a * a ? s : 2.0 * a * std::sqrt(s) - a * a; }

double RobustCost(const Eigen::VectorXd& r, const std::vector<int>& block_start, double a) {
  double cost = 0.0;
  for (size_t b = 0; b + 1 < block_start.size(); ++b)
    cost += Huber(r.segment(block_start[b], block_start[b + 1] - block_start[b]).squaredNorm(), a);
  return cost;
}

namespace {

using SetupKey = std::pair<std::size_t, std::string>;  // a setup's index and a centre's or model's key

// `key` becomes the most recently used of `order`; the least recently used beyond `kept` leave it,
// each handed to `drop` to free what it names.
template <class Drop>
void MarkUsed(std::deque<SetupKey>* order, const SetupKey& key, std::size_t kept, Drop drop) {
  if (!order->empty() && order->back() == key) return;
  std::erase(*order, key);
  order->push_back(key);
  while (order->size() > kept) {
    const SetupKey old = order->front();
    order->pop_front();
    drop(old);
  }
}

}  // namespace

// The reduced models of an FE-sized model: one factory per setup and centre (a full solve and a
// factorisation each), one reduced model per set of probes.
struct Evaluator::Reduced {
  model::Model skeleton;  // the base without its [fe] matrices, DOF map and node positions: effects are applied to copies of it
  /// A factory and its centre's effects to the last digit (ExactKey): the factory's own full solve
  /// is then an exact evaluation there (Evaluate takes it instead of solving again).
  struct Centre {
    std::unique_ptr<model::ReducedModelFactory> factory;
    std::string exact_key;
  };
  std::map<SetupKey, Centre> factories;
  std::map<SetupKey, std::unique_ptr<model::ReducedModel>> models;
  /// Reduced models in order of last use: at most kKept stay (each holds a few b × b matrices, b a
  /// few dozen — the n-sized probe blocks live once in the factory; a diagnosis visits hundreds
  /// of sets, and makes a set's model again once it was dropped).
  std::deque<SetupKey> recent;
  static constexpr std::size_t kKept = 512;
  /// Factories of centres other than the nominal one in order of last use: at most
  /// DiagnoseOptions::kept_centres stay (each holds a factorisation of K − σM and its probes'
  /// responses: gigabytes at 200 000 DOFs, where the diagnosis centres on a dozen sets in turn and
  /// grew past 16 GB); a factory's reduced models go with it, and a centre met again is solved
  /// again (the same numbers: the solve is deterministic).
  std::deque<SetupKey> recent_factories;
};

namespace {
// The key of a centre's factory: its effects as model::Describe names them.
std::string CentreKey(const std::vector<model::Effect>& effects) {
  std::string key;
  for (const auto& e : effects) key += model::Describe(e) + ";";
  return key;
}

// A set of effects to the last digit of every parameter (model::Describe rounds to 6 digits: it
// names a centre, not a point).
std::string ExactKey(const std::vector<model::Effect>& effects) {
  std::string key;
  char number[32];
  for (const auto& e : effects) {
    key += model::Describe(e);
    for (const auto& [name, value] : e.parameters) {
      std::snprintf(number, sizeof number, "%.17g", value);
      key += " " + name + "=" + number;
    }
    key += ";";
  }
  return key;
}

// A reduced-model factory centred on `centred` (a full solve and a factorisation): its basis holds
// ten modes more than an evaluation compares, enriched by the static responses of the lowest.
std::unique_ptr<model::ReducedModelFactory> MakeFactory(const model::Model& centred, const model::SolveOptions& so,
                                                        int max_modes, int test_modes) {
  model::ReducedModelOptions ro;
  ro.modes = max_modes + 10;
  ro.enriched_modes = std::min(max_modes, test_modes + 4);
  return std::make_unique<model::ReducedModelFactory>(centred, so, ro);
}

// What Evaluate hands the solver for setup `setup` (with no sensors).
model::SolveOptions EvaluationOptions(const std::string& setup, const DiagnoseOptions& options, int max_modes,
                                      bool reduced) {
  model::SolveOptions so;
  so.setup = setup;
  so.max_modes = max_modes;
  if (reduced) so.sparse_threshold = options.reduced_model_min_dofs;  // FE-sized: the lowest modes by shift-invert
  return so;
}
}  // namespace

bool SearchesReduced(const model::Model& base, const DiagnoseOptions& options) {
  const int dofs = 6 * static_cast<int>(base.bodies.size()) + base.fe.Size();
  return options.reduced_model_min_dofs > 0 && dofs >= options.reduced_model_min_dofs;
}

NominalSolve SolveNominal(const model::Model& base, const std::string& setup, const DiagnoseOptions& options,
                          int max_modes, int test_modes) {
  NominalSolve out;
  const bool reduced = SearchesReduced(base, options);
  const model::SolveOptions so = EvaluationOptions(setup, options, max_modes, reduced);
  if (!reduced) {
    out.solution = model::Solve(base, so);
    return out;
  }
  // The factory solves with more modes than an evaluation compares: the lowest `max_modes` of its
  // solution are the evaluation's (as Evaluate takes them at any centre it has a factory for).
  out.factory = MakeFactory(base, so, max_modes, test_modes);
  // Its modes only (the DOF matching's input): the factory keeps the full shapes, n × modes.
  out.solution.modes = out.factory->BaseSolution().modes;
  if (static_cast<int>(out.solution.modes.modes.size()) > max_modes) out.solution.modes.modes.resize(static_cast<std::size_t>(max_modes));
  return out;
}

Evaluator::Evaluator(const model::Model& base, std::vector<SetupData> setups, const DiagnoseOptions& options,
                     int max_modes, std::vector<NominalSolve> nominal)
    : base_(base), setups_(std::move(setups)), options_(options), max_modes_(max_modes) {
  const bool per_dof = options.shape_residual == ShapeResidual::kPerDof;
  block_start_.push_back(0);
  for (const auto& s : setups_)
    for (Eigen::Index i = 0; i < s.test_hz.size(); ++i)
      block_start_.push_back(block_start_.back() + 1 + (per_dof ? static_cast<int>(s.real_shapes.rows()) : 1));
  residual_count_ = block_start_.back();
  model_error_gain_.resize(residual_count_);
  row_dof_.assign(static_cast<size_t>(residual_count_), -1);
  Eigen::VectorXd log_hz(TestModeCount());
  int mode = 0;
  for (const auto& s : setups_)
    for (Eigen::Index i = 0; i < s.test_hz.size(); ++i, ++mode) {
      const int row = block_start_[static_cast<size_t>(mode)];
      model_error_gain_(row) = s.test_hz(i) / s.sigma_hz(i);
      if (per_dof) {
        // ε_s is the rms error of a unit-norm shape, spread over its d DOFs: ε_s / √d at each.
        const double per_row = 1.0 / std::sqrt(static_cast<double>(std::max<Eigen::Index>(1, s.real_shapes.rows())));
        for (Eigen::Index d = 0; d < s.real_shapes.rows(); ++d) {
          model_error_gain_(row + 1 + d) = per_row / s.sigma_dof(d, i);
          const Dof& dof = s.match.shared[static_cast<size_t>(d)].test_dof;
          row_dof_[static_cast<size_t>(row + 1 + d)] = static_cast<long long>(dof.node) * 16 + dof.direction + 8;
        }
      } else {
        model_error_gain_(row + 1) = 1.0 / s.sigma_shape(i);
      }
      log_hz(mode) = std::log(std::max(s.test_hz(i), 1e-300));
    }
  model_error_trend_ = Eigen::VectorXd::Zero(residual_count_);
  if (log_hz.size() > 0) {
    const double mean = log_hz.mean();
    const double sd = std::sqrt((log_hz.array() - mean).square().mean());
    if (sd > 1e-9)
      for (Eigen::Index i = 0; i < log_hz.size(); ++i) model_error_trend_(block_start_[i]) = (log_hz(i) - mean) / sd;
  }
  reduced_ = SearchesReduced(base, options);
  if (reduced_) {
    reduced_models_ = std::make_unique<Reduced>();
    reduced_models_->skeleton = base;
    reduced_models_->skeleton.fe.mass.resize(0, 0);
    reduced_models_->skeleton.fe.stiffness.resize(0, 0);
    // Nor its DOF map and node positions (the reduced models keep their own): each evaluation
    // copies the skeleton, and a 50 000-DOF map is no small copy.
    reduced_models_->skeleton.fe.dofs.clear();
    reduced_models_->skeleton.fe.node_positions.clear();
  }
  // The base solved before the evaluator existed (the setups' DOF matching): a factory becomes the
  // nominal centre's, a plain solution the baseline's. Full solves of this diagnosis all the same.
  for (std::size_t s = 0; s < nominal.size() && s < setups_.size(); ++s) {
    ++solves_;
    if (reduced_ && nominal[s].factory) {
      Reduced::Centre& centre = reduced_models_->factories[{s, ""}];
      centre.factory = std::move(nominal[s].factory);
      centre.exact_key = "";
    } else if (!reduced_ && !nominal[s].factory) {
      nominal_.resize(setups_.size());
      nominal_[s] = std::move(nominal[s].solution);
    }
  }
}

Evaluator::~Evaluator() = default;

Evaluation Evaluator::Evaluate(const std::vector<model::Effect>& effects) {
  model::Model m;
  try {
    m = base_;
    for (const auto& e : effects) m = model::ApplyEffect(m, e);
  } catch (const std::exception& e) {
    Evaluation out;
    out.error = e.what();
    return out;
  }
  const std::string centre_key = reduced_ ? CentreKey(effects) : "", exact_key = reduced_ ? ExactKey(effects) : "";
  return Compare([&](std::size_t s, const std::vector<model::PointMass>& sensors) {
    if (reduced_ && sensors.empty()) {
      // A reduced-model factory centred exactly here has solved this very model (without the
      // test's sensors, as here): its lowest modes are this solve's (a check of a set re-centred
      // at its values costs one full solve, not two).
      const auto centre = reduced_models_->factories.find({s, centre_key});
      if (centre != reduced_models_->factories.end() && centre->second.exact_key == exact_key) {
        const model::Solution& at_centre = centre->second.factory->BaseSolution();
        model::Solution sol;
        sol.modes = at_centre.modes;
        sol.rigid_body_frequencies_hz = at_centre.rigid_body_frequencies_hz;
        if (static_cast<int>(sol.modes.modes.size()) > max_modes_) sol.modes.modes.resize(static_cast<std::size_t>(max_modes_));
        return sol;
      }
    }
    if (effects.empty() && sensors.empty() && s < nominal_.size() && !nominal_[s].modes.modes.empty())
      return nominal_[s];  // the base, solved once (SolveNominal)
    model::SolveOptions so = EvaluationOptions(setups_[s].name, options_, max_modes_, reduced_);
    so.extra_masses = sensors;
    ++solves_;
    return model::Solve(m, so);
  });
}

Evaluation Evaluator::EvaluateReduced(const std::string& key, const std::vector<std::vector<model::Effect>>& probes,
                                      const std::vector<model::Effect>& centre,
                                      const std::vector<model::Effect>& effects) {
  Reduced& r = *reduced_models_;
  const std::string centre_key = CentreKey(centre);
  model::Model changed;
  try {
    changed = r.skeleton;
    for (const auto& e : effects) changed = model::ApplyEffect(changed, e);
  } catch (const std::exception& e) {
    Evaluation out;
    out.error = e.what();
    return out;
  }
  const int test_modes = TestModeCount();
  // Only part factors changed (no spring, body or point mass): the reduced model skips assembling
  // the rest again.
  bool rest_changed = false;
  for (const auto& e : effects)
    if (!((e.kind == model::EffectKind::kStiffnessScale || e.kind == model::EffectKind::kMassScale) &&
          model::TargetSprings(r.skeleton, e.target).empty() &&
          !model::TargetBody(r.skeleton, e.target) && !model::TargetParts(r.skeleton, e.target).empty()))
      rest_changed = true;
  return Compare([&](std::size_t s, const std::vector<model::PointMass>& sensors) {
    model::SolveOptions so;
    so.setup = setups_[s].name;
    so.max_modes = max_modes_;
    so.sparse_threshold = options_.reduced_model_min_dofs;
    Reduced::Centre& made = r.factories[{s, centre_key}];
    if (!made.factory) {
      model::Model centred = base_;
      for (const auto& e : centre) centred = model::ApplyEffect(centred, e);
      made.factory = MakeFactory(centred, so, max_modes_, test_modes);
      made.exact_key = ExactKey(centre);
      ++solves_;
    }
    if (!centre_key.empty())
      MarkUsed(&r.recent_factories, {s, centre_key}, static_cast<std::size_t>(options_.kept_centres),
               [&](const SetupKey& old) {
                 const std::string prefix = old.second + "|";
                 auto of_old = [&](const SetupKey& k) { return k.first == old.first && k.second.starts_with(prefix); };
                 std::erase_if(r.models, [&](const auto& entry) { return of_old(entry.first); });
                 std::erase_if(r.recent, of_old);
                 r.factories.erase(old);
               });
    const SetupKey model_key{s, centre_key + "|" + key};
    auto& reduced = r.models[model_key];
    if (!reduced) reduced = made.factory->Make(probes);
    MarkUsed(&r.recent, model_key, Reduced::kKept, [&](const SetupKey& old) { r.models.erase(old); });
    ++reduced_solves_;
    so.extra_masses = sensors;
    return reduced->Solve(changed, so, rest_changed);
  });
}

model::Solution AsTested(const SetupData& s, const std::vector<model::Solution>& per_set) {
  model::Solution out = per_set.front();
  if (per_set.size() == 1) return out;
  const auto& base = per_set.front().modes;
  // A set's weight in a mode's frequency: the energy of its measured responses, Σ |φ_i|² over its
  // DOFs — a least-squares fit of all FRFs at once weighs each set by how much of the mode it sees.
  auto energy = [&](const Eigen::VectorXcd& shape, size_t k) {
    if (s.equal_set_weights) return 1.0;
    double e = 0.0;
    for (Eigen::Index d = 0; d < shape.size(); ++d)
      if (s.set_of_dof[static_cast<size_t>(d)] == static_cast<int>(k)) e += std::norm(shape(d));
    return e;
  };
  for (size_t j = 0; j < base.modes.size(); ++j) {
    const Eigen::VectorXcd& b = base.modes[j].shape;
    double weight = energy(b, 0), frequency = weight * base.modes[j].frequency_hz;
    Eigen::VectorXcd shape = b;
    for (size_t k = 1; k < per_set.size(); ++k) {
      const auto& modes = per_set[k].modes.modes;
      // The same mode in set k: the most similar shape among the modes within 20 % in frequency
      // (small sensor masses neither reorder nor reshape modes much, close pairs aside).
      int match = -1;
      double best = -1.0;
      for (size_t m = 0; m < modes.size(); ++m) {
        if (std::abs(modes[m].frequency_hz - base.modes[j].frequency_hz) > 0.2 * base.modes[j].frequency_hz) continue;
        const double mac = std::norm(b.dot(modes[m].shape)) / (b.squaredNorm() * modes[m].shape.squaredNorm());
        if (mac > best) best = mac, match = static_cast<int>(m);
      }
      if (match < 0) continue;
      const Eigen::VectorXcd& p = modes[static_cast<size_t>(match)].shape;
      // The test's shapes are residues φ_i φ_ref stitched through the hammer DOF: scale set k's
      // values by its φ_ref over the first set's; without a usable reference, align the sign.
      std::complex<double> scale = std::real(b.dot(p)) < 0.0 ? -1.0 : 1.0;
      if (s.reference_row >= 0 && std::abs(b(s.reference_row)) > 1e-9 * b.cwiseAbs().maxCoeff())
        scale = p(s.reference_row) / b(s.reference_row);
      for (Eigen::Index d = 0; d < shape.size(); ++d)
        if (s.set_of_dof[static_cast<size_t>(d)] == static_cast<int>(k)) shape(d) = p(d) * scale;
      const double w = energy(p, k);
      weight += w;
      frequency += w * modes[static_cast<size_t>(match)].frequency_hz;
    }
    if (weight > 0.0) out.modes.modes[j].frequency_hz = frequency / weight;
    out.modes.modes[j].shape = shape;
  }
  return out;
}

Evaluation Evaluator::Compare(
    const std::function<model::Solution(std::size_t setup, const std::vector<model::PointMass>&)>& solve) {
  Evaluation out;
  out.r.resize(residual_count_);
  const bool per_dof = options_.shape_residual == ShapeResidual::kPerDof;
  try {
    int mode = 0;
    double sum_err = 0.0, sum_mac = 0.0, sum_agreement = 0.0;
    for (std::size_t index = 0; index < setups_.size(); ++index) {
      const SetupData& s = setups_[index];
      model::Solution sol;
      if (s.sensors.empty()) {
        sol = solve(index, {});
      } else {
        std::vector<model::Solution> per_set;
        for (const auto& sensors : s.sensors) per_set.push_back(solve(index, sensors));
        sol = AsTested(s, per_set);
      }
      if (sol.modes.dofs.size() != s.model_dof_count)
        throw InputError(base_.origin, "the model's observed DOFs changed while fitting");
      if (sol.modes.modes.empty()) throw InputError(base_.origin, "the model has no elastic mode");
      const Eigen::MatrixXcd model_shapes = s.match.ModelShapes(sol.modes);
      Eigen::VectorXd model_hz(sol.modes.modes.size());
      for (size_t j = 0; j < sol.modes.modes.size(); ++j) model_hz(j) = sol.modes.modes[j].frequency_hz;
      const Eigen::MatrixXd mac = correlation::MacMatrix(s.test_shapes, model_shapes);
      const correlation::Pairing pairing = correlation::PairModes(mac, s.test_hz, model_hz, options_.pairing);
      std::vector<int> partner(s.test_hz.size(), -1);
      for (const correlation::ModePair& p : pairing.pairs) partner[p.test] = p.model;
      for (Eigen::Index i = 0; i < s.test_hz.size(); ++i, ++mode) {
        const int row = block_start_[static_cast<size_t>(mode)];
        const int shape_rows = block_start_[static_cast<size_t>(mode) + 1] - row - 1;
        ModeComparison c;
        c.setup = s.name;
        c.test = static_cast<int>(index);
        c.test_mode = static_cast<int>(i);
        c.test_frequency_hz = s.test_hz(i);
        c.sigma_hz = s.sigma_hz(i);
        const int j = partner[i];
        if (j >= 0) {
          c.model_mode = j;
          c.model_frequency_hz = model_hz(j);
          c.agreement_pct = correlation::AgreementPct(model_hz(j), s.test_hz(i));
          c.mac = mac(i, j);
          out.r(row) = (model_hz(j) - s.test_hz(i)) / s.sigma_hz(i);
          if (per_dof) {
            out.r.segment(row + 1, shape_rows) =
                ShapeDifference(s.real_shapes.col(i), model_shapes, model_hz, j, s.half_power_hz(i))
                    .cwiseQuotient(s.sigma_dof.col(i));
          } else {
            const double judged =
                BlendMac(s.test_shapes.col(i), model_shapes, model_hz, j, mac(i, j), s.half_power_hz(i));
            out.r(row + 1) = (1.0 - judged) / s.sigma_shape(i);
          }
          sum_err += 100.0 * std::abs(model_hz(j) - s.test_hz(i)) / s.test_hz(i);
          sum_mac += mac(i, j);
          sum_agreement += c.agreement_pct;
          ++out.paired;
        } else {
          out.r(row) = options_.unpaired_frequency_residual * s.test_hz(i) / s.sigma_hz(i);
          // Nothing of the shape explained (MAC 0).
          if (per_dof) out.r.segment(row + 1, shape_rows) = s.real_shapes.col(i).cwiseQuotient(s.sigma_dof.col(i));
          else out.r(row + 1) = 1.0 / s.sigma_shape(i);
        }
        c.frequency_misfit_sigma = out.r(row);
        // Per DOF: the rms over the shape's DOFs, so that a shape within its noise reads about 1σ.
        c.shape_misfit_sigma =
            per_dof ? out.r.segment(row + 1, shape_rows).norm() / std::sqrt(std::max(1, shape_rows)) : out.r(row + 1);
        out.modes.push_back(c);
      }
    }
    if (out.paired > 0) {
      out.mean_abs_frequency_error_pct = sum_err / out.paired;
      out.mean_mac = sum_mac / out.paired;
      out.mean_agreement_pct = sum_agreement / out.paired;
    }
    out.cost = RobustCost(out.r, block_start_, options_.robust_threshold);
    out.ok = true;
  } catch (const std::exception& e) {
    out.ok = false;
    out.error = e.what();
  }
  return out;
}

}  // namespace ema::diagnose::detail
