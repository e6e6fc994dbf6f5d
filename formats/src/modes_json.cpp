// Test modes as MODES.json in `ema fit --json`'s layout (model-format.md, "Test modes measured by
// other tools", added turn 3): what other tools and labs hand over — frequencies with their
// measured σ and shapes at the measured DOFs only.
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "ema/core/error.hpp"
#include "ema/core/types.hpp"
#include "io_internal.hpp"

namespace ema::formats {
namespace {

using nlohmann::json;

// The line of a byte offset, for messages on a JSON syntax error.
int LineOf(const std::string& text, std::size_t byte) {
  int line = 1;
  for (std::size_t i = 0; i < byte && i < text.size(); ++i) line += text[i] == '\n';
  return line;
}

double Number(const json& j, const std::string& file, const std::string& at, bool required) {
  if (j.is_number()) return j.get<double>();
  if (!required && j.is_null()) return kNaN;
  throw InputError(file, at + ": expected a number" + (required ? "" : " or null") + ", found " +
                             std::string(j.type_name()));
}

}  // namespace

bool LooksLikeJson(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  char c = 0;
  while (in.get(c))
    if (c != ' ' && c != '\t' && c != '\r' && c != '\n') return c == '{';
  return false;
}

ModeSet ReadModeSetJson(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string(), "cannot open the modes file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return ReadModeSetJsonText(buffer.str(), path.string());
}

ModeSet ReadModeSetJsonText(const std::string& text, const std::string& file) {
  json root;
  try {
    root = json::parse(text);
  } catch (const json::parse_error& e) {
    throw InputError(file + ":" + std::to_string(LineOf(text, e.byte)),
                     "not valid JSON (" + std::string(e.what()) + "); expected `ema fit --json`'s layout {\"modes\": [...]}");
  }
  if (!root.is_object() || !root.contains("modes") || !root["modes"].is_array())
    throw InputError(file, "expected an object with a \"modes\" array (`ema fit --json`'s layout)");
  const json& modes = root["modes"];
  if (modes.empty()) throw InputError(file, "\"modes\" is empty; expected at least one mode");
  ModeSet set;
  set.source = file;
  std::map<Dof, std::size_t> index;  // DOF -> row of ModeSet::dofs (the first mode's order)
  for (std::size_t r = 0; r < modes.size(); ++r) {
    const json& m = modes[r];
    const std::string at = "modes[" + std::to_string(r) + "]";
    if (!m.is_object()) throw InputError(file, at + ": expected an object");
    if (!m.contains("frequency_hz")) throw InputError(file, at + ": missing \"frequency_hz\"");
    Mode mode;
    mode.frequency_hz = Number(m["frequency_hz"], file, at + ".frequency_hz", true);
    if (!(mode.frequency_hz > 0.0) || !std::isfinite(mode.frequency_hz))
      throw InputError(file, at + ".frequency_hz: expected a frequency > 0 Hz, found " + std::to_string(mode.frequency_hz));
    mode.damping_ratio = m.contains("damping_ratio") ? Number(m["damping_ratio"], file, at + ".damping_ratio", false) : kNaN;
    if (std::isfinite(mode.damping_ratio) && !(mode.damping_ratio >= 0.0 && mode.damping_ratio < 1.0))
      throw InputError(file, at + ".damping_ratio: expected a ratio of critical in [0, 1) (0.01 = 1 %), found " +
                                 std::to_string(mode.damping_ratio));
    auto optional = [&](const char* key) { return m.contains(key) ? Number(m[key], file, at + "." + key, false) : kNaN; };
    mode.frequency_std_hz = optional("frequency_std_hz");
    if (std::isfinite(mode.frequency_std_hz) && !(mode.frequency_std_hz >= 0.0))
      throw InputError(file, at + ".frequency_std_hz: expected a 1σ >= 0 Hz, found " + std::to_string(mode.frequency_std_hz));
    mode.damping_ratio_std = optional("damping_ratio_std");
    mode.mpc = optional("mpc");
    mode.mpd = optional("mpd_deg");
    mode.frequency_spread_hz = optional("frequency_spread_hz");
    mode.pole = FrequencyAndDampingToPole(mode.frequency_hz, std::isfinite(mode.damping_ratio) ? mode.damping_ratio : 0.0);
    if (!std::isfinite(mode.damping_ratio)) mode.damping_ratio = 0.0;
    // Roving-sensor tests: the mode as each roving set saw it (`ema fit --json`).
    if (m.contains("sets") && m["sets"].is_array())
      for (std::size_t k = 0; k < m["sets"].size(); ++k) {
        const json& e = m["sets"][k];
        const std::string where = at + ".sets[" + std::to_string(k) + "]";
        if (!e.is_object() || !e.contains("frequency_hz")) throw InputError(file, where + ": expected {\"frequency_hz\", ...}");
        mode.set_frequency_hz.push_back(Number(e["frequency_hz"], file, where + ".frequency_hz", true));
        mode.set_damping_ratio.push_back(e.contains("damping_ratio") ? Number(e["damping_ratio"], file, where + ".damping_ratio", false) : kNaN);
        mode.set_frequency_std_hz.push_back(
            e.contains("frequency_std_hz") ? Number(e["frequency_std_hz"], file, where + ".frequency_std_hz", false) : kNaN);
      }
    if (!m.contains("shape") || !m["shape"].is_array() || m["shape"].empty())
      throw InputError(file, at + ": missing \"shape\"; expected [{\"node\", \"dir\", \"value\": [re, im]}, ...] at the "
                                  "measured DOFs");
    const json& shape = m["shape"];
    std::map<Dof, std::complex<double>> values;
    for (std::size_t d = 0; d < shape.size(); ++d) {
      const json& e = shape[d];
      const std::string where = at + ".shape[" + std::to_string(d) + "]";
      if (!e.is_object() || !e.contains("node") || !e.contains("dir") || !e.contains("value"))
        throw InputError(file, where + ": expected {\"node\", \"dir\", \"value\"}");
      if (!e["node"].is_number_integer() || e["node"].get<long long>() <= 0 || e["node"].get<long long>() > 2147483647)
        throw InputError(file, where + ".node: expected a positive integer node id");
      if (!e["dir"].is_string()) throw InputError(file, where + ".dir: expected a direction such as \"+X\"");
      const int dir = ParseDirection(e["dir"].get<std::string>());
      if (dir == 0) throw InputError(file, where + ".dir: expected +X -X +Y -Y +Z -Z, found '" + e["dir"].get<std::string>() + "'");
      const json& v = e["value"];
      std::complex<double> value;
      if (v.is_number()) {
        value = {v.get<double>(), 0.0};  // a real shape, as FE codes and many tools give it
      } else if (v.is_array() && v.size() == 2 && v[0].is_number() && v[1].is_number()) {
        value = {v[0].get<double>(), v[1].get<double>()};
      } else {
        throw InputError(file, where + ".value: expected [re, im] or a number");
      }
      if (!std::isfinite(value.real()) || !std::isfinite(value.imag()))
        throw InputError(file, where + ".value: not a finite number");
      const Dof dof{static_cast<int>(e["node"].get<long long>()), dir};
      if (!values.emplace(dof, value).second)
        throw InputError(file, where + ": DOF " + DofName(dof) + " appears twice in this mode's shape");
      if (r == 0) {
        index.emplace(dof, set.dofs.size());
        set.dofs.push_back(dof);
      }
    }
    // Only the measured DOFs are listed; every mode was measured at the same ones.
    for (const auto& [dof, value] : values)
      if (!index.count(dof))
        throw InputError(file, at + ".shape: DOF " + DofName(dof) + " is not in modes[0]'s shape; expected every mode "
                                    "to list the same measured DOFs");
    if (values.size() != set.dofs.size())
      throw InputError(file, at + ".shape: " + std::to_string(values.size()) + " DOFs but modes[0] lists " +
                                  std::to_string(set.dofs.size()) + "; expected every mode to list the same measured DOFs");
    mode.shape.resize(static_cast<Eigen::Index>(set.dofs.size()));
    for (const auto& [dof, value] : values) mode.shape(static_cast<Eigen::Index>(index.at(dof))) = value;
    set.modes.push_back(std::move(mode));
  }
  return set;
}

}  // namespace ema::formats
