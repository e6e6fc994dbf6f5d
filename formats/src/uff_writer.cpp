// UFF writer: the conservative profile of spec uff.md §16 (80-column records, exact Fortran
// widths, 1P E formats with upper-case exponent letters, D for 164/2411/2420, "NONE" defaults).
#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <ostream>
#include <string>

#include "ema/core/error.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/uff.hpp"
#include "uff_lexer.hpp"

namespace ema::formats::uff {

std::string FormatE(double value, int width, int precision, char exponent_letter) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, value, std::chars_format::scientific, precision);
  std::string s(buf, r.ptr);
  for (char& c : s)
    if (c == 'e') c = exponent_letter;
  if (static_cast<int>(s.size()) < width) s.insert(0, static_cast<size_t>(width) - s.size(), ' ');
  return s;
}

namespace {

void AppendE(std::string* out, double value, int width, int precision, char letter = 'E') {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, value, std::chars_format::scientific, precision);
  const size_t len = static_cast<size_t>(r.ptr - buf);
  if (static_cast<int>(len) < width) out->append(static_cast<size_t>(width) - len, ' ');
  for (size_t i = 0; i < len; ++i) out->push_back(buf[i] == 'e' ? letter : buf[i]);
}

std::string Int(std::int64_t v, int width) {
  std::string s = std::to_string(v);
  if (static_cast<int>(s.size()) < width) s.insert(0, static_cast<size_t>(width) - s.size(), ' ');
  if (static_cast<int>(s.size()) > width)
    throw InputError("UFF writer", "integer " + s + " does not fit in I" + std::to_string(width));
  return s;
}

/// Left-justified ASCII text cut/padded to `width` (non-ASCII bytes become '?').
std::string Text(std::string_view s, int width, bool pad = true) {
  std::string out;
  for (char c : s) {
    if (static_cast<int>(out.size()) >= width) break;
    out.push_back(static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x80 ? '?' : c);
  }
  if (pad && static_cast<int>(out.size()) < width) out.append(static_cast<size_t>(width - out.size()), ' ');
  return out;
}

/// The units label, last field of 58 records 8-11: nothing follows it, so UTF-8 is safe
/// (spec §1.4); Latin-1 bytes are converted to UTF-8; cut to `width` characters.
std::string UnitsText(std::string_view s, int width) {
  std::string utf8;
  if (IsValidUtf8(s)) {
    utf8 = std::string(s);
  } else {
    for (char c : s) {
      const unsigned char u = static_cast<unsigned char>(c);
      if (u < 0x80) {
        utf8.push_back(c);
      } else {
        utf8.push_back(static_cast<char>(0xC0 | (u >> 6)));
        utf8.push_back(static_cast<char>(0x80 | (u & 0x3F)));
      }
    }
  }
  std::string out;
  int chars = 0;
  for (size_t i = 0; i < utf8.size(); ++i) {
    const unsigned char u = static_cast<unsigned char>(utf8[i]);
    if ((u & 0xC0) != 0x80) {
      if (chars == width) break;
      ++chars;
    }
    if (u < 0x20) break;
    out.push_back(utf8[i]);
  }
  return out;
}

/// A free-standing ID line (80A1): kept as given (UTF-8 allowed here), NONE when empty.
std::string IdLine(std::string_view s) {
  std::string out;
  for (char c : s) {
    if (c == '\n' || c == '\r') break;
    out.push_back(c);
  }
  while (!out.empty() && out.back() == ' ') out.pop_back();
  if (out.size() > 80) out.resize(80);
  return out.empty() ? "NONE" : out;
}

std::string OrNone(std::string_view s) { return s.empty() ? "NONE" : std::string(s); }

void CheckFinite(double v, const char* what) {
  if (!std::isfinite(v))
    throw InputError("UFF writer", std::string("cannot write a non-finite value (") + what + ") to UFF");
}

void Line(std::ostream& out, const std::string& s) {
  out.write(s.data(), static_cast<std::streamsize>(s.size()));
  out.put('\n');
}

