// ema amplitude --level F=MODES.unv --level F=MODES.unv [...] [--level-kind K] [--json AMP.json]
//
// Does a mode depend on the excitation level? Modes fitted at several levels are paired across
// the levels, and each mode's frequency and damping trends are tested (docs/amplitude.md).
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli.hpp"
#include "ema/core/error.hpp"
#include "ema/correlation/amplitude.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/io.hpp"
#include "report.hpp"

namespace ema {
namespace {

using nlohmann::json;

json NumberOrNull(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

/// σ of each mode from the `ema fit --json` file beside MODES.unv (same stem, .json), when it
/// holds the same modes (same count, frequencies within 1e-6): `frequency_std_hz` and
/// `damping_ratio_std` (cli.md, added turn 2). Empty when there is no such file or no σ.
std::vector<correlation::ModeUncertainty> SidecarUncertainty(const std::filesystem::path& modes_path,
                                                             const ModeSet& modes) {
  std::filesystem::path side = modes_path;
  side.replace_extension(".json");
  std::error_code ec;
  if (side == modes_path || !std::filesystem::is_regular_file(side, ec)) return {};
  json j;
  try {
    std::ifstream in(side);
    j = json::parse(in);
  } catch (const std::exception&) {
    return {};
  }
  if (!j.is_object() || !j.contains("modes") || !j["modes"].is_array() || j["modes"].size() != modes.modes.size())
    return {};
  std::vector<correlation::ModeUncertainty> out;
  bool any = false;
  for (std::size_t i = 0; i < modes.modes.size(); ++i) {
    const json& m = j["modes"][i];
    if (!m.is_object() || !m.contains("frequency_hz") || !m["frequency_hz"].is_number()) return {};
    const double f = m["frequency_hz"].get<double>();
    if (std::abs(f - modes.modes[i].frequency_hz) > 1e-6 * modes.modes[i].frequency_hz) return {};
    correlation::ModeUncertainty u;
    if (m.contains("frequency_std_hz") && m["frequency_std_hz"].is_number())
      u.frequency_std_hz = m["frequency_std_hz"].get<double>(), any = true;
    if (m.contains("damping_ratio_std") && m["damping_ratio_std"].is_number())
      u.damping_ratio_std = m["damping_ratio_std"].get<double>(), any = true;
    out.push_back(u);
  }
  return any ? out : std::vector<correlation::ModeUncertainty>{};
}

/// The JSON of cli.md ("ema amplitude").
json AmplitudeJson(const correlation::AmplitudeResult& r) {
  json modes = json::array();
  for (std::size_t i = 0; i < r.modes.size(); ++i) {
    const correlation::AmplitudeMode& m = r.modes[i];
    json levels = json::array();
    for (const correlation::AmplitudePoint& p : m.points)
      levels.push_back({{"level", p.level},
                        {"frequency_hz", p.frequency_hz},
                        {"damping_ratio", p.damping_ratio},
                        {"frequency_std_hz", NumberOrNull(p.frequency_std_hz)},
                        {"damping_ratio_std", NumberOrNull(p.damping_ratio_std)},
                        {"poles", p.poles}});
    modes.push_back({{"mode", i + 1},
                     {"levels", levels},
                     {"frequency_trend", correlation::FrequencyTrendToString(m.frequency_trend)},
                     {"frequency_change_pct", m.frequency_change_pct},
                     {"damping_trend", correlation::DampingTrendToString(m.damping_trend)},
                     {"damping_ratio_factor", NumberOrNull(m.damping_ratio_factor)},
                     {"frequency_slope_z", m.frequency_slope_z},
                     {"frequency_extreme_z", m.frequency_extreme_z},
                     {"damping_slope_z", m.damping_slope_z},
                     {"target_level", m.points[static_cast<std::size_t>(m.target_point)].level},
                     {"reading", m.reading}});
  }
  return {{"level_kind", correlation::LevelKindToString(r.level_kind)}, {"levels", r.levels}, {"modes", modes}};
}

}  // namespace

int RunAmplitude(const std::vector<std::string>& args) {
  namespace po = cli::po;
  const std::string usage =
      "ema amplitude --level F=MODES.unv --level F=MODES.unv [...] [--level-kind peak_force|rms_force|response]\n"
      "              [--json AMP.json] [--report AMP.html]";
  po::options_description options(
      "ema amplitude: does a mode depend on the excitation level? (frequency and damping against level, "
      "docs/amplitude.md)");
  std::vector<std::string> level_args;
  std::string kind_name = "peak_force", json_path, report_path;
  correlation::AmplitudeOptions ao;
  cli::AddHelp(&options);
  options.add_options()
      ("level", po::value(&level_args)->composing(),
       "LEVEL=MODES.unv: modes fitted at one excitation level (UFF 55 from `ema fit`; a MODES.json from\n"
       "`ema fit --json` beside it gives each mode's σ). Two or more.")
      ("level-kind", po::value(&kind_name), "what LEVEL is: peak_force (default, N), rms_force (N) or response")
      ("json", po::value(&json_path), "result as JSON (cli.md)")
      ("report", po::value(&report_path), "self-contained HTML page: f and damping against level per mode")
      ("mac-min", po::value(&ao.mac_min), "MAC a pair needs across levels (default 0.8)")
      ("frequency-floor-pct", po::value(&ao.frequency_floor_pct),
       "frequency repeatability, % of f, added to each point's σ (default 0.03)")
      ("damping-floor", po::value(&ao.damping_floor_relative),
       "damping repeatability, relative, added to each point's σ (default 0.05)")
      ("significance", po::value(&ao.significance), "a change counts beyond this many σ (default 3)");
  po::positional_options_description positional;
  po::variables_map vm;
  if (!cli::Parse(args, usage, options, positional, &vm)) return 0;
  correlation::LevelKind kind;
  if (!correlation::StringToLevelKind(kind_name, &kind))
    throw UsageError("--level-kind: expected peak_force, rms_force or response, got '" + kind_name + "'");
  std::string why;
  if (!ao.IsValid(&why)) throw UsageError(why);
  if (level_args.size() < 2)
    throw InputError("ema amplitude", "needs mode sets from at least two levels (--level F=MODES.unv twice or more), got " +
                                          std::to_string(level_args.size()));
  std::vector<std::pair<double, std::string>> parsed;
  for (const std::string& a : level_args) {
    const auto eq = a.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == a.size())
      throw UsageError("--level expects LEVEL=MODES.unv, got '" + a + "'");
    double level = 0.0;
    try {
      std::size_t used = 0;
      level = std::stod(a.substr(0, eq), &used);
      if (used != eq) throw std::invalid_argument(a);
    } catch (const std::exception&) {
      throw UsageError("--level: '" + a.substr(0, eq) + "' is not a number");
    }
    if (!(level > 0.0) || !std::isfinite(level)) throw UsageError("--level: level must be > 0, got '" + a.substr(0, eq) + "'");
    parsed.push_back({level, a.substr(eq + 1)});
  }
  for (const auto& [option, out] : {std::pair<std::string, std::string>{"--json", json_path}, {"--report", report_path}}) {
    if (out.empty()) continue;
    std::error_code ec;
    for (const auto& [level, path] : parsed)
      if (std::filesystem::path(out) == std::filesystem::path(path) ||
          (std::filesystem::exists(out, ec) && std::filesystem::equivalent(out, path, ec)))
        throw UsageError(option + " " + out + " names an input file");
  }
  std::vector<correlation::AmplitudeLevel> levels;
  for (const auto& [level, path] : parsed) {
    if (!std::filesystem::exists(path)) throw InputError(path, "mode file not found");
    correlation::AmplitudeLevel l;
    l.level = level;
    l.modes = formats::ReadModeSet(path);
    l.modes.source = path;
    l.uncertainty = SidecarUncertainty(path, l.modes);
    levels.push_back(std::move(l));
  }
  const correlation::AmplitudeResult r = correlation::AnalyseAmplitude(std::move(levels), kind, ao);

