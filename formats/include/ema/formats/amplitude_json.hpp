// The amplitude analysis (correlation::AnalyseAmplitude) as JSON: written by `ema amplitude
// --json`, put in DIAG.json's "nonlinearity" by `ema diagnose --force-level`.
#pragma once

#include <nlohmann/json.hpp>

#include "ema/correlation/amplitude.hpp"

namespace ema::formats {

/// The JSON of cli.md ("ema amplitude").
nlohmann::json AmplitudeJson(const correlation::AmplitudeResult& result);

}  // namespace ema::formats
