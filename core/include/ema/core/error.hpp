// Errors that cross module boundaries.
#pragma once

#include <algorithm>
#include <stdexcept>
#include <string>

namespace ema {

/// Bad input data: a malformed file, inconsistent records, too little data for the request.
/// The CLI maps it to exit code 1. The message names the file, the line/record and what was
/// expected, e.g. "frf.unv:345: dataset 58 record 7: expected 1024 values, found 1000".
/// Control bytes in the message (a NUL or binary garbage quoted from a bad file) are written as
/// \xNN, so what() is never cut short at a NUL and never garbles a terminal.
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& what) : std::runtime_error(Printable(what)), detail_(Printable(what)) {}
  explicit InputError(const char* what) : InputError(std::string(what)) {}

  /// Builds "where: what" (where = "file:line" or "file, record N").
  InputError(const std::string& where, const std::string& what)
      : std::runtime_error(Printable(where.empty() ? what : where + ": " + what)), where_(Printable(where)),
        detail_(Printable(what)) {}

  /// The two parts of the message ("" and the whole message when it was given as one), for a
  /// caller that names the place in its own words (a text it built and the user never saw).
  const std::string& Where() const { return where_; }
  const std::string& Detail() const { return detail_; }

  /// `text` with bytes below 0x20 (except newline and tab) and 0x7f written as \xNN, cut to
  /// 4000 bytes (a message quoting a huge garbage field stays readable).
  static std::string Printable(const std::string& text) {
    constexpr std::size_t kMax = 4000;
    std::string out;
    out.reserve(std::min(text.size(), kMax) + 8);
    for (const char c : text) {
      if (out.size() >= kMax) {
        out += " [...]";
        break;
      }
      const auto u = static_cast<unsigned char>(c);
      if ((u < 0x20 && c != '\n' && c != '\t') || u == 0x7f) {
        static const char kHex[] = "0123456789abcdef";
        out += "\\x";
        out += kHex[u >> 4];
        out += kHex[u & 15];
      } else {
        out += c;
      }
    }
    return out;
  }

 private:
  std::string where_, detail_;
};

/// A solver that did not converge on data that may well be fine (an eigensolver, a time
/// integration step): not bad input, so the CLI maps it to its own exit code 3 and the caller can
/// retry with other settings. The message names what did not converge and what to change.
class ConvergenceError : public std::runtime_error {
 public:
  explicit ConvergenceError(const std::string& what) : std::runtime_error(InputError::Printable(what)) {}
  /// Builds "where: what" (where = the model or plan file).
  ConvergenceError(const std::string& where, const std::string& what)
      : std::runtime_error(InputError::Printable(where.empty() ? what : where + ": " + what)) {}
};

/// Bad command-line usage: unknown option, missing argument. The CLI maps it to exit code 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace ema
