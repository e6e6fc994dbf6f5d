// The model file (TOML, ../shared/spec/model-format.md) and the Matrix Market / CSV files of its
// [fe] section.
#pragma once

#include <Eigen/SparseCore>
#include <filesystem>
#include <vector>

#include "ema/model/model.hpp"

namespace ema::formats {

/// Reads a model file. Errors (InputError) name the file, the key's line and what was expected;
/// unknown keys are errors that list the allowed keys. Relative `file =` / [fe] paths are resolved
/// against the model file's folder. Effects are returned pending in Model::effects.
model::Model ReadModelFile(const std::filesystem::path& path);

/// Copies `in_model` to `out` (atomic write) and appends one [[effect]] block per effect. Relative
/// paths in it (law `file =`, [fe] mass/stiffness/dofs/nodes) are rewritten to stay valid from
/// the folder of `out`; everything else is kept byte for byte.
void WriteModelWithEffects(const std::filesystem::path& in_model, const std::filesystem::path& out,
                           const std::vector<model::Effect>& effects);

/// The TOML text of one [[effect]] block (used by WriteModelWithEffects).
std::string EffectToToml(const model::Effect& effect);

/// The inline-table TOML of a law, e.g. `{ linear = { k = 6.5e6 } }`.
std::string LawToToml(const model::Law& law);

}  // namespace ema::formats
