// UFF lexer (spec uff.md §1, §2): Fortran numbers, column slicing with the UTF-8 rule, tokens,
// delimiter lines, and the buffered binary-mode input the reader pulls lines and 58b payloads from.
// The text readers (CSV, FRF tables) parse their numbers with the same ParseReal/ParseInteger.
#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>

#include "ema/core/error.hpp"
#include "ema/formats/uff.hpp"
#include "uff_lexer.hpp"

namespace ema::formats::uff {

// ------------------------------------------------------------------------------------------
// Numbers (spec §2.2)

namespace {

constexpr double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                             1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

inline bool IsBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\0'; }
inline bool IsDigit(char c) { return c >= '0' && c <= '9'; }

bool EqualsNoCase(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    char x = a[i], y = b[i];
    if (x >= 'A' && x <= 'Z') x = static_cast<char>(x + 32);
    if (y >= 'A' && y <= 'Z') y = static_cast<char>(y + 32);
    if (x != y) return false;
  }
  return true;
}

}  // namespace

std::string_view Trim(std::string_view s) {
  size_t a = 0, b = s.size();
  while (a < b && IsBlank(s[a])) ++a;
  while (b > a && IsBlank(s[b - 1])) --b;
  return s.substr(a, b - a);
}

bool ParseReal(std::string_view text, double* value) {
  std::string_view s = Trim(text);
  if (s.empty()) {  // Fortran reads a blank field as zero
    *value = 0.0;
    return true;
  }
  const char* p = s.data();
  const char* end = p + s.size();
  bool negative = false;
  if (*p == '+' || *p == '-') {
    negative = *p == '-';
    ++p;
  }
  if (p == end) return false;
  if (!IsDigit(*p) && *p != '.') {
    const std::string_view word(p, static_cast<size_t>(end - p));
    if (EqualsNoCase(word, "nan")) {
      *value = std::numeric_limits<double>::quiet_NaN();
      return true;
    }
    if (EqualsNoCase(word, "inf") || EqualsNoCase(word, "infinity")) {
      *value = negative ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
      return true;
    }
    return false;
  }
  std::uint64_t mantissa = 0;
  int digits = 0;        // significant digits accumulated
  int exp10 = 0;
  bool any_digit = false;
  bool too_many = false;
  const char* mant_begin = p;
  while (p < end && IsDigit(*p)) {
    any_digit = true;
    if (digits < 19) {
      if (mantissa != 0 || *p != '0') ++digits;
      mantissa = mantissa * 10 + static_cast<unsigned>(*p - '0');
    } else {
      too_many = true;
      ++exp10;
    }
    ++p;
  }
  if (p < end && *p == '.') {
    ++p;
    while (p < end && IsDigit(*p)) {
      any_digit = true;
      if (digits < 19) {
        if (mantissa != 0 || *p != '0') ++digits;
        mantissa = mantissa * 10 + static_cast<unsigned>(*p - '0');
        --exp10;
      } else {
        too_many = true;
      }
      ++p;
    }
  }
  if (!any_digit) return false;
  const char* mant_end = p;
  int exponent = 0;
  if (p < end) {
    char c = *p;
    if (c == 'E' || c == 'e' || c == 'D' || c == 'd' || c == 'Q' || c == 'q') ++p;
    else if (c != '+' && c != '-') return false;  // letterless exponent starts with its sign
    bool exp_negative = false;
    if (p < end && (*p == '+' || *p == '-')) {
      exp_negative = *p == '-';
      ++p;
    }
    if (p == end) return false;
    int e = 0;
    while (p < end && IsDigit(*p)) {
      if (e < 100000) e = e * 10 + (*p - '0');
      ++p;
    }
    if (p != end) return false;
    exponent = exp_negative ? -e : e;
  }
  const int total = exp10 + exponent;
  if (!too_many && mantissa < (std::uint64_t{1} << 53) && total >= -22 && total <= 22) {
    // Clinger's fast path: the mantissa and the power of ten are exact doubles, so one IEEE
    // multiplication or division rounds correctly.
    double v = static_cast<double>(mantissa);
    v = total < 0 ? v / kPow10[-total] : v * kPow10[total];
    *value = negative ? -v : v;
    return true;
  }
  // Slow path: rebuild a plain "digits.digitsE±n" string for std::from_chars (locale free).
  char buf[128];
  size_t n = 0;
  for (const char* q = mant_begin; q < mant_end && n < 100; ++q) buf[n++] = *q;
  n += static_cast<size_t>(std::snprintf(buf + n, sizeof buf - n, "e%d", exponent));
  double v = 0.0;
  const auto r = std::from_chars(buf, buf + n, v);
  if (r.ec == std::errc::result_out_of_range) {
    // Overflow is not representable data; underflow to zero is harmless.
    v = exponent < 0 ? 0.0 : std::numeric_limits<double>::infinity();
  } else if (r.ec != std::errc()) {
    return false;
  }
  *value = negative ? -v : v;
  return true;
}

