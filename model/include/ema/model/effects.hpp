// Effects: physical phenomena added on top of the base model (model-format.md, "Effects").
// Every kind is one row of a typed table (EffectKindTable): its enum (model::EffectKind), the name
// used in model files and JSON, its free parameter, the range diagnosis searches, its default prior
// and the function that applies it to a Model. ApplyEffect dispatches through the table. A kind's
// name is read into an EffectKind once, where text enters (FindEffectKind: the model file, DIAG.json,
// Python's priors), and written once, through the table (KindName); nothing else compares kind names.
//  * series_compliance(group | group/member, law): every spring of the target gets `law` in
//    series (a series chain is extended, so an air-film chain re-solves its equilibrium);
//  * stiffness_scale(group | group/member, factor): linearised stiffness of the springs x factor;
//    on an FE part target (part group, GROUP/PART, a part in no group) the parts' stiffness x factor;
//  * operating_point(group | group/member, value): replaces the setting / gap / operating
//    deflection or force of the target's non-linear laws;
//  * added_mass("points:101,102" | "all_points", mass): a point mass `mass` at each test point;
//  * mass_scale(body, factor): mass, inertia and products of the body x factor; on an FE part
//    target the parts' mass x factor;
//  * ground_spring(body, k): three translational springs of stiffness k (X, Y, Z) from the body
//    centre to ground, group "ground_spring".
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "ema/model/model.hpp"

namespace ema::model {

/// What a kind of effect acts on (the category of its targets; EffectTarget is one target).
enum class ActsOn {
  kSprings,  ///< a spring group ("joints") or one member of it ("joints/J3"); stiffness_scale also FE parts
  kPoints,   ///< "all_points" or "points:101,102"
  kBody,     ///< a body name; mass_scale also FE parts
};

/// The shape of a parameter's prior (model-format.md "Prior knowledge", docs/diagnose.md).
enum class PriorShape {
  kLogNormal,   ///< ln(value / reference) ~ N(0, σ²): factors, stiffnesses, operating values
  kHalfNormal,  ///< value ~ |N(0, (σ·model mass)²)|: an unmodelled mass, σ a share of the model's mass
};

/// One row of the vocabulary.
struct EffectKindInfo {
  EffectKind kind;
  const char* name;       ///< "series_compliance" (model files, JSON)
  const char* parameter;  ///< the free parameter diagnosis fits: "k", "factor", "value", "mass"
  ActsOn acts_on;
  bool members;           ///< also applies to one member of a group ("GROUP/MEMBER")
  /// Range searched by diagnosis, as multiples of the parameter's reference value (log scale).
  double range_low, range_high;
  /// Which end of the range means "no effect": -1 the low end (mass → 0), +1 the high end
  /// (series k → ∞), 0 neither (a factor of 1 lies inside).
  int absent_end;
  PriorShape prior_shape;
  double prior_sigma;     ///< default 1σ of the prior ([priors] `name` overrides it)
  const char* prior_meaning;
  const char* meaning;    ///< physical meaning, for --help and docs
  /// Applies the effect to `model` in place (the row's "how applied"). Throws InputError.
  void (*apply)(Model& model, const Effect& effect);
};

/// Every kind of the vocabulary, in the order of model-format.md.
const std::vector<EffectKindInfo>& EffectKindTable();
/// The row of a kind's name; nullptr for a name that is not in the vocabulary (the one parser of
/// a kind's name).
const EffectKindInfo* FindEffectKind(const std::string& name);
const EffectKindInfo& Info(EffectKind kind);
/// The kind's name in model files and JSON ("series_compliance"): Info(kind).name.
std::string KindName(EffectKind kind);

/// Applies one effect to a copy of `model` (model.effects is left as it is). Throws InputError
/// naming the effect when the target does not exist or does not apply, or a parameter is missing
/// or out of range.
Model ApplyEffect(const Model& model, const Effect& effect);

/// Applies the model's own pending [[effect]] blocks in order and clears model.effects.
Model ApplyEffects(const Model& model);

/// Every kind of the vocabulary on every group-level target it applies to, with nominal
/// starting parameters (see docs/model.md): series_compliance k = the group's mean linearised
/// stiffness (halves it); stiffness_scale factor 1; operating_point value = the group's current
/// operating value (only groups with non-linear laws); added_mass all_points mass 0 (only with
/// test points); mass_scale factor 1 per body; ground_spring k = 1e-3 x the mean linearised
/// spring stiffness.
std::vector<Effect> CandidateEffects(const Model& model);

/// The names of the effect kinds of the vocabulary, in the order of model-format.md.
const std::vector<std::string>& EffectKinds();

/// "kind target k=v ..." for messages and reports.
std::string Describe(const Effect& effect);

/// The one reader of a target's text (model-format.md "Effects"): for a kind that acts on points,
/// "all_points" or "points:101,102" (ids separated by commas); for the others a name ("joints") or
/// "GROUP/MEMBER" (split at the first '/'). The model is not consulted: whether the name is a
/// spring group, a part or a body is ApplyEffect's question. nullopt with *error saying what was
/// expected for anything else (an empty text, a bad id, "GROUP/" or "GROUP/*", which names no one
/// member); the caller says where (file and line).
std::optional<EffectTarget> ParseEffectTarget(EffectKind kind, const std::string& text, std::string* error);

/// One member of a spring group (model-format.md "Members"): a joint, bolt, pad or mount.
struct Member {
  std::string group;
  std::string name;
  std::vector<int> springs;  ///< indices into Model::springs
  EffectTarget Target() const { return EffectTarget::MemberOf(group, name); }
};

/// The members of every group, groups in order of first appearance. A spring's member is its
/// `member` key; otherwise the springs of one group joining the same two points form one member,
/// named by the longest common prefix of their names, or by the first spring's name when they
/// share none (or when that prefix is already another member's name in the group).
std::vector<Member> Members(const Model& model);

/// The test points (indices into Model::points) a points target of `effect` names: all_points or
/// the listed ids. InputError naming the effect for another target, an unknown point id, or
/// all_points on a model without points.
std::vector<int> TargetPoints(const Model& model, const Effect& effect);

/// The spring indices a spring target names: a group's name (every spring of the group) or one
/// member of it. Empty when nothing matches.
std::vector<int> TargetSprings(const Model& model, const EffectTarget& target);

/// The FE part indices (Model::fe.parts) a part target names (model-format.md "FE models built
/// from parts"): a part group's name (every part of the group), one member of it, or the name of a
/// part in no group. Empty when nothing matches.
std::vector<int> TargetParts(const Model& model, const EffectTarget& target);

/// The body a target names (a name that is a body's); nullptr otherwise.
const Body* TargetBody(const Model& model, const EffectTarget& target);

/// The operating value of a spring's non-linear law (setting, gap, deflection or force); NaN for
/// a linear law.
double OperatingValue(const Spring& spring);

}  // namespace ema::model
