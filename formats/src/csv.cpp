// CSV time data (docs/formats.md) and one-complex-value-per-line text columns.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "ema/core/error.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/uff.hpp"
#include "text_cells.hpp"
#include "text_lines.hpp"

namespace ema::formats {

namespace {

using text::Lower;
using text::Split;
using text::Trim;

struct Column {
  enum Kind { kTime, kImpact, kChannel } kind = kChannel;
  Quantity quantity = Quantity::kUnknown;
  Dof dof;
  std::string unit;
  std::string name;
};

Column ParseHeader(const std::string& raw, const std::string& where) {
  Column c;
  c.name = raw;
  std::string name = raw, unit;
  const auto lb = name.find('[');
  if (lb != std::string::npos) {
    const auto rb = name.find(']', lb);
    if (rb == std::string::npos) throw InputError(where, "column '" + raw + "': unclosed '[' in the unit");
    unit = Trim(std::string_view(name).substr(lb + 1, rb - lb - 1));
    name = Trim(std::string_view(name).substr(0, lb));
  }
  const std::string low = Lower(name);
  if (low == "time" || low == "t") {
    if (!unit.empty() && unit != "s")
      throw InputError(where, "column '" + raw + "': time must be in seconds ('s'), found '" + unit + "'");
    c.kind = Column::kTime;
    return c;
  }
  if (low == "impact") {
    c.kind = Column::kImpact;
    return c;
  }
  const auto parts = Split(name, ':');
  if (parts.size() != 3)
    throw InputError(where, "column '" + raw + "': expected 'time', 'impact' or 'role:node:direction' (e.g. acc:101:+X)");
  const std::string role = Lower(parts[0]);
  static const std::map<std::string, std::pair<Quantity, const char*>> kRoles = {
      {"force", {Quantity::kForce, "N"}},          {"f", {Quantity::kForce, "N"}},
      {"acc", {Quantity::kAcceleration, "m/s^2"}}, {"accel", {Quantity::kAcceleration, "m/s^2"}},
      {"acceleration", {Quantity::kAcceleration, "m/s^2"}}, {"vel", {Quantity::kVelocity, "m/s"}},
      {"velocity", {Quantity::kVelocity, "m/s"}},  {"disp", {Quantity::kDisplacement, "m"}},
      {"displacement", {Quantity::kDisplacement, "m"}}};
  const auto it = kRoles.find(role);
  if (it == kRoles.end())
    throw InputError(where, "column '" + raw + "': unknown role '" + parts[0] + "' (force, acc, vel or disp)");
  c.quantity = it->second.first;
  c.unit = unit.empty() ? it->second.second : unit;
  // The unit is a label (never converted), but one of another quantity is a wrong column.
  static const std::map<Quantity, std::vector<std::string>> kUnits = {
      {Quantity::kForce, {"N", "kN", "lbf"}},
      {Quantity::kAcceleration, {"m/s^2", "m/s2", "m/s/s", "mm/s^2", "g", "in/s^2"}},
      {Quantity::kVelocity, {"m/s", "mm/s", "in/s"}},
      {Quantity::kDisplacement, {"m", "mm", "um", "in"}}};
  const auto& units = kUnits.at(c.quantity);
  if (std::find(units.begin(), units.end(), c.unit) == units.end()) {
    std::string list;
    for (const auto& u : units) list += (list.empty() ? "" : ", ") + u;
    throw InputError(where, "column '" + raw + "': '" + c.unit + "' is not a unit of " + parts[0] + " (expected " + list + ")");
  }
  std::int64_t node = 0;
  if (!uff::ParseInteger(parts[1], &node) || node <= 0 || node > 2147483647)
    throw InputError(where, "column '" + raw + "': node must be a positive integer, found '" + parts[1] + "'");
  const int dir = ParseDirection(parts[2]);
  if (dir == 0) throw InputError(where, "column '" + raw + "': direction must be one of +X -X +Y -Y +Z -Z (+RX..), found '" + parts[2] + "'");
  c.dof = {static_cast<int>(node), dir};
  return c;
}

int ImpactFromFileName(const std::filesystem::path& path) {
  const std::string stem = path.stem().string();
  int end = static_cast<int>(stem.size()) - 1;
  while (end >= 0 && !std::isdigit(static_cast<unsigned char>(stem[end]))) --end;
  if (end < 0) return 1;
  int begin = end;
  while (begin > 0 && std::isdigit(static_cast<unsigned char>(stem[begin - 1]))) --begin;
  if (end - begin > 8) return 1;
  return std::stoi(stem.substr(static_cast<size_t>(begin), static_cast<size_t>(end - begin + 1)));
}

double SnapInterval(double dt) {
  const double rate = 1.0 / dt;
  const double r = std::round(rate);
  if (r >= 1.0 && std::abs(rate - r) <= 1e-6 * rate) return 1.0 / r;
  return dt;
}

std::string Shortest(double v) {
  char buf[40];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

}  // namespace

std::vector<TimeRecord> ReadCsvTimeRecords(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string(), "cannot open for reading");
  const std::string file = path.string();
  std::string line;
  std::int64_t line_no = 0;
  std::vector<Column> cols;
  char sep = ',';
  std::int64_t header_line = 0;
  while (ReadTextLine(in, &line, file, line_no + 1)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (Trim(line).empty() || line[0] == '#') continue;
    if (line.find(',') == std::string::npos) sep = line.find(';') != std::string::npos ? ';' : '\t';
    for (const auto& name : Split(line, sep)) cols.push_back(ParseHeader(name, file + ":" + std::to_string(line_no)));
    header_line = line_no;
    break;
  }
  if (cols.empty()) throw InputError(file, "empty file (expected a CSV header such as 'time,force:1:+Z,acc:101:+X')");
  const std::string hwhere = file + ":" + std::to_string(header_line);
  int time_col = -1, impact_col = -1, force_col = -1;
  std::vector<int> channel_cols;
  for (size_t i = 0; i < cols.size(); ++i) {
    if (cols[i].kind == Column::kTime) {
      if (time_col >= 0) throw InputError(hwhere, "more than one time column");
      time_col = static_cast<int>(i);
    } else if (cols[i].kind == Column::kImpact) {
      if (impact_col >= 0) throw InputError(hwhere, "more than one impact column");
      impact_col = static_cast<int>(i);
    } else {
      if (cols[i].quantity == Quantity::kForce) {
        if (force_col >= 0) throw InputError(hwhere, "more than one force column (one hammer per file)");
        force_col = static_cast<int>(i);
      }
      channel_cols.push_back(static_cast<int>(i));
    }
  }
  if (time_col < 0) throw InputError(hwhere, "no 'time' column (seconds) in the header");
  if (channel_cols.empty()) throw InputError(hwhere, "no channel column (e.g. force:1:+Z, acc:101:+X) in the header");
  const Dof reference = force_col >= 0 ? cols[force_col].dof : Dof{};

