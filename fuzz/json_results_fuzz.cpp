// libFuzzer target: every JSON writer of a result type (formats/json_codecs.hpp, the quality,
// amplitude and plan JSON of formats/, and the pipeline's: the findings, DIAG.json whole and a run's
// result, pipeline/json.hpp) given a typed result decoded from the fuzzer's bytes — texts of any
// bytes (non-UTF-8, NUL), NaN/±Inf/denormal/huge numbers, empty and large sets — must return JSON
// whose dump() succeeds and parses back. A crash, UBSan report, leak or any exception is a finding
// (the writers throw nothing, not even an InputError: their input is typed).
#include <cstdint>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "ema/formats/amplitude_json.hpp"
#include "ema/formats/json_codecs.hpp"
#include "ema/formats/plan_json.hpp"
#include "ema/formats/quality_json.hpp"
#include "ema/model/effects.hpp"
#include "ema/pipeline/json.hpp"
#include "json_fuzz_gen.hpp"

namespace {

using ema::fuzz::Gen;
using nlohmann::json;

ema::model::Law MakeLaw(Gen& g, int depth) {
  using namespace ema::model;
  switch (g.Int(0, depth > 0 ? 5 : 4)) {
    case 0: return LinearLaw{g.Double()};
    case 1: {
      TableLaw t{g.Doubles(8), g.Doubles(8), {}, {}};
      if (g.Bool()) t.operating_deflection = g.Double();
      if (g.Bool()) t.operating_force = g.Double();
      return t;
    }
    case 2: return AirFilmLaw{g.Doubles(8), g.Doubles(8), g.Double()};
    case 3: {
      HertzLaw h{g.Double(), g.Double(), g.Double(), {}, {}};
      if (g.Bool()) h.operating_deflection = g.Double();
      if (g.Bool()) h.operating_force = g.Double();
      return h;
    }
    case 4: return MicroSlipLaw{g.Double(), g.Double(), g.AnyInt()};
    default: {
      SeriesLaw s;
      s.elements.resize(g.Count(3));
      for (Law& e : s.elements) e = MakeLaw(g, depth - 1);
      s.setting = g.Double();
      if (g.Bool()) s.force = g.Double();
      return s;
    }
  }
}

ema::model::EffectKind Kind(Gen& g) {
  const auto& table = ema::model::EffectKindTable();
  return table[static_cast<std::size_t>(g.Int(0, static_cast<int>(table.size()) - 1))].kind;
}

// A candidate group's label: a kind's name or any text.
std::string KindLabel(Gen& g) { return g.Bool() ? ema::model::KindName(Kind(g)) : g.Text(); }

// A target of any form with any names (the bytes need not be UTF-8) and ids.
ema::model::EffectTarget MakeTarget(Gen& g) {
  using ema::model::EffectTarget;
  switch (g.Int(0, 5)) {
    case 0:
      return EffectTarget::MemberOf(g.Text(), g.Text());
    case 1:
      return EffectTarget::EveryMemberOf(g.Text());
    case 2:
      return EffectTarget::AllPoints();
    case 3: {
      std::vector<int> ids(g.Count(4));
      for (int& id : ids) id = g.AnyInt();
      return EffectTarget::Points(std::move(ids));
    }
    case 4:
      return EffectTarget::EveryPoint();
    default:
      return EffectTarget::Named(g.Text());
  }
}

ema::model::Effect MakeEffect(Gen& g) {
  ema::model::Effect e;
  e.kind = Kind(g);
  e.target = MakeTarget(g);
  for (std::size_t n = g.Count(4); n > 0; --n) e.parameters[g.Text()] = g.Double();
  if (g.Bool()) e.law = MakeLaw(g, 2);
  e.line = g.AnyInt();
  return e;
}

ema::diagnose::ModeComparison MakeModeComparison(Gen& g) {
  ema::diagnose::ModeComparison m;
  m.setup = g.Text();
  m.test_mode = g.Int(-1, 100000);  // an index into the setup's modes
  m.model_mode = g.Int(-1, 100000);
  m.test_frequency_hz = g.Double();
  m.model_frequency_hz = g.Double();
  m.agreement_pct = g.Double();
  m.mac = g.Double();
  m.sigma_hz = g.Double();
  m.frequency_misfit_sigma = g.Double();
  m.shape_misfit_sigma = g.Double();
  return m;
}

ema::diagnose::Candidate MakeCandidate(Gen& g) {
  ema::diagnose::Candidate c;
  c.effects.resize(g.Count(3));
  for (auto& e : c.effects) e = MakeEffect(g);
  c.parameters.resize(g.Count(5));
  for (auto& p : c.parameters) {
    p.effect_kind = Kind(g);
    p.target = MakeTarget(g);
    p.name = g.Text();
    p.value = g.Double();
    p.sigma = g.Double();
    p.prior_sigma = g.Double();
    p.lower = g.Double();
    p.upper = g.Double();
    p.at_bound = g.Bool();
    p.prior_z = g.Double();
    p.outside_prior = g.Bool();
  }
  c.kind = g.Text();
  c.target = g.Text();
  c.cost = g.Double();
  c.log_prior = g.Double();
  c.log_evidence = g.Double();
  c.score = g.Double();
  c.probability = g.Double();
  c.explained_pct = g.Double();
  c.mean_abs_frequency_error_pct = g.Double();
  c.mean_mac = g.Double();
  c.mean_agreement_pct = g.Double();
  c.paired_modes = g.AnyInt();
  c.modes.resize(g.Count(40));
  for (auto& m : c.modes) m = MakeModeComparison(g);
  c.plausible = g.Bool();
  c.reduced_chi2 = g.Double();
  c.noise_consistent = g.Bool();
  c.flags = g.Texts(3);
  c.model_error = {g.Double(), g.Double(), g.Double(), g.Bool()};
  c.reduced_model = g.Bool();
  c.tied_with = g.Texts(3);
  c.error = g.Bool() ? g.Text() : "";
  c.rank = g.AnyInt();
  return c;
}

ema::diagnose::Diagnosis MakeDiagnosis(Gen& g) {
  using namespace ema;
  diagnose::Diagnosis d;
  d.baseline = MakeCandidate(g);
  d.candidates.resize(g.Count(8));
  for (auto& c : d.candidates) c = MakeCandidate(g);
  d.steps.resize(g.Count(5));
  for (auto& s : d.steps) s = {g.Text(), g.Double(), g.Double(), g.Double()};
  d.effect_probabilities.resize(g.Count(6));
  for (auto& e : d.effect_probabilities) e = {Kind(g), MakeTarget(g), g.Double()};
  d.groups.resize(g.Count(4));
  for (auto& gr : d.groups) {
    gr.kind = KindLabel(g);
    gr.target = g.Text();
    for (std::size_t n = g.Count(4); n > 0; --n) gr.ranks.push_back(g.AnyInt());
    gr.probability = g.Double();
  }
  d.explanation = g.Text();
  d.residual_count = g.AnyInt();
  d.test_mode_count = g.AnyInt();
  d.model_solves = g.AnyInt();
  d.candidates_screened = g.AnyInt();
  return d;
}

ema::diagnose::DiagnoseOptions MakeDiagnoseOptions(Gen& g) {
  using namespace ema;
  diagnose::DiagnoseOptions o;
  o.criterion = static_cast<diagnose::Criterion>(g.Int(0, 2));
  o.frequency_floor = g.Double();
  o.shape_sigma = g.Double();
  o.max_effects = g.AnyInt();
  o.members = g.Bool();
  o.pairing.mac_min = g.Double();
  return o;
}

ema::curvefit::ModalModel MakeModalModel(Gen& g) {
  ema::curvefit::ModalModel m;
  m.outputs = g.Dofs(60);
  m.references = g.Dofs(4);
  m.transposed = g.Bool();
  m.frf_type = static_cast<ema::FrfType>(g.Int(0, 2));
  m.band_lo_hz = g.Double();
  m.band_hi_hz = g.Double();
  m.poles_fitted.resize(g.Count(20));
  for (auto& p : m.poles_fitted) p = g.Complex();
  // One residue row per FRF (o·m + i): the fit's invariant, which the writer relies on.
  const std::size_t rows = m.outputs.size() * m.references.size();
  const std::size_t cols = g.Count(std::min<std::size_t>(20, 2000 / std::max<std::size_t>(rows, 1)));
  m.residues.resize(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(cols));
  for (Eigen::Index c = 0; c < m.residues.cols(); ++c)
    for (Eigen::Index r = 0; r < m.residues.rows(); ++r) m.residues(r, c) = g.Complex();
  m.lower_residual = g.Vector(g.Bool() ? rows : g.Count(rows + 2));  // the writer checks these sizes
  m.upper_residual = g.Vector(g.Bool() ? rows : g.Count(rows + 2));
  return m;
}

ema::curvefit::FitResult MakeFit(Gen& g) {
  ema::curvefit::FitResult f;
  f.modes = g.Modes(200, 50, 2000);
  auto& d = f.diagram;
  d.orders.resize(g.Count(40));
  for (auto& order : d.orders) {
    order.resize(g.Count(20));
    for (auto& p : order) {
      p.order = g.AnyInt();
      p.lambda = g.Complex();
      p.lambda_fitted = g.Complex();
      p.frequency_hz = g.Double();
      p.damping_ratio = g.Double();
      p.participation = g.ComplexVector(g.Count(4));
      p.physical = g.Bool();
      p.label = static_cast<char>(g.provider().ConsumeIntegral<std::uint8_t>());  // any byte
    }
  }
  d.order_min = g.Int(-1000, 1000);  // orders run order_min + k: small by construction
  d.order_max = g.AnyInt();
  d.references = g.AnyInt();
  d.band_lo_hz = g.Double();
  d.band_hi_hz = g.Double();
  const std::size_t lines = g.Count(2000);
  d.frequency_hz = g.Vector(lines);
  d.sum_frf = g.Vector(lines);  // one value per line (PolyMAX's invariant)
  d.zoom_mapped = g.Bool();
  f.selected.resize(g.Count(50));
  for (auto& s : f.selected) {
    s.pole.order = g.AnyInt();
    s.pole.frequency_hz = g.Double();
    s.pole.damping_ratio = g.Double();
    s.frequency_spread_hz = g.Double();
    s.damping_spread = g.Double();
    s.cluster_size = g.AnyInt();
  }
  f.synthesis_error = g.Double();
  f.transposed = g.Bool();
  f.refine.termination = static_cast<ema::curvefit::RefineTermination>(g.Int(0, 3));
  f.refine.noise_source = static_cast<ema::curvefit::NoiseSource>(g.Int(0, 1));
  f.refine.message = g.Text();
  f.refine.iterations = g.AnyInt();
  f.refine.initial_cost = g.Double();
  f.refine.final_cost = g.Double();
  f.refine.reduced_chi2 = g.Double();
  f.model = MakeModalModel(g);
  f.dropped.resize(g.Count(10));
  for (auto& p : f.dropped) {
    p.frequency_hz = g.Double();
    p.damping_ratio = g.Double();
    p.merged_into_hz = g.Double();
    p.reason = g.Text();
  }
  f.selection_rule = g.Text();
  return f;
}

ema::frf::FrfResult MakeFrfResult(Gen& g) {
  using namespace ema;
  frf::FrfResult r;
  auto& s = r.summary;
  s.frfs.resize(g.Count(300));
  for (auto& e : s.frfs) {
    e.response = g.AnyDof();
    e.reference = g.AnyDof();
    e.averages = g.AnyInt();
    e.rejected.resize(g.Count(4));
    for (auto& x : e.rejected) {
      x.impact = g.AnyInt();
      x.set = g.Text();
      x.reason = g.Text();
    }
  }
  s.estimator = static_cast<frf::Estimator>(g.Int(0, 2));
  s.window_decay_rate = g.Double();
  s.roving_hammer = g.Bool();
  s.impacts = g.AnyInt();
  s.rejected_impacts = g.AnyInt();
  s.notes = g.Texts(8);
  r.frfs.frequency_hz = g.Vector(g.Count(2000));
  return r;
}

// Unpaired modes index `test` and `model` (the writer reads their frequencies).
ema::correlation::CorrelationResult MakeCorrelation(Gen& g, const ema::ModeSet& test, const ema::ModeSet& model) {
  using namespace ema;
  correlation::CorrelationResult r;
  r.rows.resize(g.Count(40));
  for (auto& row : r.rows) {
    row.test_mode = g.Int(-1, 100000);  // indices: only printed (+1)
    row.model_mode = g.Int(-1, 100000);
    row.test_frequency_hz = g.Double();
    row.test_damping_ratio = g.Double();
    row.model_frequency_hz = g.Double();
    row.agreement_pct = g.Double();
    row.frequency_error_pct = g.Double();
    row.mac = g.Double();
    row.remark = g.Text();
  }
  // Unpaired modes index their sets (the writer reads their frequencies).
  if (!test.modes.empty())
    for (std::size_t n = g.Count(10); n > 0; --n) r.pairing.unpaired_test.push_back(g.Int(0, static_cast<int>(test.modes.size()) - 1));
  if (!model.modes.empty())
    for (std::size_t n = g.Count(10); n > 0; --n) r.pairing.unpaired_model.push_back(g.Int(0, static_cast<int>(model.modes.size()) - 1));
  r.pairing.pairs.resize(g.Count(10));
  r.mean_agreement_pct = g.Double();
  r.min_agreement_pct = g.Double();
  r.mean_mac = g.Double();
  r.mean_abs_frequency_error_pct = g.Double();
  r.shared_dof_count = g.AnyInt();
  r.test_dof_count = g.AnyInt();
  r.comac.resize(g.Count(50));
  for (auto& c : r.comac) c = {g.AnyDof(), g.Double()};
  r.mac.resize(static_cast<Eigen::Index>(g.Count(30)), static_cast<Eigen::Index>(g.Count(30)));
  for (Eigen::Index k = 0; k < r.mac.size(); ++k) r.mac.data()[k] = g.Double();
  return r;
}

ema::correlation::AmplitudeResult MakeAmplitude(Gen& g) {
  using namespace ema;
  correlation::AmplitudeResult r;
  r.level_kind = static_cast<correlation::LevelKind>(g.Int(0, 2));
  r.levels = g.Doubles(10);
  r.modes.resize(g.Count(20));
  for (auto& m : r.modes) {
    m.points.resize(1 + g.Count(6));  // a mode is followed over >= 1 level; target_point indexes them
    for (auto& p : m.points) {
      p.level = g.Double();
      p.frequency_hz = g.Double();
      p.damping_ratio = g.Double();
      p.frequency_std_hz = g.Double();
      p.damping_ratio_std = g.Double();
      p.mode_index = g.AnyInt();
      p.poles = g.AnyInt();
    }
    m.frequency_trend = static_cast<correlation::FrequencyTrend>(g.Int(0, 3));
    m.damping_trend = static_cast<correlation::DampingTrend>(g.Int(0, 2));
    m.frequency_change_pct = g.Double();
    m.damping_ratio_factor = g.Double();
    m.target_point = g.Int(0, static_cast<int>(m.points.size()) - 1);
    m.frequency_slope_z = g.Double();
    m.frequency_extreme_z = g.Double();
    m.damping_slope_z = g.Double();
    m.reading = g.Text();
  }
  r.summary = g.Text();
  return r;
}


// The first screen as numbers (pipeline::FindingsOf's result): only "effects" reaches the JSON,
// the rest is filled too so that a writer reading it is caught.
ema::pipeline::Findings MakeFindings(Gen& g) {
  using namespace ema;
  pipeline::Findings f;
  f.effects.resize(g.Count(6));
  for (auto& e : f.effects) {
    e.effect = MakeEffect(g);
    e.parameters.resize(g.Count(4));
    for (auto& p : e.parameters) {
      p.effect_kind = Kind(g);
      p.target = MakeTarget(g);
      p.name = g.Text();
      p.value = g.Double();
      p.sigma = g.Double();
    }
    e.probability = g.Double();
    if (g.Bool()) e.wildcard = MakeTarget(g);
    e.wildcard_probability = g.Double();
    e.springs.resize(g.Count(6));
    for (auto& sp : e.springs) sp = {g.Text(), g.Double(), g.Double()};
  }
  f.rank_one_probability = g.Double();
  f.certain_among_tried_only = g.Bool();
  f.adequate = g.Bool();
  f.reduced_chi2 = g.Double();
  f.test_modes = g.AnyInt();
  f.model_inadequate = g.Bool();
  f.model_error = {g.Double(), g.Double(), g.Double(), g.Bool()};
  f.lookalikes.resize(g.Count(4));
  for (auto& l : f.lookalikes) {
    l.kind = g.Text();
    l.target = g.Text();
    l.readings = g.AnyInt();
    l.holds_rank_one = g.Bool();
    l.span = static_cast<pipeline::GroupSpan>(g.Int(0, 2));
    l.probability = g.Double();
  }
  f.checks = g.Texts(3);
  f.modes.resize(g.Count(20));
  for (auto& m : f.modes) {
    m.before = MakeModeComparison(g);
    m.after = MakeModeComparison(g);
    m.paired_before = g.Bool();
    m.paired_after = g.Bool();
    m.share_pct = g.Double();
    m.verdict = static_cast<pipeline::ModeVerdict>(g.Int(0, 3));
  }
  if (!f.modes.empty())
    for (std::size_t n = g.Count(3); n > 0; --n) f.worst_modes.push_back(g.Int(0, static_cast<int>(f.modes.size()) - 1));
  return f;
}

// `ema diagnose`'s stage: DIAG.json whole (pipeline::DiagnosisJson).
ema::pipeline::DiagnoseStage MakeDiagnoseStage(Gen& g) {
  ema::pipeline::DiagnoseStage stage;
  stage.diagnosis = MakeDiagnosis(g);
  stage.options = MakeDiagnoseOptions(g);
  stage.findings = MakeFindings(g);
  if (g.Bool()) stage.nonlinearity = MakeAmplitude(g);
  return stage;
}

// A run (pipeline::RunResult): one TestResult per project test; steps and problems index the
// tests or are -1 (the diagnosis); a test's correlations go with its fit's modes (RunResult's
// invariants, which the writer relies on).
ema::pipeline::RunResult MakeRunResult(Gen& g) {
  using namespace ema;
  pipeline::RunResult run;
  formats::Project& project = run.plan.project;
  project.name = g.Text();
  project.model = g.Text();
  project.tests.resize(g.Count(4));
  for (auto& t : project.tests) {
    t.name = g.Text();
    t.setup = g.Text();
  }
  run.tests.resize(project.tests.size());
  for (auto& t : run.tests) {
    if (g.Bool()) t.frf = pipeline::FrfStage{MakeFrfResult(g), {}, g.AnyInt()};
    if (g.Bool()) {
      FrfSet frfs;
      frfs.outputs = g.Dofs(200);
      frfs.references = g.Dofs(3);
      frfs.output_sets.resize(g.Bool() ? frfs.outputs.size() : g.Count(frfs.outputs.size() + 2));
      for (int& s : frfs.output_sets) s = g.AnyInt();
      t.frfs = std::move(frfs);
    }
    t.fit_options.select_frequencies_hz = g.Doubles(6);
    t.picked_by_hand = g.Bool();
    if (g.Bool()) {
      pipeline::FitStage fit;
      fit.fit = MakeFit(g);
      fit.stored_modes = g.Modes(40, 20, 400);
      t.fit = std::move(fit);
    }
    const ModeSet empty;
    const ModeSet& test_modes = t.fit ? t.fit->stored_modes : empty;
    if (g.Bool()) {
      model::Solution s;
      s.modes = g.Modes(40, 20, 400);
      t.model_before = std::move(s);
      if (g.Bool()) t.correlation_before = MakeCorrelation(g, test_modes, t.model_before->modes);
    }
    if (g.Bool()) {
      model::Solution s;
      s.modes = g.Modes(40, 20, 400);
      t.model_after = std::move(s);
      if (g.Bool()) t.correlation_after = MakeCorrelation(g, test_modes, t.model_after->modes);
    }
  }
  if (g.Bool()) run.diagnosis = MakeDiagnoseStage(g);
  const int tests = static_cast<int>(project.tests.size());
  run.steps.resize(g.Count(20));
  for (auto& s : run.steps) {
    s.kind = static_cast<pipeline::StepKind>(g.Int(0, 6));
    s.test = g.Int(-1, tests - 1);
    s.status = static_cast<pipeline::StepStatus>(g.Int(0, 3));
    s.error = g.Text();
  }
  run.problems.resize(g.Count(5));
  for (auto& p : run.problems) p = {g.Int(-1, tests - 1), g.Text(), g.Text()};
  run.mean_agreement_before = g.Double();
  run.mean_mac_before = g.Double();
  run.mean_agreement_after = g.Double();
  run.mean_mac_after = g.Double();
  return run;
}

// Valid JSON text, and JSON that parses back.
void Check(const json& j) {
  std::string text;
  try {
    text = j.dump();
  } catch (const json::exception& e) {
    std::fprintf(stderr, "dump() threw: %s\n", e.what());
    __builtin_trap();
  }
  try {
    (void)json::parse(text);
  } catch (const json::exception& e) {
    std::fprintf(stderr, "the dump does not parse: %s\n", e.what());
    __builtin_trap();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace ema;
  Gen g(data, size);
  switch (g.Int(0, 16)) {
    case 0: Check(formats::FrfSummaryJson(MakeFrfResult(g))); break;
    case 1: {
      const ModeSet set = g.Modes(2000, 200, 4000);
      Check(formats::ModeSetJson(set));
      break;
    }
    case 2: {
      const curvefit::FitResult f = MakeFit(g);
      Check(formats::FitModesJson(f, g.Bool() ? curvefit::RefineMethod::kMl : curvefit::RefineMethod::kNone));
      break;
    }
    case 3: {
      FrfSet frfs;
      frfs.outputs = g.Dofs(2000);
      frfs.references = g.Dofs(3);
      frfs.output_sets.resize(g.Bool() ? frfs.outputs.size() : g.Count(frfs.outputs.size() + 2));  // checked by the writer
      for (int& s : frfs.output_sets) s = g.AnyInt();
      const json j = formats::TestSetsJson(frfs);
      Check(j);
      std::vector<std::vector<int>> sets;
      Dof reference;
      (void)formats::ReadTestSets(json::parse(j.dump()), &sets, &reference);
      break;
    }
    case 4: Check(formats::ModalModelJson(MakeModalModel(g))); break;
    case 5: {
      const curvefit::FitResult f = MakeFit(g);
      curvefit::StabilityOptions o;
      o.frequency_tol = g.Double();
      o.damping_tol = g.Double();
      o.mac_min = g.Double();
      Check(formats::StabilisationJson(f, o));
      break;
    }
    case 6: {
      const ModeSet test = g.Modes(20, 40, 400);
      const ModeSet model = g.Modes(20, 40, 400);
      Check(formats::CorrelationJson(MakeCorrelation(g, test, model), test, model));
      break;
    }
    case 7: {
      model::Model m;
      m.name = g.Text();
      model::Solution sol;
      sol.modes = g.Modes(300, 60, 2000);
      sol.rigid_body_frequencies_hz = g.Doubles(6);
      sol.springs.resize(g.Count(30));
      for (auto& s : sol.springs) {
        s.name = g.Text();
        s.group = g.Text();
        s.law = g.Text();
        s.force = g.Double();
        s.deflection = g.Double();
        s.stiffness = g.Double();
        s.gap = g.Double();
        s.element_deflections = g.Doubles(4);
        s.element_stiffnesses = g.Doubles(4);
      }
      sol.energy.resize(g.Count(10));
      for (auto& e : sol.energy) {
        e.body = g.Text();
        e.share = g.Doubles(30);
      }
      Check(formats::ModelSolutionJson(m, sol, g.Text()));
      break;
    }
    case 8: Check(formats::EffectJson(MakeEffect(g))); break;
    case 9: {
      const diagnose::Diagnosis d = MakeDiagnosis(g);
      Check(formats::DiagnosisJson(d, MakeDiagnoseOptions(g)));
      break;
    }
    case 10: {
      const diagnose::Candidate before = MakeCandidate(g);
      Check(formats::DiagnosisModeRows(before, MakeCandidate(g)));
      break;
    }
    case 11: {
      frf::FrfQualityReport q;
      auto verdict = [&] { return static_cast<frf::Verdict>(g.Int(0, 1)); };
      q.reciprocity.resize(g.Count(30));
      for (auto& c : q.reciprocity) {
        c.dof_i = g.AnyDof();
        c.dof_j = g.AnyDof();
        c.relative_difference = g.Double();
        c.amplitude_ratio = g.Double();
        c.verdict = verdict();
        c.reason = g.Text();
      }
      q.driving_points.resize(g.Count(10));
      for (auto& c : q.driving_points) {
        c.dof = g.AnyDof();
        c.resonances = g.AnyInt();
        c.flipped = g.AnyInt();
        c.flipped_frequencies_hz = g.Doubles(5);
        c.sign_consistency = g.Double();
        c.verdict = verdict();
        c.reason = g.Text();
      }
      q.frfs.resize(g.Count(60));
      for (auto& s : q.frfs) {
        s.response = g.AnyDof();
        s.reference = g.AnyDof();
        s.mean_coherence = g.Double();
        s.low_coherence_fraction = g.Double();
        s.averages = g.AnyInt();
        s.median_random_error = g.Double();
        s.max_random_error = g.Double();
        s.coherence_verdict = verdict();
        s.scatter_verdict = verdict();
        s.reason = g.Text();
      }
      q.has_coherence = g.Bool();
      q.has_averages = g.Bool();
      q.coherence_map.frequency_hz = g.Vector(g.Count(400));
      q.coherence_map.labels = g.Texts(20);
      q.coherence_map.coherence.resize(static_cast<Eigen::Index>(g.Count(20)), static_cast<Eigen::Index>(g.Count(100)));
      for (Eigen::Index k = 0; k < q.coherence_map.coherence.size(); ++k) q.coherence_map.coherence.data()[k] = g.Double();
      q.notes = g.Texts(5);
      std::vector<curvefit::ModeComplexityCheck> modes(g.Count(30));
      for (auto& c : modes) {
        c.index = g.Int(-1, 100000);
        c.frequency_hz = g.Double();
        c.mpc = g.Double();
        c.mpd_deg = g.Double();
        c.mcf = g.Double();
        c.verdict = verdict();
        c.reason = g.Text();
      }
      frf::QualityOptions o;
      o.reciprocity_tolerance = g.Double();
      o.resonance_level = g.Double();
      o.coherence_min = g.Double();
      o.coherence_max_low_fraction = g.Double();
      o.scatter_max = g.Double();
      Check(formats::QualityJson(q, modes, o));
      break;
    }
    case 12: {  // PLAN.json (`ema plan --json`)
      planning::TestPlan p;
      p.candidates = g.Dofs(60);
      p.sets.resize(g.Count(8));
      for (auto& set : p.sets) set = g.Dofs(30);
      p.references = g.Dofs(4);
      p.modes.resize(g.Count(20));
      for (auto& m : p.modes) {
        m.frequency_hz = g.Double();
        m.damping_ratio = g.Double();
        m.observability = g.Double();
        m.reference_participation = g.Double();
        m.excited = g.Bool();
      }
      const auto n = static_cast<Eigen::Index>(g.Count(20));
      p.automac.resize(n, n);
      for (Eigen::Index k = 0; k < p.automac.size(); ++k) p.automac.data()[k] = g.Double();
      p.automac_max_offdiagonal = g.Double();
      p.band_lo_hz = g.Double(), p.band_hi_hz = g.Double(), p.sample_rate_hz = g.Double();
      p.samples = g.AnyInt();
      p.pulse_duration_s = g.Double(), p.sensor_mass_kg = g.Double();
      p.impacts = g.AnyInt();
      p.separations.resize(g.Count(45));
      for (auto& s : p.separations) s = {g.Text(), g.Text(), g.Double(), g.Double()};
      p.notes = g.Texts(5);
      Check(formats::TestPlanJson(p, g.Bool()));
      break;
    }
    case 13: Check(pipeline::FindingsJson(MakeFindings(g))); break;
    case 14: Check(pipeline::DiagnosisJson(MakeDiagnoseStage(g))); break;  // DIAG.json
    case 15: Check(pipeline::RunResultJson(MakeRunResult(g))); break;        // ema.run's result
    default: Check(formats::AmplitudeJson(MakeAmplitude(g))); break;
  }
  return 0;
}
