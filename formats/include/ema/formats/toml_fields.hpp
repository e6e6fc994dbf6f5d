// Checked access to TOML tables, shared by every TOML reader (model, simulation plan, project
// files) so that their errors read alike: "file:line: unknown key 'x' in [plan] (allowed: ...)".
// Header-only; the includer needs toml++ (Debian's libtomlplusplus-dev).
#pragma once

#include <set>
#include <string>
#include <toml++/toml.h>
#include <utility>

#include "ema/core/error.hpp"

namespace ema::formats {

class TomlFields {
 public:
  explicit TomlFields(std::string file) : file_(std::move(file)) {}

  /// "file:line" of a node (just "file" when toml++ knows no line).
  std::string At(const toml::node& n) const {
    const auto line = n.source().begin.line;
    return line > 0 ? file_ + ":" + std::to_string(line) : file_;
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
};

}  // namespace ema::formats
