#include "report_quality.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

namespace ema::report {

namespace {

using json = nlohmann::json;

json Round4(const json& v) {
  if (!v.is_number()) return nullptr;
  const double x = v.get<double>();
  if (!std::isfinite(x)) return nullptr;
  return RoundToDigits(x, 4);
}

bool IsArray(const json& j, const char* key) { return j.is_object() && j.contains(key) && j[key].is_array(); }

}  // namespace

json QualityData(const json& quality, const json& test_modes) {
  json out = json::object();
  if (quality.is_object() && !quality.empty()) {
    out["verdict"] = quality.value("verdict", std::string());
    out["warnings"] = quality.value("warnings", 0);
    out["reciprocity"] = IsArray(quality, "reciprocity") ? quality["reciprocity"] : json::array();
    out["driving_points"] = IsArray(quality, "driving_points") ? quality["driving_points"] : json::array();
    out["notes"] = IsArray(quality, "notes") ? quality["notes"] : json::array();
    json warn = json::array();
    int frfs = 0;
    if (IsArray(quality, "frfs")) {
      frfs = static_cast<int>(quality["frfs"].size());
      for (const json& f : quality["frfs"])
        if (f.value("reason", std::string()) != "") warn.push_back(f);
    }
    out["frf_count"] = frfs;
    out["frfs_warn"] = warn;
    const json& map = quality.contains("coherence_map") ? quality["coherence_map"] : json();
    if (IsArray(map, "frequency_hz") && IsArray(map, "labels") && IsArray(map, "coherence")) {
      const json& f = map["frequency_hz"];
      const int n = static_cast<int>(f.size());
      const int step = std::max(1, (n + kMaxMapColumns - 1) / kMaxMapColumns);
      json fx = json::array(), z = json::array();
      for (int k = 0; k < n; k += step) fx.push_back(Round4(f[k]));
      for (const json& row : map["coherence"]) {
        json zr = json::array();
        for (int k = 0; k < n; k += step) {
          double lo = std::numeric_limits<double>::infinity();
          for (int i = k; i < std::min(n, k + step) && i < static_cast<int>(row.size()); ++i)
            if (row[i].is_number()) lo = std::min(lo, row[i].get<double>());
          zr.push_back(std::isfinite(lo) ? Round4(lo) : json(nullptr));
        }
        z.push_back(std::move(zr));
      }
      out["coherence_map"] = {{"frequency_hz", fx}, {"labels", map["labels"]}, {"z", z}, {"step", step}};
    }
  }
  if (IsArray(test_modes, "modes")) {
    json modes = json::array();
    int i = 0;
    for (const json& m : test_modes["modes"]) {
      ++i;
      if (!m.is_object()) continue;
      modes.push_back({{"mode", i}, {"frequency_hz", Round4(m.value("frequency_hz", json()))},
                       {"mpc", Round4(m.value("mpc", json()))}, {"mpd_deg", Round4(m.value("mpd_deg", json()))},
                       {"mcf", Round4(m.value("mcf", json()))}});
    }
    if (!modes.empty()) out["modes"] = modes;
  }
  return out;
}

json ModeIndicatorData(const json& stabilisation) {
  json out = json::object();
  if (!stabilisation.is_object() || !stabilisation.contains("cmif")) return out;
  const json& c = stabilisation["cmif"];
  if (!IsArray(c, "frequency_hz") || !IsArray(c, "values")) return out;
  json f = json::array();
  for (const json& v : c["frequency_hz"]) f.push_back(Round4(v));
  json cmif = json::array();
  for (size_t s = 0; s < c["values"].size() && s < 2; ++s) {  // the first two singular values
    json col = json::array();
    for (const json& v : c["values"][s]) col.push_back(Round4(v));
    cmif.push_back(std::move(col));
  }
  out = {{"frequency_hz", f}, {"cmif", cmif}};
  if (stabilisation.contains("mmif") && IsArray(stabilisation["mmif"], "values") && !stabilisation["mmif"]["values"].empty()) {
    json col = json::array();
    for (const json& v : stabilisation["mmif"]["values"][0]) col.push_back(Round4(v));
    out["mmif"] = std::move(col);
  }
  return out;
}

double RoundToDigits(double value, int significant) {
  if (!std::isfinite(value)) return value;
  char text[40];
  std::snprintf(text, sizeof text, "%.*g", significant, value);
  return std::strtod(text, nullptr);
}

}  // namespace ema::report
