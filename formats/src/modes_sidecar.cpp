#include "ema/formats/modes_sidecar.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <system_error>
#include <utility>

#include "ema/core/error.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/json_codecs.hpp"

namespace ema::formats {

using json = nlohmann::json;

namespace {

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

/// A finite number given to `option` (a level of LEVEL=MODES.unv); UsageError "OPTION: expected a
/// number, got 'TEXT'", the words of cli::ParseNumber, which the command lines' other numbers go
/// through. What std::stod accepts: leading blanks, the whole text consumed, no overflow or
/// underflow (ERANGE).
double ParseLevelNumber(const std::string& text, const std::string& option) {
  const char* begin = text.c_str();
  char* end = nullptr;
  const int saved = errno;
  errno = 0;
  const double v = std::strtod(begin, &end);
  const bool range_error = errno == ERANGE;
  errno = saved;
  if (end != begin && !range_error && static_cast<std::size_t>(end - begin) == text.size() && std::isfinite(v)) return v;
  throw UsageError(option + ": expected a number, got '" + text + "'");
}

}  // namespace

bool ReadSidecarTestSets(const std::string& modes_path, const ModeSet& modes, std::vector<std::vector<int>>* roving_sets,
                         Dof* reference) {
  std::filesystem::path side = modes_path;
  std::error_code ec;
  if (side.extension() != ".json") side.replace_extension(".json");
  if (!std::filesystem::is_regular_file(side, ec)) return false;
  json j;
  try {
    std::ifstream in(side);
    j = json::parse(in);
  } catch (const std::exception&) {
    return false;
  }
  // A sidecar must hold the same modes as the file beside it.
  if (!j.is_object() || !j.contains("modes") || !j["modes"].is_array() || j["modes"].size() != modes.modes.size())
    return false;
  return ReadTestSets(j, roving_sets, reference);
}

void AttachSidecarUncertainty(const std::string& modes_path, ModeSet* modes) {
  const std::vector<correlation::ModeUncertainty> u = SidecarUncertainty(modes_path, *modes);
  for (std::size_t i = 0; i < u.size() && i < modes->modes.size(); ++i) {
    modes->modes[i].frequency_std_hz = u[i].frequency_std_hz;
    modes->modes[i].damping_ratio_std = u[i].damping_ratio_std;
  }
  if (u.empty()) return;
  // Roving-sensor tests: each mode as every roving set saw it ("sets" of `ema fit --json`).
  std::filesystem::path side = modes_path;
  side.replace_extension(".json");
  try {
    std::ifstream in(side);
    const json j = json::parse(in);
    for (std::size_t i = 0; i < modes->modes.size(); ++i) {
      const json& m = j["modes"][i];
      if (!m.contains("sets") || !m["sets"].is_array()) continue;
      Mode& mode = modes->modes[i];
      for (const json& s : m["sets"]) {
        if (!s.is_object() || !s.contains("frequency_hz") || !s["frequency_hz"].is_number()) break;
        mode.set_frequency_hz.push_back(s["frequency_hz"].get<double>());
        mode.set_damping_ratio.push_back(s.contains("damping_ratio") && s["damping_ratio"].is_number()
                                             ? s["damping_ratio"].get<double>() : kNaN);
        mode.set_frequency_std_hz.push_back(s.contains("frequency_std_hz") && s["frequency_std_hz"].is_number()
                                                ? s["frequency_std_hz"].get<double>() : kNaN);
      }
    }
  } catch (const std::exception&) {
  }
}

std::vector<std::string> AmplitudeLevelFiles(const std::vector<std::string>& level_args) {
  std::vector<std::string> files;
  for (const std::string& a : level_args) {
    const auto eq = a.find('=');
    if (eq != std::string::npos) files.push_back(a.substr(eq + 1));
  }
  return files;
}

std::vector<correlation::AmplitudeLevel> ReadAmplitudeLevels(const std::vector<std::string>& level_args,
                                                             const std::string& option) {
  std::vector<std::pair<double, std::string>> parsed;
  for (const std::string& a : level_args) {
    const auto eq = a.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == a.size())
      throw UsageError(option + " expects LEVEL=MODES.unv, got '" + a + "'");
    const double level = ParseLevelNumber(a.substr(0, eq), option);
    if (!(level > 0.0))
      throw UsageError(option + ": level must be > 0, got '" + a.substr(0, eq) + "'");
    parsed.push_back({level, a.substr(eq + 1)});
  }
  std::vector<correlation::AmplitudeLevel> levels;
  for (const auto& [level, path] : parsed) {
    if (!std::filesystem::exists(path)) throw InputError(path, "mode file not found");
    correlation::AmplitudeLevel l;
    l.level = level;
    l.modes = ReadModeSet(path);
    l.modes.source = path;
    l.uncertainty = SidecarUncertainty(path, l.modes);
    levels.push_back(std::move(l));
  }
  return levels;
}

}  // namespace ema::formats
