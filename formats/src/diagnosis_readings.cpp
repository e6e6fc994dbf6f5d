// The candidate readings of DIAG.json (`ema diagnose --json`): the JSON layout of json_codecs.cpp
// (CandidateJson, EffectJson) read back; each effect's values go through the model file's own
// rules for an [[effect]] (effect_fields.hpp), so its parameters, kind, target and law are taken
// exactly as a model file takes them.
#include "ema/formats/diagnosis_readings.hpp"

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <toml++/toml.h>

#include "ema/core/error.hpp"
#include "effect_fields.hpp"

namespace ema::formats {
namespace {

// (Helper names unique in the formats target: it is a unity build.)

// The line of a byte offset, for messages on a JSON syntax error.
int ReadingLineOf(const std::string& text, std::size_t byte) {
  int line = 1;
  for (std::size_t i = 0; i < byte && i < text.size(); ++i) line += text[i] == '\n';
  return line;
}

class DiagnosisJsonReader {
 public:
  /// `origin` names the source in messages; relative law files resolve against `base_dir`.
  DiagnosisJsonReader(std::string origin, std::filesystem::path base_dir)
      : base_dir_(std::move(base_dir)), file_(std::move(origin)) {}

  nlohmann::json Parse(const std::filesystem::path& path) const {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) throw InputError(file_, "diagnosis file not found");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(file_, "cannot open the diagnosis file");
    std::stringstream buffer;
    buffer << in.rdbuf();
    const std::string text = buffer.str();
    nlohmann::json root;
    try {
      root = nlohmann::json::parse(text);
    } catch (const nlohmann::json::parse_error& e) {
      throw InputError(file_ + ":" + std::to_string(ReadingLineOf(text, e.byte)),
                       "not valid JSON (" + std::string(e.what()) + "); expected the JSON of `ema diagnose --json`");
    }
    return root;
  }

  diagnose::ModelError ModelError(const nlohmann::json& root) const {
    diagnose::ModelError out;
    if (!root.is_object() || !root.contains("model_error") || root["model_error"].is_null()) return out;
    const nlohmann::json& e = root["model_error"];
    auto number = [&](const char* key) {
      if (!e.is_object() || !e.contains(key) || !e[key].is_number() || !(e[key].get<double>() >= 0.0))
        throw InputError(file_, std::string("\"model_error\": expected {\"frequency_rel\", \"shape\", \"dominates\"} with \"") +
                                    key + "\" a number >= 0, as `ema diagnose --json` writes it");
      return e[key].get<double>();
    };
    out.frequency_rel = number("frequency_rel");
    out.shape = number("shape");
    if (e.contains("frequency_common_rel") && e["frequency_common_rel"].is_number())
      out.frequency_common_rel = e["frequency_common_rel"].get<double>();
    out.dominates = e.contains("dominates") && e["dominates"].is_boolean() && e["dominates"].get<bool>();
    return out;
  }

  std::vector<DiagnosisReading> Read(const nlohmann::json& root) const {
    if (!root.is_object() || !root.contains("candidates") || !root["candidates"].is_array())
      throw InputError(file_, "no \"candidates\" array: expected the JSON of `ema diagnose --json` "
                              "({\"candidates\": [{\"rank\", \"kind\", \"target\", \"effects\", ...}]})");
    std::vector<DiagnosisReading> out;
    const nlohmann::json& candidates = root["candidates"];
    for (std::size_t i = 0; i < candidates.size(); ++i) out.push_back(Candidate(candidates[i], i));
    std::stable_sort(out.begin(), out.end(),
                     [](const DiagnosisReading& a, const DiagnosisReading& b) { return a.rank < b.rank; });
    return out;
  }

