// The candidate readings of DIAG.json (`ema diagnose --json`): the JSON layout of json_codecs.cpp
// (CandidateJson, EffectJson) read back; each effect goes through the model file's own [[effect]]
// reader (effect_toml.hpp), so its keys and laws are taken exactly as a model file takes them.
#include "ema/formats/diagnosis_readings.hpp"

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <toml++/toml.h>

#include "ema/core/error.hpp"
#include "toml_text.hpp"
#include "effect_toml.hpp"

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

  std::vector<DiagnosisReading> ReadFile(const std::filesystem::path& path) const {
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
    return Read(root);
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

  // {"kind", "target", "parameters": {name: value}, "law": "<inline TOML>"} as the TOML of one
  // [[effect]] block, read by the model file's reader.
  model::Effect Effect(const nlohmann::json& e, const std::string& where) const {
    if (!e.is_object()) throw InputError(file_, where + ": expected an object, found " + std::string(e.type_name()));
    std::string text = "[[effect]]\nkind = " + TomlString(String(e, "kind", where)) +
                       "\ntarget = " + TomlString(String(e, "target", where)) + "\n";
    if (const auto p = e.find("parameters"); p != e.end()) {
      if (!p->is_object()) throw InputError(file_, where + ": key 'parameters': expected an object {name: number}");
      for (const auto& [name, value] : p->items()) {
        if (!value.is_number())
          throw InputError(file_, where + ": parameter '" + name + "': expected a number, found " + value.dump());
        text += TomlString(name) + " = " + TomlFloat(value.get<double>()) + "\n";
      }
    }
    if (const auto l = e.find("law"); l != e.end() && !l->is_null()) {
      if (!l->is_string()) throw InputError(file_, where + ": key 'law': expected the inline TOML of a law as a string");
      const std::string law = l->get<std::string>();
      if (law.find_first_of("\r\n") != std::string::npos)
        throw InputError(file_, where + ": key 'law': expected the inline TOML of one law on one line, such as "
                                        "\"{ linear = { k = 6.5e6 } }\"");
      try {
        (void)toml::parse("law = " + law + "\n");  // said here, not as an error of the TOML built below
      } catch (const toml::parse_error& x) {
        throw InputError(file_, where + ": key 'law': '" + law + "' is not the inline TOML of a law such as "
                                "\"{ linear = { k = 6.5e6 } }\" (" + std::string(x.description()) + ")");
      }
      text += "law = " + law + "\n";
    }
    const std::string origin = file_ + ": " + where;
    model::Effect effect;
    try {
      effect = ParseEffectToml(text, origin, base_dir_);
    } catch (const InputError& x) {
      // Said at the candidate: the line counts in the TOML text built here, which the user never
      // sees (an error in a curve file the law names keeps that file's place).
      const bool here = x.Where().compare(0, origin.size(), origin) == 0;
      throw InputError(origin, here ? x.Detail() : x.what());
    }
    effect.line = 0;  // no line of a file
    return effect;
  }

  std::filesystem::path base_dir_;
  std::string file_;
};

}  // namespace

std::vector<DiagnosisReading> ReadDiagnosisReadings(const std::filesystem::path& path) {
  return DiagnosisJsonReader(path.string(), path.parent_path()).ReadFile(path);
}

std::vector<DiagnosisReading> ReadDiagnosisReadings(const nlohmann::json& diagnosis, const std::string& origin,
                                                    const std::filesystem::path& base_dir) {
  return DiagnosisJsonReader(origin, base_dir).Read(diagnosis);
}

}  // namespace ema::formats
