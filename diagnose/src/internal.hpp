// Internals of the diagnosis shared by its stages (not installed).
#pragma once

#include <Eigen/Core>
#include <deque>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "ema/correlation/dof_match.hpp"
#include "ema/diagnose/diagnose.hpp"
#include "ema/model/effects.hpp"
#include "ema/model/reduced.hpp"
#include "ema/model/solve.hpp"

namespace ema::diagnose::detail {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

// ---- candidates (candidates.cpp) ----

/// How one effect's free parameter maps to θ: value = ref·e^θ (log) or ref + scale·θ.
struct ParamSpec {
  std::string name;
  double ref = 1.0;
  double scale = 1.0;
  bool log = true;
  double lo = -1.0, hi = 1.0;  ///< θ bounds
  int absent_end = 0;          ///< -1: the lower bound means "no effect", +1: the upper, 0: none

  double Value(double theta) const;
  double Derivative(double theta) const;
  double Theta(double value) const;
};

/// The prior of one parameter, in θ.
struct Prior {
  model::PriorShape shape = model::PriorShape::kLogNormal;
  double centre = 0.0;  ///< θ of the prior's centre (log-normal) or unused (half-normal)
  double sigma = 1.0;   ///< 1σ in θ (log-normal) or in value (half-normal)
  double relative_sigma = 1.0;  ///< as documented (relative), for reports
  /// Log-normal only: a share `tail_share` of the prior is a broad "fault" component
  /// N(centre, tail_sigma²) — the item is as stated within its uncertainty, or grossly off (a
  /// loose bolt, a cracked weld): a reading far outside is then weighed by the data, not by how far
  /// into a Gaussian tail it lies (docs/diagnose.md "Priors"). 0: the plain log-normal.
  double tail_share = 0.0;
  double tail_sigma = 3.0;

  /// log prior density of θ (including the Jacobian of the log parameterisation).
  double LogDensity(double theta, const ParamSpec& spec) const;
  /// −d² log density / dθ² (≥ 0 where the prior is log-concave).
  double Curvature(double theta, const ParamSpec& spec) const;
  /// The residual whose square the MAP fit adds to the cost.
  double Residual(double theta, const ParamSpec& spec) const;
};

/// One candidate effect with one free parameter: kind, target, mapping, prior.
struct Atom {
  model::Effect effect;  ///< kind, target, fixed parameters
  const model::EffectKindInfo* info = nullptr;
  ParamSpec spec;
  Prior prior;
  bool hertz = false;    ///< series_compliance as a Hertz contact (modulus free, radius fixed)
  bool member = false;   ///< on one member of a group or one point
  bool part = false;     ///< on FE parts (a part group, one member, a part in no group)
  std::string group;     ///< the spring group or part group of the target ("" otherwise)
  std::string words;     ///< the target in words: "member 'J3' of part group 'joints'", "body 'top'", "point 101"

