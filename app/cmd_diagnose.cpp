// ema diagnose MODEL.toml --test [SETUP=]MODES.unv [--test SETUP2=MODES2.unv ...]
//               [--json DIAG.json] [-o UPDATED.toml] [--force-level F=MODES.unv ...]
// Ranks the physical effects the model is missing (cli.md, issue 7).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <nlohmann/json.hpp>
#include <sstream>

#include "ema/formats/amplitude_json.hpp"
#include "ema/formats/modes_sidecar.hpp"
#include "cli.hpp"
#include "ema/core/error.hpp"
#include "ema/core/text.hpp"
#include "ema/diagnose/diagnose.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/formats/json_codecs.hpp"
#include "ema/model/effects.hpp"
#include "ema/model/solve.hpp"
#include "ema/pipeline/json.hpp"
#include "stages.hpp"
#include "words.hpp"

namespace ema {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// "[SETUP=]PATH": the part before the first '=' is a setup name unless the whole text is an
// existing file (file names may contain '=').
std::pair<std::string, std::string> SplitSetup(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || fs::exists(text)) return {"", text};
  return {text.substr(0, eq), text.substr(eq + 1)};
}

// The tables of `ema diagnose` print "–" where a value does not exist.
std::string Fixed(double v, int digits) { return FixedPoint(v, digits, "–"); }

// Before/after table: every test mode of every setup, the baseline and rank-1 partners.
std::string ModeTable(const diagnose::Candidate& before, const diagnose::Candidate& after) {
  std::ostringstream out;
  out << "| setup | test mode | test f [Hz] | model f before [Hz] | agreement before [%] | MAC before | "
         "model f after [Hz] | agreement after [%] | MAC after |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  const bool several = report::SeveralTestsOfOneSetup(before.modes);
  for (size_t i = 0; i < before.modes.size() && i < after.modes.size(); ++i) {
    const auto& b = before.modes[i];
    const auto& a = after.modes[i];
    out << "| " << (b.setup.empty() ? "nominal" : b.setup) << (several ? ", test " + std::to_string(b.test + 1) : "") << " | " << b.test_mode + 1 << " | "
        << Fixed(b.test_frequency_hz, 1) << " | " << Fixed(b.model_frequency_hz, 1) << " | "
        << Fixed(b.agreement_pct, 1) << " | " << Fixed(b.mac, 3) << " | " << Fixed(a.model_frequency_hz, 1) << " | "
        << Fixed(a.agreement_pct, 1) << " | " << Fixed(a.mac, 3) << " |\n";
  }
  return out.str();
}

using report::Percent;
std::string Number(double v, int digits = 3) { return report::Significant(v, digits); }

// A probability beside a model that stays inadequate: computed with the model's error
// marginalised, but still only among the vocabulary's readings, so never said as certainty.
std::string HonestPercent(const pipeline::Findings& f) {
  if (!f.certain_among_tried_only) return Percent(f.rank_one_probability);
  return "above 99 % among the readings tried, none of which makes the model adequate";
}

