// Header-only file summaries for `ema info`.
#include "ema/formats/info.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "ema/core/error.hpp"
#include "ema/core/types.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/uff.hpp"

namespace ema::formats {

std::string FunctionTypeName(int type) {
  static const char* kNames[] = {"general",
                                 "time response",
                                 "auto spectrum",
                                 "cross spectrum",
                                 "frequency response function",
                                 "transmissibility",
                                 "coherence",
                                 "auto correlation",
                                 "cross correlation",
                                 "power spectral density",
                                 "energy spectral density",
                                 "probability density function",
                                 "spectrum",
                                 "cumulative frequency distribution",
                                 "peaks valley",
                                 "stress/cycles",
                                 "strain/cycles",
                                 "orbit",
                                 "mode indicator function",
                                 "force pattern",
                                 "partial power",
                                 "partial coherence",
                                 "eigenvalue",
                                 "eigenvector",
                                 "shock response spectrum",
                                 "finite impulse response filter",
                                 "multiple coherence",
                                 "order function",
                                 "phase compensation"};
  if (type >= 0 && type < static_cast<int>(sizeof kNames / sizeof kNames[0])) return kNames[type];
  return "type " + std::to_string(type);
}

namespace {

void AddNote(std::map<std::string, int>* notes, const std::string& n) { ++(*notes)[n]; }

std::string Number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace

std::string DirectionText(int code) {
  // Same text as ema::DirectionName, built without the string concatenation that trips a
  // GCC 12 -Wrestrict false positive when inlined here.
  static const char* kNames[] = {"-RZ", "-RY", "-RX", "-Z", "-Y", "-X", "S", "+X", "+Y", "+Z", "+RX", "+RY", "+RZ"};
  if (code < -6 || code > 6) {
    std::string out = std::to_string(code);
    out.insert(out.begin(), '?');
    return out;
  }
  return kNames[code + 6];
}

namespace {

std::string DirName(int d) { return DirectionText(d); }

}  // namespace

FileSummary SummarizeFile(const std::filesystem::path& path) {
  FileSummary s;
  s.file = path.string();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path.string(), "no such file");
  if (std::filesystem::is_directory(path, ec)) {
    // A folder, as `ema fit` reads it: FRF tables (ReadFrfSet).
    const FrfSet frfs = ReadFrfSet(path);
    s.format = "frf-table folder";
    for (const auto& entry : std::filesystem::directory_iterator(path, ec))
      if (entry.is_regular_file()) s.bytes += entry.file_size();
    for (int r = 0; r < frfs.ReferenceCount(); ++r)
      for (int o = 0; o < frfs.OutputCount(); ++o) {
        if (!frfs.h[static_cast<size_t>(r)].col(o).real().array().isFinite().any()) continue;  // not measured
        ++s.records;
        ++s.function_types[4];
      }
    for (const Dof& d : frfs.outputs) s.response_dofs.insert({d.node, d.direction});
    for (const Dof& d : frfs.references) s.reference_dofs.insert({d.node, d.direction});
    auto& a = s.abscissa[4];
    if (frfs.LineCount() > 0) {
      a.min = frfs.frequency_hz(0);
      a.max = frfs.frequency_hz(frfs.LineCount() - 1);
      a.points_min = a.points_max = frfs.LineCount();
    }
    a.units.insert("Hz");
    a.ordinate_units.insert(frfs.response_unit + " / " + frfs.force_unit);
    return s;
  }
  s.bytes = std::filesystem::file_size(path, ec);
  if (s.bytes == 0) throw InputError(path.string(), "empty file");
  if (!uff::LooksLikeUff(path)) {
    // Not UFF: try the CSV time-data convention; report the UFF problem if that fails too.
    std::vector<TimeRecord> recs;
    try {
      recs = ReadCsvTimeRecords(path);
    } catch (const InputError& e) {
      throw InputError(path.string() + ":1", std::string("neither UFF (no '    -1' delimiter on the first line) nor CSV time data (") + e.what() + ")");
    }
    s.format = "csv";
    for (const auto& r : recs) {
      ++s.records;
      ++s.function_types[1];
      s.response_dofs.insert({r.channel.node, r.channel.direction});
      if (r.reference.node != 0) s.reference_dofs.insert({r.reference.node, r.reference.direction});
      auto& a = s.abscissa[1];
      const double end = r.start_time_s + r.sample_interval_s * static_cast<double>(r.samples.size() - 1);
      if (a.points_max == 0) {
        a.min = r.start_time_s;
        a.max = end;
        a.points_min = a.points_max = static_cast<std::int64_t>(r.samples.size());
      }
      a.min = std::min(a.min, r.start_time_s);
      a.max = std::max(a.max, end);
      a.points_min = std::min<std::int64_t>(a.points_min, static_cast<std::int64_t>(r.samples.size()));
      a.points_max = std::max<std::int64_t>(a.points_max, static_cast<std::int64_t>(r.samples.size()));
      a.units.insert("s");
      if (!r.unit.empty()) a.ordinate_units.insert(r.unit);
    }
    return s;
  }
  s.format = "uff";
  uff::ReadOptions options;
  options.headers_only = true;
  uff::Reader reader(path, options);
  uff::Dataset d;
  std::map<std::string, int> notes;
  while (reader.Next(&d)) {
    ++s.datasets[d.number];
    for (const auto& n : d.notes) AddNote(&notes, n);
    if (auto* f = std::get_if<uff::Function58>(&d.body)) {
      uff::ApplyEntityNameDofs(f);
      ++s.records;
      if (f->binary) ++s.binary58;
      ++s.function_types[f->function_type];
      s.response_dofs.insert({f->response_node, f->response_direction});
      if (f->reference_node != 0 || f->reference_direction != 0)
        s.reference_dofs.insert({f->reference_node, f->reference_direction});
      auto& a = s.abscissa[f->function_type];
      // Even spacing: range from record 7. Uneven: the values are not read in a header scan.
      double lo = f->x_min, hi = f->x_min + f->dx * static_cast<double>(std::max<std::int64_t>(f->count - 1, 0));
      if (!f->even) lo = hi = std::nan("");
      if (a.points_max == 0 && a.units.empty()) {
        a.min = lo;
        a.max = hi;
        a.points_min = a.points_max = f->count;
      }
      if (std::isfinite(lo)) {
        a.min = std::isfinite(a.min) ? std::min(a.min, lo) : lo;
        a.max = std::isfinite(a.max) ? std::max(a.max, hi) : hi;
      }
      a.points_min = std::min(a.points_min, f->count);
      a.points_max = std::max(a.points_max, f->count);
      a.units.insert(f->axes[0].units);
      std::string ord = f->axes[1].units;
      if (f->axes[2].specific_data_type != 0 || f->axes[2].units != "NONE") ord += " / " + f->axes[2].units;
      a.ordinate_units.insert(ord);
    } else if (const auto* n15 = std::get_if<uff::Nodes15>(&d.body)) {
      for (const auto& n : n15->nodes) s.geometry_nodes.insert(n.label);
    } else if (const auto* n2411 = std::get_if<uff::Nodes2411>(&d.body)) {
      for (const auto& n : n2411->nodes) s.geometry_nodes.insert(n.label);
    } else if (const auto* a55 = std::get_if<uff::Data55>(&d.body)) {
      if (a55->analysis_type == 2 || a55->analysis_type == 3 || a55->analysis_type == 7) ++s.modes;
      for (const auto& nv : a55->nodes) s.shape_nodes.insert(nv.node);
    } else if (const auto* raw2414 = std::get_if<uff::RawDataset>(&d.body); raw2414 && d.number == 2414) {
      // FE results: a mode when it decodes as data at nodes of a modal analysis (as read_modes
      // and ema correlate read it).
      uff::Data55 as55;
      try {
        if (uff::Decode2414AsData55(*raw2414, path.string() + ":" + std::to_string(d.line), &as55)) {
          ++s.modes;
          for (const auto& nv : as55.nodes) s.shape_nodes.insert(nv.node);
        }
      } catch (const InputError&) {
        // counted only when readable; `ema correlate` names the problem
      }
    } else if (const auto* raw = std::get_if<uff::RawDataset>(&d.body); raw && d.number == 2412) {
      for (const auto& e : uff::DecodeElements2412(*raw, path.string(), d.line).elements) {
        ++s.elements;
        ++s.element_descriptors[e.fe_descriptor];
      }
    } else if (const auto* u = std::get_if<uff::Units164>(&d.body)) {
      s.units.push_back(u->description + " (code " + std::to_string(u->code) + ")");
    }
  }
  for (const auto& n : reader.FileNotes()) AddNote(&notes, n);
  if (s.units.empty() && !s.geometry_nodes.empty())
    AddNote(&notes, "no units dataset (164): lengths are taken as metres (geometry written in mm would read 1000x "
                    "too large; a 164 dataset or SI geometry says so)");
  for (const auto& [n, count] : notes) s.notes.push_back(count > 1 ? n + " (x" + std::to_string(count) + ")" : n);
  return s;
}

namespace {

std::string NodeList(const std::set<std::int64_t>& nodes) {
  // Compact ranges: 1-5, 7, 9-12.
  std::string out;
  auto it = nodes.begin();
  int shown = 0;
  while (it != nodes.end()) {
    std::int64_t a = *it, b = a;
    auto jt = std::next(it);
    while (jt != nodes.end() && *jt == b + 1) b = *jt++;
    if (!out.empty()) out += ", ";
    out += a == b ? std::to_string(a) : std::to_string(a) + "-" + std::to_string(b);
    it = jt;
    if (++shown == 20 && it != nodes.end()) {
      out += ", ...";
      break;
    }
  }
  return out;
}

std::string DofSummary(const std::set<std::pair<std::int64_t, int>>& dofs) {
  std::set<std::int64_t> nodes;
  std::set<int> dirs;
  for (const auto& [n, d] : dofs) {
    nodes.insert(n);
    dirs.insert(d);
  }
  std::string d;
  for (int x : dirs) {
    if (!d.empty()) d += ' ';
    d += DirName(x);
  }
  return std::to_string(dofs.size()) + " DOFs at " + std::to_string(nodes.size()) + " nodes (" + NodeList(nodes) +
         "), directions " + d;
}

}  // namespace

std::string SummaryText(const FileSummary& s) {
  std::ostringstream out;
  out << s.file << ": "
      << (s.format == "uff" ? "UFF" : s.format == "csv" ? "CSV time data" : "folder of FRF tables (as ema fit reads it)")
      << ", " << s.bytes << " bytes\n";
  if (s.format == "uff") {
    out << "datasets:";
    for (const auto& [n, c] : s.datasets) out << " " << n << " x" << c;
    if (s.binary58 > 0) out << " (" << s.binary58 << " of the 58 binary 58b)";
    out << "\n";
  }
  out << "records: " << s.records << "\n";
  for (const auto& [t, c] : s.function_types) {
    out << "  function type " << t << " (" << FunctionTypeName(t) << "): " << c;
    const auto it = s.abscissa.find(t);
    if (it != s.abscissa.end()) {
      const auto& a = it->second;
      std::string units;
      for (const auto& u : a.units) units += (units.empty() ? "" : ", ") + u;
      if (std::isfinite(a.min))
        out << ", abscissa " << Number(a.min) << " .. " << Number(a.max) << " " << units;
      else
        out << ", uneven abscissa (" << units << ")";
      out << ", " << a.points_min;
      if (a.points_max != a.points_min) out << ".." << a.points_max;
      out << " points";
      std::string ord;
      for (const auto& u : a.ordinate_units) ord += (ord.empty() ? "" : ", ") + u;
      if (!ord.empty()) out << ", ordinate units " << ord;
    }
    out << "\n";
  }
  if (!s.response_dofs.empty()) out << "responses: " << DofSummary(s.response_dofs) << "\n";
  if (!s.reference_dofs.empty()) out << "references: " << DofSummary(s.reference_dofs) << "\n";
  if (!s.geometry_nodes.empty())
    out << "geometry: " << s.geometry_nodes.size() << " nodes (" << NodeList(s.geometry_nodes) << ")\n";
  if (s.modes > 0 || !s.shape_nodes.empty())
    out << "mode shapes: " << s.modes << " modes at " << s.shape_nodes.size() << " nodes\n";
  if (s.elements > 0) {
    out << "elements: " << s.elements << " (FE descriptor";
    for (const auto& [descriptor, count] : s.element_descriptors) out << " " << descriptor << " x" << count;
    out << ")\n";
  }
  for (const auto& u : s.units) out << "units: " << u << "\n";
  for (const auto& n : s.notes) out << "note: " << n << "\n";
  return out.str();
}

}  // namespace ema::formats
