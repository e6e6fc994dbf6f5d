// TOML text the formats write by hand (the plan file, the [[effect]] blocks of a model): one rule
// for a float and one for a basic string.
#pragma once

#include <charconv>
#include <string>

namespace ema::formats {

/// The shortest text that reads back to the same double, as a TOML float ("2.0", "0.1", "1e-05", "nan").
inline std::string TomlFloat(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  std::string s(buf, r.ptr);
  if (s.find_first_of(".eEni") == std::string::npos) s += ".0";
  return s;
}

/// A TOML basic string: quotes and backslashes escaped, control bytes as \u00XX.
inline std::string TomlString(const std::string& text) {
  static const char kHex[] = "0123456789abcdef";
  std::string q = "\"";
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      q += '\\';
      q += c;
    } else if (u < 0x20 || u == 0x7f) {
      q += "\\u00";
      q += kHex[u >> 4];
      q += kHex[u & 15];
    } else {
      q += c;
    }
  }
  return q + "\"";
}

}  // namespace ema::formats