// The first lines for a model that no reading makes adequate: that first, where the misfit sits
// (rank 1's evidence per test mode), and which kinds of missing physics fit such a pattern.
void InadequateModelWords(const diagnose::Diagnosis& d, const pipeline::Findings& f, std::ostringstream* out) {
  const diagnose::ModelError& error = f.model_error;
  bool several_tests = false;
  for (const diagnose::ModeComparison& m : d.candidates.front().modes) several_tests = several_tests || m.test > 0;
  *out << "The model is NOT adequate to " << (several_tests ? "these tests" : "this test")
       << ", with or without the effects it can try: its own error (about "
       << Number(100.0 * error.frequency_rel, 2) << " % of each frequency";
  if (error.frequency_common_rel >= error.frequency_rel)
    *out << " and " << Number(100.0 * error.frequency_common_rel, 2) << " % shared by all of them";
  *out << ", 1 − MAC about " << Number(error.shape, 2)
       << ") is larger than the test's σ. The readings below are the vocabulary's best; their probabilities are "
          "computed with that error and compare them with each other only.\n";
  std::string where;
  const bool several = report::SeveralTestsOfOneSetup(d.candidates.front().modes);
  for (std::size_t i = 0; i < f.worst_modes.size(); ++i) {
    const diagnose::ModeComparison& m = d.candidates.front().modes[static_cast<std::size_t>(f.worst_modes[i])];
    where += (i ? "; " : "") + report::TestModeWords(m, several) + " (" + Number(m.test_frequency_hz, 4) + " Hz): frequency " + (m.frequency_misfit_sigma >= 0 ? "+" : "") +
             Number(m.frequency_misfit_sigma, 2) + "σ, shape " + Number(m.shape_misfit_sigma, 2) + "σ";
  }
  if (!where.empty()) *out << "  Where the misfit sits (rank 1, in the test's σ): " << where << ".\n";
  std::vector<std::string> kinds;
  if (f.pattern.all_one_way)
    kinds.push_back(std::string("distributed ") +
                    (f.pattern.model_too_stiff ? "stiffness too high or mass too low" : "stiffness too low or mass too high") +
                    " everywhere (a material property, a spread non-structural mass)");
  else if (f.pattern.mixed)
    kinds.push_back("stiffness or mass distributed differently from the model (zone-wise scatter, a boundary the model fixes or frees)");
  if (f.pattern.shapes_off_more) kinds.push_back("a missing part or a local mode (the shapes are off more than the frequencies)");
  if (f.pattern.unpaired_modes) kinds.push_back("modes the model does not have (a missing part, a local mode)");
  if (kinds.empty()) kinds.push_back("a boundary, a distributed stiffness or mass, or a missing part");
  *out << "  Missing physics that fits such a pattern: ";
  for (size_t i = 0; i < kinds.size(); ++i) *out << (i ? "; or " : "") << kinds[i];
  *out << ".\n";
}

}  // namespace