  struct Group {
    int impact;
    std::vector<double> time;
    std::vector<std::vector<double>> values;  // per channel column
    std::int64_t first_line;
  };
  std::vector<Group> groups;
  std::map<int, size_t> group_of;
  const int default_impact = ImpactFromFileName(path);
  while (ReadTextLine(in, &line, file, line_no + 1)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (Trim(line).empty() || line[0] == '#') continue;
    const auto fields = Split(line, sep);
    const std::string where = file + ":" + std::to_string(line_no);
    if (fields.size() != cols.size())
      throw InputError(where, "expected " + std::to_string(cols.size()) + " fields as in the header, found " +
                                  std::to_string(fields.size()));
    std::vector<double> v(fields.size());
    for (size_t i = 0; i < fields.size(); ++i) {
      if (fields[i].empty() || !uff::ParseReal(fields[i], &v[i]) || !std::isfinite(v[i]))
        throw InputError(where, "column '" + cols[i].name + "': expected a finite number, found '" + fields[i] + "'");
    }
    int impact = default_impact;
    if (impact_col >= 0) {
      if (v[impact_col] != std::floor(v[impact_col]) || v[impact_col] < 0 || v[impact_col] > 1e9)
        throw InputError(where, "column 'impact': expected a non-negative integer, found '" + fields[impact_col] + "'");
      impact = static_cast<int>(v[impact_col]);
    }
    auto it = group_of.find(impact);
    if (it == group_of.end()) {
      it = group_of.emplace(impact, groups.size()).first;
      groups.push_back(Group{impact, {}, std::vector<std::vector<double>>(channel_cols.size()), line_no});
    }
    Group& g = groups[it->second];
    g.time.push_back(v[time_col]);
    for (size_t c = 0; c < channel_cols.size(); ++c) g.values[c].push_back(v[channel_cols[c]]);
  }
  if (groups.empty()) throw InputError(hwhere, "no data rows after the header");
  std::vector<TimeRecord> out;
  for (auto& g : groups) {
    const std::string where = file + ":" + std::to_string(g.first_line);
    const size_t n = g.time.size();
    if (n < 2) throw InputError(where, "impact " + std::to_string(g.impact) + ": at least 2 samples needed");
    const double dt = (g.time.back() - g.time.front()) / static_cast<double>(n - 1);
    if (!(dt > 0.0)) throw InputError(where, "impact " + std::to_string(g.impact) + ": time must increase");
    for (size_t i = 0; i < n; ++i)
      if (std::abs(g.time[i] - (g.time.front() + dt * static_cast<double>(i))) > 0.1 * dt)
        throw InputError(where, "impact " + std::to_string(g.impact) + ": time is not uniformly sampled at sample " +
                                    std::to_string(i + 1) + " (t = " + Shortest(g.time[i]) + " s)");
    for (size_t c = 0; c < channel_cols.size(); ++c) {
      const Column& col = cols[channel_cols[c]];
      TimeRecord r;
      r.channel = col.dof;
      r.reference = reference;
      r.impact = g.impact;
      r.quantity = col.quantity;
      r.sample_interval_s = SnapInterval(dt);
      r.start_time_s = g.time.front();
      r.samples = std::move(g.values[c]);
      r.unit = col.unit;
      r.origin = path.filename().string() + ", column '" + col.name + "', impact " + std::to_string(g.impact);
      out.push_back(std::move(r));
    }
  }
  return out;
}

void WriteCsvTimeRecords(const std::filesystem::path& path, const std::vector<TimeRecord>& records) {
  if (records.empty()) throw InputError("CSV writer", "no time records to write");
  // Columns: one per distinct (quantity, channel); rows per impact.
  std::vector<std::pair<Quantity, Dof>> channels;
  std::vector<std::string> units;
  std::map<int, std::vector<const TimeRecord*>> by_impact;
  for (const auto& r : records) {
    const auto key = std::make_pair(r.quantity, r.channel);
    if (std::find(channels.begin(), channels.end(), key) == channels.end()) {
      channels.push_back(key);
      units.push_back(r.unit);
    }
    by_impact[r.impact].push_back(&r);
  }
  std::string text = "impact,time";
  for (size_t c = 0; c < channels.size(); ++c) {
    const char* role = channels[c].first == Quantity::kForce ? "force"
                       : channels[c].first == Quantity::kVelocity ? "vel"
                       : channels[c].first == Quantity::kDisplacement ? "disp"
                                                                      : "acc";
    text += std::string(",") + role + ":" + std::to_string(channels[c].second.node) + ":" +
            DirectionName(channels[c].second.direction);
    if (!units[c].empty()) text += "[" + units[c] + "]";
  }
  text += "\n";
  for (const auto& [impact, recs] : by_impact) {
    const TimeRecord& first = *recs.front();
    std::vector<const TimeRecord*> row(channels.size(), nullptr);
    for (const auto* r : recs) {
      if (r->samples.size() != first.samples.size() || r->sample_interval_s != first.sample_interval_s)
        throw InputError("CSV writer", "impact " + std::to_string(impact) + ": records differ in length or sample interval");
      row[std::find(channels.begin(), channels.end(), std::make_pair(r->quantity, r->channel)) - channels.begin()] = r;
    }
    for (size_t c = 0; c < row.size(); ++c)
      if (!row[c]) throw InputError("CSV writer", "impact " + std::to_string(impact) + ": a channel is missing");
    for (size_t i = 0; i < first.samples.size(); ++i) {
      text += std::to_string(impact);
      text += ',';
      text += Shortest(first.start_time_s + first.sample_interval_s * static_cast<double>(i));
      for (const auto* r : row) {
        text += ',';
        text += Shortest(r->samples[i]);
      }
      text += "\n";
    }
  }
  WriteTextFileAtomically(path, text);
}

}  // namespace ema::formats
