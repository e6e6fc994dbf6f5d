// The cells of the text tables (CSV time data, FRF tables, .mat channel names): trimming, case
// folding, splitting a line into cells at a separator, and the DOF text `101+Z` / `101:+Z`.
#pragma once

#include <cctype>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ema/core/types.hpp"
#include "ema/formats/uff.hpp"

namespace ema::formats::text {

/// Without leading/trailing blanks, tabs, CRs and double quotes (spreadsheets quote cells).
inline std::string Trim(std::string_view s) {
  size_t a = 0, b = s.size();
  while (a < b && (s[a] == ' ' || s[a] == '\t' || s[a] == '\r' || s[a] == '"')) ++a;
  while (b > a && (s[b - 1] == ' ' || s[b - 1] == '\t' || s[b - 1] == '\r' || s[b - 1] == '"')) --b;
  return std::string(s.substr(a, b - a));
}

inline std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

/// The trimmed fields of `line` between separators `sep`.
inline std::vector<std::string> Split(const std::string& line, char sep) {
  std::vector<std::string> out;
  size_t start = 0;
  for (;;) {
    const size_t p = line.find(sep, start);
    out.push_back(Trim(std::string_view(line).substr(start, p == std::string::npos ? std::string::npos : p - start)));
    if (p == std::string::npos) break;
    start = p + 1;
  }
  return out;
}

/// `101+Z`, `101:+Z`, `101-RX` (blanks ignored): a node and a signed direction.
inline std::optional<Dof> ParseDofText(const std::string& raw) {
  std::string t;
  for (char c : raw)
    if (!std::isspace(static_cast<unsigned char>(c)) && c != '"') t += c;
  size_t split = t.find(':');
  std::string node_s, dir_s;
  if (split != std::string::npos) {
    node_s = t.substr(0, split);
    dir_s = t.substr(split + 1);
  } else {
    split = t.find_first_of("+-");
    if (split == std::string::npos || split == 0) return std::nullopt;
    node_s = t.substr(0, split);
    dir_s = t.substr(split);
  }
  std::int64_t node = 0;
  if (!uff::ParseInteger(node_s, &node) || node <= 0 || node > 2147483647) return std::nullopt;
  const int dir = ParseDirection(dir_s);
  if (dir == 0) return std::nullopt;
  return Dof{static_cast<int>(node), dir};
}

}  // namespace ema::formats::text