std::optional<app::DiagnoseConfig> app::ParseDiagnoseArgs(const std::vector<std::string>& args, bool require_inputs,
                                                          const diagnose::DiagnoseOptions& base) {
  namespace po = cli::po;
  const std::string usage =
      "ema diagnose MODEL.toml --test [SETUP=]MODES.unv [--test SETUP2=MODES2.unv ...] [--json DIAG.json] "
      "[-o UPDATED.toml]";
  po::options_description options("options");
  DiagnoseConfig config;
  config.options = base;
  std::string criterion = diagnose::CriterionToString(config.options.criterion);
  std::string shape_residual = diagnose::ShapeResidualToString(config.options.shape_residual);
  std::vector<std::string> tests;
  bool no_pairs = false, no_members = false, exact_form = false;
  double shape_weight = 0.0;
  diagnose::DiagnoseOptions& dopt = config.options;
  auto model_value = po::value(&config.model_path);
  auto test_value = po::value(&tests)->composing();
  if (require_inputs) model_value->required(), test_value->required();
  options.add_options()("model", model_value, "model file (.toml)")(
      "test", test_value,
      "test modes (UFF 55) of one setup, as SETUP=MODES.unv (or MODES.unv for the nominal model); repeat per setup")(
      "json", po::value(&config.json_path), "write the ranking as JSON (DIAG.json)")(
      "output,o", po::value(&config.output),
      "write the model with the rank-1 effect(s) added as [[effect]] blocks; the files it names are written "
      "relative to its folder when they lie inside it, else absolute, so it loads wherever it is copied")(
      "bundle", po::bool_switch(&config.bundle),
      "with -o: copy every file the model names (matrices, curves, node lists) into UPDATED-files/ beside it and "
      "name them relative to it, so the folder can be moved or sent")(
      "criterion", po::value(&criterion)->default_value(criterion),
      "ranking: evidence (Laplace approximation with the priors), bic or aicc (no priors)")(
      "max-effects", po::value(&dopt.max_effects)->default_value(dopt.max_effects), "largest number of effects combined (1..3)")(
      "no-pairs", po::bool_switch(&no_pairs), "single effects only (same as --max-effects 1)")(
      "no-members", po::bool_switch(&no_members), "only whole groups, all points and bodies (no members or single points)")(
      "frequency-floor", po::value(&dopt.frequency_floor)->default_value(dopt.frequency_floor),
      "relative 1σ floor of a test frequency; a mode's σ is max(its stabilisation spread, floor × f)")(
      "shape-sigma", po::value(&dopt.shape_sigma)->default_value(dopt.shape_sigma), "1σ of (1 - MAC) (--shape-residual mac)")(
      "shape-residual", po::value(&shape_residual)->default_value(shape_residual),
      "how a test shape enters the likelihood: per-dof (its difference at each measured DOF in units of its σ "
      "there) or mac (one (1 - MAC) per mode, as before 2026-11-27; docs/diagnose.md)")(
      "shape-dof-sigma", po::value(&dopt.shape_dof_sigma)->default_value(dopt.shape_dof_sigma),
      "floor of a shape's 1σ at one DOF, relative to its rms amplitude (--shape-residual per-dof)")(
      "exact-form", po::bool_switch(&exact_form),
      "take the model's form as exact: no model error in the likelihood (docs/diagnose.md \"Model error\"; "
      "for comparison with diagnoses made before it)")(
      "effect-prior-odds", po::value(&dopt.effect_prior_odds)->default_value(dopt.effect_prior_odds),
      "prior odds of one more missing effect against one fewer, on top of the ln N of being one of N candidates "
      "(0 < odds <= 1; 1: only the ln N; docs/diagnose.md \"Model error\")")(
      "shape-weight", po::value(&shape_weight), "old form of --shape-sigma: shape σ = 0.001 / weight")(
      "mac-min", po::value(&dopt.pairing.mac_min)->default_value(dopt.pairing.mac_min), "minimum MAC of a pair while fitting")(
      "sensor-mass", po::value(&config.sensor_mass)->default_value(config.sensor_mass),
      "kg of the transducer at each measured node (one triaxial accelerometer counts once): the test's own sensors, "
      "carried by the model's prediction and never reported as a missing effect. Each roving set's sensors load the "
      "article while that set was measured, when the `ema fit --json` file beside the modes (or MODES.json itself) "
      "lists the sets; else every measured node carries its sensor throughout")(
      "force-level", po::value(&config.force_levels)->composing(),
      "modes fitted at one impact force level, as FORCE_N=MODES.unv; two or more flag amplitude-dependent "
      "stiffness");
  cli::AddHelp(&options);
  po::positional_options_description positional;
  positional.add("model", 1);
  po::variables_map vm;
  if (!cli::Parse(args, usage, options, positional, &vm)) {
    std::cout << "Default priors (relative 1σ per effect kind; a body's or spring's `uncertainty` and the model's\n"
                 "[priors] table override them; docs/diagnose.md):\n"
              << diagnose::PriorDefaultsText();
    return std::nullopt;
  }
  cli::RefuseOutputsOverInputs(vm, {"model", "test", "force-level"}, {"json", "output"});
  if (!diagnose::StringToCriterion(criterion, &dopt.criterion))
    throw UsageError("--criterion must be evidence, bic or aicc, got '" + criterion + "'");
  if (!diagnose::StringToShapeResidual(shape_residual, &dopt.shape_residual))
    throw UsageError("--shape-residual must be per-dof or mac, got '" + shape_residual + "'");
  if (no_pairs) dopt.max_effects = 1;
  if (no_members) dopt.members = false;
  if (exact_form) dopt.model_error = false;
  if (vm.count("shape-weight")) {
    if (!(shape_weight > 0.0)) throw UsageError("--shape-weight must be > 0");
    dopt.shape_sigma = 1e-3 / shape_weight;
  }
  if (std::string bad; !dopt.IsValid(&bad)) throw UsageError(bad);
  if (config.force_levels.size() == 1) throw UsageError("--force-level needs at least two levels");
  if (!(config.sensor_mass >= 0.0) || !std::isfinite(config.sensor_mass))
    throw UsageError("--sensor-mass must be a mass in kg >= 0 (0.0112 for an 11.2 g accelerometer)");

  for (const std::string& t : tests) config.tests.push_back(SplitSetup(t));
  return config;
}