void WriteReals(std::ostream& out, const double* v, size_t n, int width, int precision, int per_line, char letter,
                const char* what) {
  std::string line;
  for (size_t i = 0; i < n; ++i) {
    CheckFinite(v[i], what);
    AppendE(&line, v[i], width, precision, letter);
    if ((i + 1) % static_cast<size_t>(per_line) == 0 || i + 1 == n) {
      Line(out, line);
      line.clear();
    }
  }
}

void WriteInts(std::ostream& out, const std::int64_t* v, size_t n, int width, int per_line) {
  std::string line;
  for (size_t i = 0; i < n; ++i) {
    line += Int(v[i], width);
    if ((i + 1) % static_cast<size_t>(per_line) == 0 || i + 1 == n) {
      Line(out, line);
      line.clear();
    }
  }
}

void Write151(std::ostream& out, const Header151& h) {
  Line(out, IdLine(h.model_name));
  Line(out, IdLine(h.description));
  Line(out, IdLine(h.db_program));
  Line(out, Text(h.db_created_date, 10) + Text(h.db_created_time, 10) + Int(h.version1, 10) + Int(h.version2, 10) +
                Int(h.file_type, 10));
  Line(out, Text(h.db_saved_date, 10) + Text(h.db_saved_time, 10, false));
  Line(out, IdLine(h.uff_program));
  Line(out, Text(h.uff_written_date, 10) + Text(h.uff_written_time, 10, false));
}

void Write164(std::ostream& out, const Units164& u) {
  Line(out, Int(u.code, 10) + Text(u.description, 20) + Int(u.temperature_mode, 10));
  std::string l;
  for (double v : {u.length, u.force, u.temperature}) {
    CheckFinite(v, "164 factor");
    AppendE(&l, v, 25, 16, 'D');
  }
  Line(out, l);
  l.clear();
  CheckFinite(u.temperature_offset, "164 offset");
  AppendE(&l, u.temperature_offset, 25, 16, 'D');
  Line(out, l);
}

void Write15(std::ostream& out, const Nodes15& n) {
  for (const auto& node : n.nodes) {
    std::string l = Int(node.label, 10) + Int(node.definition_cs, 10) + Int(node.displacement_cs, 10) + Int(node.colour, 10);
    for (double v : node.xyz) {
      CheckFinite(v, "15 coordinate");
      AppendE(&l, v, 13, 5);
    }
    Line(out, l);
  }
}

void Write2411(std::ostream& out, const Nodes2411& n) {
  for (const auto& node : n.nodes) {
    Line(out, Int(node.label, 10) + Int(node.definition_cs, 10) + Int(node.displacement_cs, 10) + Int(node.colour, 10));
    WriteReals(out, node.xyz.data(), 3, 25, 16, 3, 'D', "2411 coordinate");
  }
}

void Write18(std::ostream& out, const CoordinateSystems18& s) {
  for (const auto& cs : s.systems) {
    Line(out, Int(cs.number, 10) + Int(cs.type, 10) + Int(cs.reference, 10) + Int(cs.colour, 10) + Int(cs.method, 10));
    Line(out, Text(cs.name.empty() ? "NONE" : cs.name, 40, false));
    WriteReals(out, cs.points.data(), 9, 13, 5, 6, 'E', "18 point");
  }
}

void Write2420(std::ostream& out, const CoordinateSystems2420& s) {
  Line(out, Int(s.part_uid, 10));
  Line(out, IdLine(s.part_name));
  for (const auto& cs : s.systems) {
    Line(out, Int(cs.label, 10) + Int(cs.type, 10) + Int(cs.colour, 10));
    Line(out, IdLine(cs.name));
    WriteReals(out, cs.matrix.data(), 12, 25, 16, 3, 'D', "2420 matrix");
  }
}

void Write82(std::ostream& out, const TraceLine82& t) {
  Line(out, Int(t.number, 10) + Int(static_cast<std::int64_t>(t.nodes.size()), 10) + Int(t.colour, 10));
  Line(out, IdLine(t.id));
  WriteInts(out, t.nodes.data(), t.nodes.size(), 10, 8);
}

