// The model's story across `ema run`s and the diagnosed members' places (issue 13 item 6):
// each run into one output folder appends the model version (its [[effect]] blocks and a hash of
// the file) and its agreement with the tests to OUTDIR/history.json, which the report draws as
// "the error falls" over versions; the diagnosed members are located on the model for the
// report's geometry view.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
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
  nlohmann::json diagnosis;          ///< `ema diagnose --json` of the run (rank 1 is recorded)
};

/// FNV-1a 64-bit hash of a file's bytes, as 16 hex digits ("" when it cannot be read).
std::string FileHash(const std::filesystem::path& file);

/// Appends `record` to OUTDIR/history.json (an array; created when missing, replaced atomically)
/// and returns the whole history. The entry: version (1, 2, ...), stamp, model, hash, effects
/// (the model's own [[effect]] blocks, described), agreement and MAC before and after, the
/// diagnosed rank 1 (kind, target, probability). A history that cannot be read is started anew.
nlohmann::json AppendRunHistory(const std::filesystem::path& out_dir, const RunRecord& record);

/// Where rank 1's effects act on the model: [{"target", "kind", "label", "points": [[x,y,z], ...]}]
/// (spring targets: both ends of every spring of the group or member; points: the test points;
/// bodies: the centre). Empty when the model cannot be read or rank 1 is "none".
nlohmann::json DiagnosedPlaces(const std::filesystem::path& model_file, const nlohmann::json& diagnosis);
/// The same on a model already read.
nlohmann::json DiagnosedPlaces(const model::Model& model, const nlohmann::json& diagnosis);

}  // namespace ema::app
