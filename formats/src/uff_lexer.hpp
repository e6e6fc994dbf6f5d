// The UFF lexer (uff_lexer.cpp; not installed): trimming, tokens, column slices, delimiter lines
// and the buffered input file, shared by the reader and the writer. The number parsers
// (ParseReal, ParseInteger) are public in ema/formats/uff.hpp.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace ema::formats::uff {

std::string_view Trim(std::string_view s);
bool IsValidUtf8(std::string_view s);

/// Text read from a file as UTF-8: kept as it is when it is valid UTF-8, else read as Latin-1
/// (what older tools write for "m/s²" or "°C") and converted, so that JSON and reports carry it.
std::string ToUtf8(std::string_view s);
/// A line whose content is "-1" preceded and followed only by blanks (spec §1.2).
bool IsDelimiterLine(std::string_view line);
/// Whitespace tokens; with split_signs also splits run-together numbers (spec §12.9 step 3).
std::vector<std::string_view> Tokens(std::string_view line, bool split_signs);

/// The integers of a record line, blank-separated; a token longer than `width` characters is
/// fields of `width` columns run together and is split at those columns. Throws InputError
/// (where, what + ": 'x' is not an integer"), and when fewer than `need` are found
/// (what + ": expected at least N integers, got M").
std::vector<std::int64_t> LineIntegers(std::string_view line, const std::string& where, const std::string& what,
                                       size_t need = 0, int width = 10);
/// The reals of a record line, blank-separated, run-together numbers split (spec §12.9); throws
/// InputError(where, what + ": 'x' is not a number").
std::vector<double> LineReals(std::string_view line, const std::string& where, const std::string& what);

struct Columns {
  /// 1-based inclusive columns; blanks (empty) past the end; UTF-8 lines sliced by code points.
  static std::string_view Slice(std::string_view line, int first, int last);
};

/// Buffered binary-mode file with line access and byte-exact reads/skips (for 58b payloads).
class InputFile {
 public:
  explicit InputFile(const std::filesystem::path& path);
  ~InputFile();
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  /// Next line without its terminator (LF or CRLF); valid until the next call. False at EOF.
  bool NextLine(std::string_view* line);
  /// Up to n bytes from the current position (fewer at EOF), not consumed.
  std::string_view Peek(size_t n);
  void Skip(std::uint64_t n);
  /// Moves to an absolute byte offset (used around 58b payloads).
  void Seek(std::uint64_t offset);
  size_t Read(size_t n, char* out);

  std::int64_t LineNumber() const { return line_number_; }
  void AddLines(std::int64_t n) { line_number_ += n; }
  std::uint64_t LineStart() const { return line_start_; }
  std::uint64_t Position() const { return buffer_offset_ + begin_; }
  std::uint64_t Size() const { return size_; }
  const std::string& Name() const { return name_; }

 private:
  bool Fill(size_t need);

  std::FILE* file_ = nullptr;
  std::string name_;
  std::vector<char> buffer_;
  size_t begin_ = 0, end_ = 0;
  std::uint64_t buffer_offset_ = 0;  // file offset of buffer_[0]
  std::uint64_t line_start_ = 0;
  std::uint64_t size_ = 0;
  std::int64_t line_number_ = 0;
  bool eof_ = false;
};

}  // namespace ema::formats::uff
