// ema diagnose MODEL.toml --test [SETUP=]MODES.unv [--test SETUP2=MODES2.unv ...]
//               [--json DIAG.json] [-o UPDATED.toml] [--force-level F=MODES.unv ...]
// Ranks the physical effects the model is missing (cli.md, issue 7).
#include <algorithm>
#include <cmath>
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
#include "ema/model/solve.hpp"
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

std::string Number(double v, int digits = 3) {
  char b[48];
  std::snprintf(b, sizeof b, "%.*g", digits, v);
  return b;
}

// A fitted parameter in engineering units with its 1σ: "E' = 57.2 ± 1.1 GPa", "× 0.31 ± 0.02".
std::string ParameterWords(const diagnose::FittedParameter& p, const model::Effect& e) {
  const bool sigma = std::isfinite(p.sigma);
  auto with = [&](double scale, const std::string& unit, const std::string& name) {
    return name + Number(p.value * scale) + (sigma ? " ± " + Number(p.sigma * scale, 2) : "") + unit;
  };
  const bool hertz = e.law && std::holds_alternative<model::HertzLaw>(e.law->value);
  if (p.name == "modulus" || hertz) {
    double radius = kNaN;
    if (hertz) radius = std::get<model::HertzLaw>(e.law->value).radius;
    return with(1e-9, " GPa", "Hertz contact E' = ") + (std::isfinite(radius) ? " (R' = " + Number(radius * 1e3) + " mm)" : "");
  }
  if (p.effect_kind == "series_compliance" || p.effect_kind == "ground_spring") return with(1e-6, " N/µm", "k = ");
  if (p.effect_kind == "added_mass") return with(1e3, " g per point", "");
  if (p.effect_kind == "operating_point")
    return std::abs(p.value) < 1e-3 ? with(1e6, " µm", "value = ") : with(1.0, "", "value = ");
  return with(1.0, "", "factor ");
}

// Per setup, the mean linearised stiffness of a spring group's springs with rank 1's effects, and
// of the series element the effect added: the numbers of a mount or joint an engineer compares
// with a catalogue ("per spring: 2.80 N/µm at stud-5um, ...").
std::string SpringStiffnessWords(const model::Model& model, const std::vector<model::Effect>& effects,
                                 const model::Effect& e, const std::vector<std::string>& setups) {
  if (model::TargetSprings(model, e.target).empty()) return "";
  model::Model updated = model;
  for (const auto& x : effects) updated = model::ApplyEffect(updated, x);
  const std::vector<int> springs = model::TargetSprings(updated, e.target);
  std::vector<std::string> whole, element;
  for (const std::string& setup : setups) {
    model::SolveOptions so;
    so.setup = setup;
    const model::Solution sol = model::Solve(updated, so);
    double k = 0.0, k_element = 0.0;
    int n = 0, n_element = 0;
    for (int i : springs) {
      const model::SpringState& st = sol.springs[static_cast<size_t>(i)];
      k += st.stiffness;
      ++n;
      if (e.kind == "series_compliance" && !st.element_stiffnesses.empty())
        k_element += st.element_stiffnesses.back(), ++n_element;
    }
    const std::string at = setup.empty() ? "" : " at " + setup;
    if (n) whole.push_back(Number(k / n / 1e6) + " N/µm" + at);
    if (n_element) element.push_back(Number(k_element / n_element / 1e6) + " N/µm" + at);
  }
  if (whole.empty()) return "";
  std::string out = "per spring of '" + e.target + "' now: ";
  for (size_t i = 0; i < whole.size(); ++i) out += (i ? ", " : "") + whole[i];
  if (!element.empty()) {
    out += " (the element in series alone: ";
    for (size_t i = 0; i < element.size(); ++i) out += (i ? ", " : "") + element[i];
    out += ")";
  }
  return out;
}

std::string Percent(double p) {
  char b[32];
  std::snprintf(b, sizeof b, p >= 0.9995 ? "%.1f %%" : "%.1f %%", 100.0 * p);
  return b;
}

