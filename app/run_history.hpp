// The model's story across `ema run`s (issue 13 item 6): each run into one output folder appends
// the model version (its [[effect]] blocks and a hash of the file) and its agreement with the
// tests to OUTDIR/history.json, which the report draws as "the error falls" over versions.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>
#include <string>

#include "ema/model/model.hpp"

namespace ema::app {

/// One run's entry of the history.
struct RunRecord {
  std::string stamp;                 ///< when (UTC, ISO 8601)
  std::filesystem::path model;       ///< the model file of the run
  double agreement_before = 0.0;     ///< mean agreement of the model as given, % (NaN: unknown)
  double mac_before = 0.0;
  double agreement_after = 0.0;      ///< of the model updated by the diagnosis
  double mac_after = 0.0;
  /// The diagnosis's rank 1 (kind, target, probability); empty when there was no diagnosis.
  struct RankOne {
    std::string kind, target;
    double probability = 0.0;
  };
  std::optional<RankOne> rank_one;
};

/// FNV-1a 64-bit hash of a file's bytes, as 16 hex digits ("" when it cannot be read).
std::string FileHash(const std::filesystem::path& file);

/// Appends `record` to OUTDIR/history.json (an array; created when missing, replaced atomically)
/// and returns the whole history. The entry: version (1, 2, ...), stamp, model, hash, effects
/// (the model's own [[effect]] blocks, described), agreement and MAC before and after, the
/// diagnosed rank 1 (kind, target, probability). A history that cannot be read is started anew.
nlohmann::json AppendRunHistory(const std::filesystem::path& out_dir, const RunRecord& record);

}  // namespace ema::app
