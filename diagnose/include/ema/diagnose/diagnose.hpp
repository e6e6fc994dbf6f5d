// Which physical effects is the model missing, where, and how sure is that? (docs/diagnose.md)
//
// Stages: candidates (every kind of the vocabulary on every group, member, point and body it
// applies to) → screening (a coarse scan of each candidate's parameter) → fits (the promising
// singles, Ceres, maximum a-posteriori under each parameter's prior) → combinations (forward
// selection of up to three effects with joint re-fitting and a backward check) → ranking (by
// the Laplace approximation of each candidate's evidence, as posterior probabilities that sum
// to 1 with "none") → explanation (in words, with the error falling as each effect is added).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "ema/core/names.hpp"
#include "ema/core/progress.hpp"
#include "ema/core/types.hpp"
#include "ema/correlation/dof_match.hpp"
#include "ema/correlation/pairing.hpp"
#include "ema/model/model.hpp"

namespace ema::diagnose {

/// The test modes of one setup ("" = the model's nominal operating points).
struct SetupModes {
  SetupModes() = default;
  SetupModes(std::string setup_name, ModeSet test_modes) : setup(std::move(setup_name)), modes(std::move(test_modes)) {}
  std::string setup;
  ModeSet modes;
  /// The test's own transducers (cli.md, added turn 3): `sensor_mass` kg at each measured node (one
  /// triaxial accelerometer counts once) of a roving set, while that set was measured. The model's
  /// prediction of this test carries them: each set is solved with its sensors, the frequencies
  /// averaged over the sets (weighted by their measured DOFs) and each DOF's shape taken from the
  /// set that measured it, scaled through the hammer DOF as the test's own residues are.
  double sensor_mass = 0.0;
  /// Node ids of each roving set; empty: every measured node carried its sensor throughout.
  std::vector<std::vector<int>> roving_sets;
  /// The hammer DOF (the shapes' common reference); node 0: unknown (sets aligned by sign).
  Dof reference{0, 0};
};

/// How candidates are ranked. kEvidence (default): the Laplace approximation of the posterior
/// evidence (misfit + prior + the posterior's width). kBic / kAicc: information criteria that
/// ignore the priors (kept for comparison).
enum class Criterion { kEvidence, kBic, kAicc };
inline constexpr EnumName<Criterion> kCriterionNames[] = {
    {Criterion::kEvidence, "evidence"}, {Criterion::kBic, "bic"}, {Criterion::kAicc, "aicc"}};
/// "evidence", "bic", "aicc".
std::string CriterionToString(Criterion criterion);
/// The criterion of a name; false for an unknown name.
bool StringToCriterion(const std::string& name, Criterion* criterion);

/// How a paired test shape enters the likelihood (docs/diagnose.md "Shapes in the likelihood").
enum class ShapeResidual {
  /// One residual per mode, (1 − MAC) / shape_sigma: second order in the shape's difference, so a
  /// shape that differs by 1 % per DOF weighs 10⁻⁴ — shapes barely count.
  kOneMinusMac,
  /// One residual per measured DOF: the unit-normalised test shape minus the model shape scaled to
  /// it, in units of its σ at that DOF — first order, and the direction of the difference tells a
  /// point mass from its mirror point, or from scatter spread along the structure.
  kPerDof,
};
inline constexpr EnumName<ShapeResidual> kShapeResidualNames[] = {{ShapeResidual::kOneMinusMac, "mac"},
                                                                  {ShapeResidual::kPerDof, "per-dof"}};
/// "mac", "per-dof".
std::string ShapeResidualToString(ShapeResidual shape_residual);
/// The shape residual of a name; false for an unknown name.
bool StringToShapeResidual(const std::string& name, ShapeResidual* shape_residual);

struct DiagnoseOptions {
  /// Relative 1σ floor of a test frequency: a mode's σ is max(its measured σ, floor × f). The
  /// measured σ is the mode's frequency_spread_hz (stabilisation spread from `ema fit`) when the
  /// modes file carries it. 1e-3: what a hammer test repeats to (nothing is gained by fitting
  /// below it).
  double frequency_floor = 1e-3;
  /// 1σ of (1 − MAC): shapes are measured far less precisely than frequencies (the
  /// kOneMinusMac residual).
  double shape_sigma = 0.01;
  /// How a paired test shape enters the likelihood (docs/diagnose.md "Shapes in the likelihood").
  ShapeResidual shape_residual = ShapeResidual::kPerDof;
  /// kPerDof: the floor of a shape's 1σ at one DOF, relative to the shape's rms amplitude over
  /// its DOFs (the fit's own σ of |φ| per DOF when larger, and the part of the shape out of phase
  /// with the rest — a complex test mode — adds to it).
  double shape_dof_sigma = 0.1;
  /// Residual of a test mode the model cannot pair: relative frequency error 0.5 and MAC 0.
  double unpaired_frequency_residual = 0.5;
  /// Huber threshold on one mode's residual pair, in σ: quadratic below, linear above, so one
  /// badly fitted mode does not steer the fit.
  double robust_threshold = 100.0;
  Criterion criterion = Criterion::kEvidence;
  /// Pairing while parameters move: MAC ≥ mac_min; a light frequency weight keeps modes that the
  /// few test DOFs cannot tell apart on their nearest partner.
  correlation::PairingOptions pairing{0.5, 0.05, 1.0};
  correlation::DofMatchOptions dofs;
  /// The prior of a stiffness factor: ln(factor) ~ (1 − ε)·N(0, σ²) + ε·N(0, σ_f²), σ the stated
  /// uncertainty, ε = stiffness_fault_share, σ_f = stiffness_fault_sigma. A joint or part is as
  /// stated within its uncertainty, or (ε) grossly off — loose, cracked, rubber for steel — anywhere
  /// within about ×/÷ e^(2σ_f). Without the tail a reading 6× softer than stated pays e^(−z²/2) and
  /// loses to a look-alike reading that is only 5× softer, whatever the data say
  /// (docs/diagnose.md "Priors"). 0: the plain log-normal.
  double stiffness_fault_share = 0.02;
  double stiffness_fault_sigma = 3.0;
  /// The prior odds of one more missing effect against one fewer, beyond the ln N every effect
  /// pays for being one of N candidates: each effect costs ln(1 / effect_prior_odds) more. A
  /// structure is rarely wrong in many places at once, and where the model's form is not exact a
  /// small extra effect (a few grams at one point) otherwise wins whenever it absorbs part of the
  /// model's own error (docs/diagnose.md "Model error"). 1: only the ln N.
  double effect_prior_odds = 0.25;
  /// Model error in the likelihood (docs/diagnose.md "Model error"): each test quantity's
  /// prediction error is its measurement σ combined with the model's own error — a share
  /// ε_f of the frequency, and ε_s of (1 − MAC) — whose size the data tell: the evidence of
  /// every candidate is marginalised over (ε_f, ε_s) with log-uniform priors on the ranges
  /// below. Where the model's form is exact, the small scales carry the evidence and the answers
  /// are those of an exact model; where it is not, an extra effect that absorbs a little of the
  /// model's error no longer looks decisive. false: the model's form is taken as exact.
  bool model_error = true;
  double model_error_frequency_min = 1e-5, model_error_frequency_max = 0.3;  ///< ε_f range (share of f)
  double model_error_shape_min = 1e-4, model_error_shape_max = 1.0;          ///< ε_s range (rms shape error of a unit-norm shape; 1 − MAC for kOneMinusMac)
  /// Members of groups (one joint, pad, mount) and single points are candidates too.
  bool members = true;
  /// Screening: grid points of the scan over one parameter's (log) range.
  int scan_points = 9;
  /// Member and single-point candidates fitted fully after screening (the best by their screened
  /// posterior); group, body and all-points candidates are always fitted.
  int max_fitted_singles = 14;
  /// Combinations: up to `max_effects` effects; `beam` best sets grow at each step, each by its
  /// `additions` best screened additions (re-fitted jointly).
  int max_effects = 3;
  int beam = 3;
  int additions = 4;
  /// Swap move after the combinations: each effect of the best set of each size replaced by its
  /// look-alikes (docs/diagnose.md), re-fitted and checked backward.
  bool swaps = true;
  int max_iterations = 30;
  /// Models with at least this many DOFs (FE-sized) are screened and fitted through reduced
  /// models (model/reduced.hpp: the nominal modes and each candidate's mode-shape sensitivity), the
  /// best `exact_candidates` re-fitted on a basis centred at their values and reported from full
  /// solves. 0: always full solves.
  int reduced_model_min_dofs = 200;
  /// FE-sized models: reduced-model factories (a full solve and a factorisation of K − σM each,
  /// with its probes' responses: gigabytes at 200 000 DOFs) kept for centres other than the
  /// nominal one, the least recently used dropped beyond this many with their reduced models; a
  /// centre met again is solved again, to the same numbers.
  int kept_centres = 3;
  int exact_candidates = 8;
  /// FE-sized models: of those (and their subsets), a set whose reduced-model score, less the most
  /// by which a reduced score has overstated a full one in the checks so far, is more than this many
  /// nats (ln odds: e^-7 ≈ 9·10⁻⁴, below the 0.1 % a probability is shown to) behind the best full
  /// score — by the search's evidence and by the ranking's, which marginalises the model error —
  /// keeps its reduced-model misfit (`reduced_model`); the swaps below start only from sets within
  /// it of the best. Infinity: every one of the `exact_candidates` and their subsets is checked,
  /// whatever its score. (15 until 2026-11-29: docs/diagnose.md.)
  double exact_margin = 7.0;
  /// FE-sized models: after that, the best fit of each size ≥ 2 has each effect swapped for each
  /// look-alike of the same kind (screened for its own value), and the `polish_swaps` best of those
  /// starts are re-fitted around them and judged by full solves (docs/diagnose.md "FE-sized
  /// models"). 0: off.
  int polish_swaps = 3;
  ProgressCallback progress;

