// Text helpers for every module that prints tables or HTML (the validation table, the CLI's
// tables, the report): one fixed-point rule and one HTML escape, so that the outputs agree.
#pragma once

#include <charconv>
#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>

namespace ema {

/// `value` with `decimals` digits after the point (printf "%.*f"); `not_finite` for NaN and ±Inf,
/// which each table chooses (an empty cell, "–" in Markdown, "-" in plain text).
/// The shortest decimal text of `value` that reads back (strtod) as the same double.
inline std::string ExactNumberText(double value) {
  char text[64];
  const auto result = std::to_chars(text, text + sizeof text, value);  // shortest round trip
  return std::string(text, result.ptr);
}

inline std::string FixedPoint(double value, int decimals, std::string_view not_finite = "") {
  if (!std::isfinite(value)) return std::string(not_finite);
  const int length = std::snprintf(nullptr, 0, "%.*f", decimals, value);  // sized: 1e300 has 301 digits
  std::string out(static_cast<size_t>(length), '\0');
  std::snprintf(out.data(), out.size() + 1, "%.*f", decimals, value);
  return out;
}

/// `text` safe in HTML element content and in quoted attribute values: & < > " escaped.
inline std::string HtmlEscape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

}  // namespace ema
