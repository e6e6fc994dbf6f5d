// PLAN.json (`ema plan --json`).
#include "ema/formats/plan_json.hpp"

#include "ema/formats/json_codecs.hpp"

namespace ema::formats {

nlohmann::json TestPlanJson(const planning::TestPlan& plan, bool with_separations) {
  using nlohmann::json;
  auto names = [](const std::vector<Dof>& dofs) {
    json out = json::array();
    for (const Dof& d : dofs) out.push_back(DofName(d));
    return out;
  };
  json out = {{"sensors", names(plan.Sensors())}, {"references", names(plan.references)}, {"sets", json::array()},
              {"modes", json::array()}, {"automac_max_offdiagonal", NumberOrNull(plan.automac_max_offdiagonal)},
              {"automac", json::array()},
              {"band_hz", {NumberOrNull(plan.band_lo_hz), NumberOrNull(plan.band_hi_hz)}},
              {"acquisition",
               {{"sample_rate_hz", NumberOrNull(plan.sample_rate_hz)},
                {"samples", plan.samples},
                {"record_length_s", NumberOrNull(plan.sample_rate_hz > 0.0 ? plan.samples / plan.sample_rate_hz : kNaN)},
                {"pulse_duration_s", NumberOrNull(plan.pulse_duration_s)},
                {"impacts", plan.impacts},
                {"sensor_mass_kg", NumberOrNull(plan.sensor_mass_kg)}}},
              {"notes", plan.notes}};
  for (size_t s = 0; s < plan.sets.size(); ++s)
    out["sets"].push_back({{"name", "set " + std::to_string(s + 1)}, {"sensors", names(plan.sets[s])}});
  for (const planning::PlannedMode& m : plan.modes)
    out["modes"].push_back({{"frequency_hz", NumberOrNull(m.frequency_hz)},
                            {"observability", NumberOrNull(m.observability)},
                            {"damping_ratio", NumberOrNull(m.damping_ratio)},
                            {"reference_participation", NumberOrNull(m.reference_participation)},
                            {"excited", m.excited}});
  for (Eigen::Index i = 0; i < plan.automac.rows(); ++i) {
    json row = json::array();
    for (Eigen::Index j = 0; j < plan.automac.cols(); ++j) row.push_back(NumberOrNull(plan.automac(i, j)));
    out["automac"].push_back(row);
  }
  if (with_separations) {
    out["separations"] = json::array();
    for (const planning::Separation& s : plan.separations)
      out["separations"].push_back({{"a", s.a}, {"b", s.b}, {"sigma_before", NumberOrNull(s.sigma_before)},
                                    {"sigma_after", NumberOrNull(s.sigma_after)}});
  }
  return ValidUtf8(std::move(out));
}

}  // namespace ema::formats
