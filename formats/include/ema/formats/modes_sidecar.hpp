// What a modes file's `ema fit --json` sidecar adds to it (the file beside MODES.unv with the same
// stem and .json, when it holds the same modes): each mode's σ and per-set frequencies, the test's
// roving sets and hammer DOF; and the mode sets per excitation level of `ema amplitude --level`
// and `ema diagnose --force-level`, each with the σ of its sidecar. Read by those commands and by
// the Python package.
#pragma once

#include <string>
#include <vector>

#include "ema/core/types.hpp"
#include "ema/correlation/amplitude.hpp"

namespace ema::formats {

/// Parses `LEVEL=MODES.unv` arguments of `option` (UsageError on a bad form or a level that is
/// not a positive number: "OPTION: expected a number, got 'TEXT'" as cli::ParseNumber words it)
/// and reads each mode set, with each mode's σ from the `ema fit --json` file beside it (same
/// stem, .json) when that file holds the same modes.
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

}  // namespace ema::formats
