// The readers of `ema fe-import` (fe_import.hpp): CalculiX MATRIXSTORAGE files (.sti, .mas, .dof)
// and Abaqus `FORMAT=MATRIX INPUT` matrices, written from the formats as docs/fe-parts.md
// describes them (checked on ccx 2.20 output; the Abaqus layout from the *MATRIX INPUT keyword's
// data lines). Files of a 10⁶-DOF model run to gigabytes: lines are cut from 4 MB blocks and
// numbers parsed with std::from_chars, and the matrix is built once from triplets.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <string>
#include <string_view>
#include <unordered_set>
#include <vector>

#include "ema/core/error.hpp"
#include "ema/formats/fe_import.hpp"
#include "text_lines.hpp"

namespace ema::formats {

namespace fs = std::filesystem;

namespace fe_detail {

// Lines of a text file, from large blocks (a ccx .sti of a 200k-DOF model is ~0.5 GB).
class BlockLines {
 public:
  explicit BlockLines(const fs::path& path) : file_(path.string()), in_(path, std::ios::binary) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) throw InputError(file_, "is a folder: expected a text file");
    if (!in_) throw InputError(file_, "cannot open");
  }
  // The next line (without '\n' or '\r'); false at the end. `line_no()` is its 1-based number.
  bool Next(std::string_view* line) {
    for (;;) {
      const std::size_t nl = buffer_.find('\n', pos_);
      if (nl != std::string::npos) {
        *line = Cut(pos_, nl);
        pos_ = nl + 1;
        return true;
      }
      if (eof_) {
        if (pos_ >= buffer_.size()) return false;
        *line = Cut(pos_, buffer_.size());
        pos_ = buffer_.size();
        return true;
      }
      if (buffer_.size() - pos_ > kMaxTextLine)
        throw InputError(Where(line_no_ + 1), "line longer than " + std::to_string(kMaxTextLine) +
                                                  " bytes: expected a text file");
      buffer_.erase(0, pos_);
      pos_ = 0;
      const std::size_t old = buffer_.size();
      buffer_.resize(old + kBlock);
      in_.read(buffer_.data() + old, static_cast<std::streamsize>(kBlock));
      const auto got = static_cast<std::size_t>(in_.gcount());
      buffer_.resize(old + got);
      if (got < kBlock) eof_ = true;
    }
  }
  long line_no() const { return line_no_; }
  std::string Where(long line) const { return file_ + ":" + std::to_string(line); }
  std::string Where() const { return Where(line_no_); }
  const std::string& file() const { return file_; }

 private:
  static constexpr std::size_t kBlock = 4u << 20;
  std::string_view Cut(std::size_t from, std::size_t to) {
    ++line_no_;
    std::string_view s(buffer_.data() + from, to - from);
    if (!s.empty() && s.back() == '\r') s.remove_suffix(1);
    if (s.find('\0') != std::string_view::npos)
      throw InputError(Where(), "binary data (a NUL byte): expected a text file");
    return s;
  }
  std::string file_;
  std::ifstream in_;
  std::string buffer_;
  std::size_t pos_ = 0;
  bool eof_ = false;
  long line_no_ = 0;
};

bool Blank(std::string_view s) { return s.find_first_not_of(" \t") == std::string_view::npos; }

// Fields separated by blanks and (Abaqus) commas.
int SplitFields(std::string_view s, std::string_view* fields, int max_fields) {
  int n = 0;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == ',')) ++i;
    if (i >= s.size()) break;
    std::size_t j = i;
    while (j < s.size() && s[j] != ' ' && s[j] != '\t' && s[j] != ',') ++j;
    if (n == max_fields) return max_fields + 1;
    fields[n++] = s.substr(i, j - i);
    i = j;
  }
  return n;
}

