// Internal: one effect made from values another format carries (DIAG.json's effects), with the
// model file reader's own rules for an [[effect]] table: the same parameters, kinds, targets and
// law parser, and the same messages.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <toml++/toml.h>

#include "ema/model/model.hpp"

namespace ema::formats {

/// The effect of these fields as ReadModelFile makes one of an [[effect]] table: `kind` one of
/// model::EffectKinds(), `target` read for that kind by model::ParseEffectTarget, the parameters
/// among factor/value/mass/k, `law` (nullptr: none) a law as the model file's law parser takes it.
/// InputError at `place` ("DIAG.json: candidate rank 2: effect 1"), the law's nodes included (the
/// lines of its TOML are in no file); an error in a curve file the law names gives that file's
/// line after `place`. A law's relative `file =` paths resolve against `base_dir`.
model::Effect EffectFromFields(const std::string& kind, const std::string& target,
                               const std::map<std::string, double>& parameters, const toml::node* law,
                               const std::string& place, const std::filesystem::path& base_dir);

}  // namespace ema::formats
