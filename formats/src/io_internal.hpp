// The halves of the UFF file entry points of io.cpp (core types <-> datasets), shared with
// stored_view.cpp, which hands on what a written file holds without reading it back.
#pragma once

#include <filesystem>
#include <vector>

#include "ema/core/types.hpp"
#include "ema/formats/uff.hpp"

namespace ema::formats {

/// A dataset 58 with the line it starts on (for messages).
struct Function58At {
  uff::Function58 f;
  std::int64_t line = 0;
};

/// WriteFrfSet's datasets: one 58 per measured FRF (function type 4), its coherence (type 6).
std::vector<uff::Dataset> FrfSetDatasets(const FrfSet& frfs);
/// ReadFrfSet's assembly of FRFs (type 4) and coherences (type 6); `path` names them in messages.
/// (Taken by value: the values of each record are released once copied.)
FrfSet FrfSetFromFunctions(const std::filesystem::path& path, std::vector<Function58At> frfs,
                           std::vector<Function58At> cohs);

/// WriteModeSet's datasets: 151 header, 15 geometry (when known), one 55 per mode.
std::vector<uff::Dataset> ModeSetDatasets(const ModeSet& modes);
/// ReadModeSet's assembly of the datasets of a file; `path` names it in messages and the source.
ModeSet ModeSetFromDatasets(const std::filesystem::path& path, const std::vector<uff::Dataset>& datasets);

/// True when the file's first non-blank byte is '{' (MODES.json rather than UFF).
bool LooksLikeJson(const std::filesystem::path& path);
/// Test modes in `ema fit --json`'s layout (formats/src/modes_json.cpp).
ModeSet ReadModeSetJson(const std::filesystem::path& path);

}  // namespace ema::formats