bool ToLong(std::string_view s, long* v) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  const auto r = std::from_chars(s.data(), s.data() + s.size(), *v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

bool ToDouble(std::string_view s, double* v) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  // Fortran writes 1.0D+03 for some codes: accept D as the exponent letter.
  std::string fixed;
  if (s.find_first_of("dD") != std::string_view::npos) {
    fixed.assign(s);
    std::replace(fixed.begin(), fixed.end(), 'd', 'e');
    std::replace(fixed.begin(), fixed.end(), 'D', 'e');
    s = fixed;
  }
  const auto r = std::from_chars(s.data(), s.data() + s.size(), *v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size() && std::isfinite(*v);
}

// The line of the first entry given twice: a second pass over the file, only when a check failed.
template <class KeyOf>
long FirstRepeatedLine(const fs::path& path, KeyOf key_of) {
  BlockLines lines(path);
  std::unordered_set<unsigned long long> seen;
  std::string_view line;
  while (lines.Next(&line)) {
    unsigned long long key = 0;
    if (key_of(line, &key) && !seen.insert(key).second) return lines.line_no();
  }
  return 0;
}

}  // namespace fe_detail

using fe_detail::BlockLines;

std::string FeDofText(const FeDof& dof) { return std::to_string(dof.node) + "." + std::to_string(dof.direction); }

std::vector<FeDof> ReadCalculixDofs(const fs::path& path) {
  BlockLines lines(path);
  std::vector<FeDof> dofs;
  std::map<FeDof, long> line_of;
  std::string_view line;
  while (lines.Next(&line)) {
    if (fe_detail::Blank(line)) continue;
    const std::size_t a = line.find_first_not_of(" \t"), b = line.find_last_not_of(" \t");
    const std::string_view s = line.substr(a, b - a + 1);
    const std::size_t dot = s.find('.');
    long node = 0, direction = 0;
    if (dot == std::string_view::npos || !fe_detail::ToLong(s.substr(0, dot), &node) ||
        !fe_detail::ToLong(s.substr(dot + 1), &direction))
      throw InputError(lines.Where(), "expected 'node.direction' (e.g. 17.3), found '" + std::string(s) + "'");
    if (direction < 1 || direction > 6)
      throw InputError(lines.Where(), "DOF '" + std::string(s) + "': direction " + std::to_string(direction) +
                                          " outside 1..6 (ux uy uz rx ry rz)");
    const FeDof dof{node, static_cast<int>(direction)};
    const auto [it, fresh] = line_of.emplace(dof, lines.line_no());
    if (!fresh)
      throw InputError(lines.Where(), "DOF " + FeDofText(dof) + " listed twice (first on line " +
                                          std::to_string(it->second) + ")");
    dofs.push_back(dof);
  }
  if (dofs.empty()) throw InputError(lines.file(), "no DOF: expected one 'node.direction' a line (a ccx .dof file)");
  return dofs;
}

Eigen::SparseMatrix<double> ReadCalculixMatrix(const fs::path& path, Eigen::Index size) {
  BlockLines lines(path);
  std::vector<Eigen::Triplet<double>> t;
  std::string_view line, f[4];
  long entries = 0;
  while (lines.Next(&line)) {
    if (fe_detail::Blank(line)) continue;
    long i = 0, j = 0;
    double v = 0.0;
    if (fe_detail::SplitFields(line, f, 3) != 3 || !fe_detail::ToLong(f[0], &i) || !fe_detail::ToLong(f[1], &j) ||
        !fe_detail::ToDouble(f[2], &v))
      throw InputError(lines.Where(), "expected 'row column value' (ccx MATRIXSTORAGE), found '" +
                                          std::string(line.substr(0, 120)) + "'");
    if (i < 1 || j < 1 || i > size || j > size)
      throw InputError(lines.Where(), "entry (" + std::to_string(i) + ", " + std::to_string(j) +
                                          ") outside the " + std::to_string(size) +
                                          " DOFs of the .dof file");
    if (i > j)
      throw InputError(lines.Where(), "entry (" + std::to_string(i) + ", " + std::to_string(j) +
                                          ") below the diagonal: ccx stores the upper triangle only (row <= column); "
                                          "a matrix given in full may not be symmetric");
    t.emplace_back(static_cast<int>(j - 1), static_cast<int>(i - 1), v);  // the lower triangle
    ++entries;
  }
  if (entries == 0) throw InputError(lines.file(), "no entry: expected 'row column value' lines (ccx MATRIXSTORAGE)");
  Eigen::SparseMatrix<double> m(size, size);
  m.setFromTriplets(t.begin(), t.end());
  if (m.nonZeros() != entries) {
    const long at = fe_detail::FirstRepeatedLine(path, [](std::string_view s, unsigned long long* key) {
      std::string_view g[4];
      long i = 0, j = 0;
      if (fe_detail::SplitFields(s, g, 3) != 3 || !fe_detail::ToLong(g[0], &i) || !fe_detail::ToLong(g[1], &j))
        return false;
      *key = (static_cast<unsigned long long>(i) << 32) ^ static_cast<unsigned long long>(j);
      return true;
    });
    throw InputError(at > 0 ? lines.Where(at) : lines.file(), "entry given twice (each (row, column) once)");
  }
  return m;
}

