// ema diagnose MODEL.toml --test [SETUP=]MODES.unv [--test SETUP2=MODES2.unv ...]
//               [--json DIAG.json] [-o UPDATED.toml] [--force-level F=MODES.unv ...]
// Ranks the physical effects the model is missing (cli.md, issue 7).
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <nlohmann/json.hpp>
#include <sstream>

#include "amplitude_levels.hpp"
#include "cli.hpp"
#include "ema/core/error.hpp"
#include "ema/core/text.hpp"
#include "ema/diagnose/diagnose.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/formats/json_codecs.hpp"
#include "ema/model/effects.hpp"
#include "stages.hpp"

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
  for (size_t i = 0; i < before.modes.size() && i < after.modes.size(); ++i) {
    const auto& b = before.modes[i];
    const auto& a = after.modes[i];
    out << "| " << (b.setup.empty() ? "nominal" : b.setup) << " | " << b.test_mode + 1 << " | "
        << Fixed(b.test_frequency_hz, 1) << " | " << Fixed(b.model_frequency_hz, 1) << " | "
        << Fixed(b.agreement_pct, 1) << " | " << Fixed(b.mac, 3) << " | " << Fixed(a.model_frequency_hz, 1) << " | "
        << Fixed(a.agreement_pct, 1) << " | " << Fixed(a.mac, 3) << " |\n";
  }
  return out.str();
}

// One line for the user: what, where (members named), how sure.
std::string DiagnosisSummary(const diagnose::Diagnosis& d) {
  const diagnose::Candidate& first = d.candidates.front();
  char p[32];
  std::snprintf(p, sizeof p, "%.1f %%", 100.0 * first.probability);
  if (first.effects.empty()) return std::string("Diagnosis: no missing effect (probability ") + p + ").";
  std::vector<std::string> parts;
  for (const auto& e : first.effects) {
    const auto slash = e.target.find('/');
    std::string where = slash == std::string::npos
                            ? e.target
                            : "member " + e.target.substr(slash + 1) + " of " + e.target.substr(0, slash);
    parts.push_back(e.kind + " on " + where);
  }
  std::string out = "Diagnosis: ";
  for (size_t i = 0; i < parts.size(); ++i) out += (i ? " + " : "") + parts[i];
  out += " (probability " + std::string(p) + ").";
  // Rank 1 may share its probability with near-equal variants (another point, another member):
  // how sure each of its effects is, whichever candidate holds it.
  if (first.probability < 0.9) {
    for (const auto& e : first.effects) {
      const std::string wildcard = diagnose::EffectWildcard(e.target);
      for (const auto& ep : d.effect_probabilities)
        if (ep.kind == e.kind && ep.target == wildcard) {
          std::snprintf(p, sizeof p, "%.1f %%", 100.0 * ep.probability);
          out += "\n  " + e.kind + " on " + wildcard + ": " + p + " over all candidates";
        }
    }
  }
  return out;
}

}  // namespace

std::optional<app::DiagnoseConfig> app::ParseDiagnoseArgs(const std::vector<std::string>& args, bool require_inputs) {
  namespace po = cli::po;
  const std::string usage =
      "ema diagnose MODEL.toml --test [SETUP=]MODES.unv [--test SETUP2=MODES2.unv ...] [--json DIAG.json] "
      "[-o UPDATED.toml]";
  po::options_description options("options");
  DiagnoseConfig config;
  std::string criterion = diagnose::CriterionToString(config.options.criterion);
  std::vector<std::string> tests;
  bool no_pairs = false, no_members = false;
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
      "write the model with the rank-1 effect(s) added as [[effect]] blocks; relative paths in it are rewritten so "
      "that it loads from its own folder")(
      "criterion", po::value(&criterion)->default_value(criterion),
      "ranking: evidence (Laplace approximation with the priors), bic or aicc (no priors)")(
      "max-effects", po::value(&dopt.max_effects)->default_value(dopt.max_effects), "largest number of effects combined (1..3)")(
      "no-pairs", po::bool_switch(&no_pairs), "single effects only (same as --max-effects 1)")(
      "no-members", po::bool_switch(&no_members), "only whole groups, all points and bodies (no members or single points)")(
      "frequency-floor", po::value(&dopt.frequency_floor)->default_value(dopt.frequency_floor),
      "relative 1σ floor of a test frequency; a mode's σ is max(its stabilisation spread, floor × f)")(
      "shape-sigma", po::value(&dopt.shape_sigma)->default_value(dopt.shape_sigma), "1σ of (1 - MAC)")(
      "shape-weight", po::value(&shape_weight), "old form of --shape-sigma: shape σ = 0.001 / weight")(
      "mac-min", po::value(&dopt.pairing.mac_min)->default_value(dopt.pairing.mac_min), "minimum MAC of a pair while fitting")(
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
  if (no_pairs) dopt.max_effects = 1;
  if (no_members) dopt.members = false;
  if (vm.count("shape-weight")) {
    if (!(shape_weight > 0.0)) throw UsageError("--shape-weight must be > 0");
    dopt.shape_sigma = 1e-3 / shape_weight;
  }
  if (std::string bad; !dopt.IsValid(&bad)) throw UsageError(bad);
  if (config.force_levels.size() == 1) throw UsageError("--force-level needs at least two levels");

  for (const std::string& t : tests) config.tests.push_back(SplitSetup(t));
  return config;
}