 private:
  DiagnosisReading Candidate(const nlohmann::json& c, std::size_t index) const {
    std::string where = "candidates[" + std::to_string(index) + "]";
    if (!c.is_object()) throw InputError(file_, where + ": expected an object, found " + std::string(c.type_name()));
    DiagnosisReading r;
    const auto rank = c.find("rank");
    if (rank == c.end()) throw InputError(file_, where + ": missing key 'rank'");
    const bool in_range =
        rank->is_number_unsigned() ? rank->get<std::uint64_t>() <= static_cast<std::uint64_t>(std::numeric_limits<int>::max())
        : rank->is_number_integer() ? rank->get<std::int64_t>() >= std::numeric_limits<int>::min() &&
                                          rank->get<std::int64_t>() <= std::numeric_limits<int>::max()
                                    : false;
    if (!in_range)
      throw InputError(file_, where + ": key 'rank': expected an integer, found " + rank->dump());
    r.rank = rank->get<int>();
    where = "candidate rank " + std::to_string(r.rank);
    r.kind = String(c, "kind", where);
    r.target = String(c, "target", where);
    if (const auto p = c.find("probability"); p != c.end() && !p->is_null()) {
      if (!p->is_number()) throw InputError(file_, where + ": key 'probability': expected a number or null, found " + p->dump());
      r.probability = p->get<double>();
    }
    const auto effects = c.find("effects");
    if (effects == c.end()) throw InputError(file_, where + ": missing key 'effects'");
    if (!effects->is_array()) throw InputError(file_, where + ": key 'effects': expected an array of effects");
    for (std::size_t e = 0; e < effects->size(); ++e)
      r.effects.push_back(Effect((*effects)[e], where + ": effect " + std::to_string(e + 1)));
    return r;
  }

  std::string String(const nlohmann::json& object, const char* key, const std::string& where) const {
    const auto it = object.find(key);
    if (it == object.end()) throw InputError(file_, where + ": missing key '" + key + "'");
    if (!it->is_string()) throw InputError(file_, where + ": key '" + key + "': expected a string, found " + it->dump());
    return it->get<std::string>();
  }

  // {"kind", "target", "parameters": {name: number}, "law": "<inline TOML>"}: the values handed to
  // the model file's rules for an [[effect]] (effect_fields.hpp) as they are, the law parsed once
  // from its documented field format into the table the law parser takes.
  model::Effect Effect(const nlohmann::json& e, const std::string& where) const {
    if (!e.is_object()) throw InputError(file_, where + ": expected an object, found " + std::string(e.type_name()));
    const std::string kind = String(e, "kind", where);
    const std::string target = String(e, "target", where);
    std::map<std::string, double> parameters;
    if (const auto p = e.find("parameters"); p != e.end()) {
      if (!p->is_object()) throw InputError(file_, where + ": key 'parameters': expected an object {name: number}");
      for (const auto& [name, value] : p->items()) {
        if (!value.is_number())
          throw InputError(file_, where + ": parameter '" + name + "': expected a number, found " + value.dump());
        parameters[name] = value.get<double>();
      }
    }
    std::optional<toml::table> law;
    if (const auto l = e.find("law"); l != e.end() && !l->is_null()) {
      if (!l->is_string()) throw InputError(file_, where + ": key 'law': expected the inline TOML of a law as a string");
      law = LawField(l->get<std::string>(), where);
    }
    return EffectFromFields(kind, target, parameters, law ? law->get("law") : nullptr, file_ + ": " + where, base_dir_);
  }

  // The "law" field: one inline TOML value, "{ linear = { k = 6.5e6 } }", read by toml++ as the
  // value of a key (toml++ parses documents, not lone values); on one line nothing else can follow
  // the value but a comment, so the table holds that one key.
  toml::table LawField(const std::string& law, const std::string& where) const {
    if (law.find_first_of("\r\n") != std::string::npos)
      throw InputError(file_, where + ": key 'law': expected the inline TOML of one law on one line, such as "
                                      "\"{ linear = { k = 6.5e6 } }\"");
    try {
      return toml::parse("law = " + law);
    } catch (const toml::parse_error& x) {
      throw InputError(file_, where + ": key 'law': '" + law + "' is not the inline TOML of a law such as "
                              "\"{ linear = { k = 6.5e6 } }\" (" + std::string(x.description()) + ")");
    }
  }

  std::filesystem::path base_dir_;
  std::string file_;
};

}  // namespace

nlohmann::json ReadDiagnosisJson(const std::filesystem::path& path) {
  return DiagnosisJsonReader(path.string(), path.parent_path()).Parse(path);
}

std::vector<DiagnosisReading> ReadDiagnosisReadings(const std::filesystem::path& path) {
  return ReadDiagnosisReadings(ReadDiagnosisJson(path), path.string(), path.parent_path());
}

diagnose::ModelError ReadDiagnosisModelError(const nlohmann::json& diagnosis, const std::string& origin) {
  return DiagnosisJsonReader(origin, {}).ModelError(diagnosis);
}

std::vector<DiagnosisReading> ReadDiagnosisReadings(const nlohmann::json& diagnosis, const std::string& origin,
                                                    const std::filesystem::path& base_dir) {
  return DiagnosisJsonReader(origin, base_dir).Read(diagnosis);
}

}  // namespace ema::formats