bool ParseInteger(std::string_view text, std::int64_t* value) {
  std::string_view s = Trim(text);
  if (s.empty()) {
    *value = 0;
    return true;
  }
  if (s.front() == '+') s.remove_prefix(1);
  std::int64_t v = 0;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  if (r.ec != std::errc() || r.ptr != s.data() + s.size()) return false;
  *value = v;
  return true;
}

// ------------------------------------------------------------------------------------------
// Column slicing with the UTF-8 rule of spec §1.4

std::string_view Columns::Slice(std::string_view line, int first, int last) {
  // first/last are 1-based inclusive columns.
  bool high = false;
  for (char c : line)
    if (static_cast<unsigned char>(c) >= 0x80) {
      high = true;
      break;
    }
  size_t a = static_cast<size_t>(first - 1), b = static_cast<size_t>(last);
  if (high && IsValidUtf8(line)) {
    // Map code-point columns to byte offsets.
    size_t col = 0, byte = 0, byte_a = line.size(), byte_b = line.size();
    while (byte <= line.size()) {
      if (col == a && byte_a == line.size()) byte_a = byte;
      if (col == b) {
        byte_b = byte;
        break;
      }
      if (byte == line.size()) break;
      const unsigned char c = static_cast<unsigned char>(line[byte]);
      byte += c < 0x80 ? 1 : (c >> 5) == 6 ? 2 : (c >> 4) == 14 ? 3 : 4;
      ++col;
    }
    a = std::min(byte_a, line.size());
    b = std::min(byte_b, line.size());
  }
  if (a >= line.size()) return {};
  return line.substr(a, std::min(b, line.size()) - a);
}

std::string ToUtf8(std::string_view s) {
  if (IsValidUtf8(s)) return std::string(s);
  std::string out;
  out.reserve(s.size() + 8);
  for (char c : s) {
    const unsigned char u = static_cast<unsigned char>(c);
    if (u < 0x80) {
      out.push_back(c);
    } else {
      out.push_back(static_cast<char>(0xC0 | (u >> 6)));
      out.push_back(static_cast<char>(0x80 | (u & 0x3F)));
    }
  }
  return out;
}

bool IsValidUtf8(std::string_view s) {
  size_t i = 0;
  while (i < s.size()) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    size_t n = 0;
    if (c < 0x80) n = 0;
    else if ((c >> 5) == 6) n = 1;
    else if ((c >> 4) == 14) n = 2;
    else if ((c >> 3) == 30) n = 3;
    else return false;
    if (n > 0 && i + n >= s.size()) return false;
    for (size_t k = 1; k <= n; ++k)
      if ((static_cast<unsigned char>(s[i + k]) >> 6) != 2) return false;
    i += n + 1;
  }
  return true;
}

bool IsDelimiterLine(std::string_view line) {
  size_t i = 0;
  while (i < line.size() && IsBlank(line[i])) ++i;
  if (i + 2 > line.size() || line[i] != '-' || line[i + 1] != '1') return false;
  for (size_t k = i + 2; k < line.size(); ++k)
    if (!IsBlank(line[k])) return false;
  return true;
}

std::vector<std::string_view> Tokens(std::string_view line, bool split_signs) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && IsBlank(line[i])) ++i;
    if (i >= line.size()) break;
    size_t j = i;
    while (j < line.size() && !IsBlank(line[j])) ++j;
    std::string_view tok = line.substr(i, j - i);
    if (split_signs) {
      // Split run-together numbers where a sign follows a digit or '.', not after an exponent letter.
      size_t start = 0;
      for (size_t k = 1; k < tok.size(); ++k) {
        if ((tok[k] == '+' || tok[k] == '-') && (IsDigit(tok[k - 1]) || tok[k - 1] == '.')) {
          out.push_back(tok.substr(start, k - start));
          start = k;
        }
      }
      out.push_back(tok.substr(start));
    } else {
      out.push_back(tok);
    }
    i = j;
  }
  return out;
}

std::vector<std::int64_t> LineIntegers(std::string_view line, const std::string& where, const std::string& what,
                                       size_t need, int width) {
  std::vector<std::int64_t> out;
  auto take = [&](std::string_view t) {
    std::int64_t v;
    if (!ParseInteger(t, &v)) throw InputError(where, what + ": '" + std::string(t) + "' is not an integer");
    out.push_back(v);
  };
  for (std::string_view t : Tokens(line, false)) {
    if (static_cast<int>(t.size()) <= width) {
      take(t);
      continue;
    }
    // A full field touching its neighbour: cut the token where the field columns fall.
    const size_t start = static_cast<size_t>(t.data() - line.data());
    size_t field_end = (start / width + 1) * width;
    for (size_t a = start; a < start + t.size(); field_end += width) {
      const size_t b = std::min(field_end, start + t.size());
      take(line.substr(a, b - a));
      a = b;
    }
  }
  if (out.size() < need)
    throw InputError(where, what + ": expected at least " + std::to_string(need) + " integers, got " +
                                std::to_string(out.size()));
  return out;
}

