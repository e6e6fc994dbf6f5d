// PLAN.json of `ema plan --json` (../shared/spec/cli.md "ema plan", docs/plan.md).
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ema/formats/diagnosis_readings.hpp"
#include "ema/formats/plan_file.hpp"
#include "ema/planning/plan.hpp"

namespace ema::formats {

/// {"sensors": ["101+Z", ...], "references": [...], "sets": [{"name", "sensors"}],
/// "modes": [{"frequency_hz", "observability", "damping_ratio", "reference_participation",
/// "excited"}], "automac_max_offdiagonal", "automac", "band_hz", "acquisition": {...}, "notes",
/// and "separations": [{"a", "b", "sigma_before", "sigma_after"}] when `with_separations`}.
/// Set names are "set 1", "set 2", ... as the plan file writes them.
nlohmann::json TestPlanJson(const planning::TestPlan& plan, bool with_separations);

/// The readings a diagnosis cannot tell apart (docs/plan.md "Telling look-alikes apart"): rank 1
/// and every other candidate within a factor 20 of its probability (and at least 0.001) — the
/// first screen's look-alike rule — "none" left out, at most `limit`. `origin` names the file in
/// messages (each reading's origin: "ORIGIN, candidate rank N"). InputError without a rank 1.
std::vector<planning::Reading> LookAlikeReadings(const std::vector<DiagnosisReading>& all, const std::string& origin,
                                                 size_t limit = 10);

/// The plan file of a test plan (what `ema plan` and `ema.plan` write): with `keep`, its settings
/// and sets as they were and the new sets after; else the plan's references, sampling, tip and
/// impacts with 1 % noise on force and response (a careful test, as the samples have). `setup`:
/// the setup the plan was made in. Sets are named "set 1", "set 2", ...; each new set carries the
/// plan's sensor mass at its points.
Plan PlanFileOf(const planning::TestPlan& plan, const std::optional<Plan>& keep, const std::string& setup);

/// A plan that extends `keep` measures with its settings: the plan's sampling, record, tip and
/// impacts become the kept plan's (what PLAN.json then reports).
void AdoptKeptSettings(const Plan& keep, planning::TestPlan* plan);

}  // namespace ema::formats
