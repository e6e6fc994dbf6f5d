// FRF tables (docs/formats.md, "FRF tables"): measured FRFs as text, with the DOFs named in a
// header. Two layouts: one table holding every FRF as a column, or a folder whose index names
// one complex-column file per FRF. Both end in the same FrfSet assembly.
#include <algorithm>
#include <cmath>
#include <complex>
#include <fstream>
#include <map>
#include <optional>

#include "ema/core/error.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/uff.hpp"
#include "text_cells.hpp"
#include "text_lines.hpp"

namespace ema::formats {

namespace {

using text::Lower;
using text::ParseDofText;
using text::Trim;

/// Cells of one row: split at the table's separator, or at runs of blanks when it has none.
std::vector<std::string> Cells(const std::string& line, char sep) {
  if (sep != ' ') return text::Split(line, sep);
  std::vector<std::string> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

char SeparatorOf(const std::string& header) {
  for (char c : {',', ';', '\t'})
    if (header.find(c) != std::string::npos) return c;
  return ' ';
}

/// Parses a complex cell: `(re+imj)` (Python's repr), `re+imj`, `re`, `nan` (a missing line).
std::optional<std::complex<double>> ParseComplexCell(std::string s) {
  s = Trim(s);
  if (!s.empty() && s.front() == '(') {
    if (s.back() != ')') return std::nullopt;
    s = s.substr(1, s.size() - 2);
  }
  double re = 0.0, im = 0.0;
  if (!s.empty() && (s.back() == 'j' || s.back() == 'J' || s.back() == 'i')) {
    s.pop_back();
    // Split at the last sign that is not the leading one and not part of an exponent.
    size_t split = std::string::npos;
    for (size_t i = s.size(); i-- > 1;)
      if ((s[i] == '+' || s[i] == '-') && s[i - 1] != 'e' && s[i - 1] != 'E') {
        split = i;
        break;
      }
    const std::string re_s = split == std::string::npos ? "0" : s.substr(0, split);
    const std::string im_s = split == std::string::npos ? s : s.substr(split);
    if (Trim(im_s).empty() || !uff::ParseReal(re_s, &re) || !uff::ParseReal(im_s, &im)) return std::nullopt;
    return std::complex<double>(re, im);
  }
  if (s.empty() || !uff::ParseReal(s, &re)) return std::nullopt;
  if (std::isnan(re)) im = re;  // a bare "nan" marks the whole value as missing
  return std::complex<double>(re, im);
}

/// `RESPONSE/REFERENCE` (`1+X/2+X`): the FRF's response and reference DOFs.
std::optional<std::pair<Dof, Dof>> ParseFrfName(const std::string& text) {
  const size_t slash = text.find('/');
  if (slash == std::string::npos) return std::nullopt;
  const auto response = ParseDofText(text.substr(0, slash));
  const auto reference = ParseDofText(text.substr(slash + 1));
  if (!response || !reference) return std::nullopt;
  return std::make_pair(*response, *reference);
}

Quantity ParseQuantity(const std::string& value, const std::string& where) {
  const std::string v = Lower(Trim(value));
  if (v == "acceleration" || v == "accelerance" || v == "inertance") return Quantity::kAcceleration;
  if (v == "velocity" || v == "mobility") return Quantity::kVelocity;
  if (v == "displacement" || v == "receptance" || v == "compliance") return Quantity::kDisplacement;
  throw InputError(where, "quantity: expected acceleration, velocity or displacement, found '" + Trim(value) + "'");
}

/// The next line with content, trimmed (Trim), and its number in *line_no; false at the end.
bool NextContentLine(std::istream& in, const std::string& file, std::int64_t* line_no, std::string* trimmed) {
  std::string line;
  while (ReadTextLine(in, &line, file, *line_no + 1)) {
    ++*line_no;
    *trimmed = Trim(line);
    if (!trimmed->empty()) return true;
  }
  return false;
}

/// A `# key: value` comment line (metadata), or nothing for a plain comment.
std::optional<std::pair<std::string, std::string>> MetadataOf(const std::string& line) {
  const size_t colon = line.find(':');
  if (colon == std::string::npos) return std::nullopt;
  std::string key = Lower(Trim(std::string_view(line).substr(1, colon - 1)));
  if (key != "quantity" && key != "frequency_hz") return std::nullopt;
  return std::make_pair(key, Trim(std::string_view(line).substr(colon + 1)));
}

struct TableColumn {
  std::pair<Dof, Dof> frf;  ///< response, reference
  enum Part { kComplex, kReal, kImag } part = kComplex;
};

/// Assembles named FRF columns into the set's response × reference layout; NaN where an FRF
/// was not measured. Responses and references keep the order of their first appearance.
FrfSet AssembleFrfSet(const std::vector<std::pair<Dof, Dof>>& names, const std::vector<Eigen::VectorXcd>& columns,
                      Eigen::VectorXd frequency_hz, Quantity quantity, const std::string& where) {
  FrfSet set;
  set.frequency_hz = std::move(frequency_hz);
  set.output_quantity = quantity;
  set.response_unit = quantity == Quantity::kDisplacement ? "m" : quantity == Quantity::kVelocity ? "m/s" : "m/s^2";
  auto index_of = [](std::vector<Dof>& list, const Dof& d) {
    const auto it = std::find(list.begin(), list.end(), d);
    if (it != list.end()) return static_cast<Eigen::Index>(it - list.begin());
    list.push_back(d);
    return static_cast<Eigen::Index>(list.size() - 1);
  };
  std::vector<std::pair<Eigen::Index, Eigen::Index>> at;
  for (const auto& [response, reference] : names) at.emplace_back(index_of(set.outputs, response), index_of(set.references, reference));
  const std::complex<double> missing(kNaN, kNaN);
  set.h.assign(set.references.size(), Eigen::MatrixXcd::Constant(set.LineCount(), set.OutputCount(), missing));
  std::vector<std::vector<bool>> seen(set.references.size(), std::vector<bool>(set.outputs.size(), false));
  for (size_t c = 0; c < names.size(); ++c) {
    const auto [o, r] = at[c];
    if (seen[r][o])
      throw InputError(where, "FRF " + DofName(names[c].first) + "/" + DofName(names[c].second) + " given twice");
    seen[r][o] = true;
    set.h[r].col(o) = columns[c];
  }
  return set;
}

Eigen::VectorXd UniformGrid(const std::vector<double>& f, const std::string& file, const std::vector<std::int64_t>& lines) {
  Eigen::VectorXd grid(static_cast<Eigen::Index>(f.size()));
  for (size_t i = 0; i < f.size(); ++i) grid[static_cast<Eigen::Index>(i)] = f[i];
  if (f.size() < 2) return grid;
  const double df = f[1] - f[0];
  if (!(df > 0.0)) throw InputError(file + ":" + std::to_string(lines[1]), "frequencies must increase");
  for (size_t i = 0; i < f.size(); ++i) {
    // Text tables print frequencies rounded; a step off by more than 1e-3 of a line is a real gap.
    if (std::abs(f[i] - (f.front() + df * static_cast<double>(i))) > 1e-3 * df)
      throw InputError(file + ":" + std::to_string(lines[i]),
                       "frequencies must be evenly spaced (step " + std::to_string(df) + " Hz expected)");
  }
  return grid;
}

/// One table holding every FRF as a column (or an re/im pair of columns).
FrfSet ReadInlineTable(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string(), "cannot open for reading");
  const std::string file = path.string();
  Quantity quantity = Quantity::kAcceleration;
  std::vector<TableColumn> columns;
  char sep = ',';
  std::int64_t line_no = 0;
  std::vector<double> frequency;
  std::vector<std::int64_t> lines;
  std::vector<std::vector<std::complex<double>>> values;
  const auto header_hint = "a header such as 'frequency_hz, 1+X/2+X, 1+X/3+X' (response/reference)";
  std::string trimmed;
  while (NextContentLine(in, file, &line_no, &trimmed)) {
    const std::string where = file + ":" + std::to_string(line_no);
    if (trimmed[0] == '#') {
      if (const auto meta = MetadataOf(trimmed); meta && meta->first == "quantity") quantity = ParseQuantity(meta->second, where);
      continue;
    }
    if (columns.empty()) {
      sep = SeparatorOf(trimmed);
      const auto names = Cells(trimmed, sep);
      std::string first = Lower(names.front());
      first = Trim(first.substr(0, first.find('[')));
      if (first != "frequency_hz" && first != "frequency" && first != "freq" && first != "f")
        throw InputError(where, "expected " + std::string(header_hint) + ", found '" + names.front() + "' first");
      if (names.size() < 2) throw InputError(where, "expected at least one FRF column after the frequency");
      for (size_t c = 1; c < names.size(); ++c) {
        TableColumn col;
        std::string name = names[c];
        const std::string low = Lower(name);
        if (low.rfind("re:", 0) == 0 || low.rfind("im:", 0) == 0) {
          col.part = low[0] == 'r' ? TableColumn::kReal : TableColumn::kImag;
          name = name.substr(3);
        }
        const auto frf = ParseFrfName(name);
        if (!frf) throw InputError(where, "column '" + names[c] + "': expected RESPONSE/REFERENCE such as 1+X/2+X (optionally re:/im:)");
        col.frf = *frf;
        columns.push_back(col);
      }
      values.resize(columns.size());
      continue;
    }
    const auto cells = Cells(trimmed, sep);
    if (cells.size() != columns.size() + 1)
      throw InputError(where, "expected " + std::to_string(columns.size() + 1) + " cells like the header, found " + std::to_string(cells.size()));
    double f = 0.0;
    if (!uff::ParseReal(cells[0], &f) || !std::isfinite(f))
      throw InputError(where, "frequency: expected a finite number, found '" + cells[0] + "'");
    frequency.push_back(f);
    lines.push_back(line_no);
    for (size_t c = 0; c < columns.size(); ++c) {
      const auto v = ParseComplexCell(cells[c + 1]);
      if (!v || (columns[c].part != TableColumn::kComplex && v->imag() != 0.0 && !std::isnan(v->imag())))
        throw InputError(where, "column " + std::to_string(c + 2) + ": expected " +
                                    (columns[c].part == TableColumn::kComplex ? "a complex number '(re+imj)'" : "a real number") +
                                    ", found '" + cells[c + 1] + "'");
      values[c].push_back(*v);
    }
  }
  if (columns.empty()) throw InputError(file, std::string("empty file (expected ") + header_hint + ")");
  if (frequency.empty()) throw InputError(file, "no data rows after the header");
  // Merge re:/im: pairs into one complex column per FRF.
  std::vector<std::pair<Dof, Dof>> names;
  std::vector<Eigen::VectorXcd> merged;
  std::map<std::pair<Dof, Dof>, size_t> slot;
  std::map<std::pair<Dof, Dof>, int> parts;  // bit 1: re, bit 2: im, 4: complex
  for (size_t c = 0; c < columns.size(); ++c) {
    const auto& key = columns[c].frf;
    auto [it, fresh] = slot.emplace(key, names.size());
    if (fresh) {
      names.push_back(key);
      merged.emplace_back(Eigen::VectorXcd::Zero(static_cast<Eigen::Index>(frequency.size())));
    }
    const int bit = columns[c].part == TableColumn::kReal ? 1 : columns[c].part == TableColumn::kImag ? 2 : 4;
    int& have = parts[key];
    if ((have & bit) || (have && (bit == 4 || (have & 4))))
      throw InputError(file, "FRF " + DofName(key.first) + "/" + DofName(key.second) + " given twice");
    have |= bit;
    Eigen::VectorXcd& m = merged[it->second];
    for (size_t i = 0; i < frequency.size(); ++i) {
      const auto v = values[c][i];
      auto& out = m[static_cast<Eigen::Index>(i)];
      if (bit == 4) out = v;
      else if (bit == 1) out = {v.real(), out.imag()};
      else out = {out.real(), v.real()};
    }
  }
  for (const auto& [key, have] : parts)
    if (have == 1 || have == 2)
      throw InputError(file, "FRF " + DofName(key.first) + "/" + DofName(key.second) + ": " + (have == 1 ? "im:" : "re:") +
                                 " column missing beside its " + (have == 1 ? "re:" : "im:") + " column");
  return AssembleFrfSet(names, merged, UniformGrid(frequency, file, lines), quantity, file);
}

/// A folder whose index (`frfs.csv`) names one complex-column file per FRF.
FrfSet ReadIndexedFolder(const std::filesystem::path& index) {
  std::ifstream in(index, std::ios::binary);
  if (!in) throw InputError(index.string(), "cannot open for reading");
  const std::string file = index.string();
  Quantity quantity = Quantity::kAcceleration;
  std::optional<std::pair<double, double>> grid;  // start, step
  std::vector<std::pair<Dof, Dof>> names;
  std::vector<Eigen::VectorXcd> columns;
  std::string first_file;
  int file_col = -1, response_col = -1, reference_col = -1;
  char sep = ',';
  std::int64_t line_no = 0;
  std::string trimmed;
  while (NextContentLine(in, file, &line_no, &trimmed)) {
    const std::string where = file + ":" + std::to_string(line_no);
    if (trimmed[0] == '#') {
      const auto meta = MetadataOf(trimmed);
      if (!meta) continue;
      if (meta->first == "quantity") quantity = ParseQuantity(meta->second, where);
      if (meta->first == "frequency_hz") {
        const size_t colon = meta->second.find(':');
        double start = 0.0, step = 0.0;
        if (colon == std::string::npos || !uff::ParseReal(Trim(meta->second.substr(0, colon)), &start) ||
            !uff::ParseReal(Trim(meta->second.substr(colon + 1)), &step) || !(step > 0.0) || !std::isfinite(start))
          throw InputError(where, "frequency_hz: expected START:STEP in Hz (e.g. 0:1), found '" + meta->second + "'");
        grid = std::make_pair(start, step);
      }
      continue;
    }
    if (file_col < 0) {
      sep = SeparatorOf(trimmed);
      const auto names_row = Cells(trimmed, sep);
      for (size_t c = 0; c < names_row.size(); ++c) {
        const std::string n = Lower(names_row[c]);
        if (n == "file") file_col = static_cast<int>(c);
        if (n == "response") response_col = static_cast<int>(c);
        if (n == "reference") reference_col = static_cast<int>(c);
      }
      if (file_col < 0 || response_col < 0 || reference_col < 0)
        throw InputError(where, "expected the header 'file, response, reference'");
      continue;
    }
    const auto cells = Cells(trimmed, sep);
    const int need = std::max({file_col, response_col, reference_col}) + 1;
    if (static_cast<int>(cells.size()) < need)
      throw InputError(where, "expected " + std::to_string(need) + " cells like the header, found " + std::to_string(cells.size()));
    const auto response = ParseDofText(cells[response_col]);
    const auto reference = ParseDofText(cells[reference_col]);
    if (!response) throw InputError(where, "response: expected a DOF such as 1+X, found '" + cells[response_col] + "'");
    if (!reference) throw InputError(where, "reference: expected a DOF such as 1+X, found '" + cells[reference_col] + "'");
    const std::filesystem::path column_file = index.parent_path() / cells[file_col];
    Eigen::VectorXcd column = ReadComplexColumnText(column_file);
    if (!columns.empty() && column.size() != columns.front().size())
      throw InputError(column_file.string(), "expected " + std::to_string(columns.front().size()) + " values like " +
                                                 first_file + ", found " + std::to_string(column.size()));
    if (columns.empty()) first_file = cells[file_col];
    names.emplace_back(*response, *reference);
    columns.push_back(std::move(column));
  }
  if (file_col < 0) throw InputError(file, "empty index (expected the header 'file, response, reference')");
  if (names.empty()) throw InputError(file, "the index names no FRF file");
  if (!grid) throw InputError(file, "missing '# frequency_hz: START:STEP' line (the column files hold no frequencies)");
  Eigen::VectorXd f(columns.front().size());
  for (Eigen::Index i = 0; i < f.size(); ++i) f[i] = grid->first + grid->second * static_cast<double>(i);
  return AssembleFrfSet(names, columns, std::move(f), quantity, file);
}

}  // namespace

Eigen::VectorXcd ReadComplexColumnText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string(), "cannot open for reading");
  std::vector<std::complex<double>> values;
  std::int64_t line_no = 0;
  std::string s;
  while (NextContentLine(in, path.string(), &line_no, &s)) {
    if (s[0] == '#') continue;
    const auto v = ParseComplexCell(s);
    if (!v) throw InputError(path.string() + ":" + std::to_string(line_no), "expected a complex number '(re+imj)', found '" + s + "'");
    values.push_back(*v);
  }
  if (values.empty()) throw InputError(path.string(), "empty file (expected one complex value per line)");
  Eigen::VectorXcd v(static_cast<Eigen::Index>(values.size()));
  for (size_t i = 0; i < values.size(); ++i) v[static_cast<Eigen::Index>(i)] = values[i];
  return v;
}

