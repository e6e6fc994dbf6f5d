// UFF reader: the dataset state machine, the per-dataset decoders (spec uff.md §1.2 framing,
// §3-§13), the DOFs hidden in entity names (§12.2), and the parallel split of big files.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <thread>

#include "ema/core/error.hpp"
#include "ema/core/types.hpp"
#include "ema/formats/uff.hpp"
#include "uff_lexer.hpp"

namespace ema::formats::uff {

namespace {

constexpr size_t kMaxNotes = 20;

/// The lines of one ASCII dataset (after the dataset-number line), with their line numbers.
struct Body {
  std::vector<std::string> lines;
  std::int64_t first_line = 0;  // line number of lines[0]
};

/// Error context: file, line, dataset, record/field.
struct Where {
  const std::string* file;
  int dataset;
  std::string Text(std::int64_t line) const { return *file + ":" + std::to_string(line); }
  [[noreturn]] void Fail(std::int64_t line, const std::string& what) const {
    throw InputError(Text(line), "dataset " + std::to_string(dataset) + " " + what);
  }
};

std::string Quote(std::string_view s) {
  std::string out = "'";
  for (char c : s.substr(0, 40)) out += (static_cast<unsigned char>(c) < 0x20) ? '?' : c;
  return out + (s.size() > 40 ? "...'" : "'");
}

// Text fields come out as UTF-8 (Latin-1 labels such as "m/s²" converted: ToUtf8).
std::string TrimmedString(std::string_view s) { return ToUtf8(Trim(s)); }

/// Sequential access to a Body with fixed-column numeric helpers and token fallback.
class Cursor {
 public:
  Cursor(const Body& body, const Where& where) : body_(body), where_(where) {}

  bool AtEnd() const { return index_ >= body_.lines.size(); }
  std::int64_t LineNo() const { return body_.first_line + static_cast<std::int64_t>(index_); }
  const std::string& Line(const std::string& record) const {
    if (AtEnd()) where_.Fail(LineNo(), record + ": truncated, expected another line before the end of the dataset");
    return body_.lines[index_];
  }
  std::string TakeText(const std::string& record) {
    std::string s = Line(record);
    ++index_;
    while (!s.empty() && (s.back() == ' ' || s.back() == '\r')) s.pop_back();
    return ToUtf8(s);
  }
  void SkipBlankLines() {
    while (!AtEnd() && Trim(body_.lines[index_]).empty()) ++index_;
  }
  void Advance() { ++index_; }

  std::int64_t Int(std::string_view line, int first, int last, const std::string& field) const {
    std::int64_t v = 0;
    const std::string_view s = Columns::Slice(line, first, last);
    if (!ParseInteger(s, &v))
      where_.Fail(LineNo(), field + " (columns " + std::to_string(first) + "-" + std::to_string(last) +
                                "): expected an integer, found " + Quote(Trim(s)));
    return v;
  }

  /// Reads `count` integers laid out `per_line` per line in `width` columns, across lines.
  std::vector<std::int64_t> Ints(size_t count, int width, int per_line, const std::string& record) {
    std::vector<std::int64_t> out;
    while (out.size() < count) {
      const std::string& line = Line(record);
      const size_t want = std::min<size_t>(count - out.size(), per_line);
      bool ok = true;
      std::vector<std::int64_t> got;
      for (size_t k = 0; k < want; ++k) {
        std::int64_t v;
        if (!ParseInteger(Columns::Slice(line, static_cast<int>(k) * width + 1, static_cast<int>(k + 1) * width), &v)) {
          ok = false;
          break;
        }
        got.push_back(v);
      }
      if (!ok) {
        got.clear();
        for (auto tok : Tokens(line, false)) {
          std::int64_t v;
          if (!ParseInteger(tok, &v)) where_.Fail(LineNo(), record + ": expected an integer, found " + Quote(tok));
          got.push_back(v);
        }
        if (got.size() > want) got.resize(want);
        if (got.empty()) where_.Fail(LineNo(), record + ": expected integers, found a blank line");
      }
      out.insert(out.end(), got.begin(), got.end());
      ++index_;
    }
    return out;
  }

  /// Reads `count` reals laid out `per_line` per line in `width` columns, across lines.
  std::vector<double> Reals(size_t count, int width, int per_line, const std::string& record, bool allow_non_finite) {
    std::vector<double> out;
    while (out.size() < count) {
      const std::string& line = Line(record);
      const size_t want = std::min<size_t>(count - out.size(), per_line);
      ParseRealLine(line, want, width, record, allow_non_finite, &out);
      ++index_;
    }
    return out;
  }

  void ParseRealLine(std::string_view line, size_t want, int width, const std::string& record, bool allow_non_finite,
                     std::vector<double>* out) const {
    const size_t before = out->size();
    bool ok = true;
    for (size_t k = 0; k < want; ++k) {
      const std::string_view s = Columns::Slice(line, static_cast<int>(k) * width + 1, static_cast<int>(k + 1) * width);
      double v;
      if (Trim(s).empty() || !ParseReal(s, &v)) {
        ok = false;
        break;
      }
      out->push_back(v);
    }
    if (!ok) {
      out->resize(before);
      for (auto tok : Tokens(line, true)) {
        double v;
        if (!ParseReal(tok, &v)) where_.Fail(LineNo(), record + ": expected a real number, found " + Quote(tok));
        if (out->size() - before < want) out->push_back(v);
      }
      if (out->size() == before) where_.Fail(LineNo(), record + ": expected real numbers, found a blank line");
    }
    if (!allow_non_finite)
      for (size_t k = before; k < out->size(); ++k)
        if (!std::isfinite((*out)[k])) where_.Fail(LineNo(), record + ": non-finite value not allowed");
  }

