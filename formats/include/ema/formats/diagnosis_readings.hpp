// The candidate readings of a diagnosis read back from DIAG.json (`ema diagnose --json`, cli.md
// "ema diagnose"): each candidate's rank, probability, kind and target, and its effects whole, the
// laws parsed by the model file's own law parser (so every law kind a model file takes is read
// exactly as there). `ema plan --candidates` plans the test that tells competing readings apart.
#pragma once

#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ema/diagnose/diagnose.hpp"
#include "ema/model/model.hpp"

namespace ema::formats {

/// One candidate reading of a diagnosis, as DIAG.json (`ema diagnose --json`) holds it.
struct DiagnosisReading {
  int rank = 0;
  double probability = std::numeric_limits<double>::quiet_NaN();  ///< NaN when null or absent
  std::string kind, target;            ///< as candidates[] (several effects joined with '+'); "none" for the model as given
  std::vector<model::Effect> effects;  ///< each effect whole: kind, target, parameters, law (empty for "none")
};

/// Every candidate of a DIAG.json, by rank (a stable sort: candidates of one rank keep the file's
/// order). InputError naming the file (and the candidate's rank and key) when the file is not
/// JSON, has no `candidates` array, or a candidate lacks rank/kind/target/effects or has an effect
/// that is not {"kind", "target", "parameters": {name: number}, "law": "<inline TOML>"} as a
/// model file's [[effect]] takes it (the parameters factor/value/mass/k; a law that parses).
/// A law's relative curve `file =` paths resolve against the DIAG.json's folder.
std::vector<DiagnosisReading> ReadDiagnosisReadings(const std::filesystem::path& path);

/// A DIAG.json's JSON, read once for both readers below: InputError naming the file (and the line)
/// when it is missing or not JSON.
nlohmann::json ReadDiagnosisJson(const std::filesystem::path& path);

/// The model's own error the diagnosis inferred for rank 1 (DIAG.json `model_error`, cli.md "added
/// turn 4"): all zero when it has none (`--exact-form`, a file before the field). InputError naming
/// `origin` when it is there but not {"frequency_rel", "shape", "dominates"} of numbers ≥ 0.
diagnose::ModelError ReadDiagnosisModelError(const nlohmann::json& diagnosis, const std::string& origin);

/// The same from the JSON itself (what `ema.diagnose` returns, in Python): `origin` names it in
/// messages, and a law's relative curve files resolve against `base_dir`.
std::vector<DiagnosisReading> ReadDiagnosisReadings(const nlohmann::json& diagnosis, const std::string& origin,
                                                    const std::filesystem::path& base_dir);

}  // namespace ema::formats
