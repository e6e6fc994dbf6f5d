// ema diagnose MODEL.toml --test [SETUP=]MODES.unv [--test SETUP2=MODES2.unv ...]
//               [--json DIAG.json] [-o UPDATED.toml] [--force-level F=MODES.unv ...]
// Ranks the physical effects the model is missing (cli.md, issue 7).
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "amplitude_levels.hpp"
#include "cli.hpp"
#include "ema/core/error.hpp"
#include "ema/diagnose/diagnose.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/model/effects.hpp"

namespace ema {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

json Number(double value) { return std::isfinite(value) ? json(value) : json(nullptr); }

// "[SETUP=]PATH": the part before the first '=' is a setup name unless the whole text is an
// existing file (file names may contain '=').
std::pair<std::string, std::string> SplitSetup(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || fs::exists(text)) return {"", text};
  return {text.substr(0, eq), text.substr(eq + 1)};
}

json EffectJson(const model::Effect& e) {
  json out = {{"kind", e.kind}, {"target", e.target}, {"parameters", json::object()}};
  for (const auto& [k, v] : e.parameters) out["parameters"][k] = v;
  if (e.law) out["law"] = formats::LawToToml(*e.law);
  return out;
}

json CandidateJson(const diagnose::Candidate& c) {
  json out = {{"rank", c.rank},
              {"kind", c.kind},
              {"target", c.target},
              {"parameters", json::object()},
              {"uncertainty", json::object()},
              {"prior_sigma", json::object()},
              {"probability", Number(c.probability)},
              {"mean_abs_frequency_error_pct", Number(c.mean_abs_frequency_error_pct)},
              {"mean_mac", Number(c.mean_mac)},
              {"mean_agreement_pct", Number(c.mean_agreement_pct)},
              {"score", Number(c.score)},
              {"log_evidence", Number(c.log_evidence)},
              {"log_prior", Number(c.log_prior)},
              {"cost", Number(c.cost)},
              {"explained_pct", Number(c.explained_pct)},
              {"paired_modes", c.paired_modes},
              {"plausible", c.plausible},
              {"tied_with", c.tied_with},
              {"description", diagnose::DescribeCandidate(c)},
              {"effects", json::array()}};
  const std::vector<std::string> keys = diagnose::ParameterKeys(c);
  for (size_t i = 0; i < c.parameters.size(); ++i) {
    const auto& p = c.parameters[i];
    out["parameters"][keys[i]] = p.value;
    out["uncertainty"][keys[i]] = Number(p.sigma);
    out["prior_sigma"][keys[i]] = Number(p.prior_sigma);
    if (p.at_bound) out["at_bound"].push_back(keys[i]);
  }
  for (const auto& e : c.effects) out["effects"].push_back(EffectJson(e));
  if (!c.error.empty()) out["error"] = c.error;
  return out;
}

std::string Fixed(double v, int digits) {
  if (!std::isfinite(v)) return "–";
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, v);
  return buffer;
}