// The first screen: which effects are missing and how sure, each value with its σ in engineering
// units, whether the model is then adequate to the test's noise, the look-alike readings the data
// cannot separate (folded per member and point), and what to check.
// A probability beside a model that stays inadequate: computed with the model's error
// marginalised, but still only among the vocabulary's readings, so never said as certainty.
std::string HonestPercent(const diagnose::Candidate& c) {
  if (c.noise_consistent || c.probability < 0.99) return Percent(c.probability);
  return "above 99 % among the readings tried, none of which makes the model adequate";
}

// The first lines for a model that no reading makes adequate: that first, where the misfit sits
// (rank 1's evidence per test mode), and which kinds of missing physics fit such a pattern.
void InadequateModelWords(const diagnose::Diagnosis& d, std::ostringstream* out) {
  const diagnose::Candidate& first = d.candidates.front();
  *out << "The model is NOT adequate to this test, with or without the effects it can try: its own error (about "
       << Number(100.0 * first.model_error.frequency_rel, 2) << " % of each frequency";
  if (first.model_error.frequency_common_rel >= first.model_error.frequency_rel)
    *out << " and " << Number(100.0 * first.model_error.frequency_common_rel, 2) << " % shared by all of them";
  *out << ", 1 − MAC about " << Number(first.model_error.shape, 2)
       << ") is larger than the test's σ. The readings below are the vocabulary's best; their probabilities are "
          "computed with that error and compare them with each other only.\n";
  // Where the misfit sits: the modes rank 1 leaves furthest off, in σ of the test.
  std::vector<const diagnose::ModeComparison*> modes;
  for (const auto& m : first.modes) modes.push_back(&m);
  std::sort(modes.begin(), modes.end(), [](const auto* a, const auto* b) {
    return std::hypot(a->frequency_misfit_sigma, a->shape_misfit_sigma) > std::hypot(b->frequency_misfit_sigma, b->shape_misfit_sigma);
  });
  std::string where;
  for (size_t i = 0; i < modes.size() && i < 3; ++i) {
    const auto& m = *modes[i];
    where += (i ? "; " : "") + std::string("mode ") + std::to_string(m.test_mode + 1) + (m.setup.empty() ? "" : " of " + m.setup) +
             " (" + Number(m.test_frequency_hz, 4) + " Hz): frequency " + (m.frequency_misfit_sigma >= 0 ? "+" : "") +
             Number(m.frequency_misfit_sigma, 2) + "σ, shape " + Number(m.shape_misfit_sigma, 2) + "σ";
  }
  if (!where.empty()) *out << "  Where the misfit sits (rank 1, in the test's σ): " << where << ".\n";
  // Which kinds of missing physics fit the pattern.
  int above = 0, below = 0, paired = 0;
  double frequency2 = 0.0, shape2 = 0.0, frequency_sum = 0.0;
  for (const auto& m : first.modes) {
    if (m.model_mode < 0) continue;
    ++paired;
    if (m.frequency_misfit_sigma > 1.0) ++above;
    if (m.frequency_misfit_sigma < -1.0) ++below;
    frequency_sum += m.frequency_misfit_sigma;
    frequency2 += m.frequency_misfit_sigma * m.frequency_misfit_sigma;
    shape2 += m.shape_misfit_sigma * m.shape_misfit_sigma;
  }
  std::vector<std::string> kinds;
  // Every mode off the same way, or the error the modes share inferred at least as large as the
  // one of each (DIAG.json model_error.frequency_common_rel): a distributed error of the model.
  const bool together = (paired > 0 && (above == paired || below == paired)) ||
                        (paired > 1 && first.model_error.frequency_common_rel >= first.model_error.frequency_rel);
  if (together)
    kinds.push_back(std::string("distributed ") +
                    (frequency_sum > 0.0 ? "stiffness too high or mass too low" : "stiffness too low or mass too high") +
                    " everywhere (a material property, a spread non-structural mass)");
  else if (above > 0 && below > 0)
    kinds.push_back("stiffness or mass distributed differently from the model (zone-wise scatter, a boundary the model fixes or frees)");
  if (shape2 > frequency2) kinds.push_back("a missing part or a local mode (the shapes are off more than the frequencies)");
  if (static_cast<int>(first.modes.size()) > paired) kinds.push_back("modes the model does not have (a missing part, a local mode)");
  if (kinds.empty()) kinds.push_back("a boundary, a distributed stiffness or mass, or a missing part");
  *out << "  Missing physics that fits such a pattern: ";
  for (size_t i = 0; i < kinds.size(); ++i) *out << (i ? "; or " : "") << kinds[i];
  *out << ".\n";
}