 private:
  const Body& body_;
  const Where& where_;
  size_t index_ = 0;
};

Header151 Decode151(const Body& body, const Where& where) {
  Cursor c(body, where);
  Header151 h;
  auto text = [&](std::string* s) {
    if (!c.AtEnd()) *s = c.TakeText("record");
  };
  text(&h.model_name);
  text(&h.description);
  text(&h.db_program);
  if (!c.AtEnd()) {
    const std::string line = c.Line("record 4");
    h.db_created_date = TrimmedString(Columns::Slice(line, 1, 10));
    h.db_created_time = TrimmedString(Columns::Slice(line, 11, 20));
    h.version1 = static_cast<int>(c.Int(line, 21, 30, "record 4 version"));
    h.version2 = static_cast<int>(c.Int(line, 31, 40, "record 4 version"));
    h.file_type = static_cast<int>(c.Int(line, 41, 50, "record 4 file type"));
    c.Advance();
  }
  if (!c.AtEnd()) {
    const std::string line = c.TakeText("record 5");
    h.db_saved_date = TrimmedString(Columns::Slice(line, 1, 10));
    h.db_saved_time = TrimmedString(Columns::Slice(line, 11, 20));
  }
  text(&h.uff_program);
  if (!c.AtEnd()) {
    const std::string line = c.TakeText("record 7");
    h.uff_written_date = TrimmedString(Columns::Slice(line, 1, 10));
    h.uff_written_time = TrimmedString(Columns::Slice(line, 11, 20));
  }
  return h;
}

Units164 Decode164(const Body& body, const Where& where) {
  Cursor c(body, where);
  Units164 u;
  const std::string line = c.Line("record 1");
  u.code = static_cast<int>(c.Int(line, 1, 10, "record 1 units code"));
  u.description = TrimmedString(Columns::Slice(line, 11, 30));
  u.temperature_mode = static_cast<int>(c.Int(line, 31, 40, "record 1 temperature mode"));
  c.Advance();
  const std::vector<double> f = c.Reals(4, 25, 3, "record 2 conversion factors", false);
  u.length = f[0];
  u.force = f[1];
  u.temperature = f[2];
  u.temperature_offset = f[3];
  if (u.length == 0.0 || u.force == 0.0) where.Fail(body.first_line + 1, "record 2: zero conversion factor");
  return u;
}

std::vector<NodeRecord> DecodeNodes(const Body& body, const Where& where, bool double_precision) {
  Cursor c(body, where);
  std::vector<NodeRecord> nodes;
  for (;;) {
    c.SkipBlankLines();
    if (c.AtEnd()) break;
    NodeRecord n;
    if (!double_precision) {
      const std::string& line = c.Line("node record");
      std::int64_t v[4];
      bool ok = true;
      for (int k = 0; k < 4 && ok; ++k) ok = ParseInteger(Columns::Slice(line, k * 10 + 1, k * 10 + 10), &v[k]);
      double xyz[3];
      for (int k = 0; k < 3 && ok; ++k) {
        const auto s = Columns::Slice(line, 41 + 13 * k, 53 + 13 * k);
        ok = !Trim(s).empty() && ParseReal(s, &xyz[k]);
      }
      if (!ok) {  // tokens fallback (7 values)
        const auto tok = Tokens(line, false);
        if (tok.size() != 7) where.Fail(c.LineNo(), "node record: expected 4 integers and 3 coordinates, found " + Quote(Trim(line)));
        for (int k = 0; k < 4; ++k)
          if (!ParseInteger(tok[k], &v[k])) where.Fail(c.LineNo(), "node record: expected an integer, found " + Quote(tok[k]));
        for (int k = 0; k < 3; ++k)
          if (!ParseReal(tok[4 + k], &xyz[k])) where.Fail(c.LineNo(), "node record: expected a coordinate, found " + Quote(tok[4 + k]));
      }
      for (int k = 0; k < 3; ++k)
        if (!std::isfinite(xyz[k])) where.Fail(c.LineNo(), "node record: non-finite coordinate");
      n.label = v[0];
      n.definition_cs = static_cast<int>(v[1]);
      n.displacement_cs = static_cast<int>(v[2]);
      n.colour = static_cast<int>(v[3]);
      n.xyz = {xyz[0], xyz[1], xyz[2]};
      c.Advance();
    } else {
      const auto ints = c.Ints(4, 10, 4, "record 1");
      n.label = ints[0];
      n.definition_cs = static_cast<int>(ints[1]);
      n.displacement_cs = static_cast<int>(ints[2]);
      n.colour = static_cast<int>(ints[3]);
      const auto xyz = c.Reals(3, 25, 3, "record 2 coordinates", false);
      n.xyz = {xyz[0], xyz[1], xyz[2]};
    }
    nodes.push_back(n);
  }
  return nodes;
}

CoordinateSystems18 Decode18(const Body& body, const Where& where) {
  Cursor c(body, where);
  CoordinateSystems18 out;
  for (;;) {
    c.SkipBlankLines();
    if (c.AtEnd()) break;
    CoordinateSystem18 cs;
    const auto ints = c.Ints(5, 10, 5, "record 1");
    cs.number = static_cast<int>(ints[0]);
    cs.type = static_cast<int>(ints[1]);
    cs.reference = static_cast<int>(ints[2]);
    cs.colour = static_cast<int>(ints[3]);
    cs.method = static_cast<int>(ints[4]);
    cs.name = TrimmedString(Columns::Slice(c.Line("record 2"), 1, 40));
    c.Advance();
    const auto p = c.Reals(9, 13, 6, "record 3", false);
    std::copy(p.begin(), p.end(), cs.points.begin());
    out.systems.push_back(cs);
  }
  return out;
}

CoordinateSystems2420 Decode2420(const Body& body, const Where& where) {
  Cursor c(body, where);
  CoordinateSystems2420 out;
  out.part_uid = c.Ints(1, 10, 1, "record 1")[0];
  out.part_name = c.TakeText("record 2");
  for (;;) {
    c.SkipBlankLines();
    if (c.AtEnd()) break;
    CoordinateSystem2420 cs;
    const std::string& line = c.Line("record 3");
    cs.label = static_cast<int>(c.Int(line, 1, 10, "record 3 label"));
    cs.type = static_cast<int>(c.Int(line, 11, 20, "record 3 type"));
    cs.colour = static_cast<int>(c.Int(line, 21, 30, "record 3 colour"));
    c.Advance();
    cs.name = c.TakeText("record 4");
    const auto m = c.Reals(12, 25, 3, "records 5-8 transformation matrix", false);
    std::copy(m.begin(), m.end(), cs.matrix.begin());
    out.systems.push_back(cs);
  }
  return out;
}

TraceLine82 Decode82(const Body& body, const Where& where) {
  Cursor c(body, where);
  TraceLine82 t;
  const auto ints = c.Ints(3, 10, 3, "record 1");
  t.number = static_cast<int>(ints[0]);
  if (ints[1] < 0 || ints[1] > 100000) where.Fail(body.first_line, "record 1 field 2: implausible node count " + std::to_string(ints[1]));
  t.colour = static_cast<int>(ints[2]);
  t.id = c.TakeText("record 2");
  t.nodes = c.Ints(static_cast<size_t>(ints[1]), 10, 8, "record 3 node entries");
  return t;
}

Data55 Decode55(const Body& body, const Where& where, bool allow_non_finite) {
  Cursor c(body, where);
  Data55 d;
  for (int k = 0; k < 5; ++k) d.id[k] = c.TakeText("record " + std::to_string(k + 1));
  const auto r6 = c.Ints(6, 10, 6, "record 6");
  d.model_type = static_cast<int>(r6[0]);
  d.analysis_type = static_cast<int>(r6[1]);
  d.data_characteristic = static_cast<int>(r6[2]);
  d.specific_data_type = static_cast<int>(r6[3]);
  d.data_type = static_cast<int>(r6[4]);
  d.ndv = static_cast<int>(r6[5]);
  if (d.data_type != 2 && d.data_type != 4 && d.data_type != 5 && d.data_type != 6)
    where.Fail(c.LineNo() - 1, "record 6 field 5: data type must be 2 (real) or 5 (complex), found " + std::to_string(d.data_type));
  if (d.ndv < 1 || d.ndv > 9) where.Fail(c.LineNo() - 1, "record 6 field 6: NDV must be 1..9, found " + std::to_string(d.ndv));
  const std::int64_t r7_line = c.LineNo();
  std::int64_t nint = 0, nrval = 0;
  {
    const std::string& l = c.Line("record 7");
    const auto tok = Tokens(l, false);
    if (tok.size() < 2 || !ParseInteger(tok[0], &nint) || !ParseInteger(tok[1], &nrval))
      where.Fail(r7_line, "record 7: expected NINT and NRVAL, found " + Quote(Trim(l)));
  }
  if (nint < 0 || nint > 10 || nrval < 0 || nrval > 12)
    where.Fail(r7_line, "record 7: NINT must be 0..10 and NRVAL 0..12, found " + std::to_string(nint) + ", " + std::to_string(nrval));
  // The NINT integers follow NINT and NRVAL on the same 8I10 record (wrapping after 8).
  const auto all = c.Ints(static_cast<size_t>(2 + nint), 10, 8, "record 7");
  d.integers.assign(all.begin() + 2, all.end());
  d.reals = c.Reals(static_cast<size_t>(nrval), 13, 6, "record 8", allow_non_finite);
  const size_t per_node = static_cast<size_t>(d.ndv) * (d.IsComplex() ? 2 : 1);
  for (;;) {
    c.SkipBlankLines();
    if (c.AtEnd()) break;
    Data55::NodeValues nv;
    nv.node = c.Ints(1, 10, 1, "record 9 node")[0];
    nv.values = c.Reals(per_node, 13, 6, "record 10 values of node " + std::to_string(nv.node), allow_non_finite);
    d.nodes.push_back(std::move(nv));
  }
  return d;
}

/// Decodes 58 records 1-11 from 11 lines.
void Decode58Header(const std::vector<std::string>& rec, std::int64_t first_line, const Where& where, Function58* f) {
  Body body{rec, first_line};
  Cursor c(body, where);
  for (int k = 0; k < 5; ++k) f->id[k] = c.TakeText("record " + std::to_string(k + 1));
  {
    const std::string& l = c.Line("record 6");
    f->function_type = static_cast<int>(c.Int(l, 1, 5, "record 6 field 1 function type"));
    f->function_id = c.Int(l, 6, 15, "record 6 field 2 function id");
    f->version = static_cast<int>(c.Int(l, 16, 20, "record 6 field 3 version"));
    f->load_case = c.Int(l, 21, 30, "record 6 field 4 load case");
    f->response_entity = TrimmedString(Columns::Slice(l, 32, 41));
    f->response_node = c.Int(l, 42, 51, "record 6 field 6 response node");
    f->response_direction = static_cast<int>(c.Int(l, 52, 55, "record 6 field 7 response direction"));
    f->reference_entity = TrimmedString(Columns::Slice(l, 57, 66));
    f->reference_node = c.Int(l, 67, 76, "record 6 field 9 reference node");
    f->reference_direction = static_cast<int>(c.Int(l, 77, 80, "record 6 field 10 reference direction"));
    if (std::abs(f->response_direction) > 6 || std::abs(f->reference_direction) > 6)
      where.Fail(c.LineNo(), "record 6: direction code must be -6..6");
    c.Advance();
  }
  {
    const std::string& l = c.Line("record 7");
    f->ordinate_type = static_cast<int>(c.Int(l, 1, 10, "record 7 field 1 ordinate data type"));
    f->count = c.Int(l, 11, 20, "record 7 field 2 number of values");
    const std::int64_t spacing = c.Int(l, 21, 30, "record 7 field 3 abscissa spacing");
    double v[3];
    for (int k = 0; k < 3; ++k) {
      const auto s = Columns::Slice(l, 31 + 13 * k, 43 + 13 * k);
      if (!ParseReal(s, &v[k]) || !std::isfinite(v[k]))
        where.Fail(c.LineNo(), "record 7 field " + std::to_string(4 + k) + ": expected a real number, found " + Quote(Trim(s)));
    }
    f->x_min = v[0];
    f->dx = v[1];
    f->z = v[2];
    if (f->ordinate_type != 2 && f->ordinate_type != 4 && f->ordinate_type != 5 && f->ordinate_type != 6)
      where.Fail(c.LineNo(), "record 7 field 1: ordinate data type must be 2, 4, 5 or 6, found " + std::to_string(f->ordinate_type));
    if (f->count < 0) where.Fail(c.LineNo(), "record 7 field 2: negative number of values");
    if (spacing != 0 && spacing != 1)
      where.Fail(c.LineNo(), "record 7 field 3: abscissa spacing must be 0 or 1, found " + std::to_string(spacing));
    f->even = spacing == 1;
    c.Advance();
  }
  for (int a = 0; a < 4; ++a) {
    const std::string rec_name = "record " + std::to_string(8 + a);
    const std::string& l = c.Line(rec_name);
    Axis58& ax = f->axes[a];
    std::int64_t v[4];
    bool ok = true;
    const int cols[5] = {1, 11, 16, 21, 26};
    for (int k = 0; k < 4 && ok; ++k) ok = ParseInteger(Columns::Slice(l, cols[k], cols[k + 1] - 1), &v[k]);
    if (!ok) {
      const auto tok = Tokens(l, false);
      if (tok.size() < 4) where.Fail(c.LineNo(), rec_name + ": expected data type and three unit exponents");
      for (int k = 0; k < 4; ++k)
        if (!ParseInteger(tok[k], &v[k])) where.Fail(c.LineNo(), rec_name + ": expected an integer, found " + Quote(tok[k]));
    }
    ax.specific_data_type = static_cast<int>(v[0]);
    ax.length_exponent = static_cast<int>(v[1]);
    ax.force_exponent = static_cast<int>(v[2]);
    ax.temperature_exponent = static_cast<int>(v[3]);
    ax.label = TrimmedString(Columns::Slice(l, 27, 46));
    ax.units = TrimmedString(Columns::Slice(l, 48, 67));
    c.Advance();
  }
}

/// Layout of record 12 per case (spec §12.8): column widths of one full line.
struct ValueLayout {
  int k = 1;               // numbers per point
  int widths[6] = {};      // field widths of one line
  int per_line = 6;
};

ValueLayout LayoutOf(const Function58& f) {
  ValueLayout l;
  const bool cplx = f.IsComplex(), dbl = f.IsDouble(), even = f.even;
  l.k = (cplx ? 2 : 1) + (even ? 0 : 1);
  if (!dbl) {
    l.per_line = 6;
    for (int& w : l.widths) w = 13;
  } else if (even) {
    l.per_line = 4;
    for (int& w : l.widths) w = 20;
  } else if (!cplx) {
    l.per_line = 4;
    const int w[4] = {13, 20, 13, 20};
    std::copy(w, w + 4, l.widths);
  } else {
    l.per_line = 3;
    const int w[3] = {13, 20, 20};
    std::copy(w, w + 3, l.widths);
  }
  return l;
}

}  // namespace

// ------------------------------------------------------------------------------------------

// Parallel parsing of big files (both cores): a worker parses the second half of the file, from a
// dataset boundary found near the middle, while the caller streams the first half. The split is
// only trusted when the caller's own sequential parse arrives at a start delimiter exactly at the
// split offset; otherwise (or if the worker failed) the worker's result is discarded and the caller
// simply keeps streaming, so the datasets, notes and errors are exactly those of a sequential read.
struct SecondHalf {
  std::uint64_t split = 0;             // byte offset of the start delimiter the worker began at
  std::vector<Dataset> datasets;
  std::vector<std::uint64_t> end_positions;  // file position after each dataset
  // The worker numbers lines from the split (the split's delimiter is its line 1): counting the
  // lines of the first half would cost a pass over it. The caller knows the split's line number
  // when it arrives there and shifts the datasets' lines and the notes by it.
  std::vector<std::pair<std::int64_t, std::string>> notes;  // (line from the split, text)
  std::int64_t line_shift = 0;  // caller's line of the split - 1, set in SplitReached
  bool ok = false;
  std::thread thread;
};

struct Reader::Impl {
  Impl(const std::filesystem::path& path, ReadOptions o) : in(path), options(o), file(path.string()) {}
  ~Impl() {
    if (second && second->thread.joinable()) second->thread.join();
  }