app::DiagnoseStageResult app::RunDiagnoseStage(const DiagnoseConfig& config, const model::Model& model,
                                               const std::vector<diagnose::SetupModes>& sets, std::ostream& out) {
  diagnose::DiagnoseOptions dopt = config.options;
  dopt.progress = [](double f, std::string_view stage) { cli::DrawProgress(f, std::string(stage)); };
  DiagnoseStageResult stage;
  stage.diagnosis = diagnose::Diagnose(model, sets, dopt);
  const diagnose::Diagnosis& d = stage.diagnosis;
  json& json_out = stage.json;
  json_out = formats::DiagnosisJson(d, dopt);
  const diagnose::Candidate& first = d.candidates.front();
  out << DiagnosisSummary(d) << "\n\n" << d.explanation
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
      std::snprintf(buffer, sizeof buffer, "%s%s=%.4g±%.2g", params.empty() ? "" : ", ", p.name.c_str(), p.value,
                    p.sigma);
      params += buffer;
      if (p.at_bound) params += " (at bound)";
    }
    out << "| " << c.rank << " | " << c.kind << (c.target.empty() ? "" : " of " + c.target) << " | "
              << (c.error.empty() ? params : "failed: " + c.error) << " | " << Fixed(100.0 * c.probability, 1)
              << " % | " << Fixed(c.mean_abs_frequency_error_pct, 2) << " | " << Fixed(c.mean_mac, 3) << " | "
              << Fixed(c.score, 1) << " |\n";
  }
  if (d.steps.size() > 2) {
    out << "\nThe error as each effect is added:\n";
    for (const auto& st : d.steps)
      out << "  " << (st.added.empty() ? std::string("model as given") : "+ " + st.added) << ": mean |Δf| "
                << Fixed(st.mean_abs_frequency_error_pct, 2) << " %, mean MAC " << Fixed(st.mean_mac, 3) << "\n";
  }
  out << "\nBefore/after (" << (first.kind == "none" ? "no effect" : diagnose::DescribeCandidate(first))
            << "):\n\n"
            << ModeTable(d.baseline, first);
  json_out["modes"] = formats::DiagnosisModeRows(d.baseline, first);

  if (!config.force_levels.empty()) {
    // The same analysis as `ema amplitude` (docs/amplitude.md): levels are peak forces here.
    const correlation::AmplitudeResult amplitude = correlation::AnalyseAmplitude(
        app::ReadAmplitudeLevels(config.force_levels, "--force-level"), correlation::LevelKind::kPeakForce);
    json nonlinearity = app::AmplitudeJson(amplitude);
    bool flagged = false;
    for (const auto& m : amplitude.modes)
      flagged = flagged || m.frequency_trend != correlation::FrequencyTrend::kNone ||
                m.damping_trend != correlation::DampingTrend::kNone;
    nonlinearity["flagged"] = flagged;
    nonlinearity["summary"] = amplitude.summary;
    json_out["nonlinearity"] = nonlinearity;
    out << "\n" << amplitude.summary << "\n";
  }

  stage.updated = model;
  stage.updated.effects.insert(stage.updated.effects.end(), first.effects.begin(), first.effects.end());
  if (!config.json_path.empty()) formats::WriteTextFileAtomically(config.json_path, json_out.dump(2) + "\n");
  if (!config.output.empty()) {
    if (first.effects.empty())
      std::cerr << "ema diagnose: rank 1 is 'none': " << config.output << " is the model without an added effect\n";
    formats::WriteModelWithEffects(config.model_path, config.output, first.effects);  // relative paths rewritten
    stage.updated.origin = config.output;
  }
  return stage;
}

int RunDiagnose(const std::vector<std::string>& args) {
  const std::optional<app::DiagnoseConfig> config = app::ParseDiagnoseArgs(args);
  if (!config) return 0;
  const model::Model model = formats::ReadModelFile(config->model_path);
  std::vector<diagnose::SetupModes> sets;
  for (const auto& [setup, path] : config->tests) {
    ModeSet modes = formats::ReadModeSet(path);
    if (modes.source.empty()) modes.source = path;
    app::AttachSidecarUncertainty(path, &modes);  // σ of each mode from `ema fit --json`, when beside it
    sets.push_back({setup, std::move(modes)});
  }
  app::RunDiagnoseStage(*config, model, sets, std::cout);
  return 0;
}

}  // namespace ema
