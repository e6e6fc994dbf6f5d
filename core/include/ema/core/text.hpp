// Small text helpers shared by every module that writes text for people.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>

namespace ema {

/// `text` safe inside HTML element content and double-quoted attributes: & < > " escaped (the
/// validation table of `ema correlate --table x.html` and the HTML report share this one rule).
inline std::string HtmlEscape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
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

/// `value` with `digits` decimals ("%.*f"), or `not_finite` for NaN and infinities: each table
/// keeps its own mark for a value that does not exist ("-", "–" or an empty cell).
inline std::string FormatFixed(double value, int digits, const std::string& not_finite) {
  if (!std::isfinite(value)) return not_finite;
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", digits, value);
  return text;
}

}  // namespace ema
