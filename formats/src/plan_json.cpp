// PLAN.json (`ema plan --json`).
#include "ema/formats/plan_json.hpp"

#include "ema/core/error.hpp"
#include "ema/diagnose/diagnose.hpp"
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
    // The σ they are in: the noise and the model's own error the diagnosis inferred (docs/plan.md).
    out["separation_sigma"] = {{"frequency_rel", NumberOrNull(plan.separation_frequency_sigma_rel)},
                               {"shape_dof", NumberOrNull(plan.separation_shape_sigma)}};
  }
  return ValidUtf8(std::move(out));
}

std::vector<planning::Reading> LookAlikeReadings(const std::vector<DiagnosisReading>& all, const std::string& origin,
                                                 size_t limit) {
  std::vector<planning::Reading> out;
  if (all.empty()) return out;
  const DiagnosisReading* first = nullptr;
  for (const auto& r : all)
    if (r.rank == 1 && !first) first = &r;
  if (!first) throw InputError(origin, "no candidate of rank 1; expected the `ema diagnose --json` of a diagnosis");
  const double p1 = first->probability;
  for (const auto& r : all) {
    if (r.effects.empty()) continue;  // the model as given
    const bool alike = r.rank == 1 || diagnose::IsLookAlike(r.probability, p1);  // the first screen's rule
    if (!alike) continue;
    out.push_back({r.kind + " on " + r.target, r.effects, origin + ", candidate rank " + std::to_string(r.rank)});
    if (out.size() == limit) break;
  }
  return out;
}

Plan PlanFileOf(const planning::TestPlan& plan, const std::optional<Plan>& keep, const std::string& setup) {
  Plan file;
  if (keep) {
    file = *keep;
  } else {
    file.hammer.references = plan.references;
    file.hammer.sample_rate_hz = plan.sample_rate_hz;
    file.hammer.samples_per_record = plan.samples;
    file.hammer.pulse_duration_s = plan.pulse_duration_s;
    file.hammer.impacts_per_reference = plan.impacts;
    file.hammer.force_noise = 0.01;
    file.hammer.response_noise = 0.01;
  }
  file.setup = setup;
  for (size_t s = file.sets.size(); s < plan.sets.size(); ++s) {
    RovingSet set;
    set.name = "set " + std::to_string(s + 1);
    set.sensors = plan.sets[s];
    if (plan.sensor_mass_kg > 0.0)
      for (const Dof& d : set.sensors) set.masses[d.node] = plan.sensor_mass_kg;
    file.sets.push_back(set);
  }
  file.hammer.roving_sets.clear();
  for (const RovingSet& s : file.sets) file.hammer.roving_sets.push_back(s.sensors);
  return file;
}

void AdoptKeptSettings(const Plan& keep, planning::TestPlan* plan) {
  plan->sample_rate_hz = keep.hammer.sample_rate_hz;
  plan->samples = keep.hammer.samples_per_record;
  plan->pulse_duration_s = keep.hammer.pulse_duration_s;
  plan->impacts = keep.hammer.impacts_per_reference;
}

}  // namespace ema::formats