// Rank 1's effects as the first screen and the report give them: the words once, here, with
// the numbers they stand for (DIAG.json "findings"; the report reads these fields and parses
// no text).
struct EffectFinding {
  std::string kind, target;
  std::string description;  ///< e.g. "a Hertz contact in series with group 'bearings'" (no values)
  std::string full;         ///< the same with a law's constants, as the summary line gives it
  std::string values;       ///< the fitted values in engineering units with σ, and what they mean per spring
  double probability = 0.0;  ///< over every candidate that holds this effect
  std::string wildcard;      ///< the same kind on any member/point of the group ("" when none)
  double wildcard_probability = 0.0;
};

std::vector<EffectFinding> RankOneFindings(const diagnose::Diagnosis& d, const model::Model& model) {
  std::vector<EffectFinding> out;
  const diagnose::Candidate& first = d.candidates.front();
  std::vector<std::string> setups;
  for (const auto& m : first.modes)
    if (std::find(setups.begin(), setups.end(), m.setup) == setups.end()) setups.push_back(m.setup);
  for (const model::Effect& e : first.effects) {
    EffectFinding f;
    f.kind = e.kind;
    f.target = e.target;
    diagnose::Candidate single = first;
    single.effects = {e};
    f.full = diagnose::DescribeCandidate(single);
    f.description = diagnose::DescribeCandidate(single, false);
    const std::string wildcard = diagnose::EffectWildcard(e.target);
    for (const auto& ep : d.effect_probabilities) {
      if (ep.kind == e.kind && ep.target == e.target) f.probability = ep.probability;
      if (ep.kind == e.kind && ep.target == wildcard && wildcard != e.target) {
        f.wildcard = wildcard;
        f.wildcard_probability = ep.probability;
      }
    }
    for (const auto& p : first.parameters)
      if (p.effect_kind == e.kind && p.target == e.target) f.values += (f.values.empty() ? "" : "; ") + ParameterWords(p, e);
    const std::string springs = SpringStiffnessWords(model, first.effects, e, setups);
    if (!springs.empty()) f.values += (f.values.empty() ? "" : "; ") + springs;
    out.push_back(std::move(f));
  }
  return out;
}

nlohmann::json FindingsJson(const std::vector<EffectFinding>& findings) {
  nlohmann::json out = nlohmann::json::array();
  for (const EffectFinding& f : findings) {
    nlohmann::json j = {{"kind", f.kind}, {"target", f.target}, {"description", f.description},
                        {"values", f.values}, {"probability", f.probability}};
    if (f.wildcard_probability > 0.0) j["any"] = {{"target", f.wildcard}, {"probability", f.wildcard_probability}};
    out.push_back(std::move(j));
  }
  return out;
}