FrfSet ReadFrfTable(const std::filesystem::path& path) {
  if (!std::filesystem::is_directory(path)) return ReadInlineTable(path);
  const std::filesystem::path index = path / kFrfIndexFileName;
  if (std::filesystem::exists(index)) return ReadIndexedFolder(index);
  // The pyuff beam data as published (no index): its documented DOFs, see docs/formats.md.
  bool legacy = true;
  for (int k = 1; k <= 3; ++k) legacy = legacy && std::filesystem::exists(path / ("meas_point_" + std::to_string(k) + ".txt"));
  if (!legacy)
    throw InputError(path.string(), std::string("a folder of FRF columns needs an index '") + kFrfIndexFileName +
                                        "' (header 'file, response, reference' and a '# frequency_hz: START:STEP' line; docs/formats.md)");
  std::vector<std::pair<Dof, Dof>> names;
  std::vector<Eigen::VectorXcd> columns;
  for (int k = 1; k <= 3; ++k) {
    names.push_back({Dof{1, 1}, Dof{k, 1}});
    columns.push_back(ReadComplexColumnText(path / ("meas_point_" + std::to_string(k) + ".txt")));
    if (columns.back().size() != columns.front().size())
      throw InputError((path / ("meas_point_" + std::to_string(k) + ".txt")).string(),
                       "expected " + std::to_string(columns.front().size()) + " values like meas_point_1.txt, found " +
                           std::to_string(columns.back().size()));
  }
  Eigen::VectorXd f(columns.front().size());
  for (Eigen::Index i = 0; i < f.size(); ++i) f[i] = static_cast<double>(i);
  return AssembleFrfSet(names, columns, std::move(f), Quantity::kAcceleration, path.string());
}

}  // namespace ema::formats
