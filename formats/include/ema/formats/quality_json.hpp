// The data-quality report (frf::CheckFrfQuality + curvefit::CheckModeComplexity) as JSON: written
// by `ema quality --json`, read by the HTML report's "Data quality" section, returned by the
// Python package's ema.quality().
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "ema/curvefit/complexity.hpp"
#include "ema/frf/quality.hpp"

namespace ema::formats {

/// cli.md "ema quality": {"verdict", "warnings", "reciprocity": [...], "driving_points": [...],
/// "frfs": [...], "coherence_map": {"frequency_hz", "labels", "coherence"}, "modes": [...], "notes"}.
nlohmann::json QualityJson(const frf::FrfQualityReport& frfs, const std::vector<curvefit::ModeComplexityCheck>& modes,
                           const frf::QualityOptions& options);

}  // namespace ema::formats