std::string DiagnosisSummary(const diagnose::Diagnosis& d, const std::vector<EffectFinding>& findings) {
  const diagnose::Candidate& first = d.candidates.front();
  // No reading makes the model adequate and its own error dominates the test's σ.
  const bool inadequate_model = !first.noise_consistent && first.model_error.dominates;
  std::ostringstream out;
  auto adequacy = [&](const diagnose::Candidate& c) {
    const bool tiny = c.noise_consistent && c.reduced_chi2 < 0.01;  // well inside σ (the floor may dominate it)
    out << "  " << (c.noise_consistent ? "Adequate to the test's noise: yes" : "Adequate to the test's noise: NO")
        << " — reduced χ² " << (tiny ? std::string("below 0.01") : Number(c.reduced_chi2, 3)) << " over "
        << d.test_mode_count << " test modes"
        << (tiny ? " (well inside the test's σ; each σ is at least --frequency-floor × f).\n"
            : c.noise_consistent ? " (what the measurement noise explains).\n"
                               : " (1 would be noise alone): the model still misses something these data can see"
                                 + std::string(c.effects.empty() ? "" : "; rank 1 is not the whole answer") + ".\n");
  };
  if (inadequate_model) InadequateModelWords(d, &out);
  if (first.effects.empty()) {
    if (inadequate_model)
      // Not "nothing is missing": something is, but none of the vocabulary's effects explains it
      // beyond the model's own error.
      out << "Diagnosis: no effect the model can try explains the mismatch beyond the model's own error (the model "
             "as given ranks first, probability "
          << Percent(first.probability) << "); what is missing is outside the vocabulary.\n";
    else
      out << "Diagnosis: no missing effect found (probability " << Percent(first.probability)
          << "): no candidate explains the mismatch by more than its prior and parameter cost.\n";
    out << "  Mean frequency error " << FixedPoint(first.mean_abs_frequency_error_pct, 2) << " %, mean MAC "
        << FixedPoint(first.mean_mac, 3) << ".\n";
    adequacy(first);
  } else {
    out << "Diagnosis: the model misses " << first.effects.size() << " effect" << (first.effects.size() > 1 ? "s" : "")
        << " (rank 1, probability " << HonestPercent(first) << "):\n";
    for (size_t i = 0; i < findings.size(); ++i) {
      const EffectFinding& f = findings[i];
      out << "  " << i + 1 << ". " << f.full << " — " << Percent(f.probability) << " over every candidate that holds it";
      if (f.wildcard_probability > 0.0)
        out << " (" << Percent(f.wildcard_probability) << " for " << f.kind << " on any of " << f.wildcard << ")";
      out << "\n";
      if (!f.values.empty()) out << "     " << f.values << "\n";
    }
    out << "  Mean frequency error " << FixedPoint(d.baseline.mean_abs_frequency_error_pct, 2) << " % → "
        << FixedPoint(first.mean_abs_frequency_error_pct, 2) << " %, mean MAC " << FixedPoint(d.baseline.mean_mac, 3)
        << " → " << FixedPoint(first.mean_mac, 3) << ".\n";
    adequacy(first);
  }
  // Look-alikes: the other readings within a factor 20 of rank 1's probability, one line per
  // group of the same reading on other members or points.
  std::vector<std::string> alike;
  for (const diagnose::CandidateGroup& g : d.groups) {
    const bool holds_first = std::find(g.ranks.begin(), g.ranks.end(), 1) != g.ranks.end();
    const double p = holds_first ? g.probability - first.probability : g.probability;
    const int others = static_cast<int>(g.ranks.size()) - (holds_first ? 1 : 0);
    if (others <= 0 || g.kind == "none" || !(p >= 0.05 * first.probability) || !(p >= 0.001)) continue;
    std::string text = g.kind + " on " + g.target;
    if (others > 1 || holds_first) text += " (" + std::to_string(others) + (holds_first ? " other" : "") + " reading" + (others > 1 ? "s" : "") + ")";
    alike.push_back(text + " " + Percent(p));
    if (alike.size() == 4) break;
  }
  if (!first.effects.empty())
    out << "  Look-alikes these data cannot separate: " << (alike.empty() ? std::string("none within a factor 20") : "")
        << [&] {
             std::string s;
             for (size_t i = 0; i < alike.size(); ++i) s += (i ? "; " : "") + alike[i];
             return s;
           }()
        << ".\n";
  for (const auto& flag : first.flags) out << "  Check: " << flag << ".\n";
  return out.str();
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
      "shape-sigma", po::value(&dopt.shape_sigma)->default_value(dopt.shape_sigma), "1σ of (1 - MAC)")(
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
  const std::vector<EffectFinding> findings = RankOneFindings(d, model);
  stage.summary = DiagnosisSummary(d, findings);
  json_out["summary"] = stage.summary;
  json_out["findings"] = FindingsJson(findings);
  out << stage.summary << "\n" << d.explanation
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
    formats::ModelWriteOptions write;
    write.bundle = config.bundle;
    formats::WriteModelWithEffects(config.model_path, config.output, first.effects, write);
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
    diagnose::SetupModes test{setup, std::move(modes)};
    test.sensor_mass = config->sensor_mass;
    if (test.sensor_mass > 0.0) app::ReadSidecarTestSets(path, test.modes, &test.roving_sets, &test.reference);
    sets.push_back(std::move(test));
  }
  app::RunDiagnoseStage(*config, model, sets, std::cout);
  return 0;
}

}  // namespace ema