  InputFile in;
  ReadOptions options;
  std::string file;
  std::vector<std::string> file_notes;
  bool numbering_from_split = false;  // the worker of a parallel read: notes kept with their line
  std::vector<std::pair<std::int64_t, std::string>> split_notes;
  int datasets_read = 0;
  bool saw_content = false;
  std::string_view pending;  // a start delimiter already consumed
  bool has_pending = false;
  std::unique_ptr<SecondHalf> second;  // worker of the parallel read (null when not used)
  bool serving_second = false;         // datasets now come from `second`
  size_t served = 0;

  /// A note about the file at `line` ("line N: text").
  void FileNote(std::int64_t line, std::string text) {
    if (numbering_from_split) {
      if (split_notes.size() < kMaxNotes) split_notes.emplace_back(line, std::move(text));
    } else if (file_notes.size() < kMaxNotes) {
      file_notes.push_back("line " + std::to_string(line) + ": " + text);
    }
  }

  void StartSecondHalf(const std::filesystem::path& path);
  bool SplitReached(std::uint64_t start_offset, std::int64_t start_line);
  bool Next(Dataset* ds);
  void ReadAscii58(const Where& where, Function58* f, Dataset* ds);
  void ReadBinary58(std::string_view id_line, std::int64_t id_line_no, const Where& where, Function58* f, Dataset* ds);
  size_t ParseValueLine(std::string_view line, const ValueLayout& layout, const Where& where, std::vector<double>* out,
                        size_t want, std::int64_t declared);
};

namespace {

// A likely dataset boundary at or after `from`: an end delimiter, a start delimiter, then a line
// starting with a dataset number ("58", "58b", "151", ...). Returns the start delimiter's offset,
// or 0 when none is found in the next 16 MiB.
std::uint64_t FindBoundary(const std::filesystem::path& path, std::uint64_t from) {
  std::FILE* fp = std::fopen(path.c_str(), "rb");
  if (!fp) return 0;
  std::vector<char> buf(std::size_t{1} << 24);
  std::uint64_t found = 0;
  if (fseeko(fp, static_cast<off_t>(from), SEEK_SET) == 0) {
    const size_t got = std::fread(buf.data(), 1, buf.size(), fp);
    std::string_view text(buf.data(), got);
    size_t pos = text.find('\n');  // skip the partial line
    std::vector<std::pair<size_t, std::string_view>> window;  // last three lines (offset, text)
    while (pos != std::string_view::npos && pos + 1 < text.size()) {
      const size_t start = pos + 1;
      const size_t nl = text.find('\n', start);
      if (nl == std::string_view::npos) break;
      std::string_view line = text.substr(start, nl - start);
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      window.emplace_back(start, line);
      if (window.size() > 3) window.erase(window.begin());
      if (window.size() == 3 && IsDelimiterLine(window[0].second) && IsDelimiterLine(window[1].second)) {
        std::string_view num = Trim(window[2].second);
        size_t digits = 0;
        while (digits < num.size() && num[digits] >= '0' && num[digits] <= '9') ++digits;
        if (digits > 0 && digits <= 6) {
          found = from + window[1].first;
          break;
        }
      }
      pos = nl;
    }
  }
  std::fclose(fp);
  return found;
}

}  // namespace

void Reader::Impl::StartSecondHalf(const std::filesystem::path& path) {
  const std::uint64_t size = in.Size();
  const std::uint64_t split = FindBoundary(path, size / 2);
  if (split == 0 || split >= size) return;
  second = std::make_unique<SecondHalf>();
  second->split = split;
  SecondHalf* half = second.get();
  const ReadOptions opts = options;
  half->thread = std::thread([half, path, opts, split]() {
    try {
      ReadOptions worker_options = opts;
      worker_options.parallel_min_bytes = 0;  // no recursion
      Impl worker(path, worker_options);
      worker.in.Seek(split);
      worker.numbering_from_split = true;
      worker.datasets_read = 1;  // past the "not a UFF file" checks of a file's start
      worker.saw_content = true;
      Dataset ds;
      while (worker.Next(&ds)) {
        half->datasets.push_back(std::move(ds));
        half->end_positions.push_back(worker.in.Position());
      }
      half->notes = std::move(worker.split_notes);
      half->ok = !half->datasets.empty() && half->datasets.front().offset == split;
    } catch (...) {
      half->ok = false;  // the sequential read will meet (and report) the same problem
    }
  });
}

// Called with the offset of each start delimiter the sequential parse finds: true when the worker's
// datasets take over from here (the split is confirmed and the worker succeeded).
bool Reader::Impl::SplitReached(std::uint64_t start_offset, std::int64_t start_line) {
  if (!second || serving_second || start_offset < second->split) return false;
  if (second->thread.joinable()) second->thread.join();
  if (start_offset != second->split || !second->ok) {
    second.reset();  // not a real boundary, or the worker failed: keep streaming
    return false;
  }
  second->line_shift = start_line - 1;
  for (auto& [line, text] : second->notes) FileNote(line + second->line_shift, std::move(text));
  serving_second = true;
  return true;
}

bool Reader::Impl::Next(Dataset* ds) {
  if (serving_second) {
    if (served >= second->datasets.size()) return false;
    *ds = std::move(second->datasets[served++]);
    ds->line += second->line_shift;
    ++datasets_read;
    return true;
  }
  std::string_view line;
  // BETWEEN: find a start delimiter.
  std::int64_t start_line = 0;
  std::uint64_t start_offset = 0;
  int junk = 0;
  for (;;) {
    if (!in.NextLine(&line)) {
      if (datasets_read == 0) {
        if (!saw_content) throw InputError(file, "empty file (no UFF dataset)");
        throw InputError(file + ":1", "not a UFF file: no '    -1' dataset delimiter found");
      }
      return false;
    }
    if (in.LineNumber() == 1 && line.size() >= 3 && static_cast<unsigned char>(line[0]) == 0xEF &&
        static_cast<unsigned char>(line[1]) == 0xBB && static_cast<unsigned char>(line[2]) == 0xBF)
      line.remove_prefix(3);  // UTF-8 BOM
    if (!Trim(line).empty()) saw_content = true;
    if (IsDelimiterLine(line)) {
      start_line = in.LineNumber();
      start_offset = in.LineStart();
      if (SplitReached(start_offset, start_line)) return Next(ds);
      break;
    }
    if (second && !serving_second && in.LineStart() > second->split) SplitReached(in.LineStart(), in.LineNumber());  // passed it: discard
    if (!Trim(line).empty()) {
      if (datasets_read == 0 && junk == 0 && in.LineNumber() > 200)
        throw InputError(file + ":1", "not a UFF file: no '    -1' dataset delimiter in the first 200 lines");
      if (++junk == 1) FileNote(in.LineNumber(), "text outside a dataset ignored");
    }
  }
  // DATASET_NUMBER
  for (;;) {
    if (!in.NextLine(&line)) {
      FileNote(start_line, "'-1' at the end of the file without a dataset");
      return false;
    }
    if (IsDelimiterLine(line)) {  // stray end delimiter: the new one starts the dataset
      start_line = in.LineNumber();
      start_offset = in.LineStart();
      continue;
    }
    break;
  }
  const std::int64_t number_line = in.LineNumber();
  const auto tokens = Tokens(line, false);
  std::string_view num = tokens.empty() ? std::string_view() : tokens[0];
  bool binary = false;
  if (!num.empty() && (num.back() == 'b' || num.back() == 'B')) {
    binary = true;
    num.remove_suffix(1);
  }
  std::int64_t number = 0;
  if (num.empty() || !ParseInteger(num, &number) || number <= 0 || number > 999999)
    throw InputError(file + ":" + std::to_string(number_line),
                     "expected a dataset number after the '-1' delimiter of line " + std::to_string(start_line) +
                         ", found " + Quote(Trim(line)));
  ds->number = static_cast<int>(number);
  ds->line = start_line;
  ds->offset = start_offset;
  ds->notes.clear();
  const Where where{&file, ds->number};
  ++datasets_read;

  if (number == 58) {
    Function58 f;
    if (binary) {
      const std::string id(line);
      ReadBinary58(id, number_line, where, &f, ds);
    } else {
      if (tokens.size() > 1) ds->notes.push_back("58: extra text on the dataset-number line ignored");
      ReadAscii58(where, &f, ds);
    }
    ds->body = std::move(f);
    return true;
  }
  if (binary) throw InputError(file + ":" + std::to_string(number_line), "binary variant of dataset " + std::to_string(number) + " is not supported (only 58b)");

  // ASCII_BODY: collect the lines until the end delimiter.
  Body body;
  body.first_line = number_line + 1;
  std::vector<std::string> raw{std::string(line)};
  bool closed = false;
  while (in.NextLine(&line)) {
    if (IsDelimiterLine(line)) {
      closed = true;
      break;
    }
    body.lines.emplace_back(line);
  }
  if (!closed) ds->notes.push_back("dataset " + std::to_string(number) + " has no closing '-1' (end of file)");
  switch (number) {
    case 151: ds->body = Decode151(body, where); break;
    case 164: ds->body = Decode164(body, where); break;
    case 15: ds->body = Nodes15{DecodeNodes(body, where, false)}; break;
    case 2411: ds->body = Nodes2411{DecodeNodes(body, where, true)}; break;
    case 18: ds->body = Decode18(body, where); break;
    case 2420: ds->body = Decode2420(body, where); break;
    case 82: ds->body = Decode82(body, where); break;
    case 55: ds->body = Decode55(body, where, options.allow_non_finite); break;
    default: {
      RawDataset r;
      r.lines = std::move(raw);
      for (auto& l : body.lines) r.lines.push_back(std::move(l));
      // 2412 (elements, DecodeElements2412) and 2414 (analysis results, ReadModeSet's FE modes)
      // decode on demand: no note.
      if (number != 2412 && number != 2414) ds->notes.push_back("dataset " + std::to_string(number) + " is not decoded; kept verbatim");
      ds->body = std::move(r);
    }
  }
  return true;
}

/// Eight ASCII digits at p as their value, or -1 when one of them is not a digit. Little-endian
/// SWAR: the digit test and the pairwise combination (10·a + b, then 100·, then 10⁴·) work on
/// all eight bytes of one 64-bit word at once.
static inline std::int64_t EightDigits(const char* p) {
  std::uint64_t v;
  std::memcpy(&v, p, 8);
  // A byte is a digit when it is >= '0' (no borrow from v - '0'...) and <= '9' (+0x46 stays < 0x80).
  if (((v + 0x4646464646464646ull) | (v - 0x3030303030303030ull)) & 0x8080808080808080ull) return -1;
  v -= 0x3030303030303030ull;
  v = v * 10 + (v >> 8);  // byte pairs: 10·d[2i] + d[2i+1] in the even bytes
  const std::uint64_t lo = (v & 0x000000FF000000FFull) * (100 + (1000000ull << 32));
  const std::uint64_t hi = ((v >> 16) & 0x000000FF000000FFull) * (1 + (10000ull << 32));
  return static_cast<std::int64_t>((lo + hi) >> 32);
}

/// Fast path for one fixed-width field in the canonical Fortran forms ("  1.23450E-02",
/// "-3.09944E-004", "0.12345-100", D exponents). Returns 1 with *out set, 0 for a blank field,
/// -1 when the general parser must decide (NaN, many digits, odd forms).
static inline int FastField(const char* p, const char* e, double* out) {
  static constexpr double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                                      1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
  // Canonical 1PE20.12 (" -3.529729047530E-04", C "%20.12E", the double-precision form of
  // record 12): 13 digits as 1 + 8 + 4, read a word at a time.
  if constexpr (std::endian::native == std::endian::little) {
    if (e - p == 20 && p[3] == '.' && p[16] == 'E' && p[0] == ' ' && (p[1] == ' ' || p[1] == '-') &&
        (p[17] == '-' || p[17] == '+')) {
      const unsigned lead = static_cast<unsigned>(p[2] - '0'), x1 = static_cast<unsigned>(p[18] - '0'),
                     x2 = static_cast<unsigned>(p[19] - '0');
      const std::int64_t mid = EightDigits(p + 4);
      const char tail[8] = {p[12], p[13], p[14], p[15], '0', '0', '0', '0'};
      const std::int64_t last = EightDigits(tail);  // the 4 digits, times 10^4
      if (lead <= 9u && x1 <= 9u && x2 <= 9u && mid >= 0 && last >= 0) {
        const std::uint64_t m = lead * 1000000000000ull + static_cast<std::uint64_t>(mid) * 10000u +
                                static_cast<std::uint64_t>(last) / 10000u;
        const int t = static_cast<int>(x1 * 10 + x2) * (p[17] == '-' ? -1 : 1) - 12;
        if (t >= -22 && t <= 22) {
          double v = static_cast<double>(m);  // < 10^13 < 2^53: exact
          v = t < 0 ? v / kPow10[-t] : v * kPow10[t];
          *out = p[1] == '-' ? -v : v;
          return 1;
        }
      }
    }
  }
  // Canonical 1PE13.5 (" -1.47553E-02", C "%13.5E"): fixed positions, no loops.
  if (e - p == 13 && p[3] == '.' && (p[9] == 'E' || p[9] == 'e') && p[0] == ' ' && (p[1] == ' ' || p[1] == '-') &&
      (p[10] == '-' || p[10] == '+')) {
    unsigned d[8] = {static_cast<unsigned>(p[2] - '0'),  static_cast<unsigned>(p[4] - '0'),
                     static_cast<unsigned>(p[5] - '0'),  static_cast<unsigned>(p[6] - '0'),
                     static_cast<unsigned>(p[7] - '0'),  static_cast<unsigned>(p[8] - '0'),
                     static_cast<unsigned>(p[11] - '0'), static_cast<unsigned>(p[12] - '0')};
    unsigned bad = 0;
    for (unsigned x : d) bad |= x > 9u ? 1u : 0u;
    if (!bad) {
      const std::uint64_t m = d[0] * 100000u + d[1] * 10000u + d[2] * 1000u + d[3] * 100u + d[4] * 10u + d[5];
      const int ex = static_cast<int>(d[6] * 10 + d[7]) * (p[10] == '-' ? -1 : 1);
      const int t = ex - 5;
      if (t >= -22 && t <= 22) {
        double v = static_cast<double>(m);
        v = t < 0 ? v / kPow10[-t] : v * kPow10[t];
        *out = p[1] == '-' ? -v : v;
        return 1;
      }
    }
  }
  while (p < e && *p == ' ') ++p;
  if (p == e) return 0;
  bool negative = false;
  if (*p == '-' || *p == '+') {
    negative = *p == '-';
    ++p;
  }
  std::uint64_t m = 0;
  const char* s = p;
  while (p < e && static_cast<unsigned>(*p - '0') < 10u) m = m * 10 + static_cast<unsigned>(*p++ - '0');
  int digits = static_cast<int>(p - s);
  int exp10 = 0;
  if (p < e && *p == '.') {
    ++p;
    const char* f = p;
    while (p < e && static_cast<unsigned>(*p - '0') < 10u) m = m * 10 + static_cast<unsigned>(*p++ - '0');
    exp10 = -static_cast<int>(p - f);
    digits += static_cast<int>(p - f);
  }
  if (digits == 0 || digits > 18) return -1;
  int ex = 0;
  if (p < e && *p != ' ') {
    const char c = *p;
    if (c == 'E' || c == 'e' || c == 'D' || c == 'd') ++p;
    else if (c != '+' && c != '-') return -1;
    bool en = false;
    if (p < e && (*p == '+' || *p == '-')) {
      en = *p == '-';
      ++p;
    }
    const char* xs = p;
    // At most 3 exponent digits on this path (longer ones go to ParseReal): accumulating more
    // would overflow `ex` ("1E9999999999").
    while (p < e && static_cast<unsigned>(*p - '0') < 10u && p - xs < 4) ex = ex * 10 + (*p++ - '0');
    if (p == xs || p - xs > 3) return -1;
    if (en) ex = -ex;
  }
  while (p < e && *p == ' ') ++p;
  if (p != e) return -1;
  const int t = exp10 + ex;
  if (m >= (std::uint64_t{1} << 53) || t < -22 || t > 22) return -1;
  double v = static_cast<double>(m);
  v = t < 0 ? v / kPow10[-t] : v * kPow10[t];  // exact operands: correctly rounded
  *out = negative ? -v : v;
  return 1;
}

size_t Reader::Impl::ParseValueLine(std::string_view line, const ValueLayout& layout, const Where& where,
                                    std::vector<double>* out, size_t want, std::int64_t declared) {
  // Fixed columns first (fast path); whitespace/sign tokens when a slice does not parse
  // (spec §12.9). Numbers beyond `want` must be zero padding (observed writers pad the last
  // line); anything else contradicts N of record 7. Returns the number of padding values.
  const size_t before = out->size();
  size_t pos = 0;
  bool ok = true;
  int field = 0;
  const char* d = line.data();
  const size_t n = line.size();
  while (out->size() - before < want && field < layout.per_line && pos < n) {
    const size_t len = std::min(static_cast<size_t>(layout.widths[field]), n - pos);
    double v;
    const int r = FastField(d + pos, d + pos + len, &v);
    if (r == 0) break;  // a blank slice at the end of a short last line is not a value
    if (r < 0) {
      const std::string_view s(d + pos, len);
      if (Trim(s).empty()) break;
      if (!ParseReal(s, &v)) {
        ok = false;
        break;
      }
    }
    out->push_back(v);
    pos += len;
    ++field;
  }
  std::string_view rest = ok ? line.substr(std::min(pos, n)) : std::string_view();
  if (!ok) {
    out->resize(before);
    rest = line;
  }
  size_t padding = 0;
  if (!Trim(rest).empty()) {
    for (auto tok : Tokens(rest, true)) {
      double v;
      if (!ParseReal(tok, &v))
        where.Fail(in.LineNumber(), "record 12: expected a real number, found " + Quote(tok) + " (value " +
                                        std::to_string(out->size() + 1) + ")");
      if (out->size() - before < want) {
        out->push_back(v);
      } else if (v != 0.0) {
        where.Fail(in.LineNumber(), "record 12: more values than the N = " + std::to_string(declared) +
                                        " declared in record 7 field 2");
      } else {
        ++padding;
      }
    }
  }
  if (!options.allow_non_finite)
    for (size_t k = before; k < out->size(); ++k)
      if (!std::isfinite((*out)[k]))
        where.Fail(in.LineNumber(), "record 12: non-finite value (value " + std::to_string(k + 1) + ") not allowed");
  return padding;
}

void Reader::Impl::ReadAscii58(const Where& where, Function58* f, Dataset* ds) {
  std::vector<std::string> rec;
  std::string_view line;
  const std::int64_t first = in.LineNumber() + 1;
  while (rec.size() < 11) {
    if (!in.NextLine(&line) || IsDelimiterLine(line))
      where.Fail(in.LineNumber(), "record " + std::to_string(rec.size() + 1) +
                                      ": truncated, the dataset ends before its 11 header records");
    rec.emplace_back(line);
  }
  Decode58Header(rec, first, where, f);
  const ValueLayout layout = LayoutOf(*f);
  const std::uint64_t total = static_cast<std::uint64_t>(f->count) * static_cast<std::uint64_t>(layout.k);
  std::vector<double> values;
  const bool parse = !options.headers_only;
  if (parse) {
    if (total > (std::uint64_t{1} << 34)) where.Fail(first + 6, "record 7 field 2: implausible number of values");
    values.reserve(static_cast<size_t>(std::min<std::uint64_t>(total, in.Size() / 8 + 16)));
  }
  std::uint64_t counted = 0;  // headers_only: lines seen
  bool closed = false;
  size_t extra = 0;
  while (in.NextLine(&line)) {
    if (IsDelimiterLine(line)) {
      closed = true;
      break;
    }
    if (!parse) {
      ++counted;
      continue;
    }
    if (values.size() < total) {
      extra += ParseValueLine(line, layout, where, &values, static_cast<size_t>(total - values.size()), f->count);
    } else {
      extra += ParseValueLine(line, layout, where, &values, 0, f->count);
    }
  }
  if (!closed) ds->notes.push_back("58: no closing '-1' (end of file)");
  if (parse && values.size() < total && options.allow_truncated && values.size() % layout.k == 0) {
    ds->notes.push_back("58: truncated, got " + std::to_string(values.size()) + " of " + std::to_string(total) +
                        " values; N reduced to " + std::to_string(values.size() / layout.k));
    f->count = static_cast<std::int64_t>(values.size() / layout.k);
  } else if (parse && values.size() < total)
    where.Fail(in.LineNumber(), "record 12: truncated, got " + std::to_string(values.size()) + " of " +
                                    std::to_string(total) + " values declared in record 7 (N = " +
                                    std::to_string(f->count) + ")");
  if (extra > 0) ds->notes.push_back("58: " + std::to_string(extra) + " zero padding values after N ignored");
  f->values_read = parse;
  if (!parse) return;
  const size_t ky = f->IsComplex() ? 2 : 1;
  if (f->even && static_cast<size_t>(layout.k) == ky) {
    // The values already are y (real, or re/im pairs): handed over, not copied (a copy of a
    // 0.5 GB file's payload costs a tenth of its read in page faults alone).
    f->y = std::move(values);
  } else {
    const size_t n = static_cast<size_t>(f->count);
    if (!f->even) f->x.resize(n);
    f->y.resize(n * ky);
    for (size_t i = 0; i < n; ++i) {
      const double* g = &values[i * layout.k];
      size_t o = 0;
      if (!f->even) f->x[i] = g[o++];
      for (size_t q = 0; q < ky; ++q) f->y[i * ky + q] = g[o + q];
    }
  }
}

namespace {

/// True when the bytes look like the end of a 58b payload: optional EOL, "-1" line or EOF.
int DelimiterAfterPayload(std::string_view b, bool at_eof_if_empty) {
  // Returns -1 if not a delimiter, else the number of EOL bytes before it (0, 1 or 2); 3 = EOF.
  if (b.empty()) return at_eof_if_empty ? 3 : -1;
  size_t i = 0, eol = 0;
  if (b.substr(0, 2) == "\r\n") eol = i = 2;
  else if (b[0] == '\n') eol = i = 1;
  size_t blanks = 0;
  while (i < b.size() && b[i] == ' ') {
    ++i;
    ++blanks;
  }
  if (blanks > 10 || i + 2 > b.size() || b[i] != '-' || b[i + 1] != '1') return -1;
  i += 2;
  if (i < b.size() && b[i] != '\r' && b[i] != '\n' && b[i] != ' ') return -1;
  return static_cast<int>(eol);
}

double LoadF32(const char* p, bool big) {
  std::uint32_t u;
  std::memcpy(&u, p, 4);
  if (big) u = __builtin_bswap32(u);
  return static_cast<double>(std::bit_cast<float>(u));
}
double LoadF64(const char* p, bool big) {
  std::uint64_t u;
  std::memcpy(&u, p, 8);
  if (big) u = __builtin_bswap64(u);
  return std::bit_cast<double>(u);
}

}  // namespace

void Reader::Impl::ReadBinary58(std::string_view id_line, std::int64_t id_line_no, const Where& where, Function58* f,
                                Dataset* ds) {
  // Identifier line (spec §13.1); columns first, tokens as fallback.
  std::int64_t byte_order = 0, fp_format = 0, nlines = 0, nbytes = 0;
  auto col = [&](int a, int b, std::int64_t* v) { return ParseInteger(Columns::Slice(id_line, a, b), v); };
  if (!(col(8, 13, &byte_order) && col(14, 19, &fp_format) && col(20, 31, &nlines) && col(32, 43, &nbytes))) {
    const auto tok = Tokens(id_line, false);
    if (tok.size() < 5 || !ParseInteger(tok[1], &byte_order) || !ParseInteger(tok[2], &fp_format) ||
        !ParseInteger(tok[3], &nlines) || !ParseInteger(tok[4], &nbytes))
      throw InputError(file + ":" + std::to_string(id_line_no),
                       "dataset 58b identifier line: expected byte order, format, line count and byte count, found " +
                           Quote(Trim(id_line)));
  }
  if (nlines == 0) nlines = 11;
  const std::string at = file + ":" + std::to_string(id_line_no);
  if (byte_order != 1 && byte_order != 2)
    throw InputError(at, "dataset 58b identifier field 3: byte order must be 1 (little) or 2 (big), found " + std::to_string(byte_order));
  if (fp_format != 2)
    throw InputError(at, "dataset 58b identifier field 4: only IEEE 754 floating point (2) is supported, found " + std::to_string(fp_format));
  if (nlines != 11) throw InputError(at, "dataset 58b identifier field 5: expected 11 ASCII lines, found " + std::to_string(nlines));
  if (nbytes < 0) throw InputError(at, "dataset 58b identifier field 6: negative byte count");
  f->binary = true;
  f->big_endian = byte_order == 2;

  std::vector<std::string> rec;
  std::string_view line;
  while (rec.size() < 11) {
    if (!in.NextLine(&line) || IsDelimiterLine(line))
      where.Fail(in.LineNumber(), "(58b) record " + std::to_string(rec.size() + 1) + ": truncated header");
    rec.emplace_back(line);
  }
  Decode58Header(rec, id_line_no + 1, where, f);
  const std::int64_t payload_line = in.LineNumber() + 1;
  const std::uint64_t n = static_cast<std::uint64_t>(f->count);
  const bool cplx = f->IsComplex(), dbl = f->IsDouble();
  const std::uint64_t yb = (dbl ? 8 : 4) * (cplx ? 2 : 1);
  const std::uint64_t l_spec = n * (yb + (f->even ? 0 : 4));
  const std::uint64_t l_alt = f->even || !dbl ? l_spec : n * (yb + 8);
  const std::uint64_t l_all_double = dbl ? l_alt : n * ((cplx ? 16 : 8) + (f->even ? 0 : 8));
  std::vector<std::uint64_t> cands{l_spec};
  if (l_alt != l_spec) cands.push_back(l_alt);
  if (l_all_double != l_spec && l_all_double != l_alt) cands.push_back(l_all_double);
  std::sort(cands.begin(), cands.end());
  // Prefer NNNN when it is one of the candidates.
  auto it = std::find(cands.begin(), cands.end(), static_cast<std::uint64_t>(nbytes));
  if (it != cands.end()) std::rotate(cands.begin(), it, it + 1);
  const std::uint64_t start = in.Position();
  const std::uint64_t remaining = in.Size() > start ? in.Size() - start : 0;
  std::uint64_t chosen = 0;
  int eol = -1;
  for (std::uint64_t c : cands) {
    if (c > remaining) continue;
    in.Seek(start + c);
    eol = DelimiterAfterPayload(in.Peek(64), c == remaining);
    if (eol >= 0) {
      chosen = c;
      break;
    }
  }
  if (eol < 0)
    throw InputError(file + ":" + std::to_string(payload_line),
                     "dataset 58b payload: declared " + std::to_string(nbytes) + " bytes, expected " +
                         std::to_string(l_spec) + " for N = " + std::to_string(n) +
                         ", and no '-1' delimiter follows any plausible payload length");
  if (static_cast<std::int64_t>(chosen) != nbytes)
    ds->notes.push_back("58b: byte count " + std::to_string(nbytes) + " disagrees with record 7; used " + std::to_string(chosen));
  if (eol == 1 || eol == 2) ds->notes.push_back("58b: line break after the payload");
  if (eol == 3) ds->notes.push_back("58b: no closing '-1' after the payload (end of file)");
  // Now positioned at start + chosen when we skipped; read the payload from the start.
  const bool abscissa64 = !f->even && chosen == l_alt && l_alt != l_spec;
  const bool values64 = dbl || (chosen == l_all_double && chosen != l_spec);
  if (values64 && !dbl) ds->notes.push_back("58b: declared single precision but payload is double; decoded as double");
  f->values_read = !options.headers_only;
  if (!options.headers_only) {
    in.Seek(start);
    std::string payload(static_cast<size_t>(chosen), '\0');
    in.Read(payload.size(), payload.data());
    const bool big = f->big_endian;
    const size_t ky = cplx ? 2 : 1;
    const size_t vb = values64 ? 8 : 4, xb = f->even ? 0 : (abscissa64 ? 8 : 4);
    if (!f->even) f->x.resize(n);
    f->y.resize(n * ky);
    const char* p = payload.data();
    for (size_t i = 0; i < n; ++i) {
      if (!f->even) {
        f->x[i] = xb == 8 ? LoadF64(p, big) : LoadF32(p, big);
        p += xb;
      }
      for (size_t q = 0; q < ky; ++q) {
        const double v = vb == 8 ? LoadF64(p, big) : LoadF32(p, big);
        if (!options.allow_non_finite && !std::isfinite(v))
          where.Fail(payload_line, "(58b) payload: non-finite value at point " + std::to_string(i + 1));
        f->y[i * ky + q] = v;
        p += vb;
      }
    }
    in.AddLines(static_cast<std::int64_t>(std::count(payload.begin(), payload.end(), '\n')));
  } else {
    in.Seek(start + chosen);
  }
  // Closing delimiter (possibly after an EOL).
  if (eol != 3) {
    if (!in.NextLine(&line)) return;
    if (Trim(line).empty()) in.NextLine(&line);
    if (!IsDelimiterLine(line)) where.Fail(in.LineNumber(), "(58b): expected the closing '-1' after the payload");
  }
}

bool DecodeEntityName(std::string_view name, std::int64_t* node, int* direction) {
  std::string_view s = Trim(name);
  if (!s.empty() && s.front() == '.') s.remove_prefix(1);
  size_t i = 0;
  while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i;
  if (i == 0 || i > 10) return false;
  std::int64_t n = 0;
  if (!ParseInteger(s.substr(0, i), &n) || n <= 0) return false;
  s.remove_prefix(i);
  if (!s.empty() && (s.front() == '.' || s.front() == ':')) s.remove_prefix(1);
  int sign = 1;
  if (!s.empty() && (s.front() == '+' || s.front() == '-')) {
    sign = s.front() == '-' ? -1 : 1;
    s.remove_prefix(1);
  } else if (!s.empty() && (s.back() == '+' || s.back() == '-')) {
    sign = s.back() == '-' ? -1 : 1;
    s.remove_suffix(1);
  }
  const int axis = AxisCode(s);
  if (axis == 0) return false;
  *node = n;
  *direction = sign * axis;
  return true;
}

bool ApplyEntityNameDofs(Function58* f) {
  bool changed = false;
  std::int64_t node;
  int dir;
  if (f->response_node == 0 && f->response_direction == 0 && DecodeEntityName(f->response_entity, &node, &dir)) {
    f->response_node = node;
    f->response_direction = dir;
    changed = true;
  }
  if (f->reference_node == 0 && f->reference_direction == 0 && DecodeEntityName(f->reference_entity, &node, &dir)) {
    f->reference_node = node;
    f->reference_direction = dir;
    changed = true;
  }
  return changed;
}

// ------------------------------------------------------------------------------------------

Reader::Reader(const std::filesystem::path& path, ReadOptions options) : impl_(std::make_unique<Impl>(path, options)) {
  if (options.parallel_min_bytes > 0 && !options.headers_only && impl_->in.Size() >= options.parallel_min_bytes &&
      impl_->in.Size() <= options.parallel_max_bytes &&
      std::thread::hardware_concurrency() >= 2)
    impl_->StartSecondHalf(path);
}
Reader::~Reader() = default;
bool Reader::Next(Dataset* dataset) { return impl_->Next(dataset); }
const std::vector<std::string>& Reader::FileNotes() const { return impl_->file_notes; }
std::uint64_t Reader::FileSize() const { return impl_->in.Size(); }
bool Reader::ServingParallelHalf() const { return impl_->serving_second; }
std::uint64_t Reader::Position() const {
  if (impl_->serving_second)
    return impl_->served == 0 ? impl_->second->split : impl_->second->end_positions[impl_->served - 1];
  return impl_->in.Position();
}

std::vector<Dataset> ReadFile(const std::filesystem::path& path, ReadOptions options) {
  Reader reader(path, options);
  std::vector<Dataset> out;
  Dataset ds;
  while (reader.Next(&ds)) out.push_back(std::move(ds));
  return out;
}

bool LooksLikeUff(const std::filesystem::path& path) {
  std::FILE* fp = std::fopen(path.c_str(), "rb");
  if (!fp) return false;
  char buf[4096];
  const size_t got = std::fread(buf, 1, sizeof buf, fp);
  std::fclose(fp);
  std::string_view s(buf, got);
  if (s.substr(0, 3) == "\xEF\xBB\xBF") s.remove_prefix(3);
  while (!s.empty()) {
    const size_t nl = s.find('\n');
    std::string_view line = s.substr(0, nl);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (!Trim(line).empty()) return IsDelimiterLine(line);
    if (nl == std::string_view::npos) break;
    s.remove_prefix(nl + 1);
  }
  return false;
}

}  // namespace ema::formats::uff