  /// True when every option is in range; else false with the reason in *error (Ceres style).
  bool IsValid(std::string* error) const;
};

/// One fitted parameter with its posterior 1σ.
struct FittedParameter {
  model::EffectKind effect_kind = model::EffectKind::kSeriesCompliance;
  model::EffectTarget target;  ///< its effect's target
  std::string name;      ///< "k" (series_compliance: the law's k), "factor", "value", "mass", "modulus"
  double value = kNaN;
  double sigma = kNaN;   ///< NaN when the posterior is singular
  double prior_sigma = kNaN;  ///< the prior's 1σ (relative, see docs/diagnose.md)
  double lower = kNaN, upper = kNaN;   ///< the range searched (widened when a fit reached an end)
  bool at_bound = false;
  /// How far the value lies from the model's nominal one, in σ of its prior (log-normal: ln-ratio
  /// over σ; an unmodelled mass: mass over its σ). |z| > 3: far outside the stated uncertainty.
  double prior_z = kNaN;
  bool outside_prior = false;
};

/// What the diagnosis inferred about the model's own error beyond the measurement σ (cli.md,
/// added turn 4): the most probable scales given a candidate's fit.
struct ModelError {
  double frequency_rel = 0.0;  ///< 1σ of a frequency prediction, a share of f
  double shape = 0.0;          ///< 1σ of a shape residual (1 − MAC of unit-normalised shapes)
  /// 1σ of a frequency error shared across the modes (a share of f): a shift common to all (the
  /// model's overall stiffness-to-mass ratio — a modulus, a density, a spread non-structural mass)
  /// and a trend with ln f (shear and rotary inertia a beam lacks, a mesh too coarse), each of
  /// that size at one standard deviation of ln f.
  double frequency_common_rel = 0.0;
  /// True when it exceeds the measurement σ (in the mean over the test modes): the misfit is the
  /// model's, not the test's.
  bool dominates = false;
};

/// One mode of one setup before/after.
struct ModeComparison {
  std::string setup;
  /// Which test (index into Diagnose's `tests`): two tests of one setup — a repeat, a follow-up —
  /// share a setup's name and its model error (docs/diagnose.md "Model error") but not their modes.
  int test = 0;
  int test_mode = -1;   ///< index into that test's modes
  int model_mode = -1;  ///< -1: unpaired
  double test_frequency_hz = kNaN;
  double model_frequency_hz = kNaN;
  double agreement_pct = kNaN;
  double mac = kNaN;
  double sigma_hz = kNaN;                ///< the test frequency's 1σ the fit used
  double frequency_misfit_sigma = kNaN;  ///< (model − test) / σ (unpaired: the penalty residual)
  double shape_misfit_sigma = kNaN;      ///< (1 − MAC, blended for close modes) / shape σ
};

/// One outcome: the baseline ("none"), one effect, or several.
struct Candidate {
  std::vector<model::Effect> effects;       ///< with fitted parameters; empty for "none"
  std::vector<FittedParameter> parameters;
  /// A label of the combination, for people and JSON: "none", an effect kind's name, or
  /// "kind1+kind2". Decisions go by `effects` (IsNone), never by this text.
  std::string kind;
  /// A label of the targets, as `kind` is of the kinds: "" for none, "t1+t2" (model::TargetText)
  /// for several. Decisions go by `effects`, never by this text.
  std::string target;
  double cost = kNaN;                       ///< robust sum of squared residuals in σ
  double log_prior = 0.0;                   ///< log prior density at the fitted parameters
  double log_evidence = kNaN;               ///< Laplace approximation
  double score = kNaN;                      ///< −2 log evidence (or the criterion); lower is better
  double probability = kNaN;                ///< posterior probability among all ranked candidates
  double explained_pct = kNaN;              ///< 100 (1 − J/J_baseline)
  double mean_abs_frequency_error_pct = kNaN;  ///< over paired modes of all setups
  double mean_mac = kNaN;
  double mean_agreement_pct = kNaN;
  int paired_modes = 0;
  std::vector<ModeComparison> modes;
  bool plausible = true;                    ///< false when a parameter ends at its far bound
  /// The remaining frequency misfit per test mode in units of the test modes' own σ²:
  /// Σ ((f_model − f_test)/σ)² / max(1, modes − parameters). cli.md, added turn 3.
  double reduced_chi2 = kNaN;
  /// True when that misfit is what the measurement noise explains (χ² below its 99 % quantile for
  /// those degrees of freedom): the model then misses nothing these data can show.
  bool noise_consistent = false;
  /// The model's own error inferred with this candidate's effects (cli.md `model_error`).
  ModelError model_error;
  /// Sentences an engineer should read: a value far outside its stated uncertainty ("the stiffness
  /// of part 'clamp' is 50× lower than modelled: check it").
  std::vector<std::string> flags;
  bool reduced_model = false;               ///< misfit from a reduced model (FE-sized models, not among the best)
  std::vector<std::string> tied_with;       ///< candidates the data cannot tell apart
  std::string error;                        ///< non-empty when the candidate could not be evaluated
  int rank = 0;                             ///< 1 = most likely
  Eigen::VectorXd residuals;                ///< weighted residuals, for the tie test