AbaqusMatrix ReadAbaqusMatrix(const fs::path& path, const std::vector<FeDof>* given, double symmetry_tolerance) {
  BlockLines lines(path);
  struct Entry {
    FeDof a, b;
    double v;
  };
  std::vector<Entry> entries;
  std::map<FeDof, long> first_line;  // a label's first line (messages)
  std::string_view line, f[6];
  while (lines.Next(&line)) {
    if (fe_detail::Blank(line)) continue;
    const std::size_t a = line.find_first_not_of(" \t");
    if (line[a] == '*') continue;  // a keyword or ** comment line
    long n1 = 0, d1 = 0, n2 = 0, d2 = 0;
    double v = 0.0;
    if (fe_detail::SplitFields(line, f, 5) != 5 || !fe_detail::ToLong(f[0], &n1) || !fe_detail::ToLong(f[1], &d1) ||
        !fe_detail::ToLong(f[2], &n2) || !fe_detail::ToLong(f[3], &d2) || !fe_detail::ToDouble(f[4], &v))
      throw InputError(lines.Where(), "expected 'row node, row dof, column node, column dof, value' (Abaqus "
                                      "FORMAT=MATRIX INPUT), found '" + std::string(line.substr(0, 120)) + "'");
    for (long d : {d1, d2})
      if (d < 1 || d > 6)
        throw InputError(lines.Where(), "dof " + std::to_string(d) + " outside 1..6 (ux uy uz rx ry rz)");
    const FeDof r{n1, static_cast<int>(d1)}, c{n2, static_cast<int>(d2)};
    for (const FeDof& dof : {r, c}) {
      const auto it = first_line.try_emplace(dof, lines.line_no()).first;
      if (given && !std::binary_search(given->begin(), given->end(), dof))
        throw InputError(lines.Where(), "DOF " + FeDofText(dof) + " is not in the nominal run's DOF map");
      (void)it;
    }
    entries.push_back({r, c, v});
  }
  if (entries.empty())
    throw InputError(lines.file(), "no entry: expected 'node, dof, node, dof, value' lines (Abaqus MATRIX INPUT)");
  AbaqusMatrix out;
  if (given) {
    out.dofs = *given;
  } else {
    out.dofs.reserve(first_line.size());
    for (const auto& [dof, at] : first_line) out.dofs.push_back(dof);
  }
  const auto row = [&](const FeDof& d) {
    return static_cast<int>(std::lower_bound(out.dofs.begin(), out.dofs.end(), d) - out.dofs.begin());
  };
  const auto n = static_cast<Eigen::Index>(out.dofs.size());
  std::vector<Eigen::Triplet<double>> low, up;  // entries given below (and on) / above the diagonal
  double scale = 0.0;
  for (const Entry& e : entries) {
    const int i = row(e.a), j = row(e.b);
    scale = std::max(scale, std::abs(e.v));
    if (i >= j) low.emplace_back(i, j, e.v);
    else up.emplace_back(j, i, e.v);  // mirrored into the lower triangle
  }
  Eigen::SparseMatrix<double> lower(n, n), upper(n, n);
  lower.setFromTriplets(low.begin(), low.end());
  upper.setFromTriplets(up.begin(), up.end());
  const auto key_of = [](std::string_view s, unsigned long long* key) {
    std::string_view g[6];
    long n1 = 0, d1 = 0, n2 = 0, d2 = 0;
    if (fe_detail::SplitFields(s, g, 5) != 5 || !fe_detail::ToLong(g[0], &n1) || !fe_detail::ToLong(g[1], &d1) ||
        !fe_detail::ToLong(g[2], &n2) || !fe_detail::ToLong(g[3], &d2))
      return false;
    *key = std::hash<std::string>()(std::to_string(n1) + "." + std::to_string(d1) + "/" + std::to_string(n2) + "." +
                                    std::to_string(d2));
    return true;
  };
  if (lower.nonZeros() != static_cast<long>(low.size()) || upper.nonZeros() != static_cast<long>(up.size())) {
    const long at = fe_detail::FirstRepeatedLine(path, key_of);
    throw InputError(at > 0 ? lines.Where(at) : lines.file(), "entry given twice (each (row, column) once)");
  }
  long strictly_lower = 0;
  for (int c = 0; c < lower.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(lower, c); it; ++it) strictly_lower += it.row() != it.col();
  if (upper.nonZeros() == 0) {
    out.lower = std::move(lower);
  } else if (strictly_lower == 0) {
    out.lower = lower + upper;  // the upper triangle (and the diagonal)
  } else {
    // Both triangles: each entry must have its mirror, equal within the tolerance.
    const Eigen::SparseMatrix<double> strict = lower.triangularView<Eigen::StrictlyLower>();
    const Eigen::SparseMatrix<double> diff = strict - upper;
    for (int c = 0; c < diff.outerSize(); ++c) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(diff, c); it; ++it) {
        if (!(std::abs(it.value()) > symmetry_tolerance * scale)) continue;
        const FeDof a = out.dofs[static_cast<std::size_t>(it.row())], b = out.dofs[static_cast<std::size_t>(it.col())];
        // The line of the entry above the diagonal (a second pass).
        BlockLines again(path);
        std::string_view s;
        long at = 0;
        while (at == 0 && again.Next(&s)) {
          std::string_view g[6];
          long n1 = 0, d1 = 0, n2 = 0, d2 = 0;
          if (fe_detail::SplitFields(s, g, 5) == 5 && fe_detail::ToLong(g[0], &n1) && fe_detail::ToLong(g[1], &d1) &&
              fe_detail::ToLong(g[2], &n2) && fe_detail::ToLong(g[3], &d2) &&
              ((FeDof{n1, static_cast<int>(d1)} == b && FeDof{n2, static_cast<int>(d2)} == a) ||
               (FeDof{n1, static_cast<int>(d1)} == a && FeDof{n2, static_cast<int>(d2)} == b)))
            at = again.line_no();
        }
        char text[200];
        std::snprintf(text, sizeof text, "entry (%s, %s) = %.6g but (%s, %s) = %.6g: not symmetric",
                      FeDofText(a).c_str(), FeDofText(b).c_str(), strict.coeff(it.row(), it.col()),
                      FeDofText(b).c_str(), FeDofText(a).c_str(), upper.coeff(it.row(), it.col()));
        throw InputError(at > 0 ? lines.Where(at) : lines.file(), text);
      }
    }
    out.lower = std::move(lower);
  }
  return out;
}