// Before/after table: every test mode of every setup, the baseline and rank-1 partners.
std::string ModeTable(const diagnose::Candidate& before, const diagnose::Candidate& after, json* rows) {
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
    rows->push_back({{"setup", b.setup},
                     {"test_mode", b.test_mode + 1},
                     {"test_frequency_hz", b.test_frequency_hz},
                     {"model_frequency_hz_before", Number(b.model_frequency_hz)},
                     {"agreement_pct_before", Number(b.agreement_pct)},
                     {"mac_before", Number(b.mac)},
                     {"model_frequency_hz_after", Number(a.model_frequency_hz)},
                     {"agreement_pct_after", Number(a.agreement_pct)},
                     {"mac_after", Number(a.mac)}});
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

int RunDiagnose(const std::vector<std::string>& args) {
  namespace po = cli::po;
  const std::string usage =
      "ema diagnose MODEL.toml --test [SETUP=]MODES.unv [--test SETUP2=MODES2.unv ...] [--json DIAG.json] "
      "[-o UPDATED.toml]";
  po::options_description options("options");
  std::string model_path, json_path, out_path, criterion = "evidence";
  std::vector<std::string> tests, force_levels;
  bool no_pairs = false, no_members = false;
  double shape_weight = 0.0;
  diagnose::DiagnoseOptions dopt;
  options.add_options()("model", po::value(&model_path)->required(), "model file (.toml)")(
      "test", po::value(&tests)->required()->composing(),
      "test modes (UFF 55) of one setup, as SETUP=MODES.unv (or MODES.unv for the nominal model); repeat per setup")(
      "json", po::value(&json_path), "write the ranking as JSON (DIAG.json)")(
      "output,o", po::value(&out_path),
      "write the model with the rank-1 effect(s) added as [[effect]] blocks; relative paths in it are rewritten so "
      "that it loads from its own folder")(
      "criterion", po::value(&criterion)->default_value("evidence"),
      "ranking: evidence (Laplace approximation with the priors), bic or aicc (no priors)")(
      "max-effects", po::value(&dopt.max_effects)->default_value(3), "largest number of effects combined (1..3)")(
      "no-pairs", po::bool_switch(&no_pairs), "single effects only (same as --max-effects 1)")(
      "no-members", po::bool_switch(&no_members), "only whole groups, all points and bodies (no members or single points)")(
      "frequency-floor", po::value(&dopt.frequency_floor)->default_value(dopt.frequency_floor),
      "relative 1σ floor of a test frequency; a mode's σ is max(its stabilisation spread, floor × f)")(
      "shape-sigma", po::value(&dopt.shape_sigma)->default_value(dopt.shape_sigma), "1σ of (1 - MAC)")(
      "shape-weight", po::value(&shape_weight), "old form of --shape-sigma: shape σ = 0.001 / weight")(
      "mac-min", po::value(&dopt.pairing.mac_min)->default_value(0.5), "minimum MAC of a pair while fitting")(
      "force-level", po::value(&force_levels)->composing(),
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
    return 0;
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
  if (force_levels.size() == 1) throw UsageError("--force-level needs at least two levels");

  const model::Model model = formats::ReadModelFile(model_path);
  std::vector<diagnose::SetupModes> sets;
  for (const std::string& t : tests) {
    auto [setup, path] = SplitSetup(t);
    ModeSet modes = formats::ReadModeSet(path);
    if (modes.source.empty()) modes.source = path;
    app::AttachSidecarUncertainty(path, &modes);  // σ of each mode from `ema fit --json`, when beside it
    sets.push_back({setup, std::move(modes)});
  }
  dopt.progress = [](double f, std::string_view stage) { cli::DrawProgress(f, std::string(stage)); };
  const diagnose::Diagnosis d = diagnose::Diagnose(model, sets, dopt);

  json out;
  out["baseline"] = {{"mean_abs_frequency_error_pct", Number(d.baseline.mean_abs_frequency_error_pct)},
                     {"mean_mac", Number(d.baseline.mean_mac)},
                     {"mean_agreement_pct", Number(d.baseline.mean_agreement_pct)},
                     {"score", Number(d.baseline.score)},
                     {"cost", Number(d.baseline.cost)},
                     {"paired_modes", d.baseline.paired_modes}};
  out["candidates"] = json::array();
  for (const auto& c : d.candidates) out["candidates"].push_back(CandidateJson(c));
  out["criterion"] = diagnose::CriterionToString(dopt.criterion);
  out["options"] = {{"frequency_floor", dopt.frequency_floor}, {"shape_sigma", dopt.shape_sigma},
                    {"max_effects", dopt.max_effects}, {"members", dopt.members},
                    {"mac_min", dopt.pairing.mac_min}};  // the effective options, for reproducibility
  out["residual_count"] = d.residual_count;
  out["test_modes"] = d.test_mode_count;
  out["model_solves"] = d.model_solves;
  out["candidates_screened"] = d.candidates_screened;
  out["explanation"] = d.explanation;
  out["effect_probabilities"] = json::array();
  for (const auto& e : d.effect_probabilities)
    out["effect_probabilities"].push_back({{"kind", e.kind}, {"target", e.target}, {"probability", e.probability}});
  out["steps"] = json::array();
  for (const auto& st : d.steps)
    out["steps"].push_back({{"added", st.added},
                            {"mean_abs_frequency_error_pct", Number(st.mean_abs_frequency_error_pct)},
                            {"mean_mac", Number(st.mean_mac)},
                            {"mean_agreement_pct", Number(st.mean_agreement_pct)}});
  json mode_rows = json::array();
  const diagnose::Candidate& first = d.candidates.front();

  std::cout << DiagnosisSummary(d) << "\n\n" << d.explanation
            << "\n\n| rank | candidate | parameters | probability | mean |Δf| [%] | mean MAC | score |\n"
            << "|---:|---|---|---:|---:|---:|---:|\n";
  int shown = 0;
  for (const auto& c : d.candidates) {
    if (++shown > 15) {
      std::cout << "| … | " << d.candidates.size() - 15 << " more in DIAG.json | | | | | |\n";
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
    std::cout << "| " << c.rank << " | " << c.kind << (c.target.empty() ? "" : " of " + c.target) << " | "
              << (c.error.empty() ? params : "failed: " + c.error) << " | " << Fixed(100.0 * c.probability, 1)
              << " % | " << Fixed(c.mean_abs_frequency_error_pct, 2) << " | " << Fixed(c.mean_mac, 3) << " | "
              << Fixed(c.score, 1) << " |\n";
  }
  if (d.steps.size() > 2) {
    std::cout << "\nThe error as each effect is added:\n";
    for (const auto& st : d.steps)
      std::cout << "  " << (st.added.empty() ? std::string("model as given") : "+ " + st.added) << ": mean |Δf| "
                << Fixed(st.mean_abs_frequency_error_pct, 2) << " %, mean MAC " << Fixed(st.mean_mac, 3) << "\n";
  }
  std::cout << "\nBefore/after (" << (first.kind == "none" ? "no effect" : diagnose::DescribeCandidate(first))
            << "):\n\n"
            << ModeTable(d.baseline, first, &mode_rows);
  out["modes"] = mode_rows;

  if (!force_levels.empty()) {
    // The same analysis as `ema amplitude` (docs/amplitude.md): levels are peak forces here.
    const correlation::AmplitudeResult amplitude = correlation::AnalyseAmplitude(
        app::ReadAmplitudeLevels(force_levels, "--force-level"), correlation::LevelKind::kPeakForce);
    json nonlinearity = app::AmplitudeJson(amplitude);
    bool flagged = false;
    for (const auto& m : amplitude.modes)
      flagged = flagged || m.frequency_trend != correlation::FrequencyTrend::kNone ||
                m.damping_trend != correlation::DampingTrend::kNone;
    nonlinearity["flagged"] = flagged;
    nonlinearity["summary"] = amplitude.summary;
    out["nonlinearity"] = nonlinearity;
    std::cout << "\n" << amplitude.summary << "\n";
  }

  if (!json_path.empty()) formats::WriteTextFileAtomically(json_path, out.dump(2) + "\n");
  if (!out_path.empty()) {
    if (first.effects.empty())
      std::cerr << "ema diagnose: rank 1 is 'none': " << out_path << " is the model without an added effect\n";
    formats::WriteModelWithEffects(model_path, out_path, first.effects);  // relative paths rewritten
  }
  return 0;
}

}  // namespace ema