  model::Effect With(double theta) const;
  std::string Label() const;  ///< "stiffness_scale of 'joints/J3'"
};

/// -1 / +1 when θ sits on the lower / upper bound, 0 inside.
inline int BoundEnd(const ParamSpec& s, double theta) {
  const double margin = 1e-3 * (s.hi - s.lo);
  return theta <= s.lo + margin ? -1 : (theta >= s.hi - margin ? +1 : 0);
}

/// Every candidate atom of the model (the "candidates" stage).
std::vector<Atom> BuildAtoms(const model::Model& base, const DiagnoseOptions& options);

// ---- residuals (evaluate.cpp) ----

struct SetupData {
  std::string name;
  correlation::DofMatch match;
  Eigen::MatrixXcd test_shapes;
  Eigen::VectorXd test_hz;
  Eigen::VectorXd sigma_hz;  ///< 1σ of each test frequency
  Eigen::VectorXd sigma_shape;  ///< 1σ of each test mode's (1 − MAC) (ShapeResidual::kOneMinusMac)
  /// ShapeResidual::kPerDof: each test shape made real (rotated by its principal phase) and divided
  /// by its norm, one column per mode over the matched DOFs, and its 1σ per DOF in those units.
  Eigen::MatrixXd real_shapes;
  Eigen::MatrixXd sigma_dof;
  Eigen::VectorXd half_power_hz;  ///< 2ζf of each test mode: model modes closer than this blend
  size_t model_dof_count = 0;
  /// The test's sensors per roving set (empty: none declared): each set is solved with its own.
  std::vector<std::vector<model::PointMass>> sensors;
  std::vector<double> set_weight;  ///< per set: its measured DOFs (the frequency average's weight)
  std::vector<int> set_of_dof;     ///< per model observed DOF: the set that measured its node (-1: none)
  int reference_row = -1;          ///< model observed DOF of the hammer DOF (-1: unknown)
  /// The test's frequencies are the equal-weight means over its roving sets (`ema fit` fitted each
  /// set with its own poles): the model's are averaged alike. Otherwise each set weighs by the
  /// energy of the mode at its measured DOFs (how a fit of all sets at once weighs them).
  bool equal_set_weights = false;
};

/// The model's modes as the test saw them: each roving set's solution with its sensors, frequencies
/// averaged over the sets, each DOF's shape from the set that measured it (SetupModes).
model::Solution AsTested(const SetupData& setup, const std::vector<model::Solution>& per_set);

struct Evaluation {
  bool ok = false;
  std::string error;
  /// Per test mode a block (Evaluator::BlockStart): its frequency error, then its shape residual
  /// (one row, or one per measured DOF), in σ; setups in order.
  Eigen::VectorXd r;
  std::vector<ModeComparison> modes;
  double cost = 0.0;  ///< robust (Huber) sum over modes
  double mean_abs_frequency_error_pct = kNaN;
  double mean_mac = kNaN;
  double mean_agreement_pct = kNaN;
  int paired = 0;
};

/// The base's own solution for one setup (no effects, no sensors), solved once for the whole
/// diagnosis: the setups' DOF matching, the baseline's evaluation and — on an FE-sized model — the
/// search's reduced models at the nominal centre all take it. There `factory` holds it (the
/// reduced-model factory centred on the base: its full solve and factorisation) and `solution`
/// only its modes; else `solution` is the whole solve.
struct NominalSolve {
  model::Solution solution;
  std::unique_ptr<model::ReducedModelFactory> factory;
};

/// Whether the diagnosis of `base` searches through reduced models (it is FE-sized:
/// DiagnoseOptions::reduced_model_min_dofs).
bool SearchesReduced(const model::Model& base, const DiagnoseOptions& options);

/// `base` solved for `setup` as the Evaluator solves it, with `max_modes` modes; through a
/// reduced-model factory when `SearchesReduced` (its basis enriched for `test_modes` test modes).
NominalSolve SolveNominal(const model::Model& base, const std::string& setup, const DiagnoseOptions& options,
                          int max_modes, int test_modes);

class Evaluator {
 public:
  /// `nominal`: per setup, the base solved by SolveNominal (or empty: solved when first needed).
  Evaluator(const model::Model& base, std::vector<SetupData> setups, const DiagnoseOptions& options, int max_modes,
            std::vector<NominalSolve> nominal = {});
  ~Evaluator();
  int ResidualCount() const { return residual_count_; }
  /// Where each test mode's block of residuals starts (one more entry: the end): its frequency
  /// row first, then its shape rows.
  const std::vector<int>& BlockStart() const { return block_start_; }
  int TestModeCount() const { return static_cast<int>(block_start_.size()) - 1; }
  /// Per residual, the model-error scale in units of its measurement σ: f_test / σ_f for a
  /// frequency, 1 / σ_shape for a (1 − MAC) row, 1 / (√d · σ_dof) for a shape DOF of d. A model
  /// error ε adds (ε · gain)² to its variance in σ².
  const Eigen::VectorXd& ModelErrorGain() const { return model_error_gain_; }
  /// Per residual row: ln f of its test mode standardised over every test mode (0 on shape rows
  /// and when all modes share one frequency) — the pattern of a model error that grows or shrinks
  /// with frequency (shear and rotary inertia a beam model lacks, a mesh too coarse).
  const Eigen::VectorXd& ModelErrorTrend() const { return model_error_trend_; }
  /// Per residual row: the test DOF a per-DOF shape row measures (node · 16 + direction + 8), −1 on
  /// frequency and (1 − MAC) rows — which rows of two tests of one setup see the same point.
  const std::vector<long long>& RowDof() const { return row_dof_; }
  int Solves() const { return solves_; }
  int ReducedSolves() const { return reduced_solves_; }
  /// Exact: the model with `effects` solved in full for every setup.
  Evaluation Evaluate(const std::vector<model::Effect>& effects);
  /// True when the model is FE-sized (DiagnoseOptions::reduced_model_min_dofs): EvaluateReduced
  /// then solves through reduced models.
  bool UsesReducedModels() const { return reduced_; }
  /// The model with `effects` solved through the reduced model whose basis holds the base's modes
  /// (or, with `centre`, the modes of the base with those effects) and the responses to `probes`;
  /// `key` names the set of probes (one reduced model per key, centre and setup).
  Evaluation EvaluateReduced(const std::string& key, const std::vector<std::vector<model::Effect>>& probes,
                             const std::vector<model::Effect>& centre, const std::vector<model::Effect>& effects);
  const DiagnoseOptions& Options() const { return options_; }