namespace fe_detail {

std::string Upper(std::string_view s) {
  std::string u(s);
  for (char& c : u) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return u;
}

std::string Trimmed(std::string_view s) {
  const std::size_t a = s.find_first_not_of(" \t"), b = s.find_last_not_of(" \t");
  return a == std::string_view::npos ? std::string() : std::string(s.substr(a, b - a + 1));
}

// A keyword line's parameter (`ELSET=J1` → "J1"), upper case; "" when absent; "=" for a flag.
std::string Parameter(std::string_view line, const std::string& key) {
  std::size_t at = 0;
  while (at < line.size()) {
    const std::size_t comma = line.find(',', at);
    const std::string part = Trimmed(line.substr(at, comma == std::string_view::npos ? line.npos : comma - at));
    const std::size_t eq = part.find('=');
    if (Upper(Trimmed(part.substr(0, eq))) == key) return eq == std::string::npos ? "=" : Upper(Trimmed(part.substr(eq + 1)));
    if (comma == std::string_view::npos) break;
    at = comma + 1;
  }
  return "";
}

}  // namespace fe_detail

const std::vector<int>* FeElementSets::Find(const std::string& name) const {
  const std::string u = fe_detail::Upper(name);
  for (const auto& [set, elements] : sets)
    if (set == u) return &elements;
  return nullptr;
}

