// Data of the report's "Data quality" section and of the mode indicators drawn on the
// stabilisation diagram, prepared from the JSON the steps wrote (`ema quality`'s layout,
// `ema fit --stabilisation` "cmif"/"mmif", `ema fit --json` mpc/mpd_deg/mcf).
#pragma once

#include <nlohmann/json.hpp>

namespace ema::report {

/// {"verdict", "warnings", "reciprocity", "driving_points", "frfs_warn": [...], "notes",
///  "coherence_map": {"frequency_hz", "labels", "z"} (at most kMaxMapColumns columns, each the
///  minimum of the lines it stands for, so dips stay visible), "modes": [{"mode", "frequency_hz",
///  "mpc", "mpd_deg", "mcf"}]}; an empty object when neither input carries anything.
nlohmann::json QualityData(const nlohmann::json& quality, const nlohmann::json& test_modes);

/// {"frequency_hz", "cmif": [[first singular value], [second]], "mmif": [smallest eigenvalue]} from
/// the stabilisation JSON; an empty object when it has no "cmif".
nlohmann::json ModeIndicatorData(const nlohmann::json& stabilisation);

inline constexpr int kMaxMapColumns = 400;

/// `value` to `significant` digits ("%.*g"): the page carries no more than a plot can show.
/// Not finite: unchanged.
double RoundToDigits(double value, int significant);

}  // namespace ema::report
