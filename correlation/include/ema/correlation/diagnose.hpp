// Which physical effect is the model missing? (issue 7, algorithms.md §6.5–§6.7)
//
// Every effect of the vocabulary (ema::model::CandidateEffects) is added to the model in turn,
// its parameter fitted (Ceres, log-parameterised, bounded, Huber loss, numeric derivatives) to
// the paired test modes of all setups at once, and the candidates are ranked by an information
// criterion that charges each free parameter, next to a "none" outcome (the baseline model).
// The best pairs of effects are tried after the singles.
#pragma once

#include <string>
#include <vector>

#include "ema/core/progress.hpp"
#include "ema/core/types.hpp"
#include "ema/correlation/dof_match.hpp"
#include "ema/correlation/pairing.hpp"
#include "ema/model/model.hpp"

namespace ema::correlation {

/// The test modes of one setup ("" = the model's nominal operating points).
struct SetupModes {
  std::string setup;
  ModeSet modes;
};

enum class InformationCriterion { kAicc, kBic };

struct DiagnoseOptions {
  /// Residual weights (§6.1): relative frequency error and (1 − MAC). Frequencies are measured
  /// far better than shapes, hence the smaller shape weight.
  double frequency_weight = 1.0;
  double shape_weight = 0.1;
  /// Residuals of a test mode the model cannot pair: constant (relative frequency, 1 − MAC).
  double unpaired_frequency_residual = 0.5;
  /// Huber loss threshold on a residual: quadratic below, linear above, so one badly fitted
  /// test mode does not steer the fit.
  double robust_threshold = 0.1;
  /// Accuracy floor of a residual (0.1 % in frequency): the criterion uses J + N·floor², so a
  /// parameter is not rewarded for fitting below what hammer tests can measure.
  double residual_floor = 1e-3;
  /// BIC charges ln(N) per parameter, AICc about 2: BIC keeps "none" first on pure noise.
  InformationCriterion criterion = InformationCriterion::kBic;
  /// Pairing while parameters move: MAC ≥ mac_min; a light frequency weight keeps modes that the
  /// few test DOFs cannot tell apart on their nearest partner.
  PairingOptions pairing{0.5, 0.05, 1.0};
  DofMatchOptions dofs;
  /// Grid points of the initial scan over a single parameter's (log) range before Ceres refines.
  int scan_points = 13;
  int max_iterations = 30;
  /// Pairs: each of the best `pair_pool` single candidates with every other one (0 = no pairs).
  int pair_pool = 3;
  ProgressCallback progress;
};

/// One fitted parameter with its 1-σ uncertainty from the Jacobian at the optimum.
struct FittedParameter {
  std::string effect_kind;
  std::string name;      ///< "k" (series_compliance: the law's k), "factor", "value", "mass"
  double value = kNaN;
  double sigma = kNaN;   ///< NaN when the Jacobian is singular (parameter not identifiable)
  double lower = kNaN, upper = kNaN;
  bool at_bound = false;
};

/// One mode of one setup before/after.
struct ModeComparison {
  std::string setup;
  int test_mode = -1;   ///< index into that setup's test modes
  int model_mode = -1;  ///< -1: unpaired
  double test_frequency_hz = kNaN;
  double model_frequency_hz = kNaN;
  double agreement_pct = kNaN;
  double mac = kNaN;
};

/// One outcome: the baseline ("none"), one effect, or a pair of effects.
struct Candidate {
  std::vector<model::Effect> effects;       ///< with fitted parameters; empty for "none"
  std::vector<FittedParameter> parameters;
  std::string kind;                         ///< "none", an effect kind, or "kind1+kind2"
  std::string target;                       ///< "" for none, "t1+t2" for pairs
  double cost = kNaN;                       ///< robust weighted sum of squared residuals
  double score = kNaN;                      ///< information criterion (lower is better)
  double explained_pct = kNaN;              ///< 100 (1 − J/J_baseline)
  double mean_abs_frequency_error_pct = kNaN;  ///< over paired modes of all setups
  double mean_mac = kNaN;
  int paired_modes = 0;
  std::vector<ModeComparison> modes;
  bool plausible = true;                    ///< false when a parameter ends at its bound
  std::vector<std::string> tied_with;       ///< candidates the data cannot tell apart (|cos| > 0.95)
  std::string error;                        ///< non-empty when the candidate could not be evaluated
  int rank = 0;                             ///< 1 = most likely
  Eigen::VectorXd residuals;                ///< unweighted by the loss, for the tie test
};

struct Diagnosis {
  Candidate baseline;                 ///< the model as given (also in `candidates` as "none")
  std::vector<Candidate> candidates;  ///< ranked, rank 1 first; includes "none"
  std::string explanation;            ///< in words, for the user
  int residual_count = 0;
  int test_mode_count = 0;
  int model_solves = 0;
};

/// Ranks the candidate missing effects of `model` against `tests` (one entry per setup).
/// Throws InputError when a setup is not defined by the model, when test nodes are not test
/// points of the model, or when too few modes pair to fit any parameter.
Diagnosis Diagnose(const model::Model& model, const std::vector<SetupModes>& tests, const DiagnoseOptions& options = {});

/// The words for one candidate's effect(s), e.g. "a compliance of 6.4 N/µm in series with group
/// 'bearings'".
std::string DescribeCandidate(const Candidate& candidate);

// ---- Amplitude dependence (§6.7, issue 7 item 4) ----

/// Modes fitted from the impacts of one force level.
struct ForceLevelModes {
  double force_n = kNaN;  ///< peak (or RMS) impact force of the level
  ModeSet modes;
};

struct NonlinearityOptions {
  /// Flag a mode when |f(max force) − f(min force)| / f > max(repeatability_factor × the
  /// repeatability, min_change). Repeatability: the modes' frequency_spread_hz when known.
  double repeatability_factor = 3.0;
  double min_change = 0.002;
  double mac_min = 0.6;
};

struct AmplitudeTrend {
  int reference_mode = -1;               ///< index in the lowest force level's modes
  std::vector<double> force_n;           ///< levels where the mode was found
  std::vector<double> frequency_hz;
  double change_pct = 0.0;               ///< (f(max F) − f(min F)) / f(min F) · 100
  double slope_pct_per_decade = 0.0;     ///< least-squares slope of f vs log10 F, % of f per decade
  double threshold_pct = 0.0;
  bool flagged = false;
  std::string trend;                     ///< "softening", "hardening" or "none"
};

struct NonlinearityReport {
  std::vector<AmplitudeTrend> modes;
  bool any_flagged = false;
  std::string summary;
};

/// Tracks each mode over the force levels (paired by MAC with the lowest level) and flags a
/// stiffness that depends on amplitude, with the trend. Throws InputError with < 2 levels.
NonlinearityReport DetectAmplitudeDependence(std::vector<ForceLevelModes> levels, const NonlinearityOptions& options = {});

}  // namespace ema::correlation
