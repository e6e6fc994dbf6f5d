// The data-quality report (frf::CheckFrfQuality + curvefit::CheckModeComplexity) as JSON and as
// a text summary: shared by `ema quality` and the HTML report's "Data quality" section.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ema/curvefit/complexity.hpp"
#include "ema/frf/quality.hpp"

namespace ema {

/// cli.md "ema quality": {"verdict", "warnings", "reciprocity": [...], "driving_points": [...],
/// "frfs": [...], "coherence_map": {"frequency_hz", "labels", "coherence"}, "modes": [...], "notes"}.
nlohmann::json QualityJson(const frf::FrfQualityReport& frfs, const std::vector<curvefit::ModeComplexityCheck>& modes,
                           const frf::QualityOptions& options);

/// Human summary: one line per check that warns, counts of those that pass.
std::string QualityText(const frf::FrfQualityReport& frfs, const std::vector<curvefit::ModeComplexityCheck>& modes);

}  // namespace ema
