// Internal: one [[effect]] block read from TOML text with the model file reader's own rules (the
// same keys, the same law parser), for files that carry effects outside a model file (DIAG.json).
#pragma once

#include <filesystem>
#include <string>

#include "ema/model/model.hpp"

namespace ema::formats {

/// Parses `text`, which must hold exactly one [[effect]] block in the layout EffectToToml writes
/// (kind, target, the parameters factor/value/mass/k, law), as ReadModelFile reads an [[effect]].
/// InputError "origin:line: what" (line within `text`); a law's relative `file =` paths resolve
/// against `base_dir`.
model::Effect ParseEffectToml(const std::string& text, const std::string& origin, const std::filesystem::path& base_dir);

}  // namespace ema::formats