  /// The model as given: no effect added.
  bool IsNone() const { return effects.empty(); }
};

/// The error falling as rank 1's effects are added one at a time (each subset re-fitted).
struct Step {
  std::string added;  ///< the effect added at this step ("" for the baseline)
  double mean_abs_frequency_error_pct = kNaN;
  double mean_mac = kNaN;
  double mean_agreement_pct = kNaN;
};

/// How sure the diagnosis is of one effect, whichever candidate holds it: the summed probability
/// of the candidates that contain it. `target` is exact ("bearings", "joints/J3", "points:101")
/// or, summed over the members of a group or over single points, "joints/*" or "points:*"
/// (EffectTarget::Form::kEveryMember, kEveryPoint). Where the data cannot tell which member or
/// point (several near-equal candidates), the wildcard's probability is the one to read.
struct EffectProbability {
  model::EffectKind kind = model::EffectKind::kSeriesCompliance;
  model::EffectTarget target;
  double probability = 0.0;
};

/// The wildcard an effect target is summed under: every member of the group ("GROUP/*") for a
/// member, every point ("points:*") for a single point, nullopt for any other target.
std::optional<model::EffectTarget> EffectWildcard(const model::EffectTarget& target);

/// The effect probabilities of ranked candidates, most probable first (≥ 1 % only).
std::vector<EffectProbability> EffectProbabilities(const std::vector<Candidate>& ranked);

/// Candidates that are one reading on different members or points (the same kinds on the same
/// groups): the data tell them apart only by which member or point, so reports show them as one
/// row. `kind` is the candidates' label ("none", "kind1+kind2"; decide by their effects), `target`
/// a label too: the texts of the wildcard targets ("joints/*", "points:*") joined with '+'.
struct CandidateGroup {
  std::string kind;
  std::string target;
  std::vector<int> ranks;   ///< ranks of its candidates, best first
  double probability = 0.0; ///< summed over them
};

/// The look-alike rule (docs/diagnose.md "Look-alikes"): a reading of probability `p` is a
/// look-alike of rank 1 (probability `p_first`) when it is within a factor 20 of it and at least
/// 0.1 % probable — the readings these data cannot separate from rank 1.
inline constexpr double kLookAlikeFactor = 20.0;
inline bool IsLookAlike(double p, double p_first) { return p >= p_first / kLookAlikeFactor && p >= 0.001; }

/// The groups of look-alike candidates, in the order of their best rank (failed candidates left out).
std::vector<CandidateGroup> GroupCandidates(const std::vector<Candidate>& ranked);

struct Diagnosis {
  Candidate baseline;                 ///< the model as given (also in `candidates` as "none")
  std::vector<Candidate> candidates;  ///< ranked, rank 1 first; includes "none"
  std::vector<Step> steps;            ///< baseline, then rank 1's effects added in turn
  std::vector<EffectProbability> effect_probabilities;  ///< per effect, most probable first
  std::vector<CandidateGroup> groups;  ///< look-alike candidates folded into one row each
  std::string explanation;            ///< in words, for the user
  int residual_count = 0;
  int test_mode_count = 0;
  int model_solves = 0;
  int candidates_screened = 0;        ///< single candidates scanned
};

/// Ranks the candidate missing effects of `model` against `tests` (one entry per setup).
/// Throws InputError when a setup is not defined by the model, when test nodes are not test
/// points of the model, or when too few modes pair to fit any parameter; UsageError for invalid
/// options.
Diagnosis Diagnose(const model::Model& model, const std::vector<SetupModes>& tests, const DiagnoseOptions& options = {});

/// The words for one candidate's effect(s), e.g. "a compliance of 6.4 N/µm in series with member
/// 'J3' of group 'joints'". with_law_values = false leaves out a law's constants that the words
/// would otherwise give in parentheses ("a Hertz contact in series with group 'bearings'"), for
/// where the values follow in engineering units with their σ.
std::string DescribeCandidate(const Candidate& candidate, bool with_law_values = true);

/// The JSON parameter key of each of a candidate's parameters: `name` for one effect,
/// `kind.name` for several (cli.md), `kind.name[target]` when a kind appears twice.
std::vector<std::string> ParameterKeys(const Candidate& candidate);

/// Defaults of the priors per kind, as text for --help and docs.
std::string PriorDefaultsText();

}  // namespace ema::diagnose
