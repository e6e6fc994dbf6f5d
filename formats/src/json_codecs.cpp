#include "ema/formats/json_codecs.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <string_view>

#include "ema/formats/model_file.hpp"
#include "ema/model/effects.hpp"

namespace ema::formats {

using json = nlohmann::json;

json NumberOrNull(double value) { return std::isfinite(value) ? json(value) : json(nullptr); }

json ComplexJson(std::complex<double> value) { return json::array({value.real(), value.imag()}); }

namespace {

// RFC 3629 UTF-8, byte ranges as in its table (and as nlohmann's decoder checks them).
bool IsUtf8(std::string_view s) {
  std::size_t i = 0;
  auto in = [&](std::size_t k, unsigned lo, unsigned hi) {
    if (k >= s.size()) return false;
    const unsigned c = static_cast<unsigned char>(s[k]);
    return c >= lo && c <= hi;
  };
  while (i < s.size()) {
    const unsigned c = static_cast<unsigned char>(s[i]);
    if (c < 0x80) {
      i += 1;
    } else if (c >= 0xC2 && c <= 0xDF) {
      if (!in(i + 1, 0x80, 0xBF)) return false;
      i += 2;
    } else if (c >= 0xE0 && c <= 0xEF) {
      const unsigned lo = c == 0xE0 ? 0xA0 : 0x80, hi = c == 0xED ? 0x9F : 0xBF;
      if (!in(i + 1, lo, hi) || !in(i + 2, 0x80, 0xBF)) return false;
      i += 3;
    } else if (c >= 0xF0 && c <= 0xF4) {
      const unsigned lo = c == 0xF0 ? 0x90 : 0x80, hi = c == 0xF4 ? 0x8F : 0xBF;
      if (!in(i + 1, lo, hi) || !in(i + 2, 0x80, 0xBF) || !in(i + 3, 0x80, 0xBF)) return false;
      i += 4;
    } else {
      return false;
    }
  }
  return true;
}

void MakeUtf8(json& j) {
  if (j.is_string()) {
    std::string& s = j.get_ref<std::string&>();
    if (!IsUtf8(s)) s = JsonText(s);
  } else if (j.is_array()) {
    for (json& e : j) MakeUtf8(e);
  } else if (j.is_object()) {
    bool keys = true;
    for (auto it = j.begin(); it != j.end(); ++it) {
      MakeUtf8(it.value());
      keys = keys && IsUtf8(it.key());
    }
    if (keys) return;
    json fixed = json::object();
    for (auto it = j.begin(); it != j.end(); ++it) fixed[JsonText(it.key())] = std::move(it.value());
    j = std::move(fixed);
  }
}

}  // namespace

std::string JsonText(std::string_view text) {
  if (IsUtf8(text)) return std::string(text);
  std::string out;
  out.reserve(text.size() + text.size() / 2);
  for (const char c : text) {
    const unsigned u = static_cast<unsigned char>(c);
    if (u < 0x80) {
      out.push_back(c);
    } else {
      out.push_back(static_cast<char>(0xC0 | (u >> 6)));
      out.push_back(static_cast<char>(0x80 | (u & 0x3F)));
    }
  }
  return out;
}

json ValidUtf8(json j) {
  MakeUtf8(j);
  return j;
}

json FrfSummaryJson(const frf::FrfResult& result) {
  const frf::FrfSummary& s = result.summary;
  const FrfSet& set = result.frfs;
  json frfs = json::array();
  for (const frf::FrfSummaryEntry& e : s.frfs) {
    json rejected = json::array();
    for (const frf::RejectedImpact& r : e.rejected)
      rejected.push_back({{"impact", r.impact}, {"reason", r.reason}, {"file", r.set}});
    frfs.push_back({{"response_node", e.response.node},
                    {"response_dir", DirectionName(e.response.direction)},
                    {"reference_node", e.reference.node},
                    {"reference_dir", DirectionName(e.reference.direction)},
                    {"averages", e.averages},
                    {"rejected", rejected}});
  }
  const int lines = set.LineCount();
  return ValidUtf8({{"frfs", frfs},
          {"estimator", frf::EstimatorName(s.estimator)},
          {"window_decay_rate", s.window_decay_rate},
          {"roving_hammer", s.roving_hammer},
          {"impacts", s.impacts},
          {"rejected_impacts", s.rejected_impacts},
          {"lines", lines},
          {"frequency_min_hz", lines > 0 ? set.frequency_hz[0] : 0.0},
          {"frequency_max_hz", lines > 0 ? set.frequency_hz[lines - 1] : 0.0},
          {"notes", s.notes}});
}

json ModeJson(const ModeSet& set, std::size_t mode) {
  const Mode& m = set.modes[mode];
  json shape = json::array();
  for (std::size_t d = 0; d < set.dofs.size(); ++d) {
    const auto i = static_cast<Eigen::Index>(d);
    json entry = {{"node", set.dofs[d].node}, {"dir", DirectionName(set.dofs[d].direction)}, {"value", ComplexJson(m.shape[i])}};
    if (m.shape_std.size() == m.shape.size()) entry["std"] = NumberOrNull(m.shape_std[i]);
    shape.push_back(entry);
  }
  json participation = json::array();
  for (Eigen::Index i = 0; i < m.participation.size(); ++i) participation.push_back(ComplexJson(m.participation[i]));
  json out = {{"frequency_hz", m.frequency_hz},
          {"damping_ratio", m.damping_ratio},
          {"frequency_std_hz", NumberOrNull(m.frequency_std_hz)},
          {"damping_ratio_std", NumberOrNull(m.damping_ratio_std)},
          {"mpc", NumberOrNull(m.mpc)},
          {"mpd_deg", NumberOrNull(m.mpd)},
          {"mcf", NumberOrNull(m.mcf)},
          {"pole", ComplexJson(m.pole)},
          {"frequency_spread_hz", NumberOrNull(m.frequency_spread_hz)},
          {"damping_spread", NumberOrNull(m.damping_spread)},
          {"unit_modal_mass", m.unit_modal_mass},
          {"participation", participation},
          {"shape", shape}};
  // Roving-sensor tests: the mode as each roving set saw it (frequency_hz is their mean).
  if (!m.set_frequency_hz.empty()) {
    json sets = json::array();
    for (std::size_t k = 0; k < m.set_frequency_hz.size(); ++k)
      sets.push_back({{"frequency_hz", m.set_frequency_hz[k]},
                      {"damping_ratio", k < m.set_damping_ratio.size() ? NumberOrNull(m.set_damping_ratio[k]) : json()},
                      {"frequency_std_hz",
                       k < m.set_frequency_std_hz.size() ? NumberOrNull(m.set_frequency_std_hz[k]) : json()}});
    out["sets"] = sets;
  }
  return out;
}

json ModeSetJson(const ModeSet& set) {
  json modes = json::array();
  for (std::size_t r = 0; r < set.modes.size(); ++r) modes.push_back(ModeJson(set, r));
  return {{"modes", modes}};
}

namespace {

json RefinementJson(const curvefit::FitResult& fit, curvefit::RefineMethod method) {
  const auto& r = fit.refine;
  return {{"method", curvefit::RefineMethodToString(method)},
          {"termination", curvefit::RefineTerminationToString(r.termination)},
          {"noise_source", curvefit::NoiseSourceToString(r.noise_source)},
          {"iterations", r.iterations},
          {"initial_cost", NumberOrNull(r.initial_cost)},
          {"final_cost", NumberOrNull(r.final_cost)},
          {"reduced_chi2", NumberOrNull(r.reduced_chi2)},
          {"message", r.message}};
}

}  // namespace

json TestSetsJson(const FrfSet& frfs) {
  json out = json::object();
  if (!frfs.output_sets.empty() && frfs.output_sets.size() == frfs.outputs.size()) out["roving_sets"] = frfs.RovingSetNodes();
  if (frfs.references.size() == 1)
    out["reference"] = {{"node", frfs.references[0].node}, {"dir", DirectionName(frfs.references[0].direction)}};
  return out;
}

bool ReadTestSets(const json& j, std::vector<std::vector<int>>* roving_sets, Dof* reference) {
  if (!j.is_object() || !j.contains("roving_sets") || !j["roving_sets"].is_array()) return false;
  std::vector<std::vector<int>> sets;
  for (const json& set : j["roving_sets"]) {
    if (!set.is_array()) return false;
    std::vector<int> nodes;
    for (const json& n : set) {
      if (!n.is_number_integer() || n.get<long long>() <= 0 || n.get<long long>() > 2147483647) return false;
      nodes.push_back(static_cast<int>(n.get<long long>()));
    }
    sets.push_back(std::move(nodes));
  }
  *roving_sets = std::move(sets);
  if (j.contains("reference") && j["reference"].is_object() && j["reference"].contains("node") &&
      j["reference"]["node"].is_number_integer() && j["reference"].contains("dir") && j["reference"]["dir"].is_string())
    *reference = {static_cast<int>(j["reference"]["node"].get<long long>()),
                  ParseDirection(j["reference"]["dir"].get<std::string>())};
  return true;
}

json ModalModelJson(const curvefit::ModalModel& model) {
  json poles = json::array();
  for (const auto& p : model.poles_fitted) poles.push_back(ComplexJson(p));
  json frfs = json::array();
  const int m = static_cast<int>(model.references.size());
  for (int o = 0; o < static_cast<int>(model.outputs.size()); ++o)
    for (int i = 0; i < m; ++i) {
      const int c = o * m + i;
      // Measured orientation: the response is the output unless the fit used reciprocity.
      const Dof& response = model.transposed ? model.references[i] : model.outputs[o];
      const Dof& reference = model.transposed ? model.outputs[o] : model.references[i];
      json residues = json::array();
      for (int r = 0; r < model.residues.cols(); ++r) residues.push_back(ComplexJson(model.residues(c, r)));
      frfs.push_back({{"response_node", response.node},
                      {"response_dir", DirectionName(response.direction)},
                      {"reference_node", reference.node},
                      {"reference_dir", DirectionName(reference.direction)},
                      {"residues", residues},
                      {"lower_residual", c < model.lower_residual.size() ? model.lower_residual[c] : 0.0},
                      {"upper_residual", c < model.upper_residual.size() ? model.upper_residual[c] : 0.0}});
    }
  const char* type = model.frf_type == FrfType::kReceptance ? "receptance"
                     : model.frf_type == FrfType::kMobility ? "mobility"
                                                             : "accelerance";
  return {{"frf_type", type}, {"band_hz", {model.band_lo_hz, model.band_hi_hz}}, {"poles", poles}, {"frfs", frfs}};
}

json FitModesJson(const curvefit::FitResult& fit, curvefit::RefineMethod refine) {
  json out = ModeSetJson(fit.modes);
  for (std::size_t r = 0; r < fit.modes.modes.size() && r < fit.selected.size(); ++r) {
    out["modes"][r]["order"] = fit.selected[r].pole.order;
    out["modes"][r]["cluster_orders"] = fit.selected[r].cluster_size;
  }
  out["synthesis_error"] = fit.synthesis_error;
  out["reciprocity_transposed"] = fit.transposed;
  if (!fit.diagram.orders.empty())
    out["polymax"] = {{"orders", {fit.diagram.order_min, fit.diagram.order_max}},
                      {"zoom_band", fit.diagram.zoom_mapped},
                      {"selection", fit.selection_rule}};
  if (!fit.dropped.empty()) {
    json dropped = json::array();
    for (const auto& d : fit.dropped)
      dropped.push_back({{"frequency_hz", d.frequency_hz},
                         {"damping_ratio", d.damping_ratio},
                         {"merged_into_hz", NumberOrNull(d.merged_into_hz)},
                         {"reason", d.reason}});
    out["dropped"] = dropped;
  }
  if (!fit.selected.empty()) {
    out["refinement"] = RefinementJson(fit, refine);
    out["modal_model"] = ModalModelJson(fit.model);
  }
  return ValidUtf8(std::move(out));
}

json StabilisationJson(const curvefit::FitResult& fit, const curvefit::StabilityOptions& stab) {
  const auto& d = fit.diagram;
  json orders = json::array();
  for (std::size_t k = 0; k < d.orders.size(); ++k) {
    json poles = json::array();
    for (const auto& p : d.orders[k]) {
      json part = json::array();
      for (Eigen::Index i = 0; i < p.participation.size(); ++i) part.push_back(ComplexJson(p.participation[i]));
      poles.push_back({{"frequency_hz", p.frequency_hz},
                       {"damping_ratio", p.damping_ratio},
                       {"pole", ComplexJson(p.lambda)},
                       {"label", std::string(1, p.label)},
                       {"physical", p.physical},
                       {"participation", part}});
    }
    orders.push_back({{"order", d.order_min + static_cast<int>(k)}, {"poles", poles}});
  }
  json selected = json::array();
  for (const auto& s : fit.selected)
    selected.push_back({{"order", s.pole.order},
                        {"frequency_hz", s.pole.frequency_hz},
                        {"damping_ratio", s.pole.damping_ratio},
                        {"frequency_spread_hz", NumberOrNull(s.frequency_spread_hz)},
                        {"damping_spread", NumberOrNull(s.damping_spread)},
                        {"cluster_orders", s.cluster_size}});
  json mif = json::array();
  for (Eigen::Index k = 0; k < d.frequency_hz.size(); ++k) mif.push_back({d.frequency_hz[k], d.sum_frf[k]});
  return ValidUtf8({{"band_hz", {d.band_lo_hz, d.band_hi_hz}},
          {"references", d.references},
          {"order_min", d.order_min},
          {"order_max", d.order_max},
          {"criteria", {{"frequency_tol", stab.frequency_tol}, {"damping_tol", stab.damping_tol}, {"mac_min", stab.mac_min}}},
          {"labels", {{"s", "stable (frequency, damping, vector)"}, {"d", "frequency and damping"},
                      {"v", "frequency and vector"}, {"f", "frequency"}, {"o", "new or unstable"}}},
          {"orders", orders},
          {"selected", selected},
          {"sum_frf", mif}});
}

json ModelSolutionJson(const model::Model& model, const model::Solution& sol, const std::string& setup) {
  json j = ModeSetJson(sol.modes);
  j["model"] = model.name;
  j["setup"] = setup;
  j["rigid_body_frequencies_hz"] = sol.rigid_body_frequencies_hz;
  j["springs"] = json::array();
  for (const model::SpringState& s : sol.springs) {
    json js{{"name", s.name},     {"group", s.group},             {"law", s.law},
            {"force_n", s.force}, {"deflection_m", s.deflection}, {"stiffness_n_per_m", s.stiffness}};
    if (!std::isnan(s.gap)) js["gap_m"] = s.gap;
    if (!s.element_deflections.empty()) {
      js["element_deflections_m"] = s.element_deflections;
      js["element_stiffnesses_n_per_m"] = s.element_stiffnesses;
    }
    j["springs"].push_back(js);
  }
  j["energy_share"] = json::array();
  for (const model::EnergyShare& e : sol.energy) j["energy_share"].push_back({{"body", e.body}, {"share", e.share}});
  return ValidUtf8(std::move(j));
}

json CorrelationJson(const correlation::CorrelationResult& r, const ModeSet& test, const ModeSet& model) {
  json out;
  out["pairs"] = json::array();
  for (const auto& row : r.rows) {
    if (!row.paired()) continue;
    out["pairs"].push_back({{"test_mode", row.test_mode + 1},
                            {"model_mode", row.model_mode + 1},
                            {"test_frequency_hz", row.test_frequency_hz},
                            {"test_damping_ratio", NumberOrNull(row.test_damping_ratio)},
                            {"model_frequency_hz", row.model_frequency_hz},
                            {"agreement_pct", row.agreement_pct},
                            {"frequency_error_pct", row.frequency_error_pct},
                            {"mac", row.mac},
                            {"remark", row.remark}});
  }
  out["unpaired_test"] = json::array();
  for (int i : r.pairing.unpaired_test)
    out["unpaired_test"].push_back({{"test_mode", i + 1},
                                    {"test_frequency_hz", test.modes[i].frequency_hz},
                                    {"test_damping_ratio", NumberOrNull(test.modes[i].damping_ratio)}});
  out["unpaired_model"] = json::array();
  for (int j : r.pairing.unpaired_model)
    out["unpaired_model"].push_back({{"model_mode", j + 1}, {"model_frequency_hz", model.modes[j].frequency_hz}});
  out["summary"] = {{"mean_agreement_pct", NumberOrNull(r.mean_agreement_pct)},
                    {"min_agreement_pct", NumberOrNull(r.min_agreement_pct)},
                    {"mean_mac", NumberOrNull(r.mean_mac)},
                    {"mean_abs_frequency_error_pct", NumberOrNull(r.mean_abs_frequency_error_pct)},
                    {"shared_dofs", r.shared_dof_count},
                    {"test_dofs", r.test_dof_count},
                    {"paired", r.pairing.pairs.size()}};
  out["comac"] = json::array();
  for (const auto& c : r.comac)
    out["comac"].push_back({{"node", c.dof.node}, {"dir", DirectionName(c.dof.direction)}, {"comac", c.comac}});
  json mac = json::array();
  for (Eigen::Index i = 0; i < r.mac.rows(); ++i) {
    json row = json::array();
    for (Eigen::Index j = 0; j < r.mac.cols(); ++j) row.push_back(r.mac(i, j));
    mac.push_back(row);
  }
  out["mac"] = mac;  // rows: test modes, columns: model modes
  return ValidUtf8(std::move(out));
}

json EffectJson(const model::Effect& e) {
  json out = {
      {"kind", model::KindName(e.kind)}, {"target", model::TargetText(e.target)}, {"parameters", json::object()}};
  for (const auto& [k, v] : e.parameters) out["parameters"][k] = v;
  if (e.law) out["law"] = LawToToml(*e.law);
  return ValidUtf8(std::move(out));
}

namespace {

json CandidateJson(const diagnose::Candidate& c) {
  json out = {{"rank", c.rank},
              {"kind", c.kind},
              {"target", c.target},
              {"parameters", json::object()},
              {"uncertainty", json::object()},
              {"prior_sigma", json::object()},
              {"probability", NumberOrNull(c.probability)},
              {"mean_abs_frequency_error_pct", NumberOrNull(c.mean_abs_frequency_error_pct)},
              {"mean_mac", NumberOrNull(c.mean_mac)},
              {"mean_agreement_pct", NumberOrNull(c.mean_agreement_pct)},
              {"score", NumberOrNull(c.score)},
              {"log_evidence", NumberOrNull(c.log_evidence)},
              {"log_prior", NumberOrNull(c.log_prior)},
              {"cost", NumberOrNull(c.cost)},
              {"explained_pct", NumberOrNull(c.explained_pct)},
              {"paired_modes", c.paired_modes},
              {"plausible", c.plausible},
              {"reduced_chi2", NumberOrNull(c.reduced_chi2)},
              {"noise_consistent", c.noise_consistent},
              {"flags", c.flags},
              {"prior_z", json::object()},
              {"tied_with", c.tied_with},
              {"description", diagnose::DescribeCandidate(c)},
              {"effects", json::array()}};
  const std::vector<std::string> keys = diagnose::ParameterKeys(c);
  for (std::size_t i = 0; i < c.parameters.size(); ++i) {
    const auto& p = c.parameters[i];
    out["parameters"][keys[i]] = p.value;
    out["uncertainty"][keys[i]] = NumberOrNull(p.sigma);
    out["prior_sigma"][keys[i]] = NumberOrNull(p.prior_sigma);
    out["prior_z"][keys[i]] = NumberOrNull(p.prior_z);
    if (p.at_bound) out["at_bound"].push_back(keys[i]);
    if (p.outside_prior) out["outside_prior"].push_back(keys[i]);
  }
  if (c.reduced_model) out["reduced_model"] = true;
  // cli.md, added turn 4: the model's own error inferred with this candidate, and the effects
  // whose value lies beyond 3σ of the stated uncertainty.
  out["model_error"] = ModelErrorJson(c.model_error);
  out["outside_stated"] = json::array();
  for (const auto& p : c.parameters)
    if (p.outside_prior)
      out["outside_stated"].push_back(
          {{"target", model::TargetText(p.target)}, {"sigmas", NumberOrNull(std::abs(p.prior_z))}});
  // Evidence per test mode: where the candidate leaves the model against the test, in σ.
  out["modes"] = json::array();
  for (const auto& m : c.modes)
    out["modes"].push_back({{"setup", m.setup},
                            {"test", m.test + 1},
                            {"test_mode", m.test_mode + 1},
                            {"test_frequency_hz", m.test_frequency_hz},
                            {"sigma_hz", NumberOrNull(m.sigma_hz)},
                            {"model_frequency_hz", NumberOrNull(m.model_frequency_hz)},
                            {"frequency_misfit_sigma", NumberOrNull(m.frequency_misfit_sigma)},
                            {"mac", NumberOrNull(m.mac)},
                            {"shape_misfit_sigma", NumberOrNull(m.shape_misfit_sigma)}});
  for (const auto& e : c.effects) out["effects"].push_back(EffectJson(e));
  if (!c.error.empty()) out["error"] = c.error;
  return out;
}

}  // namespace

json ModelErrorJson(const diagnose::ModelError& error) {
  return {{"frequency_rel", NumberOrNull(error.frequency_rel)},
          {"shape", NumberOrNull(error.shape)},
          {"frequency_common_rel", NumberOrNull(error.frequency_common_rel)},
          {"dominates", error.dominates}};
}

json DiagnosisJson(const diagnose::Diagnosis& d, const diagnose::DiagnoseOptions& options) {
  json out;
  out["baseline"] = {{"mean_abs_frequency_error_pct", NumberOrNull(d.baseline.mean_abs_frequency_error_pct)},
                     {"mean_mac", NumberOrNull(d.baseline.mean_mac)},
                     {"mean_agreement_pct", NumberOrNull(d.baseline.mean_agreement_pct)},
                     {"score", NumberOrNull(d.baseline.score)},
                     {"cost", NumberOrNull(d.baseline.cost)},
                     {"paired_modes", d.baseline.paired_modes}};
  out["candidates"] = json::array();
  for (const auto& c : d.candidates) out["candidates"].push_back(CandidateJson(c));
  if (!d.candidates.empty()) out["model_error"] = out["candidates"].front()["model_error"];  // rank 1's (cli.md)
  out["criterion"] = diagnose::CriterionToString(options.criterion);
  out["options"] = {{"frequency_floor", options.frequency_floor}, {"shape_sigma", options.shape_sigma},
                    {"shape_residual", diagnose::ShapeResidualToString(options.shape_residual)},
                    {"shape_dof_sigma", options.shape_dof_sigma},
                    {"max_effects", options.max_effects}, {"members", options.members},
                    {"model_error", options.model_error}, {"effect_prior_odds", options.effect_prior_odds},
                    {"mac_min", options.pairing.mac_min}};  // the effective options, for reproducibility
  out["residual_count"] = d.residual_count;
  out["test_modes"] = d.test_mode_count;
  out["model_solves"] = d.model_solves;
  out["candidates_screened"] = d.candidates_screened;
  out["explanation"] = d.explanation;
  out["effect_probabilities"] = json::array();
  for (const auto& e : d.effect_probabilities)
    out["effect_probabilities"].push_back(
        {{"kind", model::KindName(e.kind)}, {"target", model::TargetText(e.target)}, {"probability", e.probability}});
  // Look-alike candidates folded into one row each (the same reading on another member or point).
  out["groups"] = json::array();
  for (const auto& g : d.groups)
    out["groups"].push_back({{"kind", g.kind}, {"target", g.target}, {"ranks", g.ranks}, {"probability", g.probability}});
  out["steps"] = json::array();
  for (const auto& st : d.steps)
    out["steps"].push_back({{"added", st.added},
                            {"mean_abs_frequency_error_pct", NumberOrNull(st.mean_abs_frequency_error_pct)},
                            {"mean_mac", NumberOrNull(st.mean_mac)},
                            {"mean_agreement_pct", NumberOrNull(st.mean_agreement_pct)}});
  return ValidUtf8(std::move(out));
}

json DiagnosisModeRows(const diagnose::Candidate& before, const diagnose::Candidate& after) {
  json rows = json::array();
  for (std::size_t i = 0; i < before.modes.size() && i < after.modes.size(); ++i) {
    const auto& b = before.modes[i];
    const auto& a = after.modes[i];
    rows.push_back({{"setup", b.setup},
                    {"test", b.test + 1},
                    {"test_mode", b.test_mode + 1},
                    {"test_frequency_hz", b.test_frequency_hz},
                    {"model_frequency_hz_before", NumberOrNull(b.model_frequency_hz)},
                    {"agreement_pct_before", NumberOrNull(b.agreement_pct)},
                    {"mac_before", NumberOrNull(b.mac)},
                    {"model_frequency_hz_after", NumberOrNull(a.model_frequency_hz)},
                    {"agreement_pct_after", NumberOrNull(a.agreement_pct)},
                    {"mac_after", NumberOrNull(a.mac)},
                    {"sigma_hz", NumberOrNull(b.sigma_hz)},
                    {"frequency_misfit_sigma_before", NumberOrNull(b.frequency_misfit_sigma)},
                    {"frequency_misfit_sigma_after", NumberOrNull(a.frequency_misfit_sigma)},
                    {"shape_misfit_sigma_before", NumberOrNull(b.shape_misfit_sigma)},
                    {"shape_misfit_sigma_after", NumberOrNull(a.shape_misfit_sigma)}});
  }
  return ValidUtf8(std::move(rows));
}

}  // namespace ema::formats
