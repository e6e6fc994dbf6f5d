// What a diagnosis finds, as numbers: rank 1's effects with their values, σ and summed
// probabilities, the look-alike readings the data cannot separate, the adequacy to the test's
// noise, where the misfit sits and which kinds of missing physics fit its pattern, and the
// evidence per test mode. Every edge — the terminal's first screen, DIAG.json's "findings", the
// HTML report — words these same numbers; none re-derives them (docs/architecture.md).
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "ema/diagnose/diagnose.hpp"
#include "ema/model/model.hpp"

namespace ema::pipeline {

/// The mean linearised stiffness of a spring target's springs in one setup, with rank 1's effects.
struct SpringStiffness {
  std::string setup;
  double per_spring_n_per_m = std::numeric_limits<double>::quiet_NaN();
  /// series_compliance: the element it added in series alone (NaN otherwise).
  double element_n_per_m = std::numeric_limits<double>::quiet_NaN();
};

/// One effect of rank 1.
struct EffectFinding {
  model::Effect effect;                             ///< kind, target, fitted values, law
  std::vector<diagnose::FittedParameter> parameters;  ///< its fitted parameters with their 1σ
  double probability = 0.0;                         ///< summed over every candidate that holds it
  /// The same kind on any member or point of its group ("joints/*", "points:*"; none when the
  /// target has no such wildcard or no candidate held it), with that summed probability.
  std::optional<model::EffectTarget> wildcard;
  double wildcard_probability = 0.0;
  std::vector<SpringStiffness> springs;             ///< spring targets: per setup of the tests
};

/// What the readings of a group of look-alikes differ in.
enum class GroupSpan {
  kPoints,    ///< the test point an effect sits at
  kMembers,   ///< the member of a group (a joint, a mount, an FE part)
  kReadings,  ///< both, or the readings are otherwise different
};

/// The span of `group` among `diagnosis`'s candidates (the effects that differ from its best one's).
GroupSpan SpanOf(const diagnose::Diagnosis& diagnosis, const diagnose::CandidateGroup& group);

/// A group of readings within a factor 20 of rank 1's probability (diagnose::IsLookAlike).
struct LookAlike {
  std::string kind, target;   ///< the group's kinds and wildcard targets ("joints/*", "points:*")
  int readings = 0;           ///< readings of the group other than rank 1
  bool holds_rank_one = false;  ///< the group is rank 1's reading on other members or points
  GroupSpan span = GroupSpan::kReadings;
  double probability = 0.0;   ///< summed over those readings (rank 1 left out)
};

enum class ModeVerdict { kWithinNoise, kMarginal, kMisfit, kUnpaired };

/// One test mode: as the model gives it and with rank 1's effects.
struct ModeEvidence {
  diagnose::ModeComparison before, after;
  bool paired_before = false, paired_after = false;
  /// The mode's share of the fall in χ² (frequency and shape, in σ²) from before to after, %; NaN
  /// when nothing fell.
  double share_pct = std::numeric_limits<double>::quiet_NaN();
  ModeVerdict verdict = ModeVerdict::kUnpaired;  ///< after: > 3σ misfit, > 2σ marginal
};

/// When the model as given ranks first and stays inadequate: the most probable reading with
/// effects, when it is a look-alike of rank 1 (within a factor 20), takes at least half of the
/// mean frequency error away and moves every paired mode the same way by within a factor 2 of
/// each other. Such a uniform shift (an added mass spread over all points, a material constant)
/// and an error every frequency of the model shares are one pattern in the frequencies, so the
/// data cannot tell the two apart and the priors order them: the reading is inside the
/// vocabulary, and an engineer who trusts the model to better than that error should take it.
/// (A point mass that absorbs some scatter moves the modes tens of times apart: not said here.)
struct ModelErrorLookAlike {
  int rank = 0;
  std::string description;                          ///< diagnose::DescribeCandidate
  double probability = 0.0;
  double error_after_pct = std::numeric_limits<double>::quiet_NaN();  ///< its mean frequency error
  diagnose::ModelError model_error;                 ///< the model's own error inferred with it
};

/// The kinds of missing physics the misfit pattern of rank 1 fits, when no reading of the
/// vocabulary makes the model adequate.
struct MisfitPattern {
  bool all_one_way = false;          ///< every mode off the same way, or the shared error dominates
  bool model_too_stiff = false;      ///< with all_one_way: model frequencies high (stiffness too high / mass too low)
  bool mixed = false;                ///< modes off both ways: stiffness or mass distributed differently
  bool shapes_off_more = false;      ///< the shapes are off more than the frequencies
  bool unpaired_modes = false;       ///< test modes the model does not have
};

struct Findings {
  std::vector<EffectFinding> effects;      ///< rank 1's, in its order; empty when rank 1 is "none"
  double rank_one_probability = 0.0;
  /// Probability worth saying as certainty only when rank 1 is adequate or below 99 %.
  bool certain_among_tried_only = false;
  bool adequate = false;                   ///< rank 1 consistent with the test's noise
  bool well_inside_noise = false;          ///< adequate with reduced χ² below 0.01
  double reduced_chi2 = std::numeric_limits<double>::quiet_NaN();
  int test_modes = 0;
  /// No reading makes the model adequate and its own error dominates the test's σ.
  bool model_inadequate = false;
  diagnose::ModelError model_error;        ///< rank 1's
  MisfitPattern pattern;                   ///< with model_inadequate
  std::vector<int> worst_modes;            ///< indices into `modes`, furthest off first (at most 3)
  std::vector<LookAlike> lookalikes;       ///< at most 4, most probable group first
  /// Rank 1 "none" in a model that stays inadequate: the reading the model's error also explains.
  std::optional<ModelErrorLookAlike> model_error_lookalike;
  std::vector<std::string> checks;         ///< rank 1's flags
  std::vector<ModeEvidence> modes;         ///< every test mode of every setup
  double error_before_pct = std::numeric_limits<double>::quiet_NaN(), error_after_pct = error_before_pct;
  double mac_before = error_before_pct, mac_after = error_before_pct;
};

/// The findings of `diagnosis` of `model` (the nominal model: rank 1's springs are re-solved with
/// its effects for SpringStiffness).
Findings FindingsOf(const diagnose::Diagnosis& diagnosis, const model::Model& model);

}  // namespace ema::pipeline
