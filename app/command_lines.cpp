// The command line of each stage's config (CommandLine): the one place a typed config is said as
// the `ema <x>` arguments that would run it — `ema run`'s logs, `ema pick`'s "equivalent", the
// report's selection line. Options at their defaults are left out; paths are shell words.
#include <algorithm>
#include <string_view>

#include "ema/core/names.hpp"
#include "stages.hpp"
#include "words.hpp"

namespace ema::app {

using report::SelectText;

namespace {

std::string Words(const std::vector<std::string>& words) {
  std::string text;
  for (const std::string& w : words) text += (text.empty() ? "" : " ") + w;
  return text;
}

}  // namespace

std::string ShellWord(const std::string& text) {
  const bool plain = !text.empty() && std::all_of(text.begin(), text.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || std::string_view("_./:=,+-").find(c) != std::string_view::npos;
  });
  if (plain) return text;
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

std::string CommandLine(const SimulateConfig& config) {
  std::vector<std::string> w = {"simulate", ShellWord(config.model_path), "--plan", ShellWord(config.plan_path), "-o",
                                ShellWord(config.output)};
  if (!config.setup.empty()) w.insert(w.end(), {"--setup", ShellWord(config.setup)});
  if (config.binary) w.push_back("--binary");
  return Words(w);
}

std::string CommandLine(const FrfConfig& config) {
  std::vector<std::string> w = {"frf"};
  for (const std::string& input : config.inputs) w.push_back(ShellWord(input));
  w.insert(w.end(), {"-o", ShellWord(config.output), "--estimator", frf::EstimatorName(config.options.estimator)});
  if (!config.json_path.empty()) w.insert(w.end(), {"--json", ShellWord(config.json_path)});
  const frf::FrfOptions defaults;
  if (config.options.band_lo_hz != defaults.band_lo_hz || config.options.band_hi_hz != defaults.band_hi_hz)
    w.insert(w.end(), {"--band", ExactNumberText(config.options.band_lo_hz) + ":" + ExactNumberText(config.options.band_hi_hz)});
  if (config.binary) w.push_back("--binary");
  return Words(w);
}

std::string CommandLine(const FitConfig& config) {
  const curvefit::FitOptions& o = config.options;
  const curvefit::FitOptions defaults;
  std::vector<std::string> w = {"fit", ShellWord(config.input)};
  if (o.data.band_lo_hz != defaults.data.band_lo_hz || o.data.band_hi_hz != defaults.data.band_hi_hz)
    w.insert(w.end(), {"--band", ExactNumberText(o.data.band_lo_hz) + ":" + ExactNumberText(o.data.band_hi_hz)});
  if (o.polymax.order_max != defaults.polymax.order_max) w.insert(w.end(), {"--order-max", std::to_string(o.polymax.order_max)});
  if (o.method != defaults.method) w.insert(w.end(), {"--method", NameOf(curvefit::kFitMethodNames, o.method)});
  if (o.refine != defaults.refine) w.insert(w.end(), {"--refine", curvefit::RefineMethodToString(o.refine)});
  if (o.stability.frequency_tol != defaults.stability.frequency_tol)
    w.insert(w.end(), {"--freq-tol", ExactNumberText(o.stability.frequency_tol)});
  if (o.stability.damping_tol != defaults.stability.damping_tol)
    w.insert(w.end(), {"--damping-tol", ExactNumberText(o.stability.damping_tol)});
  if (o.stability.mac_min != defaults.stability.mac_min) w.insert(w.end(), {"--mac-min", ExactNumberText(o.stability.mac_min)});
  if (o.polymax.threads != defaults.polymax.threads) w.insert(w.end(), {"--threads", std::to_string(o.polymax.threads)});
  if (!o.select_frequencies_hz.empty()) w.insert(w.end(), {"--select", SelectText(o.select_frequencies_hz)});
  if (!config.output.empty()) w.insert(w.end(), {"-o", ShellWord(config.output)});
  if (!config.json_path.empty()) w.insert(w.end(), {"--json", ShellWord(config.json_path)});
  if (!config.stabilisation_path.empty()) w.insert(w.end(), {"--stabilisation", ShellWord(config.stabilisation_path)});
  if (!config.plot_path.empty()) w.insert(w.end(), {"--plot", ShellWord(config.plot_path)});
  return Words(w);
}

std::string CommandLine(const ModelConfig& config) {
  std::vector<std::string> w = {"model", ShellWord(config.model_path)};
  if (!config.options.setup.empty()) w.insert(w.end(), {"--setup", ShellWord(config.options.setup)});
  w.insert(w.end(), {"-o", ShellWord(config.output)});
  if (!config.json_path.empty()) w.insert(w.end(), {"--json", ShellWord(config.json_path)});
  if (config.binary) w.push_back("--binary");
  if (config.explain) w.push_back("--explain");
  return Words(w);
}

std::string CommandLine(const CorrelateConfig& config) {
  std::vector<std::string> w = {"correlate", ShellWord(config.test_path), ShellWord(config.model_path)};
  if (!config.setup.empty()) w.insert(w.end(), {"--setup", ShellWord(config.setup)});
  if (!config.json_path.empty()) w.insert(w.end(), {"--json", ShellWord(config.json_path)});
  if (!config.table_path.empty()) w.insert(w.end(), {"--table", ShellWord(config.table_path)});
  const correlation::CorrelationOptions defaults;
  if (config.options.pairing.mac_min != defaults.pairing.mac_min)
    w.insert(w.end(), {"--mac-min", ExactNumberText(config.options.pairing.mac_min)});
  return Words(w);
}

std::string CommandLine(const DiagnoseConfig& config) {
  std::vector<std::string> w = {"diagnose", ShellWord(config.model_path)};
  for (const auto& [setup, path] : config.tests) w.insert(w.end(), {"--test", ShellWord((setup.empty() ? "" : setup + "=") + path)});
  if (!config.json_path.empty()) w.insert(w.end(), {"--json", ShellWord(config.json_path)});
  if (!config.output.empty()) w.insert(w.end(), {"-o", ShellWord(config.output)});
  if (config.sensor_mass > 0.0) w.insert(w.end(), {"--sensor-mass", ExactNumberText(config.sensor_mass)});
  if (config.bundle) w.push_back("--bundle");
  const diagnose::DiagnoseOptions& o = config.options;
  const diagnose::DiagnoseOptions defaults;
  if (o.criterion != defaults.criterion) w.insert(w.end(), {"--criterion", diagnose::CriterionToString(o.criterion)});
  if (o.max_effects != defaults.max_effects) w.insert(w.end(), {"--max-effects", std::to_string(o.max_effects)});
  if (o.members != defaults.members) w.push_back("--no-members");
  if (o.frequency_floor != defaults.frequency_floor) w.insert(w.end(), {"--frequency-floor", ExactNumberText(o.frequency_floor)});
  if (o.shape_sigma != defaults.shape_sigma) w.insert(w.end(), {"--shape-sigma", ExactNumberText(o.shape_sigma)});
  if (o.shape_residual != defaults.shape_residual)
    w.insert(w.end(), {"--shape-residual", diagnose::ShapeResidualToString(o.shape_residual)});
  if (o.shape_dof_sigma != defaults.shape_dof_sigma)
    w.insert(w.end(), {"--shape-dof-sigma", ExactNumberText(o.shape_dof_sigma)});
  if (o.model_error != defaults.model_error) w.push_back("--exact-form");
  if (o.effect_prior_odds != defaults.effect_prior_odds)
    w.insert(w.end(), {"--effect-prior-odds", ExactNumberText(o.effect_prior_odds)});
  if (o.pairing.mac_min != defaults.pairing.mac_min) w.insert(w.end(), {"--mac-min", ExactNumberText(o.pairing.mac_min)});
  for (const std::string& level : config.force_levels) w.insert(w.end(), {"--force-level", ShellWord(level)});
  return Words(w);
}

}  // namespace ema::app
