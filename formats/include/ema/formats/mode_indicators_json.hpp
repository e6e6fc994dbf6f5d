// CMIF and MMIF (curvefit::ComputeModeIndicators) as the "cmif"/"mmif" keys of the
// `ema fit --stabilisation` JSON (docs/quality.md).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "ema/core/types.hpp"
#include "ema/curvefit/fit_data.hpp"

namespace ema::formats {

/// Adds {"cmif": {"frequency_hz", "values"}, "mmif": {...}} to `stabilisation`, computed on the
/// same band and lines as the fit (`options`).
void AddModeIndicatorsJson(nlohmann::json* stabilisation, const FrfSet& frfs, const curvefit::FitDataOptions& options,
                           const std::string& source);

}  // namespace ema::formats