FeElementSets ReadInpElementSets(const fs::path& path) {
  using fe_detail::Upper;
  BlockLines lines(path);
  FeElementSets out;
  out.file = path;
  std::map<long, int> index;  // element number → index
  std::map<std::string, std::vector<int>> sets;
  std::map<std::string, std::size_t> order;
  const auto set_of = [&](const std::string& name) -> std::vector<int>& {
    order.try_emplace(name, order.size());
    return sets[name];
  };
  enum class Block { kNone, kElement, kElset };
  Block block = Block::kNone;
  std::string elset;
  bool generate = false;
  std::vector<long> pending;  // an element record continued on the next line
  long pending_line = 0;
  std::string_view line;
  const auto finish_element = [&]() {
    if (pending.empty()) return;
    if (pending.size() < 2) throw InputError(lines.Where(pending_line), "element " + std::to_string(pending[0]) + " has no node");
    const long id = pending[0];
    std::vector<long> nodes(pending.begin() + 1, pending.end());
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    if (!index.emplace(id, static_cast<int>(out.nodes.size())).second)
      throw InputError(lines.Where(pending_line), "element " + std::to_string(id) + " defined twice");
    if (!elset.empty()) set_of(elset).push_back(static_cast<int>(out.nodes.size()));
    out.nodes.push_back(std::move(nodes));
    pending.clear();
  };
  std::vector<std::pair<std::string, std::vector<std::string>>> set_members;  // *ELSET data by name, resolved at the end
  std::vector<long> set_member_lines;
  while (lines.Next(&line)) {
    const std::string t = fe_detail::Trimmed(line);
    if (t.empty() || t.rfind("**", 0) == 0) continue;
    if (t[0] == '*') {
      if (block == Block::kElement) finish_element();
      const std::string keyword = Upper(fe_detail::Trimmed(std::string_view(t).substr(1, t.find(',') == std::string::npos ? t.npos : t.find(',') - 1)));
      block = Block::kNone;
      if (keyword == "INCLUDE")
        throw InputError(lines.Where(), "*INCLUDE is not followed: give the deck with its included files inlined");
      if (keyword == "ELEMENT") {
        block = Block::kElement;
        elset = fe_detail::Parameter(t, "ELSET");
        if (elset == "=") elset.clear();
      } else if (keyword == "ELSET") {
        block = Block::kElset;
        elset = fe_detail::Parameter(t, "ELSET");
        if (elset.empty() || elset == "=") throw InputError(lines.Where(), "*ELSET without ELSET=NAME");
        generate = fe_detail::Parameter(t, "GENERATE") == "=";
        set_of(elset);
      }
      continue;
    }
    if (block == Block::kNone) continue;
    std::vector<std::string_view> fields;
    {
      std::size_t at = 0;
      while (at <= t.size()) {
        const std::size_t comma = t.find(',', at);
        const std::string_view f = std::string_view(t).substr(at, comma == std::string::npos ? t.npos : comma - at);
        const std::size_t a = f.find_first_not_of(" \t");
        if (a != std::string_view::npos) fields.push_back(f.substr(a, f.find_last_not_of(" \t") - a + 1));
        if (comma == std::string::npos) break;
        at = comma + 1;
      }
    }
    if (block == Block::kElement) {
      if (pending.empty()) pending_line = lines.line_no();
      for (const std::string_view f : fields) {
        long v = 0;
        if (!fe_detail::ToLong(f, &v))
          throw InputError(lines.Where(), "*ELEMENT data: expected 'element, node, node, ...', found '" + std::string(f) + "'");
        pending.push_back(v);
      }
      if (t.back() != ',') finish_element();  // a record ending in ',' goes on
    } else if (generate) {
      long a = 0, b = 0, step = 1;
      if (fields.size() < 2 || fields.size() > 3 || !fe_detail::ToLong(fields[0], &a) || !fe_detail::ToLong(fields[1], &b) ||
          (fields.size() == 3 && !fe_detail::ToLong(fields[2], &step)) || step < 1 || b < a)
        throw InputError(lines.Where(), "*ELSET, GENERATE: expected 'first, last[, step]'");
      std::vector<std::string> ids;
      for (long e = a; e <= b; e += step) ids.push_back(std::to_string(e));
      set_members.push_back({elset, std::move(ids)});
      set_member_lines.push_back(lines.line_no());
    } else {
      std::vector<std::string> ids;
      for (const std::string_view f : fields) ids.emplace_back(f);
      set_members.push_back({elset, std::move(ids)});
      set_member_lines.push_back(lines.line_no());
    }
  }
  if (block == Block::kElement) finish_element();
  for (std::size_t k = 0; k < set_members.size(); ++k) {
    for (const std::string& id : set_members[k].second) {
      long e = 0;
      if (fe_detail::ToLong(id, &e)) {
        const auto it = index.find(e);
        if (it == index.end())
          throw InputError(lines.Where(set_member_lines[k]), "*ELSET " + set_members[k].first + ": element " + id + " is not defined");
        set_of(set_members[k].first).push_back(it->second);
      } else {
        const auto it = sets.find(Upper(id));
        if (it == sets.end())
          throw InputError(lines.Where(set_member_lines[k]), "*ELSET " + set_members[k].first + ": no element set '" + id + "'");
        const std::vector<int> copy = it->second;
        std::vector<int>& to = set_of(set_members[k].first);
        to.insert(to.end(), copy.begin(), copy.end());
      }
    }
  }
  if (out.nodes.empty()) throw InputError(lines.file(), "no *ELEMENT: expected an input deck with its elements");
  out.sets.resize(order.size());
  for (auto& [name, elements] : sets) {
    std::sort(elements.begin(), elements.end());
    elements.erase(std::unique(elements.begin(), elements.end()), elements.end());
    out.sets[order[name]] = {name, std::move(elements)};
  }
  return out;
}

FeRun FeRunNamed(const std::string& text) {
  FeRun run;
  const fs::path p(text);
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".mtx") {
    run.code = FeRun::Code::kAbaqus;
    run.stiffness = p;
    const std::string name = p.filename().string();
    const auto at = name.rfind("_STIF");
    if (at != std::string::npos) {
      const fs::path mass = p.parent_path() / (name.substr(0, at) + "_MASS" + name.substr(at + 5));
      std::error_code ec;
      if (fs::exists(mass, ec)) run.mass = mass;
    }
    return run;
  }
  fs::path job = p;
  if (ext == ".sti" || ext == ".mas" || ext == ".dof" || ext == ".inp") job.replace_extension();
  run.code = FeRun::Code::kCalculix;
  run.stiffness = fs::path(job.string() + ".sti");
  run.mass = fs::path(job.string() + ".mas");
  run.dofs = fs::path(job.string() + ".dof");
  return run;
}

}  // namespace ema::formats
