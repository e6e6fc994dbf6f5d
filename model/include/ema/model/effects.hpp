// Effects: physical phenomena added on top of the base model (model-format.md, "Effects").
// Each kind is a small transformation of a Model value:
//  * series_compliance(group, law): every spring of the group gets `law` in series (a series
//    chain is extended, so an air-film chain re-solves its equilibrium with the extra element);
//  * stiffness_scale(group, factor): linearised stiffness of the group's springs x factor;
//  * operating_point(group, value): replaces the setting / gap / operating deflection or force of
//    the group's non-linear laws;
//  * added_mass("points:101,102" | "all_points", mass): a point mass `mass` at each test point;
//  * mass_scale(body, factor): mass, inertia and products of the body x factor;
//  * ground_spring(body, k): three translational springs of stiffness k (X, Y, Z) from the body
//    centre to ground, group "ground_spring".
#pragma once

#include <string>
#include <vector>

#include "ema/model/model.hpp"

namespace ema::model {

/// Applies one effect to a copy of `model` (model.effects is left as it is). Throws InputError
/// naming the effect when the kind is unknown, the target does not exist or does not apply, or a
/// parameter is missing or out of range.
Model ApplyEffect(const Model& model, const Effect& effect);

/// Applies the model's own pending [[effect]] blocks in order and clears model.effects.
Model ApplyEffects(const Model& model);

/// Every kind of the vocabulary on every target it applies to, with nominal starting parameters
/// (see docs/model.md): series_compliance k = the group's mean linearised stiffness (halves it);
/// stiffness_scale factor 1; operating_point value = the group's current operating value (only
/// groups with non-linear laws); added_mass all_points mass 0 (only with test points);
/// mass_scale factor 1 per body; ground_spring k = 1e-3 x the mean linearised spring stiffness.
std::vector<Effect> CandidateEffects(const Model& model);

/// The effect kinds of the vocabulary, in the order of model-format.md.
const std::vector<std::string>& EffectKinds();

/// "kind target k=v ..." for messages and reports.
std::string Describe(const Effect& effect);

}  // namespace ema::model
