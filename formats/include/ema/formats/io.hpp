// File-level entry points that turn files into the core vocabulary types and back.
// (UFF dataset-level access lives in ema/formats/uff.hpp.)
#pragma once

#include <filesystem>
#include <vector>

#include "ema/core/types.hpp"

namespace ema::formats {

struct WriteOptions {
  bool binary = false;  ///< write 58b (binary) where the dataset allows it; ASCII otherwise
};

/// Hammer-test time data: UFF 58/58b function-type-1 records, or CSV (docs/formats.md), chosen by
/// content (a CSV file does not start with a UFF delimiter). Throws InputError naming file/line.
std::vector<TimeRecord> ReadTimeRecords(const std::filesystem::path& path);

/// Writes time records as UFF 58 (function type 1) in the convention `ema frf` reads.
void WriteTimeRecords(const std::filesystem::path& path, const std::vector<TimeRecord>& records,
                      const WriteOptions& options = {});

/// FRFs (UFF 58 function type 4) and, when present, coherences (type 6) of one test.
FrfSet ReadFrfSet(const std::filesystem::path& path);

/// Writes FRFs (type 4) and coherences (type 6) with correct units and data-type codes.
void WriteFrfSet(const std::filesystem::path& path, const FrfSet& frfs, const WriteOptions& options = {});

/// Mode shapes (UFF 55) with geometry from datasets 15/2411 when the file holds them.
ModeSet ReadModeSet(const std::filesystem::path& path);

/// Writes 151 header, 15 geometry (when known) and one 55 complex-mode dataset per mode.
void WriteModeSet(const std::filesystem::path& path, const ModeSet& modes, const WriteOptions& options = {});

}  // namespace ema::formats