 private:
  // Residuals of every setup's test modes against the model modes `solve` gives for that setup
  // with the given extra (sensor) masses.
  Evaluation Compare(const std::function<model::Solution(std::size_t setup, const std::vector<model::PointMass>&)>& solve);

  struct Reduced;
  const model::Model& base_;
  std::vector<SetupData> setups_;
  const DiagnoseOptions& options_;
  int max_modes_ = 0;
  int residual_count_ = 0;
  std::vector<int> block_start_;
  Eigen::VectorXd model_error_gain_;
  Eigen::VectorXd model_error_trend_;
  std::vector<long long> row_dof_;
  int solves_ = 0;
  int reduced_solves_ = 0;
  bool reduced_ = false;
  std::unique_ptr<Reduced> reduced_models_;
  /// Per setup, the base's solution (without reduced models; with them the nominal factory holds it).
  std::vector<model::Solution> nominal_;
};

/// Modal phase collinearity of a complex shape (1 = a real mode up to one phase, 0 = circular).
double PhaseCollinearity(const Eigen::VectorXcd& shape);

/// A complex shape as a real one: rotated by the phase that makes it most nearly real
/// (½ arg Σ φ²), its real part returned and the out-of-phase part in `out_of_phase` (both in the
/// shape's own units; a real mode has none).
Eigen::VectorXd RealShape(const Eigen::VectorXcd& shape, Eigen::VectorXd* out_of_phase = nullptr);

/// The first-order shape residual of a real, unit-norm test shape against model mode `j`: the
/// test shape minus its least-squares fit by model mode `j`, blended toward its fit by the span of
/// `j` and the model modes too close to tell apart with the same weight BlendMac uses. Its squared
/// norm is 1 − MAC (blended) of the real shapes.
Eigen::VectorXd ShapeDifference(const Eigen::VectorXd& test_real, const Eigen::MatrixXcd& model_shapes,
                                const Eigen::VectorXd& model_hz, int j, double half_power_hz);

/// The MAC a test shape is judged by against model mode `j`: its MAC with `j`, raised toward its
/// MAC with the subspace of `j` and the model modes too close to `j` for a hammer test to
/// separate (weight exp(−(Δf / half-power bandwidth)²) of the closest one).
double BlendMac(const Eigen::VectorXcd& test_shape, const Eigen::MatrixXcd& model_shapes, const Eigen::VectorXd& model_hz,
                int j, double plain_mac, double half_power_hz);

/// Huber cost of one mode's residual pair (s = squared norm): s for s ≤ a², 2a√s − a² beyond.
double Huber(double s, double a);
/// Σ over the mode blocks of Huber(|r_block|², a).
double RobustCost(const Eigen::VectorXd& r, const std::vector<int>& block_start, double a);

// ---- fits (fit.cpp) ----

/// One set of atoms with its parameters at the MAP and the Laplace evidence there.
struct Fit {
  std::vector<int> atoms;  ///< indices into the atom list, sorted
  std::vector<double> theta;
  std::shared_ptr<const Evaluation> eval;
  double objective = kInf;  ///< ½ cost − log prior (what the MAP fit minimises)
  double log_prior = 0.0;
  double log_evidence = -kInf;
  double score = kInf;      ///< −2 log evidence (model error marginalised), or BIC / AICc: the ranking
  /// −2 log evidence with the model's form taken as exact (measurement σ alone): what the search
  /// steers by. Marginalised over the model error, poor fits lie too close together for a
  /// greedy search to tell which way is better; the ranking then weighs what it found honestly.
  double search_score = kInf;
  Eigen::VectorXd sigma_theta;
  ModelError model_error;   ///< the most probable model-error scales (DiagnoseOptions::model_error)
  /// Per test mode, the most probable model error of its shape (each mode has its own: a pair of
  /// close modes mixed by the model's error is off where the rest are not). Empty: none inferred.
  Eigen::VectorXd shape_error_per_mode;
  bool ok = false;
  bool exact = true;        ///< eval from full solves (false: through a reduced model)
  std::string error;
};

/// Evaluations of sets of atoms, cached by (set, θ): Ceres evaluates every mode's residual block
/// at the same points, and each point costs one model solve per setup.
class Problem {
 public:
  Problem(Evaluator* evaluator, std::vector<Atom>* atoms) : evaluator_(evaluator), atoms_(atoms) {}
  /// The evaluation of a set at θ: through the set's reduced model on FE-sized models (centred
  /// where Recentre put it), else exact.
  std::shared_ptr<const Evaluation> At(const std::vector<int>& set, const std::vector<double>& theta);
  /// The evaluation of a set at θ through a reduced model on the centre of another set,
  /// `centre_set` (where Recentre put that one; its factorisation and modes reused, the set's
  /// own probes added: no full solve while that centre is kept). Exact when `centre_set` has no
  /// centre or the model is not FE-sized. Not cached: At(set, θ) stays on the set's own centre.
  std::shared_ptr<const Evaluation> AtCentreOf(const std::vector<int>& centre_set, const std::vector<int>& set,
                                               const std::vector<double>& theta);
  /// Always exact (full solves): what is reported.
  std::shared_ptr<const Evaluation> Exact(const std::vector<int>& set, const std::vector<double>& theta);
  /// From now on, the set's reduced model is centred on θ (its basis from a full solve there).
  void Recentre(const std::vector<int>& set, const std::vector<double>& theta);
  /// From now on, the set's reduced model is centred where `centre_set`'s is (that centre's full
  /// solve and factorisation reused, the set's own probes added: no full solve while it is kept);
  /// on the nominal centre when `centre_set` has none.
  void RecentreOn(const std::vector<int>& set, const std::vector<int>& centre_set);
  bool Reduced() const { return evaluator_->UsesReducedModels(); }
  /// Widens one side of an atom's searched range (end −1: the lower, +1: the upper) 1000-fold
  /// (log parameters; a linear one by its range's width).
  void Widen(int atom, int end);
  std::vector<model::Effect> Effects(const std::vector<int>& set, const std::vector<double>& theta) const;
  double LogPrior(const std::vector<int>& set, const std::vector<double>& theta) const;
  /// ½ cost − log prior; +∞ when the model could not be solved.
  double Objective(const std::vector<int>& set, const std::vector<double>& theta);
  const std::vector<Atom>& Atoms() const { return *atoms_; }
  Evaluator& Eval() { return *evaluator_; }
  int ResidualCount() const { return evaluator_->ResidualCount(); }