void Write55(std::ostream& out, const Data55& d) {
  for (const auto& id : d.id) Line(out, IdLine(id));
  Line(out, Int(d.model_type, 10) + Int(d.analysis_type, 10) + Int(d.data_characteristic, 10) +
                Int(d.specific_data_type, 10) + Int(d.data_type, 10) + Int(d.ndv, 10));
  std::vector<std::int64_t> r7{static_cast<std::int64_t>(d.integers.size()), static_cast<std::int64_t>(d.reals.size())};
  r7.insert(r7.end(), d.integers.begin(), d.integers.end());
  WriteInts(out, r7.data(), r7.size(), 10, 8);
  WriteReals(out, d.reals.data(), d.reals.size(), 13, 5, 6, 'E', "55 record 8");
  const size_t per_node = static_cast<size_t>(d.ndv) * (d.IsComplex() ? 2 : 1);
  for (const auto& nv : d.nodes) {
    if (nv.values.size() != per_node)
      throw InputError("UFF writer", "dataset 55 node " + std::to_string(nv.node) + ": expected " +
                                         std::to_string(per_node) + " values");
    Line(out, Int(nv.node, 10));
    WriteReals(out, nv.values.data(), nv.values.size(), 13, 5, 6, 'E', "55 shape value");
  }
}

std::string AxisRecord(const Axis58& a) {
  return Int(a.specific_data_type, 10) + Int(a.length_exponent, 5) + Int(a.force_exponent, 5) +
         Int(a.temperature_exponent, 5) + " " + Text(OrNone(a.label), 20) + " " + UnitsText(OrNone(a.units), 20);
}

void Write58Header(std::ostream& out, const Function58& f) {
  for (const auto& id : f.id) Line(out, IdLine(id));
  Line(out, Int(f.function_type, 5) + Int(f.function_id, 10) + Int(f.version, 5) + Int(f.load_case, 10) + " " +
                Text(OrNone(f.response_entity), 10) + Int(f.response_node, 10) + Int(f.response_direction, 4) + " " +
                Text(OrNone(f.reference_entity), 10) + Int(f.reference_node, 10) + Int(f.reference_direction, 4));
  std::string r7 = Int(f.ordinate_type, 10) + Int(f.count, 10) + Int(f.even ? 1 : 0, 10);
  CheckFinite(f.x_min, "58 abscissa minimum");
  CheckFinite(f.dx, "58 abscissa increment");
  CheckFinite(f.z, "58 z value");
  AppendE(&r7, f.even ? f.x_min : 0.0, 13, 5);
  AppendE(&r7, f.even ? f.dx : 0.0, 13, 5);
  AppendE(&r7, f.z, 13, 5);
  Line(out, r7);
  for (const auto& a : f.axes) Line(out, AxisRecord(a));
}

void Check58(const Function58& f) {
  const size_t ky = f.IsComplex() ? 2 : 1;
  if (f.ordinate_type != 2 && f.ordinate_type != 4 && f.ordinate_type != 5 && f.ordinate_type != 6)
    throw InputError("UFF writer", "dataset 58: ordinate type must be 2, 4, 5 or 6");
  if (f.y.size() != static_cast<size_t>(f.count) * ky)
    throw InputError("UFF writer", "dataset 58: " + std::to_string(f.y.size()) + " values for N = " + std::to_string(f.count));
  if (!f.even && f.x.size() != static_cast<size_t>(f.count))
    throw InputError("UFF writer", "dataset 58: uneven spacing needs N abscissa values");
}

void Write58Ascii(std::ostream& out, const Function58& f) {
  Write58Header(out, f);
  const size_t n = static_cast<size_t>(f.count), ky = f.IsComplex() ? 2 : 1;
  const bool dbl = f.IsDouble();
  // Group per point: [x] y... ; widths per spec §12.8.
  const int yw = dbl ? 20 : 13, yp = dbl ? 12 : 5;
  const int per_line = !dbl ? 6 : (f.even ? 4 : (ky == 1 ? 4 : 3));
  std::string line;
  int on_line = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!f.even) {
      CheckFinite(f.x[i], "58 abscissa");
      AppendE(&line, f.x[i], 13, 5);
      ++on_line;
    }
    for (size_t q = 0; q < ky; ++q) {
      const double v = f.y[i * ky + q];
      CheckFinite(v, "58 value");
      AppendE(&line, v, yw, yp);
      if (++on_line == per_line) {
        Line(out, line);
        line.clear();
        on_line = 0;
      }
    }
  }
  if (on_line > 0) Line(out, line);
}

