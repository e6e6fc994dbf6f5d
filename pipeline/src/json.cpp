#include "ema/pipeline/json.hpp"

#include <cmath>

#include "ema/formats/amplitude_json.hpp"
#include "ema/formats/json_codecs.hpp"
#include "ema/formats/mode_indicators_json.hpp"
#include "ema/model/effects.hpp"

namespace ema::pipeline {

namespace {

using json = nlohmann::json;

using formats::NumberOrNull;

}  // namespace

json FitModesJson(const FitStage& stage, const FrfSet& frfs) {
  json out = formats::FitModesJson(stage.fit, stage.options.refine);
  out.update(formats::TestSetsJson(frfs));  // roving sets and hammer DOF, when known
  return formats::ValidUtf8(std::move(out));
}

json FitStabilisationJson(const FitStage& stage, const FrfSet& frfs, const std::string& source) {
  json out = formats::StabilisationJson(stage.fit, stage.options.stability);
  formats::AddModeIndicatorsJson(&out, frfs, stage.options.data, source);  // CMIF/MMIF (docs/quality.md)
  return formats::ValidUtf8(std::move(out));  // the source is a file name: any bytes
}

json FindingsJson(const Findings& findings) {
  json out = json::array();
  for (const EffectFinding& f : findings.effects) {
    diagnose::Candidate single;
    single.effects = {f.effect};
    single.kind = model::KindName(f.effect.kind);
    single.target = model::TargetText(f.effect.target);
    json parameters = json::array();
    for (const diagnose::FittedParameter& p : f.parameters)
      parameters.push_back({{"name", p.name}, {"value", NumberOrNull(p.value)}, {"sigma", NumberOrNull(p.sigma)}});
    json springs = json::array();
    for (const SpringStiffness& s : f.springs)
      springs.push_back({{"setup", s.setup},
                         {"per_spring_n_per_m", NumberOrNull(s.per_spring_n_per_m)},
                         {"element_n_per_m", NumberOrNull(s.element_n_per_m)}});
    json j = {{"kind", model::KindName(f.effect.kind)},
              {"target", model::TargetText(f.effect.target)},
              {"description", diagnose::DescribeCandidate(single, false)},
              {"probability", f.probability},
              {"parameters", std::move(parameters)},
              {"springs", std::move(springs)}};
    if (f.wildcard) j["any"] = {{"target", model::TargetText(*f.wildcard)}, {"probability", f.wildcard_probability}};
    out.push_back(std::move(j));
  }
  return formats::ValidUtf8(std::move(out));  // targets and setups are the model's texts
}

json DiagnosisJson(const DiagnoseStage& stage) {
  const diagnose::Diagnosis& d = stage.diagnosis;
  json out = formats::DiagnosisJson(d, stage.options);
  if (!d.candidates.empty()) out["modes"] = formats::DiagnosisModeRows(d.baseline, d.candidates.front());
  out["findings"] = FindingsJson(stage.findings);
  // Rank 1 "none" in a model that stays inadequate: the reading its own error also explains.
  out["model_error_lookalike"] = nullptr;
  if (const auto& l = stage.findings.model_error_lookalike)
    out["model_error_lookalike"] = {{"rank", l->rank},
                                    {"description", l->description},
                                    {"probability", l->probability},
                                    {"mean_abs_frequency_error_pct", NumberOrNull(l->error_after_pct)},
                                    {"model_error", formats::ModelErrorJson(l->model_error)}};
  if (stage.nonlinearity) {
    json nonlinearity = formats::AmplitudeJson(*stage.nonlinearity);
    bool flagged = false;
    for (const auto& m : stage.nonlinearity->modes)
      flagged = flagged || m.frequency_trend != correlation::FrequencyTrend::kNone ||
                m.damping_trend != correlation::DampingTrend::kNone;
    nonlinearity["flagged"] = flagged;
    nonlinearity["summary"] = stage.nonlinearity->summary;
    out["nonlinearity"] = std::move(nonlinearity);
  }
  return formats::ValidUtf8(std::move(out));
}

json RunResultJson(const RunResult& run) {
  const formats::Project& project = run.plan.project;
  json tests = json::array();
  for (std::size_t t = 0; t < project.tests.size(); ++t) {
    const TestResult& r = run.tests[t];
    auto correlation = [&](const std::optional<correlation::CorrelationResult>& c, const std::optional<model::Solution>& s) {
      return c && s && r.fit ? formats::CorrelationJson(*c, r.fit->stored_modes, s->modes) : json(nullptr);
    };
    json simulated = nullptr;  // a rehearsal's simulated test (plan = "PLAN.toml")
    if (r.simulated)
      simulated = {{"plan", project.tests[t].plan ? project.tests[t].plan->string() : std::string()},
                   {"truth", run.TruthPath(t).string()},
                   {"records", r.simulated->records.size()},
                   {"sets", r.simulated->sets},
                   {"references", r.simulated->references},
                   {"impacts_per_reference", r.simulated->impacts_per_reference},
                   {"in_time", r.simulated->in_time},
                   {"undamped", r.simulated->undamped}};
    tests.push_back({{"name", project.tests[t].name},
                     {"setup", project.tests[t].setup},
                     {"simulated", std::move(simulated)},
                     {"frf", r.frf ? formats::FrfSummaryJson(r.frf->result) : json(nullptr)},
                     {"modes", r.fit && r.frfs ? FitModesJson(*r.fit, *r.frfs) : json(nullptr)},
                     {"select_hz", r.fit_options.select_frequencies_hz},
                     {"picked_by_hand", r.picked_by_hand},
                     {"correlation_before", correlation(r.correlation_before, r.model_before)},
                     {"correlation_after", correlation(r.correlation_after, r.model_after)}});
  }
  static const char* const kStatus[] = {"done", "failed", "skipped", "given"};
  json steps = json::array();
  for (const StepRecord& s : run.steps)
    steps.push_back({{"step", StepName(s.kind)},
                     {"test", s.test >= 0 ? json(project.tests[static_cast<std::size_t>(s.test)].name) : json(nullptr)},
                     {"status", kStatus[static_cast<int>(s.status)]},
                     {"error", s.error}});
  json problems = json::array();
  for (const RunProblem& p : run.problems)
    problems.push_back({{"test", p.test >= 0 ? json(project.tests[static_cast<std::size_t>(p.test)].name) : json(nullptr)},
                        {"what", p.what},
                        {"error", p.error}});
  return formats::ValidUtf8(json{{"project", project.name},
                                 {"model", project.model.string()},
                                 {"tests", std::move(tests)},
                                 {"diagnosis", run.diagnosis ? DiagnosisJson(*run.diagnosis) : json(nullptr)},
                                 {"steps", std::move(steps)},
                                 {"problems", std::move(problems)},
                                 {"mean_agreement_pct_before", NumberOrNull(run.mean_agreement_before)},
                                 {"mean_mac_before", NumberOrNull(run.mean_mac_before)},
                                 {"mean_agreement_pct_after", NumberOrNull(run.mean_agreement_after)},
                                 {"mean_mac_after", NumberOrNull(run.mean_mac_after)}});
}

}  // namespace ema::pipeline
