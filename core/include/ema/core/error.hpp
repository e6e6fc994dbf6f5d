// Errors that cross module boundaries.
#pragma once

#include <stdexcept>
#include <string>

namespace ema {

/// Bad input data: a malformed file, inconsistent records, too little data for the request.
/// The CLI maps it to exit code 1. The message names the file, the line/record and what was
/// expected, e.g. "frf.unv:345: dataset 58 record 7: expected 1024 values, found 1000".
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;

  /// Builds "where: what" (where = "file:line" or "file, record N").
  InputError(const std::string& where, const std::string& what)
      : std::runtime_error(where.empty() ? what : where + ": " + what) {}
};

/// Bad command-line usage: unknown option, missing argument. The CLI maps it to exit code 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace ema