  std::cout << r.modes.size() << " mode(s) followed over " << r.levels.size() << " levels ("
            << correlation::LevelKindToString(kind) << ")\n";
  for (std::size_t i = 0; i < r.modes.size(); ++i) {
    const correlation::AmplitudeMode& m = r.modes[i];
    std::cout << "mode " << i + 1 << ": frequency " << correlation::FrequencyTrendToString(m.frequency_trend)
              << ", damping " << correlation::DampingTrendToString(m.damping_trend) << " | " << m.reading << "\n";
    std::cout << "    level        f [Hz]    zeta [%]\n";
    for (const correlation::AmplitudePoint& p : m.points)
      std::cout << "    " << std::setw(9) << std::setprecision(4) << p.level << std::fixed << std::setw(13)
                << std::setprecision(4) << p.frequency_hz << std::setw(12) << std::setprecision(4)
                << 100.0 * p.damping_ratio << std::defaultfloat << "\n";
  }
  if (!r.unpaired.empty())
    std::cout << r.unpaired.size() << " mode(s) found at one level only (not followed)\n";
  if (!json_path.empty()) formats::WriteTextFileAtomically(json_path, AmplitudeJson(r).dump(2) + "\n");
  if (!report_path.empty()) {
    report::ReportInput page;
    page.title = "ema amplitude";
    page.subtitle = std::to_string(r.levels.size()) + " levels (" + correlation::LevelKindToString(kind) + ")";
    std::istringstream lines(r.summary);
    for (std::string line; std::getline(lines, line);) page.summary.push_back(line);
    page.amplitude = AmplitudeJson(r);
    formats::WriteTextFileAtomically(report_path, report::RenderHtml(page));
  }
  return 0;
}

}  // namespace ema
