#include "ema/formats/amplitude_json.hpp"

#include "ema/formats/json_codecs.hpp"

namespace ema::formats {

using json = nlohmann::json;

json AmplitudeJson(const correlation::AmplitudeResult& r) {
  json modes = json::array();
  for (std::size_t i = 0; i < r.modes.size(); ++i) {
    const correlation::AmplitudeMode& m = r.modes[i];
    json levels = json::array();
    for (const correlation::AmplitudePoint& p : m.points)
      levels.push_back({{"level", p.level},
                        {"frequency_hz", p.frequency_hz},
                        {"damping_ratio", p.damping_ratio},
                        {"frequency_std_hz", NumberOrNull(p.frequency_std_hz)},
                        {"damping_ratio_std", NumberOrNull(p.damping_ratio_std)},
                        {"poles", p.poles}});
    modes.push_back({{"mode", i + 1},
                     {"levels", levels},
                     {"frequency_trend", correlation::FrequencyTrendToString(m.frequency_trend)},
                     {"frequency_change_pct", m.frequency_change_pct},
                     {"damping_trend", correlation::DampingTrendToString(m.damping_trend)},
                     {"damping_ratio_factor", NumberOrNull(m.damping_ratio_factor)},
                     {"frequency_slope_z", m.frequency_slope_z},
                     {"frequency_extreme_z", m.frequency_extreme_z},
                     {"damping_slope_z", m.damping_slope_z},
                     {"target_level", m.points[static_cast<std::size_t>(m.target_point)].level},
                     {"reading", m.reading}});
  }
  // The readings are text: valid UTF-8 whatever bytes they hold (formats::ValidUtf8).
  return ValidUtf8({{"level_kind", correlation::LevelKindToString(r.level_kind)}, {"levels", r.levels}, {"modes", modes}});
}

}  // namespace ema::formats
