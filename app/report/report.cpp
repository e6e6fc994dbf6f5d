// Assembles the report page: the data object (report_data.cpp helpers) and the embedded assets.
#include "report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "ema/core/text.hpp"
#include "ema/formats/json_codecs.hpp"
#include "ema/formats/quality_json.hpp"
#include "ema/pipeline/json.hpp"
#include "embedded_assets.hpp"
#include "words.hpp"
#include "report_quality.hpp"

namespace ema::report {

namespace {

using json = nlohmann::json;

// Five significant digits: plenty for a plot, and keeps the page small.
double Round(double value) { return RoundToDigits(value, 5); }

json Rounded(const Eigen::VectorXd& values) {
  json out = json::array();
  for (double v : values) out.push_back(std::isfinite(v) ? json(Round(v)) : json(nullptr));
  return out;
}

std::string Label(const Dof& dof) { return DofName(dof); }

// Lines shown in the FRF and stabilisation plots: the fit band widened by 10 %, or everything.
std::vector<int> DisplayLines(const FrfSet& frfs, double lo, double hi) {
  std::vector<int> lines;
  const bool band = hi > lo;
  const double margin = band ? 0.1 * (hi - lo) : 0.0;
  for (int i = 0; i < frfs.LineCount(); ++i) {
    const double f = frfs.frequency_hz[i];
    if (f <= 0.0) continue;
    if (band && (f < lo - margin || f > hi + margin)) continue;
    lines.push_back(i);
  }
  // At most ~1500 points per trace: stride the lines if the FRFs are finer than a screen can show.
  const int stride = std::max<int>(1, static_cast<int>(lines.size()) / 1500 + 1);
  if (stride > 1) {
    std::vector<int> kept;
    for (size_t i = 0; i < lines.size(); i += stride) kept.push_back(lines[i]);
    lines.swap(kept);
  }
  return lines;
}

json FrfData(const SetupResults& setup) {
  json out = json::object();
  if (!setup.frfs || setup.frfs->LineCount() == 0) return out;
  const FrfSet& frfs = *setup.frfs;
  const std::vector<int> lines = DisplayLines(frfs, setup.band_lo_hz, setup.band_hi_hz);
  Eigen::VectorXd f(static_cast<int>(lines.size()));
  for (int i = 0; i < f.size(); ++i) f[i] = frfs.frequency_hz[lines[i]];
  out["frequency_hz"] = Rounded(f);
  // The fit's own modal model (refined poles, residues, residual terms); no fit: no fit curve.
  const Eigen::VectorXcd no_fit = Eigen::VectorXcd::Constant(frfs.LineCount(), {kNaN, kNaN});
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(f.size());
  json list = json::array();
  for (int r = 0; r < frfs.ReferenceCount(); ++r) {
    for (int o = 0; o < frfs.OutputCount(); ++o) {
      const Eigen::VectorXcd h = frfs.h[r].col(o);
      if (!h.allFinite() && !(h.array() == h.array()).any()) continue;  // not measured
      const Eigen::VectorXcd fit =
          setup.fit ? curvefit::SynthesiseMeasuredFrf(setup.fit->model, frfs.outputs[o], frfs.references[r], frfs.frequency_hz)
                    : no_fit;
      Eigen::VectorXd mag(f.size()), phase(f.size()), fit_mag(f.size()), fit_phase(f.size());
      for (int i = 0; i < f.size(); ++i) {
        const std::complex<double> v = h[lines[i]], w = fit[lines[i]];
        mag[i] = std::abs(v);
        phase[i] = std::arg(v) * 180.0 / M_PI;
        fit_mag[i] = std::abs(w);
        fit_phase[i] = std::arg(w) * 180.0 / M_PI;
        if (std::isfinite(mag[i])) sum[i] += mag[i];
      }
      json item = {{"label", Label(frfs.outputs[o]) + " / " + Label(frfs.references[r])},
                   {"magnitude", Rounded(mag)},
                   {"phase_deg", Rounded(phase)},
                   {"fit_magnitude", Rounded(fit_mag)},
                   {"fit_phase_deg", Rounded(fit_phase)}};
      if (!frfs.coherence.empty() && r < static_cast<int>(frfs.coherence.size()) && frfs.coherence[r].cols() > o) {
        Eigen::VectorXd coh(f.size());
        for (int i = 0; i < f.size(); ++i) coh[i] = frfs.coherence[r](lines[i], o);
        item["coherence"] = Rounded(coh);
      }
      list.push_back(std::move(item));
    }
  }
  out["frfs"] = std::move(list);
  out["sum_magnitude"] = Rounded(sum);
  out["unit"] = frfs.response_unit + "/" + frfs.force_unit;
  return out;
}

// The MAC matrix of the correlation step (test modes as rows), not recomputed here.
json MacData(const std::optional<CorrelationView>& correlation) {
  if (!correlation) return json::object();
  const Eigen::MatrixXd& mac = correlation->result.mac;
  json values = json::array();
  for (Eigen::Index i = 0; i < mac.rows(); ++i) {
    json row = json::array();
    for (Eigen::Index j = 0; j < mac.cols(); ++j) row.push_back(std::isfinite(mac(i, j)) ? json(Round(mac(i, j))) : json(nullptr));
    values.push_back(std::move(row));
  }
  auto labels = [](const ModeSet& set, const char* prefix) {
    json out = json::array();
    for (size_t m = 0; m < set.modes.size(); ++m) {
      char text[64];
      std::snprintf(text, sizeof text, "%s%zu %.1f Hz", prefix, m + 1, set.modes[m].frequency_hz);
      out.push_back(text);
    }
    return out;
  };
  return {{"test", labels(correlation->test, "T")},
          {"model", labels(correlation->model, "M")},
          {"values", values},
          {"shared_dofs", correlation->result.shared_dof_count}};
}

json ModeData(const ModeSet& test, const SetupResults& setup) {
  json out = json::object();
  if (test.modes.empty() || setup.geometry.empty()) return out;
  json nodes = json::array();
  std::map<int, int> index;
  for (const Node& node : setup.geometry) {
    index[node.id] = static_cast<int>(nodes.size());
    nodes.push_back({{"id", node.id},
                     {"x", Round(node.position.x())},
                     {"y", Round(node.position.y())},
                     {"z", Round(node.position.z())}});
  }
  json modes = json::array();
  for (const Mode& mode : test.modes) {
    // Per node: [re x, re y, re z, im x, im y, im z], normalised to the largest translation; a
    // value measured along -X is drawn as the opposite value along +X.
    std::vector<std::array<std::complex<double>, 3>> u(setup.geometry.size());
    double largest = 0.0;
    for (size_t d = 0; d < test.dofs.size() && static_cast<Eigen::Index>(d) < mode.shape.size(); ++d) {
      const Dof& dof = test.dofs[d];
      auto it = index.find(dof.node);
      const int axis = std::abs(dof.direction);
      if (it == index.end() || axis < 1 || axis > 3) continue;
      const std::complex<double> value = dof.direction < 0 ? -mode.shape[static_cast<Eigen::Index>(d)]
                                                           : mode.shape[static_cast<Eigen::Index>(d)];
      u[it->second][axis - 1] = value;
      largest = std::max(largest, std::abs(value));
    }
    json shape = json::array();
    for (const auto& v : u) {
      json row = json::array();
      for (int k = 0; k < 3; ++k) row.push_back(largest > 0 ? Round(v[k].real() / largest) : 0.0);
      for (int k = 0; k < 3; ++k) row.push_back(largest > 0 ? Round(v[k].imag() / largest) : 0.0);
      shape.push_back(std::move(row));
    }
    modes.push_back({{"frequency_hz", Round(mode.frequency_hz)},
                     {"damping_ratio", Round(mode.damping_ratio)},
                     {"shape", std::move(shape)}});
  }
  json lines = json::array();
  for (const auto& [a, b] : setup.lines)
    if (index.count(a) && index.count(b)) lines.push_back({index[a], index[b]});
  out = {{"nodes", nodes}, {"lines", lines}, {"modes", modes}};
  return out;
}

// The fitted test modes with their 1-sigma (MODES.json frequency_std_hz, damping_ratio_std) and
// the poles the fit dropped, for the report's mode table. Values as ema fit wrote them.
json TestModeTable(const json& test_modes) {
  json out = json::object();
  if (!test_modes.is_object() || !test_modes.contains("modes") || !test_modes["modes"].is_array()) return out;
  auto number = [](const json& j, const char* key) -> json {
    return j.is_object() && j.contains(key) && j[key].is_number() ? json(j[key].get<double>()) : json(nullptr);
  };
  json rows = json::array();
  for (const json& m : test_modes["modes"])
    rows.push_back({{"frequency_hz", number(m, "frequency_hz")},
                    {"frequency_std_hz", number(m, "frequency_std_hz")},
                    {"damping_ratio", number(m, "damping_ratio")},
                    {"damping_ratio_std", number(m, "damping_ratio_std")},
                    {"mpc", number(m, "mpc")},
                    {"mpd_deg", number(m, "mpd_deg")},
                    {"mcf", number(m, "mcf")}});
  out["modes"] = rows;
  if (test_modes.contains("refinement")) out["refinement"] = test_modes["refinement"];
  if (test_modes.contains("dropped")) out["dropped"] = test_modes["dropped"];
  return out;
}

json StabilisationData(const SetupResults& setup) {
  const StabilisationPoints points = ReadStabilisation(setup.stabilisation);
  if (points.order.empty()) return json::object();
  json order = json::array(), f = json::array(), zeta = json::array(), status = json::array();
  for (size_t i = 0; i < points.order.size(); ++i) {
    order.push_back(points.order[i]);
    f.push_back(Round(points.frequency_hz[i]));
    zeta.push_back(std::isfinite(points.damping_ratio[i]) ? json(Round(points.damping_ratio[i])) : json(nullptr));
    status.push_back(points.status[i]);
  }
  return {{"order", order}, {"frequency_hz", f}, {"damping_ratio", zeta}, {"status", status}};
}

// Keeps a JSON text safe inside a <script> element.
std::string ScriptSafe(std::string text) {
  for (size_t at = text.find("</"); at != std::string::npos; at = text.find("</", at + 3)) text.replace(at, 2, "<\\/");
  return text;
}

}  // namespace

json BuildReportData(const ReportInput& input) {
  json data = {{"title", input.title}, {"subtitle", input.subtitle}};
  data["files"] = input.steps;
  data["problems"] = input.problems;
  data["diagnosis"] = input.diagnosis ? pipeline::DiagnosisJson(*input.diagnosis) : json::object();
  data["diagnosis_view"] = input.diagnosis ? DiagnosisView(*input.diagnosis) : json::object();
  if (!input.amplitude.is_null()) data["amplitude"] = input.amplitude;
  data["diagnosed_places"] = input.diagnosed_places.is_null() ? json::array() : input.diagnosed_places;
  data["history"] = input.history.is_null() ? json::array() : input.history;
  data["next_test"] = input.next_test;
  json setups = json::array();
  for (const SetupResults& setup : input.setups) {
    // The fit's modes as `ema fit --json` writes them (the mode table, the quality section).
    const json test_modes = setup.fit ? formats::FitModesJson(*setup.fit, setup.refine) : json();
    const ModeSet no_modes;
    const ModeSet& test = setup.fit ? setup.fit->modes : no_modes;
    json s = {{"name", setup.name}};
    s["band_hz"] = {setup.band_lo_hz, setup.band_hi_hz};
    s["stabilisation"] = StabilisationData(setup);
    s["mode_indicators"] = ModeIndicatorData(setup.stabilisation);
    s["quality"] = QualityData(setup.quality, test_modes);
    json selected = json::array();
    for (const Mode& m : test.modes) selected.push_back(Round(m.frequency_hz));
    s["selected_hz"] = selected;
    if (!setup.selection.is_null()) s["selection"] = setup.selection;
    s["frf"] = FrfData(setup);
    s["mac_before"] = MacData(setup.correlation_before);
    s["mac_after"] = MacData(setup.correlation_after);
    auto correlation_json = [](const std::optional<CorrelationView>& c) {
      return c ? formats::CorrelationJson(c->result, c->test, c->model) : json::object();
    };
    s["correlation_before"] = correlation_json(setup.correlation_before);
    s["correlation_after"] = correlation_json(setup.correlation_after);
    s["shapes"] = ModeData(test, setup);
    s["test_mode_table"] = TestModeTable(test_modes);
    json rejected = json::array();
    if (setup.frf_summary.is_object() && setup.frf_summary.contains("frfs") && setup.frf_summary["frfs"].is_array()) {
      for (const json& frf : setup.frf_summary["frfs"]) {
        if (!frf.contains("rejected") || !frf["rejected"].is_array()) continue;
        for (const json& r : frf["rejected"]) {
          json entry = r;
          const std::string reference =
              std::to_string(frf.value("reference_node", 0)) + frf.value("reference_dir", std::string());
          entry["frf"] = std::to_string(frf.value("response_node", 0)) + frf.value("response_dir", std::string()) +
                         " / " + reference;
          entry["reference"] = reference;  // the impacted DOF, for the page's table (no label parsed back)
          rejected.push_back(std::move(entry));
        }
      }
    }
    s["rejected"] = rejected;
    // The run's headline per test: how many FRFs, rejected impacts and fitted modes.
    int frf_count = 0;
    if (setup.frf_summary.is_object() && setup.frf_summary.contains("frfs") && setup.frf_summary["frfs"].is_array())
      frf_count = static_cast<int>(setup.frf_summary["frfs"].size());
    else if (setup.frfs)
      frf_count = setup.frfs->OutputCount() * setup.frfs->ReferenceCount();
    s["frf_count"] = frf_count;
    if (!setup.rehearsal.empty()) s["rehearsal"] = setup.rehearsal;
    s["mode_count"] = test.modes.size();
    setups.push_back(std::move(s));
  }
  data["setups"] = std::move(setups);
  // What the headline's agreement compares, when the tests carried sensors the model leaves out.
  double sensor_mass_kg = 0.0;
  for (const SetupResults& setup : input.setups) sensor_mass_kg = std::max(sensor_mass_kg, setup.sensor_mass_kg);
  if (const std::string note = AgreementBasisWords(sensor_mass_kg); !note.empty())
    data["agreement_note"] = note;
  return data;
}

ReportInput ReportInputOf(const pipeline::RunResult& run, const RunPage& page) {
  const formats::Project& project = run.plan.project;
  ReportInput input;
  input.title = project.title;
  input.subtitle = page.subtitle;
  input.steps = page.files;
  input.history = page.history;
  input.problems = page.problems;
  input.diagnosis = run.diagnosis;
  input.diagnosed_places = run.diagnosis && run.nominal
                               ? DiagnosedPlaces(*run.nominal, run.diagnosis->diagnosis.candidates.front().effects)
                               : json::array();
  if (run.next_test) {
    const pipeline::NextTest& next = *run.next_test;
    auto dof = [](const Dof& d) { return json{{"node", d.node}, {"dir", DirectionName(d.direction)}}; };
    json sets = json::array();
    for (const std::vector<Dof>& set : next.plan.sets) {
      json list = json::array();
      for (const Dof& d : set) list.push_back(dof(d));
      sets.push_back(std::move(list));
    }
    json references = json::array();
    for (const Dof& d : next.plan.references) references.push_back(dof(d));
    json separations = json::array();
    for (const planning::Separation& sep : next.plan.separations)
      separations.push_back({{"a", sep.a}, {"b", sep.b}, {"sigma_before", sep.sigma_before}, {"sigma_after", sep.sigma_after}});
    input.next_test = {{"test", project.tests[static_cast<std::size_t>(next.test)].name},
                       {"readings", next.readings},
                       {"sets", std::move(sets)},
                       {"kept_sets", next.kept_sets},
                       {"references", std::move(references)},
                       {"separations", std::move(separations)},
                       {"automac_max_offdiagonal", next.plan.automac_max_offdiagonal}};
  } else if (!run.next_test_error.empty()) {
    input.next_test = {{"error", run.next_test_error}};
  }
  // Test points of the model's [[point]] entries given by position (points given by FE node have
  // none), for the animated shapes.
  std::vector<Node> geometry;
  if (run.nominal)
    for (const model::TestPoint& p : run.nominal->points)
      if (!p.where.IsNode() && p.where.has_at) geometry.push_back(Node{p.id, p.where.at});
  for (std::size_t t = 0; t < project.tests.size(); ++t) {
    const formats::ProjectTest& test = project.tests[t];
    const pipeline::TestResult& r = run.tests[t];
    SetupResults s;
    s.name = test.name;
    s.rehearsal = RehearsalWords(test);
    s.sensor_mass_kg = test.sensor_mass;
    if (r.frf) s.frf_summary = formats::FrfSummaryJson(r.frf->result);
    if (r.fit && r.frfs) {
      s.stabilisation = pipeline::FitStabilisationJson(*r.fit, *r.frfs, run.FrfPath(t).string());
      s.fit = r.fit->fit;
      s.refine = r.fit->options.refine;
      s.selection = {{"select", SelectText(r.fit->options.select_frequencies_hz)},
                     {"by_hand", r.picked_by_hand},
                     {"rule", r.fit->fit.selection_rule},
                     {"command", t < page.fit_commands.size() ? page.fit_commands[t] : std::string()},
                     {"modes_json", (std::filesystem::path(test.name) / "modes.json").generic_string()}};
      if (r.correlation_before && r.model_before)
        s.correlation_before = CorrelationView{*r.correlation_before, r.fit->stored_modes, r.model_before->modes};
      if (r.correlation_after && r.model_after)
        s.correlation_after = CorrelationView{*r.correlation_after, r.fit->stored_modes, r.model_after->modes};
    }
    s.geometry = geometry;
    s.lines = project.lines;
    s.band_lo_hz = project.fit.data.band_lo_hz;
    s.band_hi_hz = project.fit.data.band_hi_hz;
    if (r.frfs) s.frfs = r.frfs;
    if (r.quality) s.quality = formats::QualityJson(*r.quality, {}, r.quality_options);
    input.setups.push_back(std::move(s));
  }
  return input;
}

std::string RenderHtml(const pipeline::RunResult& run, const RunPage& page) { return RenderHtml(ReportInputOf(run, page)); }

std::string RenderHtml(const ReportInput& input) {
  const std::string data = ScriptSafe(BuildReportData(input).dump());
  std::string plotly(PlotlyJs());
  std::string script(ReportJs());
  for (std::string* js : {&plotly, &script})
    for (size_t at = js->find("</script"); at != std::string::npos; at = js->find("</script", at + 3))
      js->replace(at, 2, "<\\/");
  std::string html;
  html.reserve(plotly.size() + data.size() + 65536);
  html += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  html += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  html += "<title>" + HtmlEscape(input.title) + "</title>\n<style>\n";
  html += ReportCss();
  html += "</style>\n<script>\n";
  html += plotly;
  html += "\n</script>\n</head>\n<body>\n<header><h1>" + HtmlEscape(input.title) + "</h1><p class=\"subtitle\">" +
          HtmlEscape(input.subtitle) + "</p></header>\n<main id=\"report\"></main>\n";
  html += "<footer>Written by <code>ema run</code>. Charts: plotly.js (MIT licence), embedded; this file needs no "
          "network.</footer>\n";
  html += "<script id=\"ema-data\" type=\"application/json\">" + data + "</script>\n<script>\n";
  html += script;
  html += "\n</script>\n</body>\n</html>\n";
  return html;
}

}  // namespace ema::report