std::string app::DiagnosisSummary(const pipeline::DiagnoseStage& stage) {
  const diagnose::Diagnosis& d = stage.diagnosis;
  const pipeline::Findings& f = stage.findings;
  std::ostringstream out;
  auto adequacy = [&] {
    out << "  " << (f.adequate ? "Adequate to the test's noise: yes" : "Adequate to the test's noise: NO")
        << " — reduced χ² " << (f.well_inside_noise ? std::string("below 0.01") : Number(f.reduced_chi2, 3)) << " over "
        << f.test_modes << " test modes"
        << (f.well_inside_noise ? " (well inside the test's σ; each σ is at least --frequency-floor × f).\n"
            : f.adequate ? " (what the measurement noise explains).\n"
                         : " (1 would be noise alone): the model still misses something these data can see" +
                               std::string(f.effects.empty() ? "" : "; rank 1 is not the whole answer") + ".\n");
  };
  if (f.model_inadequate) InadequateModelWords(d, f, &out);
  if (f.effects.empty()) {
    if (f.model_inadequate) {
      // Not "nothing is missing": something is, but none of the vocabulary's effects explains it
      // beyond the model's own error — outside the vocabulary, unless a reading the model's error
      // also explains is inside it after all (Findings::model_error_lookalike).
      const std::string alike = report::ModelErrorLookAlikeWords(f);
      out << "Diagnosis: no effect the model can try explains the mismatch beyond the model's own error (the model "
             "as given ranks first, probability "
          << Percent(f.rank_one_probability) << ")"
          << (alike.empty() ? std::string("; what is missing is outside the vocabulary.") : alike) << "\n";
    } else
      out << "Diagnosis: no missing effect found (probability " << Percent(f.rank_one_probability)
          << "): no candidate explains the mismatch by more than its prior and parameter cost.\n";
    out << "  Mean frequency error " << FixedPoint(f.error_after_pct, 2) << " %, mean MAC " << FixedPoint(f.mac_after, 3)
        << ".\n";
    adequacy();
  } else {
    out << "Diagnosis: the model misses " << f.effects.size() << " effect" << (f.effects.size() > 1 ? "s" : "")
        << " (rank 1, probability " << HonestPercent(f) << "):\n";
    for (size_t i = 0; i < f.effects.size(); ++i) {
      const pipeline::EffectFinding& e = f.effects[i];
      diagnose::Candidate single;
      single.effects = {e.effect};
      out << "  " << i + 1 << ". " << diagnose::DescribeCandidate(single) << " — " << Percent(e.probability)
          << " over every candidate that holds it";
      if (e.wildcard)
        out << " (" << Percent(e.wildcard_probability) << " for " << model::KindName(e.effect.kind) << " on any of "
            << model::TargetText(*e.wildcard) << ")";
      out << "\n";
      const std::string values = report::EffectValuesWords(e);
      if (!values.empty()) out << "     " << values << "\n";
    }
    out << "  Mean frequency error " << FixedPoint(f.error_before_pct, 2) << " % → " << FixedPoint(f.error_after_pct, 2)
        << " %, mean MAC " << FixedPoint(f.mac_before, 3) << " → " << FixedPoint(f.mac_after, 3) << ".\n";
    adequacy();
    std::string alike;
    for (const pipeline::LookAlike& l : f.lookalikes) {
      std::string text = l.kind + " on " + l.target;
      if (l.readings > 1 || l.holds_rank_one)
        text += " (" + std::to_string(l.readings) + (l.holds_rank_one ? " other" : "") + " reading" + (l.readings > 1 ? "s" : "") + ")";
      alike += (alike.empty() ? "" : "; ") + text + " " + Percent(l.probability);
    }
    out << "  Look-alikes these data cannot separate: " << (alike.empty() ? std::string("none within a factor 20") : alike)
        << ".\n";
  }
  for (const std::string& check : f.checks) out << "  Check: " << check << ".\n";
  return out.str();
}

pipeline::DiagnoseStage app::RunDiagnoseStage(const DiagnoseConfig& config, const model::Model& model,
                                              const std::vector<diagnose::SetupModes>& sets, std::ostream& out) {
  // The same analysis as `ema amplitude` (docs/amplitude.md) with --force-level: levels are peak forces.
  std::vector<correlation::AmplitudeLevel> levels;
  if (!config.force_levels.empty()) levels = formats::ReadAmplitudeLevels(config.force_levels, "--force-level");
  pipeline::DiagnoseStage stage = pipeline::DiagnoseModel(model, sets, config.options, std::move(levels),
                                                          [](double f, std::string_view s) { cli::DrawProgress(f, std::string(s)); });
  if (!config.output.empty()) stage.updated.origin = config.output;
  WriteDiagnosis(config, stage);
  PrintDiagnosis(stage, out);
  return stage;
}

