// A bounded std::getline for the text formats (CSV time data, curves, DOF maps, node lists,
// Matrix Market, column text): binary garbage is recognised on its first line, and memory stays
// proportional to one line of useful content, never to the file.
#pragma once

#include <cstdint>
#include <ios>
#include <istream>
#include <string>

#include "ema/core/error.hpp"

namespace ema::formats {

/// Longest text line accepted (a CSV row of a few hundred channels is a few kB).
constexpr std::size_t kMaxTextLine = 1u << 20;

/// Reads the next line into `line` (without '\n'; a trailing '\r' stays) and returns true, or
/// false at the end of input. Throws InputError "file:line_no: ..." when the line holds a NUL
/// byte (binary data) or is longer than kMaxTextLine, after reading at most kMaxTextLine bytes.
inline bool ReadTextLine(std::istream& in, std::string* line, const std::string& file, std::int64_t line_no) {
  line->clear();
  std::streambuf* buf = in.rdbuf();
  if (!in.good() || buf == nullptr) return false;
  for (;;) {
    int c = 0;
    try {
      c = buf->sbumpc();
    } catch (const std::ios_base::failure& e) {
      // libstdc++'s filebuf throws when the read itself fails, e.g. on a folder opened as a file.
      throw InputError(file + ":" + std::to_string(line_no), std::string("cannot read (") + e.what() +
                                                                  "): expected a text file");
    }
    if (c == std::char_traits<char>::eof()) {
      if (line->empty()) {
        in.setstate(std::ios::eofbit | std::ios::failbit);
        return false;
      }
      in.setstate(std::ios::eofbit);
      return true;
    }
    if (c == '\n') return true;
    if (c == 0)
      throw InputError(file + ":" + std::to_string(line_no),
                       "binary data (a NUL byte at column " + std::to_string(line->size() + 1) +
                           "): expected a text file");
    if (line->size() >= kMaxTextLine)
      throw InputError(file + ":" + std::to_string(line_no),
                       "line longer than " + std::to_string(kMaxTextLine) + " bytes: expected a text file");
    line->push_back(static_cast<char>(c));
  }
}

}  // namespace ema::formats
