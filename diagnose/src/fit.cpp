// Stage 3, fits: the maximum a-posteriori parameters of one set of effects (Ceres) and the
// Laplace approximation of its evidence at that point:
//   log Z ≈ −½ J(θ*) + log p(θ*) + (k/2) ln 2π − ½ ln det H,
// J the robust misfit in σ, p the prior in θ, H = Σ_b w_b J_bᵀJ_b + prior curvature the
// posterior Hessian (Gauss–Newton, Huber weights w_b per mode block).
#include <algorithm>
#include <ceres/ceres.h>

#include "ema/core/solver_logging.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <map>

#include "internal.hpp"

namespace ema::diagnose::detail {
namespace {

// Ceres' numeric step is relative to |x|; parameters are stored as x = θ + kOffset so that the
// step (1e-4 |x| ≈ 1e-3 in θ, a 0.1 % change of the physical parameter) stays well above the
// noise of the model's own root finders, whatever θ is.
constexpr double kOffset = 10.0;
constexpr double kRelativeStep = 1e-4;
constexpr double kJacobianStep = 1e-3;  // central differences in θ for the Hessian

struct ModeBlock {
  Problem* problem;
  std::vector<int> set;
  int index;
  /// Per residual, 1/√(1 + (ε·gain)²): the residuals in units of measurement σ and model error
  /// combined (empty: measurement σ alone).
  std::shared_ptr<const Eigen::VectorXd> scale;
  bool operator()(double const* const* parameters, double* residuals) const {
    std::vector<double> theta(set.size());
    for (size_t k = 0; k < set.size(); ++k) theta[k] = parameters[0][k] - kOffset;
    const auto e = problem->At(set, theta);
    if (!e->ok) return false;
    const std::vector<int>& start = problem->Eval().BlockStart();
    for (int row = start[index], i = 0; row < start[index + 1]; ++row, ++i)
      residuals[i] = scale ? e->r(row) * (*scale)(row) : e->r(row);
    return true;
  }
};

// Per residual, the factor that turns a residual in measurement σ into one in measurement σ and
// model error combined: σ_total² = σ² (1 + (ε·gain)²), ε the frequency scale on frequency rows
// and the shape scale on shape rows.
// `shape_per_mode`: each test mode's own shape scale (empty: 0 for every mode). The refit it
// serves takes each row alone even where tests of one setup share a mode's error (the evidence
// does not: SharedErrorGroups) — it only needs the rows' relative weights.
Eigen::VectorXd ModelErrorScale(const Evaluator& evaluator, double frequency_rel, const Eigen::VectorXd& shape_per_mode) {
  const Eigen::VectorXd& gain = evaluator.ModelErrorGain();
  const std::vector<int>& blocks = evaluator.BlockStart();
  Eigen::VectorXd scale(gain.size());
  for (size_t m = 0; m + 1 < blocks.size(); ++m)
    for (int i = blocks[m]; i < blocks[m + 1]; ++i) {
      const double shape = shape_per_mode.size() > 0 ? shape_per_mode(static_cast<Eigen::Index>(m)) : 0.0;
      const double g = gain(i) * (i == blocks[m] ? frequency_rel : shape);
      scale(i) = 1.0 / std::sqrt(1.0 + g * g);
    }
  return scale;
}

// The test modes whose model error is one draw: those of tests of one setup paired with one model
// mode. The structure and its model are the same in each such test, only the noise differs, so
// the model's error of that mode is the same in all of them; counted once per test it would be
// counted as evidence once per test (a follow-up test diagnosed with the first: docs/diagnose.md
// "Model error"). A mode of a lone test, or an unpaired one, is a group of its own.
std::vector<std::vector<int>> SharedErrorGroups(const std::vector<ModeComparison>& modes) {
  std::vector<std::vector<int>> groups;
  std::map<std::pair<std::string, int>, size_t> group_of;
  for (int m = 0; m < static_cast<int>(modes.size()); ++m) {
    const ModeComparison& c = modes[static_cast<size_t>(m)];
    if (c.model_mode < 0) {
      groups.push_back({m});
      continue;
    }
    const auto [at, added] = group_of.try_emplace({c.setup, c.model_mode}, groups.size());
    if (added) groups.emplace_back();
    groups[at->second].push_back(m);
  }
  return groups;
}

// Rows that share one model error of pattern v (in σ; v_i = ε·gain_i): their covariance is
// I + v vᵀ. Whitens the rows of `x` in place — (I + v vᵀ)^(−½) x = x + ((1 + |v|²)^(−½) − 1) v̂ v̂ᵀ x,
// for one row x / √(1 + v²) — and returns the Gaussian's normalisation −½ ln(1 + |v|²).
double WhitenShared(const Eigen::VectorXd& v, Eigen::MatrixXd* x) {
  const double c = v.squaredNorm(), scale = 1.0 / std::sqrt(1.0 + c);
  if (v.size() == 1) *x *= scale;
  else if (c > 0.0) {
    const Eigen::VectorXd unit = v / std::sqrt(c);
    const Eigen::RowVectorXd along = unit.transpose() * *x;
    *x += (scale - 1.0) * unit * along;
  }
  return std::log(scale);
}

// Grid points of a log-uniform prior over [lo, hi]: their centres in ln ε, equal weights.
std::vector<double> LogGrid(double lo, double hi, int points) {
  std::vector<double> out(points);
  const double a = std::log(lo), step = (std::log(hi) - a) / points;
  for (int i = 0; i < points; ++i) out[i] = std::exp(a + (i + 0.5) * step);
  return out;
}

// Grid sizes over ln ε_f and each mode's ln ε_s: the marginal likelihood varies smoothly in ln ε
// (a step of 0.5 in ln ε_f, 0.6 in ln ε_s moves it by far less than the candidates' differences).
constexpr int kFrequencyErrorPoints = 20;
constexpr int kShapeErrorPoints = 14;
// The shared frequency shift ε_c: a coarser grid (a step of 0.86 in ln ε_c) — its evidence is
// a single direction's, flatter in ε_c than the independent scales'.
constexpr int kCommonErrorPoints = 12;

struct PriorBlock {
  const Atom* atom;
  int index;
  bool operator()(double const* const* parameters, double* residuals) const {
    residuals[0] = atom->prior.Residual(parameters[0][index] - kOffset, atom->spec);
    return std::isfinite(residuals[0]);
  }
};

}  // namespace

std::shared_ptr<const Evaluation> Problem::Cached(std::deque<std::pair<Key, std::shared_ptr<const Evaluation>>>* cache,
                                                  const Key& key, const std::function<Evaluation()>& evaluate) {
  for (const auto& [k, value] : *cache)
    if (k == key) return value;
  auto value = std::make_shared<const Evaluation>(evaluate());
  cache->emplace_back(key, value);
  if (cache->size() > 24) cache->pop_front();
  return value;
}

Evaluation Problem::OnCentre(const std::vector<int>& set, const std::vector<double>& theta,
                            const std::vector<int>& centre_set, const std::vector<double>* centre_theta) {
  // Its probes are its atoms, each at a value that changes the model (linear effects give one
  // direction whatever the value; the others near the centre): an atom of the centre's set from
  // its value there, the others from their reference.
  std::vector<std::vector<model::Effect>> probes;
  std::string key;
  for (size_t k = 0; k < set.size(); ++k) {
    const Atom& a = (*atoms_)[set[k]];
    const auto in_centre = std::find(centre_set.begin(), centre_set.end(), set[k]);
    const double at = centre_theta && in_centre != centre_set.end()
                          ? (*centre_theta)[static_cast<size_t>(in_centre - centre_set.begin())] - 0.5
                          : (a.spec.absent_end == 0 ? -0.5 : 0.0);
    probes.push_back({a.With(at)});
    key += std::to_string(set[k]) + ",";
  }
  const std::vector<model::Effect> centred =
      centre_theta ? Effects(centre_set, *centre_theta) : std::vector<model::Effect>{};
  return evaluator_->EvaluateReduced(key, probes, centred, Effects(set, theta));
}

std::shared_ptr<const Evaluation> Problem::At(const std::vector<int>& set, const std::vector<double>& theta) {
  if (set.empty() || !evaluator_->UsesReducedModels()) return Exact(set, theta);
  return Cached(&cache_, {set, theta}, [&] {
    const auto centre = centres_.find(set);
    return centre != centres_.end() ? OnCentre(set, theta, centre->second.set, &centre->second.theta)
                                    : OnCentre(set, theta, {}, nullptr);
  });
}

std::shared_ptr<const Evaluation> Problem::AtCentreOf(const std::vector<int>& centre_set, const std::vector<int>& set,
                                                      const std::vector<double>& theta) {
  const auto centre = centres_.find(centre_set);
  if (set.empty() || !evaluator_->UsesReducedModels() || centre == centres_.end()) return Exact(set, theta);
  return std::make_shared<const Evaluation>(OnCentre(set, theta, centre->second.set, &centre->second.theta));
}

std::shared_ptr<const Evaluation> Problem::Exact(const std::vector<int>& set, const std::vector<double>& theta) {
  return Cached(&exact_cache_, {set, theta}, [&] { return evaluator_->Evaluate(Effects(set, theta)); });
}

void Problem::Widen(int atom, int end) {
  ParamSpec& s = (*atoms_)[static_cast<size_t>(atom)].spec;
  const double step = s.log ? std::log(1000.0) : s.hi - s.lo;
  if (end < 0) s.lo -= step;
  else s.hi += step;
}

void Problem::Recentre(const std::vector<int>& set, const std::vector<double>& theta) {
  centres_[set] = {set, theta};
  std::erase_if(cache_, [&](const auto& entry) { return entry.first.first == set; });
}

void Problem::RecentreOn(const std::vector<int>& set, const std::vector<int>& centre_set) {
  const auto centre = centres_.find(centre_set);
  if (centre != centres_.end()) centres_[set] = centre->second;  // std::map: `centre` stays valid
  else centres_.erase(set);
  std::erase_if(cache_, [&](const auto& entry) { return entry.first.first == set; });
}

std::vector<model::Effect> Problem::Effects(const std::vector<int>& set, const std::vector<double>& theta) const {
  std::vector<model::Effect> effects;
  for (size_t k = 0; k < set.size(); ++k) effects.push_back((*atoms_)[set[k]].With(theta[k]));
  return effects;
}

double Problem::LogPrior(const std::vector<int>& set, const std::vector<double>& theta) const {
  double lp = 0.0;
  for (size_t k = 0; k < set.size(); ++k) {
    const Atom& a = (*atoms_)[set[k]];
    lp += a.prior.LogDensity(theta[k], a.spec);
  }
  return lp;
}

double Problem::Objective(const std::vector<int>& set, const std::vector<double>& theta) {
  const auto e = At(set, theta);
  if (!e->ok) return kInf;
  // The MAP objective: the prior's residuals (without the log Jacobian), as Ceres minimises it.
  double prior = 0.0;
  for (size_t k = 0; k < set.size(); ++k) {
    const Atom& a = (*atoms_)[set[k]];
    const double r = a.prior.Residual(theta[k], a.spec);
    prior += 0.5 * r * r;
  }
  return 0.5 * e->cost + prior;
}

Fit Assess(Problem* problem, const std::vector<int>& set, const std::vector<double>& theta,
           const DiagnoseOptions& options, bool exact) {
  Fit f;
  f.atoms = set;
  f.theta = theta;
  f.exact = exact || !problem->Reduced() || set.empty();
  f.eval = exact ? problem->Exact(set, theta) : problem->At(set, theta);
  if (!f.eval->ok) {
    f.error = f.eval->error;
    return f;
  }
  f.ok = true;
  f.objective = 0.5 * f.eval->cost;
  for (size_t k = 0; k < set.size(); ++k) {
    const Atom& a = problem->Atoms()[set[k]];
    const double r = a.prior.Residual(theta[k], a.spec);
    f.objective += 0.5 * r * r;
  }
  f.log_prior = problem->LogPrior(set, theta);
  const int k = static_cast<int>(set.size());
  const int n = problem->ResidualCount();
  const double a = options.robust_threshold;
  f.sigma_theta = Eigen::VectorXd::Constant(k, kNaN);
  // Central-difference Jacobian of the residuals in θ (in measurement σ).
  Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(n, k);
  bool ok = true;
  for (int i = 0; i < k && ok; ++i) {
    std::vector<double> plus = theta, minus = theta;
    plus[i] += kJacobianStep;
    minus[i] -= kJacobianStep;
    auto ep = problem->At(set, plus);
    auto em = problem->At(set, minus);
    // A reduced model far from its centre can turn a softened part's stiffness indefinite; the
    // full model then says what the neighbourhood is (benchmark case 159).
    if (!ep->ok || !em->ok) {
      ep = problem->Exact(set, plus);
      em = problem->Exact(set, minus);
    }
    if (!ep->ok || !em->ok) ok = false;
    else jac.col(i) = (ep->r - em->r) / (2.0 * kJacobianStep);
  }
  if (!ok) {
    // Without the data's curvature the Laplace evidence is only the prior's, far too high.
    f.ok = false;
    f.error = "the evidence could not be computed: the model does not solve next to the fitted values";
  }
  Eigen::VectorXd prior_curvature(k);
  for (int i = 0; i < k; ++i) {
    const Atom& atom = problem->Atoms()[set[i]];
    // A floor of one over the searched range keeps H regular where neither data nor prior bind.
    const double width = atom.spec.hi - atom.spec.lo;
    prior_curvature(i) = atom.prior.Curvature(theta[i], atom.spec) + 1.0 / (width * width);
  }
  // The structure prior: every set of k effects out of the N candidates is a priori as likely
  // as the others of its size, so each effect costs ln N (many look-alike candidates — one per
  // point, per member — must not fit the noise by sheer number), and one more effect is
  // effect_prior_odds as likely as one fewer.
  const double structure =
      -k * (std::log(static_cast<double>(problem->Atoms().size())) - std::log(options.effect_prior_odds));
  const Eigen::VectorXd& gain = problem->Eval().ModelErrorGain();

  // The Laplace evidence at θ with the residuals in units of σ_total = σ·√(1 + (ε·gain)²) and a
  // frequency error shared across the modes — a relative shift c₀·f common to all and a trend
  // c₁·t·f in t = standardised ln f, (c₀, c₁) ~ N(0, ε_c² I) marginalised analytically. With r̃ the
  // scaled residuals and U (n × 2) the two patterns in them (U_i = gain_i·scale_i·(1, t_i) on
  // frequency rows), the covariance is I + ε_c² U Uᵀ, so (Woodbury, M = I/ε_c² + UᵀU)
  //   r̃ᵀ(I + ε_c² U Uᵀ)⁻¹ r̃ = |r̃|² − bᵀ M⁻¹ b,   b = Uᵀr̃,
  //   log Z(ε) = −½ J(θ; ε) − Σ ln √(1 + (ε·gain)²) − ½ ln det(I + ε_c² UᵀU) + log p(θ)
  //              + (k/2) ln 2π − ½ ln det H(ε) + structure,
  // J the Huber cost with the shared part removed in the Huber-weighted metric and H the posterior
  // Hessian in the same metric (the Gaussian's normalisation is relative to the measurement σ,
  // common to all candidates). Without the shared terms, six modes that all sit 0.3 % high
  // (a spread mass the model lacks) read as six independent errors that one added point mass
  // "explains"; with them they are one error of the model's overall stiffness-to-mass ratio.
  const Eigen::VectorXd& trend = problem->Eval().ModelErrorTrend();
  const std::vector<int>& blocks = problem->Eval().BlockStart();
  const int modes = static_cast<int>(blocks.size()) - 1;
  // The frequency rows at a frequency scale ε_f: J, U and the Hessian's frequency part.
  struct Scaled {
    double cost_w = 0.0;         // Huber cost of the scaled frequency residuals
    double log_norm = 0.0;       // Σ ln scale over the frequency rows
    Eigen::Vector2d ur = Eigen::Vector2d::Zero();  // Uᵀ W r̃ (W the Huber weights)
    Eigen::Matrix2d uu = Eigen::Matrix2d::Zero();  // Uᵀ W U
    Eigen::MatrixXd jwj;         // Σ w J̃ᵀJ̃ of the frequency rows + prior curvature
    Eigen::MatrixXd jwu;         // J̃ᵀ W U (k × 2)
  };
  // Test modes of several tests of one setup paired with one model mode share its model error
  // (SharedErrorGroups): their frequency rows are whitened together; a lone test's are each alone.
  const std::vector<std::vector<int>> groups = SharedErrorGroups(f.eval->modes);
  auto scaled_at = [&](double frequency_rel) {
    Scaled out;
    out.jwj = prior_curvature.asDiagonal();
    out.jwu = Eigen::MatrixXd::Zero(k, 2);
    for (const std::vector<int>& group : groups) {
      // Per member its frequency row: the residual, the two shared patterns and the Jacobian row.
      const int n_rows = static_cast<int>(group.size());
      Eigen::VectorXd v(n_rows);
      Eigen::MatrixXd x(n_rows, 3 + k);
      for (int i = 0; i < n_rows; ++i) {
        const int b = blocks[group[i]];
        v(i) = gain(b) * frequency_rel;
        x(i, 0) = f.eval->r(b);
        x(i, 1) = gain(b);
        x(i, 2) = gain(b) * trend(b);
        x.row(i).tail(k) = jac.row(b);
      }
      out.log_norm += WhitenShared(v, &x);
      for (int i = 0; i < n_rows; ++i) {
        const double r = x(i, 0);
        out.cost_w += Huber(r * r, a);
        const double w = r * r <= a * a ? 1.0 : a / std::abs(r);
        const Eigen::Vector2d u(x(i, 1), x(i, 2));
        out.ur += w * r * u;
        out.uu += w * u * u.transpose();
        if (k > 0 && ok) {
          const Eigen::RowVectorXd jb = x.row(i).tail(k);
          out.jwj += w * jb.transpose() * jb;
          out.jwu += w * jb.transpose() * u.transpose();
        }
      }
    }
    return out;
  };
  // The shape rows, each test mode with its own model error ε_s,m (log-uniform, marginalised on
  // the grid): a scale mixture per mode, so a pair of close modes that the model's error mixes
  // costs what such an error costs, not what a structure-wide one would (an extra mass that
  // "explains" two mixed modes of twelve no longer wins). No model error: the measurement σ alone.
  struct Shapes {
    double log_likelihood = 0.0;
    Eigen::MatrixXd jwj;               // Σ J̃ᵀJ̃ of the shape rows, each mode at its most probable ε_s,m
    Eigen::VectorXd most_probable;     // per mode
  };
  // A group of test modes (one model mode seen by several tests of one setup) has one shape
  // error: one ε_s marginalised for the group, and its rows at one test DOF whitened together.
  // Per group, its shape rows by test DOF (a row without one — (1 − MAC) — or of a lone mode alone).
  std::vector<std::vector<std::vector<int>>> shape_rows(groups.size());
  const std::vector<long long>& row_dof = problem->Eval().RowDof();
  for (size_t g = 0; g < groups.size(); ++g) {
    std::map<long long, size_t> at_dof;
    for (int m : groups[g])
      for (int row = blocks[m] + 1; row < blocks[m + 1]; ++row) {
        const long long dof = row_dof[static_cast<size_t>(row)];
        if (dof < 0 || groups[g].size() == 1) {
          shape_rows[g].push_back({row});
          continue;
        }
        const auto [it, added] = at_dof.try_emplace(dof, shape_rows[g].size());
        if (added) shape_rows[g].emplace_back();
        shape_rows[g][it->second].push_back(row);
      }
  }
  auto shapes_at = [&](const std::vector<double>& grid) {
    Shapes out;
    out.jwj = Eigen::MatrixXd::Zero(k, k);
    out.most_probable = Eigen::VectorXd::Zero(modes);
    for (size_t g = 0; g < groups.size(); ++g) {
      double best = -kInf, sum = 0.0, best_e = 0.0;
      std::vector<double> values;
      Eigen::MatrixXd best_jwj = Eigen::MatrixXd::Zero(k, k);
      for (double e : grid.empty() ? std::vector<double>{0.0} : grid) {
        double value = 0.0;
        Eigen::MatrixXd jwj = Eigen::MatrixXd::Zero(k, k);
        for (const std::vector<int>& rows : shape_rows[g]) {
          const int n_rows = static_cast<int>(rows.size());
          Eigen::VectorXd v(n_rows);
          Eigen::MatrixXd x(n_rows, 1 + k);
          for (int i = 0; i < n_rows; ++i) {
            v(i) = gain(rows[i]) * e;
            x(i, 0) = f.eval->r(rows[i]);
            x.row(i).tail(k) = jac.row(rows[i]);
          }
          value += WhitenShared(v, &x) - 0.5 * x.col(0).squaredNorm();
          jwj += x.rightCols(k).transpose() * x.rightCols(k);
        }
        values.push_back(value);
        if (value > best) best = value, best_e = e, best_jwj = jwj;
      }
      for (double v : values) sum += std::exp(v - best);
      out.log_likelihood += best + std::log(sum / static_cast<double>(values.size()));
      for (int m : groups[g]) out.most_probable(m) = best_e;
      if (k > 0 && ok) out.jwj += best_jwj;
    }
    return out;
  };
  // The Laplace evidence at θ with the residuals in units of σ_total = σ·√(1 + (ε·gain)²) and a
  // frequency error shared across the modes — a relative shift c₀·f common to all and a trend
  // c₁·t·f in t = standardised ln f, (c₀, c₁) ~ N(0, ε_c² I) marginalised analytically. With r̃ the
  // scaled frequency residuals and U (modes × 2) the two patterns in them (U_i = gain_i·scale_i·(1,
  // t_i)), the covariance is I + ε_c² U Uᵀ, so (Woodbury, M = I/ε_c² + UᵀU)
  //   r̃ᵀ(I + ε_c² U Uᵀ)⁻¹ r̃ = |r̃|² − bᵀ M⁻¹ b,   b = Uᵀr̃,
  //   log Z(ε) = −½ J_f(θ; ε_f) − Σ ln √(1 + (ε_f·gain)²) − ½ ln det(I + ε_c² UᵀU) + log L_shapes
  //              + log p(θ) + (k/2) ln 2π − ½ ln det H(ε) + structure,
  // J_f the Huber cost of the frequencies with the shared part removed in the Huber-weighted
  // metric, L_shapes the shapes' likelihood marginalised mode by mode, and H the posterior Hessian
  // in the same metric (the Gaussian's normalisation is relative to the measurement σ, common to
  // all candidates). Without the shared terms, six modes that all sit 0.3 % high (a spread mass
  // the model lacks) read as six independent errors that one added point mass "explains"; with
  // them they are one error of the model's overall stiffness-to-mass ratio.
  auto evidence_at = [&](const Scaled& sc, const Shapes& sh, double common, Eigen::VectorXd* sigma) {
    double explained = 0.0, log_det_shared = 0.0;
    Eigen::Matrix2d m_inv = Eigen::Matrix2d::Zero();
    if (common > 0.0) {
      const double c2 = common * common;
      const Eigen::Matrix2d m = Eigen::Matrix2d::Identity() / c2 + sc.uu;
      m_inv = m.inverse();
      explained = sc.ur.dot(m_inv * sc.ur);
      log_det_shared = std::log((Eigen::Matrix2d::Identity() + c2 * sc.uu).determinant());
    }
    const double log_likelihood =
        -0.5 * (sc.cost_w - explained) + sc.log_norm - 0.5 * log_det_shared + sh.log_likelihood;
    if (k == 0) return log_likelihood;
    const Eigen::MatrixXd h = sc.jwj + sh.jwj - sc.jwu * m_inv * sc.jwu.transpose();
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(h);
    double log_det = 0.0;
    bool pd = ldlt.info() == Eigen::Success && ldlt.isPositive();
    if (pd)
      for (int i = 0; i < k; ++i) {
        const double d = ldlt.vectorD()(i);
        if (!(d > 0.0)) pd = false;
        else log_det += std::log(d);
      }
    if (!pd) log_det = (h.diagonal().array().max(1e-300)).log().sum();
    if (sigma && ok && pd) *sigma = ldlt.solve(Eigen::MatrixXd::Identity(k, k)).diagonal().cwiseSqrt();
    return log_likelihood + f.log_prior + 0.5 * k * std::log(2.0 * M_PI) - 0.5 * log_det + structure;
  };

  const double exact_form_log_evidence = evidence_at(scaled_at(0.0), shapes_at({}), 0.0, &f.sigma_theta);
  if (!options.model_error) {
    f.log_evidence = exact_form_log_evidence;
  } else {
    // Marginalised over the model-error scales (log-uniform priors, docs/diagnose.md "Model
    // error"); the parameters' σ and the reported scales are those of the most probable pair.
    const std::vector<double> ef = LogGrid(options.model_error_frequency_min, options.model_error_frequency_max,
                                           kFrequencyErrorPoints);
    const std::vector<double> es = LogGrid(options.model_error_shape_min, options.model_error_shape_max, kShapeErrorPoints);
    const std::vector<double> ec = LogGrid(options.model_error_frequency_min, options.model_error_frequency_max,
                                           kCommonErrorPoints);
    const Shapes shapes = shapes_at(es);
    double best = -kInf, sum = 0.0;
    std::vector<double> values;
    values.reserve(ef.size() * ec.size());
    size_t best_at = 0;
    for (double x : ef) {
      const Scaled sc = scaled_at(x);
      for (double z : ec) {
        values.push_back(evidence_at(sc, shapes, z, nullptr));
        if (values.back() > best) best = values.back(), best_at = values.size() - 1;
      }
    }
    for (double v : values) sum += std::exp(v - best);
    f.log_evidence = best + std::log(sum) - std::log(static_cast<double>(values.size()));
    f.model_error.frequency_rel = ef[best_at / ec.size()];
    f.model_error.frequency_common_rel = ec[best_at % ec.size()];
    f.shape_error_per_mode = shapes.most_probable;
    // The shapes' scale reported: the rms over the test modes of each one's most probable.
    f.model_error.shape = modes > 0 ? std::sqrt(shapes.most_probable.squaredNorm() / modes) : 0.0;
    evidence_at(scaled_at(f.model_error.frequency_rel), shapes, f.model_error.frequency_common_rel, &f.sigma_theta);
    // Dominates: in the mean over the test modes, the model's error exceeds the measurement σ.
    double frequency_share = 0.0, shape_share = 0.0;
    const double ef2 = std::pow(f.model_error.frequency_rel, 2) + std::pow(f.model_error.frequency_common_rel, 2);
    for (int m = 0; m < modes; ++m) {
      const int b = blocks[m], shape_rows = blocks[m + 1] - blocks[m] - 1;
      frequency_share += ef2 * gain(b) * gain(b);
      // A shape's share: its model-error variance over its rows' measurement variance, averaged.
      if (shape_rows > 0)
        shape_share += (shapes.most_probable(m) * gain.segment(b + 1, shape_rows)).squaredNorm() / shape_rows;
    }
    f.model_error.dominates = frequency_share / std::max(1, modes) > 1.0 || shape_share / std::max(1, modes) > 1.0;
  }
  f.search_score = -2.0 * exact_form_log_evidence;
  switch (options.criterion) {
    case Criterion::kEvidence:
      f.score = -2.0 * f.log_evidence;
      break;
    case Criterion::kBic:
      f.score = f.eval->cost + k * std::log(static_cast<double>(n));
      break;
    case Criterion::kAicc:
      f.score = f.eval->cost + 2.0 * k + (n - k - 1 > 0 ? 2.0 * k * (k + 1) / (n - k - 1) : 1e9);
      break;
  }
  if (options.criterion != Criterion::kEvidence) f.search_score = f.score;
  return f;
}

namespace {

// The MAP θ from `start` (Ceres), residuals scaled by `scale` (null: measurement σ alone).
std::vector<double> SolveMap(Problem* problem, const std::vector<int>& set, const std::vector<double>& start,
                             const DiagnoseOptions& options, const std::shared_ptr<const Eigen::VectorXd>& scale) {
  const int k = static_cast<int>(set.size());
  std::vector<double> x(k);
  for (int i = 0; i < k; ++i) x[i] = start[i] + kOffset;
  ceres::Problem cp;
  ceres::NumericDiffOptions nd;
  nd.relative_step_size = kRelativeStep;
  const std::vector<int>& blocks = problem->Eval().BlockStart();
  for (int m = 0; m + 1 < static_cast<int>(blocks.size()); ++m) {
    auto* cost = new ceres::DynamicNumericDiffCostFunction<ModeBlock, ceres::CENTRAL>(
        new ModeBlock{problem, set, m, scale}, ceres::TAKE_OWNERSHIP, nd);
    cost->AddParameterBlock(k);
    cost->SetNumResiduals(blocks[m + 1] - blocks[m]);
    cp.AddResidualBlock(cost, new ceres::HuberLoss(options.robust_threshold), x.data());
  }
  for (int i = 0; i < k; ++i) {
    auto* cost = new ceres::DynamicNumericDiffCostFunction<PriorBlock, ceres::CENTRAL>(
        new PriorBlock{&problem->Atoms()[set[i]], i}, ceres::TAKE_OWNERSHIP, nd);
    cost->AddParameterBlock(k);
    cost->SetNumResiduals(1);
    cp.AddResidualBlock(cost, nullptr, x.data());
  }
  for (int i = 0; i < k; ++i) {
    const ParamSpec& s = problem->Atoms()[set[i]].spec;
    cp.SetParameterLowerBound(x.data(), i, s.lo + kOffset);
    cp.SetParameterUpperBound(x.data(), i, s.hi + kOffset);
  }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = options.max_iterations;
  so.function_tolerance = 1e-10;
  so.parameter_tolerance = 1e-8;
  so.gradient_tolerance = 1e-14;
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  so.num_threads = 1;
  QuietSolverLogging();
  ceres::Solver::Summary summary;
  ceres::Solve(so, &cp, &summary);
  std::vector<double> theta(k);
  for (int i = 0; i < k; ++i) theta[i] = x[i] - kOffset;
  return theta;
}

}  // namespace

Fit FitSet(Problem* problem, const std::vector<int>& set, const std::vector<double>& start,
           const DiagnoseOptions& options) {
  const std::vector<double> theta = SolveMap(problem, set, start, options, nullptr);
  const double at_end = problem->Objective(set, theta);
  const double at_start = problem->Objective(set, start);
  return Assess(problem, set, at_start < at_end ? start : theta, options);
}

Fit RefitUnderModelError(Problem* problem, const Fit& fit, const DiagnoseOptions& options) {
  // Where the model's own error dominates the test's σ, the measurement σ alone over-weighs the
  // most precise modes: the parameters are fitted again with each residual in units of both
  // (the scales inferred at the first optimum), and the better evidence kept.
  if (!options.model_error || !fit.ok || !fit.model_error.dominates || fit.atoms.empty()) return fit;
  const auto scale = std::make_shared<const Eigen::VectorXd>(
      ModelErrorScale(problem->Eval(), fit.model_error.frequency_rel, fit.shape_error_per_mode));
  Fit again = Assess(problem, fit.atoms, SolveMap(problem, fit.atoms, fit.theta, options, scale), options, fit.exact);
  return again.ok && again.log_evidence > fit.log_evidence ? again : fit;
}

}  // namespace ema::diagnose::detail
