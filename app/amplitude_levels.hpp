// Reading mode sets per excitation level and writing the amplitude analysis as JSON: shared by
// `ema amplitude` and `ema diagnose --force-level`, so both run the same analysis.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ema/correlation/amplitude.hpp"

namespace ema::app {

/// Parses `LEVEL=MODES.unv` arguments of `option` (UsageError on a bad form or a level that is
/// not a positive number) and reads each mode set, with each mode's σ from the `ema fit --json`
/// file beside it (same stem, .json) when that file holds the same modes.
std::vector<correlation::AmplitudeLevel> ReadAmplitudeLevels(const std::vector<std::string>& level_args,
                                                             const std::string& option);

/// The mode files named by `LEVEL=MODES.unv` arguments (for the outputs-over-inputs check).
std::vector<std::string> AmplitudeLevelFiles(const std::vector<std::string>& level_args);

/// Fills each mode's frequency_std_hz / damping_ratio_std from the `ema fit --json` file beside
/// `modes_path` (same stem, .json) when it holds the same modes; UFF 55 carries no σ. Used by
/// `ema diagnose` to weigh each test mode by how well it was measured.
void AttachSidecarUncertainty(const std::string& modes_path, ModeSet* modes);

/// The roving sets and the hammer DOF of a test as `ema fit --json` records them: read from the
/// modes file itself when it is MODES.json, else from the `ema fit --json` file beside it (same
/// stem, .json) when that holds the same modes. False when neither knows them.
bool ReadSidecarTestSets(const std::string& modes_path, const ModeSet& modes, std::vector<std::vector<int>>* roving_sets,
                         Dof* reference);

/// The JSON of cli.md ("ema amplitude").
nlohmann::json AmplitudeJson(const correlation::AmplitudeResult& result);

}  // namespace ema::app
