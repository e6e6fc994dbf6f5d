// Checked access to TOML tables, shared by every TOML reader (model, simulation plan, project
// files) so that their errors read alike: "file:line: unknown key 'x' in [plan] (allowed: ...)".
// Header-only; the includer needs toml++ (Debian's libtomlplusplus-dev).
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <set>
#include <string>
#include <toml++/toml.h>
#include <utility>

#include "ema/core/error.hpp"

namespace ema::formats {

/// The node's value when it is a TOML integer within int's range; nothing otherwise (a float, a
/// string, 2^40). Every integer key goes through here rather than node::value<int64_t>(): on a
/// float that one casts before its range check (undefined behaviour for `node = 7.7e105`, found
/// by fuzz_model_file), and a plain int cast would wrap 2^32 + 1 to node 1.
inline std::optional<int> IntValue(const toml::node& n) {
  const toml::value<std::int64_t>* v = n.as_integer();
  if (!v) return std::nullopt;
  const std::int64_t x = v->get();
  if (x < std::numeric_limits<int>::min() || x > std::numeric_limits<int>::max()) return std::nullopt;
  return static_cast<int>(x);
}

/// Whether the lines of the TOML read are a file's: kInNoFile for TOML that is a value inside
/// another format (DIAG.json's "law" string), whose line numbers the user could find nowhere.
enum class TomlLines { kOfTheFile, kInNoFile };

class TomlFields {
 public:
  /// `file` names the source in messages: the file, or with kInNoFile the place of the value
  /// ("DIAG.json: candidate rank 2: effect 1"), which is then every node's place.
  explicit TomlFields(std::string file, TomlLines lines = TomlLines::kOfTheFile)
      : file_(std::move(file)), lines_(lines) {}

  /// "file:line" of a node (just "file" when toml++ knows no line or the lines are in no file).
  std::string At(const toml::node& n) const {
    const auto line = n.source().begin.line;
    return line > 0 && lines_ == TomlLines::kOfTheFile ? file_ + ":" + std::to_string(line) : file_;
  }

  /// Unknown keys are an error that names the key, its line and the keys allowed there.
  void CheckKeys(const toml::table& t, const std::set<std::string>& allowed, const std::string& context) const {
    for (const auto& [key, value] : t) {
      if (allowed.count(std::string(key.str()))) continue;
      std::string list;
      for (const auto& a : allowed) list.append(list.empty() ? "" : ", ").append(a);
      throw InputError(At(value), "unknown key '" + std::string(key.str()) + "' in " + context + " (allowed: " + list + ")");
    }
  }

 protected:
  std::string file_;
  TomlLines lines_;
};

}  // namespace ema::formats
