// PLAN.json of `ema plan --json` (../shared/spec/cli.md "ema plan", docs/plan.md).
#pragma once

#include <nlohmann/json.hpp>

#include "ema/planning/plan.hpp"

namespace ema::formats {

/// {"sensors": ["101+Z", ...], "references": [...], "sets": [{"name", "sensors"}],
/// "modes": [{"frequency_hz", "observability", "damping_ratio", "reference_participation",
/// "excited"}], "automac_max_offdiagonal", "automac", "band_hz", "acquisition": {...}, "notes",
/// and "separations": [{"a", "b", "sigma_before", "sigma_after"}] when `with_separations`}.
/// Set names are "set 1", "set 2", ... as the plan file writes them.
nlohmann::json TestPlanJson(const planning::TestPlan& plan, bool with_separations);

}  // namespace ema::formats