void app::WriteDiagnosis(const DiagnoseConfig& config, const pipeline::DiagnoseStage& stage) {
  if (!config.json_path.empty())
    formats::WriteTextFileAtomically(config.json_path, pipeline::DiagnosisJson(stage).dump(2) + "\n");
  if (!config.output.empty()) {
    const std::vector<model::Effect>& effects = stage.diagnosis.candidates.front().effects;
    if (effects.empty())
      std::cerr << "ema diagnose: rank 1 is 'none': " << config.output << " is the model without an added effect\n";
    formats::ModelWriteOptions write;
    write.bundle = config.bundle;
    formats::WriteModelWithEffects(config.model_path, config.output, effects, write);
  }
}

void app::PrintDiagnosis(const pipeline::DiagnoseStage& stage, std::ostream& out) {
  const diagnose::Diagnosis& d = stage.diagnosis;
  const diagnose::Candidate& first = d.candidates.front();
  out << DiagnosisSummary(stage) << "\n" << d.explanation
      << "\n\n| rank | candidate | parameters | probability | mean |Δf| [%] | mean MAC | score |\n"
      << "|---:|---|---|---:|---:|---:|---:|\n";
  int shown = 0;
  for (const auto& c : d.candidates) {
    if (++shown > 15) {
      out << "| … | " << d.candidates.size() - 15 << " more in DIAG.json | | | | | |\n";
      break;
    }
    std::string params;
    for (const auto& p : c.parameters) {
      char buffer[128];
      std::snprintf(buffer, sizeof buffer, "%s%s=%.4g±%.2g", params.empty() ? "" : ", ", p.name.c_str(), p.value, p.sigma);
      params += buffer;
      if (p.at_bound) params += " (at bound)";
    }
    out << "| " << c.rank << " | " << c.kind << (c.target.empty() ? "" : " of " + c.target) << " | "
        << (c.error.empty() ? params : "failed: " + c.error) << " | " << Fixed(100.0 * c.probability, 1) << " % | "
        << Fixed(c.mean_abs_frequency_error_pct, 2) << " | " << Fixed(c.mean_mac, 3) << " | " << Fixed(c.score, 1) << " |\n";
  }
  if (d.steps.size() > 2) {
    out << "\nThe error as each effect is added:\n";
    for (const auto& st : d.steps)
      out << "  " << (st.added.empty() ? std::string("model as given") : "+ " + st.added) << ": mean |Δf| "
          << Fixed(st.mean_abs_frequency_error_pct, 2) << " %, mean MAC " << Fixed(st.mean_mac, 3) << "\n";
  }
  out << "\nBefore/after (" << (first.effects.empty() ? "no effect" : diagnose::DescribeCandidate(first)) << "):\n\n"
      << ModeTable(d.baseline, first);
  if (stage.nonlinearity) out << "\n" << stage.nonlinearity->summary << "\n";
}

int RunDiagnose(const std::vector<std::string>& args) {
  const std::optional<app::DiagnoseConfig> config = app::ParseDiagnoseArgs(args);
  if (!config) return 0;
  const model::Model model = formats::ReadModelFile(config->model_path);
  std::vector<diagnose::SetupModes> sets;
  for (const auto& [setup, path] : config->tests) {
    ModeSet modes = formats::ReadModeSet(path);
    if (modes.source.empty()) modes.source = path;
    formats::AttachSidecarUncertainty(path, &modes);  // σ of each mode from `ema fit --json`, when beside it
    diagnose::SetupModes test{setup, std::move(modes)};
    test.sensor_mass = config->sensor_mass;
    if (test.sensor_mass > 0.0) formats::ReadSidecarTestSets(path, test.modes, &test.roving_sets, &test.reference);
    sets.push_back(std::move(test));
  }
  app::RunDiagnoseStage(*config, model, sets, std::cout);
  return 0;
}

}  // namespace ema