void Write58Binary(std::ostream& out, const Function58& f) {
  const size_t n = static_cast<size_t>(f.count), ky = f.IsComplex() ? 2 : 1;
  const bool dbl = f.IsDouble();
  const size_t vb = dbl ? 8 : 4, xb = f.even ? 0 : 4;
  const std::uint64_t nbytes = n * (xb + ky * vb);
  std::string id = "    58b" + Int(1, 6) + Int(2, 6) + Int(11, 12) + Int(static_cast<std::int64_t>(nbytes), 12) +
                   Int(0, 6) + Int(0, 6) + Int(0, 12) + Int(0, 12);
  Line(out, id);
  Write58Header(out, f);
  std::string payload;
  payload.reserve(static_cast<size_t>(nbytes));
  auto put32 = [&](double v) {
    const std::uint32_t u = std::bit_cast<std::uint32_t>(static_cast<float>(v));
    char b[4];
    std::memcpy(b, &u, 4);  // x86/ARM little endian; byte order 1 declared
    payload.append(b, 4);
  };
  auto put64 = [&](double v) {
    const std::uint64_t u = std::bit_cast<std::uint64_t>(v);
    char b[8];
    std::memcpy(b, &u, 8);
    payload.append(b, 8);
  };
  static_assert(std::endian::native == std::endian::little, "58b writer assumes a little-endian host");
  for (size_t i = 0; i < n; ++i) {
    if (!f.even) {
      CheckFinite(f.x[i], "58 abscissa");
      put32(f.x[i]);
    }
    for (size_t q = 0; q < ky; ++q) {
      const double v = f.y[i * ky + q];
      CheckFinite(v, "58 value");
      dbl ? put64(v) : put32(v);
    }
  }
  out.write(payload.data(), static_cast<std::streamsize>(payload.size()));
  Line(out, "    -1");
}

}  // namespace

int DatasetNumberOf(const DatasetBody& body) {
  static constexpr int kNumbers[] = {151, 164, 15, 2411, 18, 2420, 82, 55, 58, 0};
  return kNumbers[body.index()];
}

void WriteDataset(std::ostream& out, const DatasetBody& body, const WriteOptions& options) {
  if (const auto* raw = std::get_if<RawDataset>(&body)) {
    Line(out, "    -1");
    for (const auto& l : raw->lines) Line(out, l);
    Line(out, "    -1");
    return;
  }
  if (const auto* f = std::get_if<Function58>(&body)) {
    Check58(*f);
    Line(out, "    -1");
    if (options.binary) {
      Write58Binary(out, *f);  // writes its own closing delimiter glued to the payload
      return;
    }
    Line(out, "    58");
    Write58Ascii(out, *f);
    Line(out, "    -1");
    return;
  }
  Line(out, "    -1");
  Line(out, Int(DatasetNumberOf(body), 6));
  std::visit(
      [&](const auto& d) {
        using T = std::decay_t<decltype(d)>;
        if constexpr (std::is_same_v<T, Header151>) Write151(out, d);
        else if constexpr (std::is_same_v<T, Units164>) Write164(out, d);
        else if constexpr (std::is_same_v<T, Nodes15>) Write15(out, d);
        else if constexpr (std::is_same_v<T, Nodes2411>) Write2411(out, d);
        else if constexpr (std::is_same_v<T, CoordinateSystems18>) Write18(out, d);
        else if constexpr (std::is_same_v<T, CoordinateSystems2420>) Write2420(out, d);
        else if constexpr (std::is_same_v<T, TraceLine82>) Write82(out, d);
        else if constexpr (std::is_same_v<T, Data55>) Write55(out, d);
      },
      body);
  Line(out, "    -1");
}

void WriteDataset(std::ostream& out, const Dataset& dataset, const WriteOptions& options) {
  WriteDataset(out, dataset.body, options);
}

void WriteFile(const std::filesystem::path& path, const std::vector<Dataset>& datasets, const WriteOptions& options) {
  WriteFileAtomically(path, [&](std::ostream& out) {
    for (const auto& d : datasets) WriteDataset(out, d, options);
  });
}

}  // namespace ema::formats::uff
