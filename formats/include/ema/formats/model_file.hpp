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

/// How WriteModelWithEffects writes the files the model names.
struct ModelWriteOptions {
  /// false: each path (law `file =`, [fe] mass/stiffness/dofs/nodes) is written relative to the
  /// output's folder when the file lies inside it, else absolute, so the written model loads
  /// wherever it is copied on the same machine. true: every referenced file is copied into
  /// `<out's stem>-files/` beside the output and named relative to it, so the output's folder
  /// can be moved or sent as a whole.
  bool bundle = false;
};

/// Copies `in_model` to `out` (atomic write) and appends one [[effect]] block per effect. Paths in
/// it are rewritten as `options` says; everything else is kept byte for byte.
void WriteModelWithEffects(const std::filesystem::path& in_model, const std::filesystem::path& out,
                           const std::vector<model::Effect>& effects, const ModelWriteOptions& options = {});

/// The TOML text of one [[effect]] block (used by WriteModelWithEffects).
std::string EffectToToml(const model::Effect& effect);

/// The inline-table TOML of a law, e.g. `{ linear = { k = 6.5e6 } }`.
std::string LawToToml(const model::Law& law);

}  // namespace ema::formats
