// Internals of the diagnosis shared by its stages (not installed).
#pragma once

#include <Eigen/Core>
#include <deque>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "ema/correlation/dof_match.hpp"
#include "ema/diagnose/diagnose.hpp"
#include "ema/model/effects.hpp"

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
  std::string group;     ///< the spring group of a springs target ("" otherwise)

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
  Eigen::VectorXd sigma_shape;  ///< 1σ of each test mode's (1 − MAC)
  Eigen::VectorXd half_power_hz;  ///< 2ζf of each test mode: model modes closer than this blend
  size_t model_dof_count = 0;
};

struct Evaluation {
  bool ok = false;
  std::string error;
  Eigen::VectorXd r;  ///< 2 per test mode (frequency, shape) in σ, setups in order
  std::vector<ModeComparison> modes;
  double cost = 0.0;  ///< robust (Huber) sum over modes
  double mean_abs_frequency_error_pct = kNaN;
  double mean_mac = kNaN;
  double mean_agreement_pct = kNaN;
  int paired = 0;
};

class Evaluator {
 public:
  Evaluator(const model::Model& base, std::vector<SetupData> setups, const DiagnoseOptions& options, int max_modes);
  int ResidualCount() const { return residual_count_; }
  int Solves() const { return solves_; }
  Evaluation Evaluate(const std::vector<model::Effect>& effects);
  const DiagnoseOptions& Options() const { return options_; }

 private:
  const model::Model& base_;
  std::vector<SetupData> setups_;
  const DiagnoseOptions& options_;
  int max_modes_ = 0;
  int residual_count_ = 0;
  int solves_ = 0;
};

/// Modal phase collinearity of a complex shape (1 = a real mode up to one phase, 0 = circular).
double PhaseCollinearity(const Eigen::VectorXcd& shape);

/// The MAC a test shape is judged by against model mode `j`: its MAC with `j`, raised toward its
/// MAC with the subspace of `j` and the model modes too close to `j` for a hammer test to
/// separate (weight exp(−(Δf / half-power bandwidth)²) of the closest one).
double BlendMac(const Eigen::VectorXcd& test_shape, const Eigen::MatrixXcd& model_shapes, const Eigen::VectorXd& model_hz,
                int j, double plain_mac, double half_power_hz);

/// Huber cost of one mode's residual pair (s = squared norm): s for s ≤ a², 2a√s − a² beyond.
double Huber(double s, double a);
double RobustCost(const Eigen::VectorXd& r, double a);

// ---- fits (fit.cpp) ----

/// One set of atoms with its parameters at the MAP and the Laplace evidence there.
struct Fit {
  std::vector<int> atoms;  ///< indices into the atom list, sorted
  std::vector<double> theta;
  std::shared_ptr<const Evaluation> eval;
  double objective = kInf;  ///< ½ cost − log prior (what the MAP fit minimises)
  double log_prior = 0.0;
  double log_evidence = -kInf;
  double score = kInf;      ///< −2 log evidence, or BIC / AICc
  Eigen::VectorXd sigma_theta;
  bool ok = false;
  std::string error;
};

/// Evaluations of sets of atoms, cached by (set, θ): Ceres evaluates every mode's residual block
/// at the same points, and each point costs one model solve per setup.
class Problem {
 public:
  Problem(Evaluator* evaluator, const std::vector<Atom>* atoms) : evaluator_(evaluator), atoms_(atoms) {}
  std::shared_ptr<const Evaluation> At(const std::vector<int>& set, const std::vector<double>& theta);
  std::vector<model::Effect> Effects(const std::vector<int>& set, const std::vector<double>& theta) const;
  double LogPrior(const std::vector<int>& set, const std::vector<double>& theta) const;
  /// ½ cost − log prior; +∞ when the model could not be solved.
  double Objective(const std::vector<int>& set, const std::vector<double>& theta);
  const std::vector<Atom>& Atoms() const { return *atoms_; }
  Evaluator& Eval() { return *evaluator_; }
  int ResidualCount() const { return evaluator_->ResidualCount(); }

 private:
  Evaluator* evaluator_;
  const std::vector<Atom>* atoms_;
  std::deque<std::pair<std::pair<std::vector<int>, std::vector<double>>, std::shared_ptr<const Evaluation>>> cache_;
};

/// MAP refinement from `start` (Ceres: bounded, Huber loss, prior residuals, central numeric
/// differences), then the Laplace evidence at the optimum.
Fit FitSet(Problem* problem, const std::vector<int>& set, const std::vector<double>& start, const DiagnoseOptions& options);

/// The evidence and posterior σ of a set at given θ (no refinement).
Fit Assess(Problem* problem, const std::vector<int>& set, const std::vector<double>& theta, const DiagnoseOptions& options);

// ---- search (search.cpp) ----

struct SearchResult {
  std::vector<Fit> fits;  ///< every fitted set (singles and combinations), deduplicated
  int screened = 0;
};

/// Screening, fits of the promising singles and forward/backward combinations.
SearchResult Search(Problem* problem, const DiagnoseOptions& options);

/// Fits a given set from the θ of its fitted subsets (used for the "error falls" steps).
Fit FitSubset(Problem* problem, const std::vector<Fit>& known, const std::vector<int>& set, const DiagnoseOptions& options);

// ---- ranking and explanation (explain.cpp) ----

Candidate MakeCandidate(Problem* problem, const Fit& fit, double baseline_cost);
void Rank(std::vector<Candidate>* all, const Candidate& none);
std::string Explain(const std::vector<Candidate>& ranked, const Candidate& none);
std::string FormatNumber(double v, int significant = 3);
std::string Join(const std::vector<std::string>& parts, const std::string& sep);

}  // namespace ema::diagnose::detail
