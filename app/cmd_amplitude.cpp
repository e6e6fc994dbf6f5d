// ema amplitude --level F=MODES.unv --level F=MODES.unv [...] [--level-kind K] [--json AMP.json]
//
// Does a mode depend on the excitation level? Modes fitted at several levels are paired across
// the levels, and each mode's frequency and damping trends are tested (docs/amplitude.md).
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli.hpp"
#include "ema/core/error.hpp"
#include "ema/correlation/amplitude.hpp"
#include "ema/formats/amplitude_json.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/modes_sidecar.hpp"
#include "report.hpp"
#include "stages.hpp"

namespace ema {

std::optional<app::AmplitudeConfig> app::ParseAmplitudeArgs(const std::vector<std::string>& args) {
  namespace po = cli::po;
  const std::string usage =
      "ema amplitude --level F=MODES.unv --level F=MODES.unv [...] [--level-kind peak_force|rms_force|response]\n"
      "              [--json AMP.json] [--report AMP.html]";
  po::options_description options(
      "ema amplitude: does a mode depend on the excitation level? (frequency and damping against level, "
      "docs/amplitude.md)");
  AmplitudeConfig config;
  std::string kind_name = correlation::LevelKindToString(config.kind);
  correlation::AmplitudeOptions& ao = config.options;
  cli::AddHelp(&options);
  options.add_options()
      ("level", po::value(&config.level_args)->composing(),
       "LEVEL=MODES.unv: modes fitted at one excitation level (UFF 55 from `ema fit`; a MODES.json from\n"
       "`ema fit --json` beside it gives each mode's σ). Two or more.")
      ("level-kind", po::value(&kind_name)->default_value(kind_name), "what LEVEL is: peak_force (N), rms_force (N) or response")
      ("json", po::value(&config.json_path), "result as JSON (cli.md)")
      ("report", po::value(&config.report_path), "self-contained HTML page: f and damping against level per mode")
      ("mac-min", cli::Defaulted(&ao.mac_min), "MAC a pair needs across levels")
      ("frequency-floor-pct", cli::Defaulted(&ao.frequency_floor_pct),
       "frequency repeatability, % of f, added to each point's σ")
      ("damping-floor", cli::Defaulted(&ao.damping_floor_relative),
       "damping repeatability, relative, added to each point's σ")
      ("significance", cli::Defaulted(&ao.significance), "a change counts beyond this many σ");
  po::positional_options_description positional;
  po::variables_map vm;
  if (!cli::Parse(args, usage, options, positional, &vm)) return std::nullopt;
  cli::RefuseOutputsOverInputs(vm, {"level"}, {"json", "report"});
  if (!correlation::StringToLevelKind(kind_name, &config.kind))
    throw UsageError("--level-kind: expected peak_force, rms_force or response, got '" + kind_name + "'");
  std::string why;
  if (!ao.IsValid(&why)) throw UsageError(why);
  if (config.level_args.size() < 2)
    throw InputError("ema amplitude", "needs mode sets from at least two levels (--level F=MODES.unv twice or more), got " +
                                          std::to_string(config.level_args.size()));
  return config;
}

correlation::AmplitudeResult app::RunAmplitudeStage(const AmplitudeConfig& config,
                                                    std::vector<correlation::AmplitudeLevel> levels, std::ostream& out) {
  const correlation::LevelKind kind = config.kind;
  const correlation::AmplitudeResult r = correlation::AnalyseAmplitude(std::move(levels), kind, config.options);

  out << r.modes.size() << " mode(s) followed over " << r.levels.size() << " levels ("
            << correlation::LevelKindToString(kind) << ")\n";
  for (std::size_t i = 0; i < r.modes.size(); ++i) {
    const correlation::AmplitudeMode& m = r.modes[i];
    out << "mode " << i + 1 << ": frequency " << correlation::FrequencyTrendToString(m.frequency_trend)
              << ", damping " << correlation::DampingTrendToString(m.damping_trend) << " | " << m.reading << "\n";
    out << "    level        f [Hz]    zeta [%]\n";
    for (const correlation::AmplitudePoint& p : m.points)
      out << "    " << std::setw(9) << std::setprecision(4) << p.level << std::fixed << std::setw(13)
                << std::setprecision(4) << p.frequency_hz << std::setw(12) << std::setprecision(4)
                << 100.0 * p.damping_ratio << std::defaultfloat << "\n";
  }
  if (!r.unpaired.empty())
    out << r.unpaired.size() << " mode(s) found at one level only (not followed)\n";
  if (!config.json_path.empty()) formats::WriteTextFileAtomically(config.json_path, formats::AmplitudeJson(r).dump(2) + "\n");
  if (!config.report_path.empty()) {
    report::ReportInput page;
    page.title = "ema amplitude";
    page.subtitle = std::to_string(r.levels.size()) + " levels (" + correlation::LevelKindToString(kind) + ")";
    page.amplitude = formats::AmplitudeJson(r);
    formats::WriteTextFileAtomically(config.report_path, report::RenderHtml(page));
  }
  return r;
}

int RunAmplitude(const std::vector<std::string>& args) {
  const std::optional<app::AmplitudeConfig> config = app::ParseAmplitudeArgs(args);
  if (!config) return 0;
  app::RunAmplitudeStage(*config, formats::ReadAmplitudeLevels(config->level_args, "--level"), std::cout);
  return 0;
}

}  // namespace ema