 private:
  using Key = std::pair<std::vector<int>, std::vector<double>>;
  /// The set at θ through a reduced model centred at `centre_set` at *centre_theta (null: the
  /// nominal centre).
  Evaluation OnCentre(const std::vector<int>& set, const std::vector<double>& theta, const std::vector<int>& centre_set,
                      const std::vector<double>* centre_theta);
  std::shared_ptr<const Evaluation> Cached(std::deque<std::pair<Key, std::shared_ptr<const Evaluation>>>* cache,
                                           const Key& key, const std::function<Evaluation()>& evaluate);
  Evaluator* evaluator_;
  std::vector<Atom>* atoms_;
  std::deque<std::pair<Key, std::shared_ptr<const Evaluation>>> cache_, exact_cache_;
  /// Where a set's reduced model is centred: a set (its own, or another's by RecentreOn) at θ.
  struct Centre {
    std::vector<int> set;
    std::vector<double> theta;
  };
  std::map<std::vector<int>, Centre> centres_;
};

/// MAP refinement from `start` (Ceres: bounded, Huber loss, prior residuals, central numeric
/// differences), then the Laplace evidence at the optimum.
Fit FitSet(Problem* problem, const std::vector<int>& set, const std::vector<double>& start, const DiagnoseOptions& options);

/// The fit again with each residual in units of measurement σ and the model error it inferred,
/// when that error dominates (DiagnoseOptions::model_error); the better evidence is returned.
Fit RefitUnderModelError(Problem* problem, const Fit& fit, const DiagnoseOptions& options);

/// The evidence and posterior σ of a set at given θ (no refinement); `exact`: its misfit from full
/// solves (the Jacobian still through the set's reduced model, when it has one).
Fit Assess(Problem* problem, const std::vector<int>& set, const std::vector<double>& theta, const DiagnoseOptions& options,
           bool exact = false);

// ---- search (search.cpp) ----

struct SearchResult {
  std::vector<Fit> fits;  ///< every fitted set (singles and combinations), deduplicated
  int screened = 0;
};

/// Screening, fits of the promising singles and forward/backward combinations.
SearchResult Search(Problem* problem, const DiagnoseOptions& options);

/// A set in canonical (sorted) order with its θ.
std::pair<std::vector<int>, std::vector<double>> Sorted(const std::vector<int>& set, const std::vector<double>& theta);

/// A fitted set without its k-th effect, the others' fitted parameters as the start.
std::pair<std::vector<int>, std::vector<double>> WithoutOne(const Fit& f, size_t k);

/// Best point of `candidate` added to `base_set` (θ of the base held): a coarse grid over its
/// range, then golden-section steps between the best point's neighbours. Returns (objective, θ).
std::pair<double, double> Screen(Problem* p, const std::vector<int>& base_set, const std::vector<double>& base_theta,
                                 int candidate, int points);

/// Effects the data may confuse with each other: any kind on the same spring or part group (or
/// its members), the same kind on any FE part, any mass effect for a mass effect, else the same
/// kind (search.cpp "Swap").
bool LookAlike(const Atom& a, const Atom& b);

/// Fits a given set from the θ of its fitted subsets (used for the "error falls" steps).
Fit FitSubset(Problem* problem, const std::vector<Fit>& known, const std::vector<int>& set, const DiagnoseOptions& options);

// ---- ranking and explanation (explain.cpp) ----

Candidate MakeCandidate(Problem* problem, const Fit& fit, double baseline_cost);
void Rank(std::vector<Candidate>* all, const Candidate& none);
std::string Explain(const std::vector<Candidate>& ranked, const Candidate& none);
std::string FormatNumber(double v, int significant = 3);
std::string Join(const std::vector<std::string>& parts, const std::string& sep);

}  // namespace ema::diagnose::detail