std::vector<double> LineReals(std::string_view line, const std::string& where, const std::string& what) {
  std::vector<double> out;
  for (std::string_view t : Tokens(line, true)) {
    double v;
    if (!ParseReal(t, &v)) throw InputError(where, what + ": '" + std::string(t) + "' is not a number");
    out.push_back(v);
  }
  return out;
}

// ------------------------------------------------------------------------------------------
// Buffered binary-mode input with 64-bit offsets.

InputFile::InputFile(const std::filesystem::path& path) : name_(path.string()) {
  file_ = std::fopen(path.c_str(), "rb");
  if (!file_) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) throw InputError(path.string(), "no such file");
    throw InputError(path.string(), std::string("cannot open for reading: ") + std::strerror(errno));
  }
  std::error_code ec;
  size_ = std::filesystem::file_size(path, ec);
  if (ec) size_ = 0;
  // 4 MiB blocks for big files; small files get a buffer of their own size (cheap opens).
  buffer_.resize(static_cast<size_t>(std::clamp<std::uint64_t>(size_ + 1, 4096, std::uint64_t{1} << 22)));
}

InputFile::~InputFile() {
  if (file_) std::fclose(file_);
}

bool InputFile::Fill(size_t need) {
  // Ensures end_ - begin_ >= need unless EOF. Compacts, grows and reads.
  if (end_ - begin_ >= need) return true;
  if (eof_) return false;
  if (begin_ > 0) {
    std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
    buffer_offset_ += begin_;
    end_ -= begin_;
    begin_ = 0;
  }
  if (need > buffer_.size()) buffer_.resize(std::max(need, buffer_.size() * 2));
  while (end_ < need && !eof_) {
    if (end_ == buffer_.size()) buffer_.resize(buffer_.size() * 2);
    const size_t got = std::fread(buffer_.data() + end_, 1, buffer_.size() - end_, file_);
    if (got == 0) eof_ = true;
    end_ += got;
  }
  return end_ - begin_ >= need;
}

bool InputFile::NextLine(std::string_view* line) {
  size_t scan_from = begin_;
  for (;;) {
    const char* base = buffer_.data();
    const void* nl = std::memchr(base + scan_from, '\n', end_ - scan_from);
    if (nl) {
      const size_t pos = static_cast<size_t>(static_cast<const char*>(nl) - base);
      size_t len = pos - begin_;
      if (len > 0 && base[begin_ + len - 1] == '\r') --len;
      *line = std::string_view(base + begin_, len);
      line_start_ = buffer_offset_ + begin_;
      begin_ = pos + 1;
      ++line_number_;
      return true;
    }
    if (eof_) {
      if (begin_ >= end_) return false;
      size_t len = end_ - begin_;
      if (len > 0 && base[begin_ + len - 1] == '\r') --len;
      *line = std::string_view(base + begin_, len);
      line_start_ = buffer_offset_ + begin_;
      begin_ = end_;
      ++line_number_;
      return true;
    }
    const size_t have = end_ - begin_;
    // UFF text lines are 80 columns; 58b data is read by byte count, never as a line. A "line" of
    // megabytes is binary garbage (or a file of NULs): stop here instead of buffering the file.
    constexpr size_t kMaxLine = size_t{1} << 20;
    if (have > kMaxLine)
      throw InputError(name_ + ":" + std::to_string(line_number_ + 1),
                       "no end of line in the first " + std::to_string(kMaxLine) +
                           " bytes of this line: expected UFF text lines of 80 columns (binary data?)");
    Fill(have + 1);  // may move the data to the front of the buffer
    scan_from = begin_ + have;
  }
}

std::string_view InputFile::Peek(size_t n) {
  Fill(n);
  return std::string_view(buffer_.data() + begin_, std::min(n, end_ - begin_));
}

void InputFile::Skip(std::uint64_t n) {
  const std::uint64_t in_buffer = end_ - begin_;
  if (n <= in_buffer) {
    begin_ += static_cast<size_t>(n);
    return;
  }
  const std::uint64_t target = Position() + n;
  begin_ = end_ = 0;
  buffer_offset_ = target;
  eof_ = false;
  if (fseeko(file_, static_cast<off_t>(target), SEEK_SET) != 0) eof_ = true;
}

void InputFile::Seek(std::uint64_t offset) {
  if (offset >= buffer_offset_ && offset <= buffer_offset_ + end_) {
    begin_ = static_cast<size_t>(offset - buffer_offset_);
    return;
  }
  begin_ = end_ = 0;
  buffer_offset_ = offset;
  eof_ = false;
  if (fseeko(file_, static_cast<off_t>(offset), SEEK_SET) != 0) eof_ = true;
}

size_t InputFile::Read(size_t n, char* out) {
  size_t done = 0;
  while (done < n) {
    if (begin_ == end_ && !Fill(std::min<size_t>(n - done, buffer_.size()))) {
      if (begin_ == end_) break;
    }
    const size_t take = std::min(n - done, end_ - begin_);
    std::memcpy(out + done, buffer_.data() + begin_, take);
    begin_ += take;
    done += take;
  }
  return done;
}

}  // namespace ema::formats::uff
