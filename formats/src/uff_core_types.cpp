// UFF datasets <-> core vocabulary types (docs/formats.md): time records (58, type 1), FRF sets
// (58, types 4 and 6) and mode sets (55 with 15/2411/2414 geometry and results). The entry points
// of ema/formats/io.hpp; time data that is not UFF goes on to csv.cpp or mat.cpp, FRFs that are
// not UFF to frf_table.cpp.
#include "ema/formats/io.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <ctime>
#include <map>
#include <set>
#include <sstream>

#include <Eigen/Geometry>

#include "ema/core/error.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/uff.hpp"
#include "io_internal.hpp"

namespace ema::formats {

namespace {

using uff::Dataset;
using uff::Function58;

std::string OriginOf(const std::filesystem::path& path, int index, const Dataset& d) {
  return path.filename().string() + ", dataset 58 #" + std::to_string(index) + " (line " + std::to_string(d.line) + ")";
}

Quantity QuantityOf(int specific_data_type) {
  switch (specific_data_type) {
    case 8: return Quantity::kDisplacement;
    case 11: return Quantity::kVelocity;
    case 12: return Quantity::kAcceleration;
    case 13: return Quantity::kForce;
    default: return Quantity::kUnknown;
  }
}

std::string UnitsOf(const uff::Axis58& a) { return a.units == "NONE" ? std::string() : a.units; }

/// Standard (length, force) exponents of table 12.5 for a translational DOF.
std::pair<int, int> ExponentsOf(Quantity q) {
  switch (q) {
    case Quantity::kDisplacement:
    case Quantity::kVelocity:
    case Quantity::kAcceleration: return {1, 0};
    case Quantity::kForce: return {0, 1};
    default: return {0, 0};
  }
}

const char* LabelOf(Quantity q) {
  switch (q) {
    case Quantity::kDisplacement: return "Displacement";
    case Quantity::kVelocity: return "Velocity";
    case Quantity::kAcceleration: return "Acceleration";
    case Quantity::kForce: return "Force";
    default: return "NONE";
  }
}

/// E13.5 stores 6 significant digits, so dt = 1/51200 comes back as 1.95313E-05. Snap the
/// increment to 1/round(1/dx) when that is within the printed precision (spec §2.3).
double SnapIncrement(double dx) {
  if (!(dx > 0.0)) return dx;
  const double rate = 1.0 / dx;
  const double r = std::round(rate);
  if (r >= 1.0 && std::abs(rate - r) <= 5e-6 * rate) return 1.0 / r;
  return dx;
}

std::string Today() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  static const char* kMonths[] = {"Jan", "Feb", "Mar", "Apr", "May", "Jun", "Jul", "Aug", "Sep", "Oct", "Nov", "Dec"};
  char buf[32];
  std::snprintf(buf, sizeof buf, "%02d-%s-%02d %02d:%02d:%02d", tm.tm_mday, kMonths[tm.tm_mon], tm.tm_year % 100,
                tm.tm_hour, tm.tm_min, tm.tm_sec);
  return buf;
}

/// "file:LINE" of record `record` of an ASCII dataset that starts (its "-1" line) on `dataset_line`:
/// the dataset number follows the delimiter, record 1 the number.
std::string RecordWhere(const std::filesystem::path& path, std::int64_t dataset_line, int record) {
  return path.string() + ":" + std::to_string(dataset_line + 1 + record);
}

/// "key=value" pairs from an ID line that starts with "ema " (our own metadata).
std::map<std::string, std::string> EmaKeys(const std::string& id) {
  std::map<std::string, std::string> out;
  if (id.rfind("ema ", 0) != 0) return out;
  std::istringstream in(id.substr(4));
  std::string tok;
  while (in >> tok) {
    const auto eq = tok.find('=');
    if (eq != std::string::npos) out[tok.substr(0, eq)] = tok.substr(eq + 1);
  }
  return out;
}

std::string Repr(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

bool GetDouble(const std::map<std::string, std::string>& keys, const std::string& k, double* v) {
  const auto it = keys.find(k);
  return it != keys.end() && uff::ParseReal(it->second, v);
}

}  // namespace

// ------------------------------------------------------------------------------------------
// Time records

std::vector<TimeRecord> ReadTimeRecords(const std::filesystem::path& path) {
  if (!uff::LooksLikeUff(path)) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) throw InputError(path.string(), "no such file");
    if (std::filesystem::file_size(path, ec) == 0) throw InputError(path.string(), "empty file");
    if (LooksLikeMat(path)) return ReadMatTimeRecords(path);
    return ReadCsvTimeRecords(path);
  }
  uff::Reader reader(path);
  Dataset d;
  std::vector<TimeRecord> out;
  std::vector<std::int64_t> load_cases, versions;
  int index = 0;
  while (reader.Next(&d)) {
    if (d.number != 58) continue;
    ++index;
    auto& f = std::get<Function58>(d.body);
    if (f.function_type != 1) continue;
    uff::ApplyEntityNameDofs(&f);
    const std::string where = path.string() + ":" + std::to_string(d.line);
    if (f.IsComplex()) throw InputError(RecordWhere(path, d.line, 7), "dataset 58 record 7 field 1: a time record must be real (type 2 or 4)");
    if (f.count < 2) throw InputError(RecordWhere(path, d.line, 7), "dataset 58 record 7 field 2: a time record needs at least 2 samples");
    TimeRecord r;
    r.channel = {static_cast<int>(f.response_node), f.response_direction};
    r.reference = {static_cast<int>(f.reference_node), f.reference_direction};
    r.impact = static_cast<int>(f.load_case);
    r.quantity = QuantityOf(f.axes[1].specific_data_type);
    if (f.even) {
      r.sample_interval_s = SnapIncrement(f.dx);
      r.start_time_s = f.x_min;
    } else {
      // Uneven storage of a uniform grid: accept when the abscissa is uniform to its precision.
      const double dt = (f.x.back() - f.x.front()) / static_cast<double>(f.count - 1);
      for (std::int64_t i = 0; i < f.count; ++i)
        if (std::abs(f.x[i] - (f.x.front() + dt * i)) > 1e-3 * dt)
          throw InputError(RecordWhere(path, d.line, 12), "dataset 58 record 12: time abscissa is not uniformly spaced (point " +
                                      std::to_string(i + 1) + ")");
      r.sample_interval_s = SnapIncrement(dt);
      r.start_time_s = f.x.front();
    }
    if (!(r.sample_interval_s > 0.0))
      throw InputError(RecordWhere(path, d.line, 7), "dataset 58 record 7 field 5: sample interval must be > 0");
    r.samples = f.y;
    r.unit = UnitsOf(f.axes[1]);
    r.origin = OriginOf(path, index, d);
    load_cases.push_back(f.load_case);
    versions.push_back(f.version);
    out.push_back(std::move(r));
  }
  if (out.empty()) throw InputError(path.string(), "no time records (dataset 58 with function type 1) in the file");

  // Impact grouping (docs/formats.md): load case ids when they differ; else sequence numbers
  // (record 6 field 3) when they differ; else file order, a new impact at each force record of
  // a hammer point.
  const auto distinct = [](const std::vector<std::int64_t>& v) { return std::set<std::int64_t>(v.begin(), v.end()).size() > 1; };
  if (!distinct(load_cases)) {
    if (distinct(versions)) {
      for (size_t i = 0; i < out.size(); ++i) out[i].impact = static_cast<int>(versions[i]);
    } else {
      std::map<Dof, int> counter;  // per hammer point
      int current = 0;
      Dof current_ref;
      for (auto& r : out) {
        if (r.quantity == Quantity::kForce) {
          const Dof ref = r.reference.node != 0 ? r.reference : r.channel;
          current = ++counter[ref];
          current_ref = ref;
        }
        r.impact = std::max(current, 1);
      }
    }
  }
  // Records without a reference DOF take the DOF of the force record of their impact.
  std::map<int, Dof> force_of_impact;
  for (const auto& r : out)
    if (r.quantity == Quantity::kForce && r.reference.node == 0) force_of_impact.emplace(r.impact, r.channel);
  for (auto& r : out)
    if (r.reference.node == 0) {
      const auto it = force_of_impact.find(r.impact);
      if (it != force_of_impact.end()) r.reference = it->second;
    }
  return out;
}

void WriteTimeRecords(const std::filesystem::path& path, const std::vector<TimeRecord>& records,
                      const WriteOptions& options) {
  std::vector<Dataset> out;
  int id = 0;
  for (const auto& r : records) {
    Function58 f;
    f.id[0] = "ema time record " + DofName(r.channel);
    f.id[1] = "impact " + std::to_string(r.impact) + " at " + DofName(r.reference);
    f.id[2] = Today();
    f.id[3] = "NONE";
    f.id[4] = std::isfinite(r.full_scale) ? "ema full_scale=" + Repr(r.full_scale) : "NONE";
    f.function_type = 1;
    f.function_id = ++id;
    f.load_case = r.impact;
    f.response_node = r.channel.node;
    f.response_direction = r.channel.direction;
    f.reference_node = r.reference.node;
    f.reference_direction = r.reference.direction;
    f.ordinate_type = 4;
    f.count = static_cast<std::int64_t>(r.samples.size());
    f.even = true;
    f.x_min = r.start_time_s;
    f.dx = r.sample_interval_s;
    f.axes[0] = {17, 0, 0, 0, "Time", "s"};
    const auto [l, fe] = ExponentsOf(r.quantity);
    f.axes[1] = {static_cast<int>(r.quantity), l, fe, 0, LabelOf(r.quantity), r.unit.empty() ? "NONE" : r.unit};
    f.axes[2] = {0, 0, 0, 0, "NONE", "NONE"};
    f.axes[3] = {0, 0, 0, 0, "NONE", "NONE"};
    f.y = r.samples;
    out.push_back(Dataset{58, 0, 0, {}, std::move(f)});
  }
  uff::WriteFile(path, out, {options.binary});
}

// ------------------------------------------------------------------------------------------
// FRFs

FrfSet ReadFrfSet(const std::filesystem::path& path) {
  if (std::filesystem::is_directory(path)) return ReadFrfTable(path);
  if (!uff::LooksLikeUff(path)) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) throw InputError(path.string(), "no such file");
    if (std::filesystem::file_size(path, ec) == 0) throw InputError(path.string(), "empty file");
    return ReadFrfTable(path);
  }
  uff::Reader reader(path);
  Dataset d;
  std::vector<Function58At> frfs, cohs;
  while (reader.Next(&d)) {
    if (d.number != 58) continue;
    auto& f = std::get<Function58>(d.body);
    uff::ApplyEntityNameDofs(&f);
    if (f.function_type == 4) frfs.push_back({std::move(f), d.line});
    else if (f.function_type == 6) cohs.push_back({std::move(f), d.line});
  }
  return FrfSetFromFunctions(path, std::move(frfs), std::move(cohs));
}

FrfSet FrfSetFromFunctions(const std::filesystem::path& path, std::vector<Function58At> frfs,
                           std::vector<Function58At> cohs) {
  using Item = Function58At;
  if (frfs.empty()) throw InputError(path.string(), "no FRFs (dataset 58 with function type 4) in the file");

  FrfSet set;
  // Frequency grid: common increment; the union of the ranges (missing lines are NaN).
  auto grid_of = [&](const Item& it, double* x0, double* dx, std::int64_t* n) {
    const Function58& f = it.f;
    const std::string where = path.string() + ":" + std::to_string(it.line);
    *n = f.count;
    if (f.even) {
      *x0 = f.x_min;
      *dx = f.dx;
    } else {
      *x0 = f.x.empty() ? 0.0 : f.x.front();
      *dx = f.count > 1 ? (f.x.back() - f.x.front()) / static_cast<double>(f.count - 1) : 0.0;
      for (std::int64_t i = 0; i < f.count; ++i)
        if (std::abs(f.x[i] - (*x0 + *dx * i)) > 1e-3 * std::abs(*dx) + 1e-12)
          throw InputError(RecordWhere(path, it.line, 12), "dataset 58 record 12: frequency abscissa is not uniformly spaced (point " +
                                      std::to_string(i + 1) + ")");
    }
    if (f.count > 1 && !(*dx > 0.0)) throw InputError(RecordWhere(path, it.line, 7), "dataset 58 record 7 field 5: frequency increment must be > 0");
  };
  double x0 = 0, dx = 0;
  std::int64_t n = 0;
  grid_of(frfs.front(), &x0, &dx, &n);
  double lo = x0, hi = x0 + dx * static_cast<double>(n - 1);
  for (const auto& it : frfs) {
    double a, b;
    std::int64_t m;
    grid_of(it, &a, &b, &m);
    if (m > 1 && std::abs(b - dx) > 1e-5 * dx)
      throw InputError(RecordWhere(path, it.line, 7),
                       "dataset 58 record 7 field 5: frequency increment " + uff::FormatE(b, 0, 5) +
                           " differs from the first FRF's " + uff::FormatE(dx, 0, 5));
    lo = std::min(lo, a);
    hi = std::max(hi, a + dx * static_cast<double>(m - 1));
    const auto keys = EmaKeys(it.f.id[4]);
    double g0, gl;
    if (GetDouble(keys, "grid_start", &g0) && GetDouble(keys, "grid_lines", &gl) && gl >= 1 && gl < 1e9) {
      lo = std::min(lo, g0);
      hi = std::max(hi, g0 + dx * (gl - 1));
    }
  }
  const std::int64_t lines = n > 1 ? static_cast<std::int64_t>(std::llround((hi - lo) / dx)) + 1 : n;
  set.frequency_hz.resize(lines);
  for (std::int64_t i = 0; i < lines; ++i) set.frequency_hz[i] = lo + dx * static_cast<double>(i);

  auto index_of = [](std::vector<Dof>& v, Dof x) {
    auto it = std::find(v.begin(), v.end(), x);
    if (it != v.end()) return static_cast<int>(it - v.begin());
    v.push_back(x);
    return static_cast<int>(v.size()) - 1;
  };
  for (const auto& it : frfs) {
    index_of(set.outputs, {static_cast<int>(it.f.response_node), it.f.response_direction});
    index_of(set.references, {static_cast<int>(it.f.reference_node), it.f.reference_direction});
  }
  const std::complex<double> nan_c(kNaN, kNaN);
  // Each block filled in place (no temporary to copy). Lines no dataset covers are NaN: filled
  // per column the first time a dataset writes it (outside its range) and, at the end, for the
  // columns none wrote, rather than NaN over the whole set first and the values over that.
  set.h.resize(set.references.size());
  for (Eigen::MatrixXcd& block : set.h) block.resize(lines, set.OutputCount());
  std::vector<char> written(set.references.size() * static_cast<size_t>(set.OutputCount()), 0);
  bool quantity_set = false;
  std::map<std::pair<int, int>, int> averages;
  for (auto& it : frfs) {
    Function58& f = it.f;
    const std::string where = path.string() + ":" + std::to_string(it.line);
    if (!f.IsComplex()) throw InputError(RecordWhere(path, it.line, 7), "dataset 58 record 7 field 1: an FRF must be complex (type 5 or 6)");
    const int o = index_of(set.outputs, {static_cast<int>(f.response_node), f.response_direction});
    const int r = index_of(set.references, {static_cast<int>(f.reference_node), f.reference_direction});
    double a, b;
    std::int64_t m;
    grid_of(it, &a, &b, &m);
    const std::int64_t off = n > 1 ? std::llround((a - lo) / dx) : 0;
    std::complex<double>* column = set.h[r].col(o).data();
    char& seen = written[static_cast<size_t>(r) * set.OutputCount() + o];
    if (!seen) {
      std::fill(column, column + off, nan_c);
      std::fill(column + off + m, column + lines, nan_c);
      seen = 1;
    }
    // y holds re, im pairs: the array layout of std::complex<double> ([complex.numbers]).
    std::copy(f.y.data(), f.y.data() + 2 * m, reinterpret_cast<double*>(column + off));
    const Quantity q = QuantityOf(f.axes[1].specific_data_type);
    if (!quantity_set && q != Quantity::kUnknown && q != Quantity::kForce) {
      set.output_quantity = q;
      quantity_set = true;
      if (!UnitsOf(f.axes[1]).empty()) set.response_unit = UnitsOf(f.axes[1]);
      if (!UnitsOf(f.axes[2]).empty()) set.force_unit = UnitsOf(f.axes[2]);
    }
    const auto keys = EmaKeys(f.id[4]);
    double v;
    if (GetDouble(keys, "averages", &v)) averages[{r, o}] = static_cast<int>(v);
    if (GetDouble(keys, "window_decay", &v)) set.window_decay_rate = v;
    if (GetDouble(keys, "roving_hammer", &v)) set.roving_hammer = v != 0.0;
    // The roving set of the output (ID line 4, "ema set=K"; files of other tools: unknown).
    if (double k; GetDouble(EmaKeys(f.id[3]), "set", &k) && k >= 0.0 && k < 1e6) {
      if (set.output_sets.size() < set.outputs.size()) set.output_sets.resize(set.outputs.size(), -1);
      set.output_sets[static_cast<size_t>(o)] = static_cast<int>(k);
    }
    std::vector<double>().swap(f.y);  // copied: its memory serves the next stage, not a second copy
  }
  for (int r = 0; r < set.ReferenceCount(); ++r)
    for (int o = 0; o < set.OutputCount(); ++o)
      if (!written[static_cast<size_t>(r) * set.OutputCount() + o]) set.h[r].col(o).setConstant(nan_c);
  if (!set.output_sets.empty()) {
    set.output_sets.resize(set.outputs.size(), -1);
    // Sets are known for every output or for none.
    if (std::find(set.output_sets.begin(), set.output_sets.end(), -1) != set.output_sets.end()) set.output_sets.clear();
  }
  if (!averages.empty()) {
    set.averages = Eigen::MatrixXi::Zero(set.ReferenceCount(), set.OutputCount());
    for (const auto& [k, v] : averages) set.averages(k.first, k.second) = v;
  }
  if (!cohs.empty()) {
    set.coherence.assign(set.references.size(), Eigen::MatrixXd::Constant(lines, set.OutputCount(), kNaN));
    for (const auto& it : cohs) {
      const Function58& f = it.f;
      const Dof out{static_cast<int>(f.response_node), f.response_direction};
      const Dof ref{static_cast<int>(f.reference_node), f.reference_direction};
      const auto oi = std::find(set.outputs.begin(), set.outputs.end(), out);
      const auto ri = std::find(set.references.begin(), set.references.end(), ref);
      if (oi == set.outputs.end() || ri == set.references.end()) continue;  // coherence without its FRF
      double a, b;
      std::int64_t m;
      grid_of(it, &a, &b, &m);
      const std::int64_t off = n > 1 ? std::llround((a - lo) / dx) : 0;
      if (off < 0 || off + m > lines) continue;
      const size_t k = f.IsComplex() ? 2 : 1;
      for (std::int64_t i = 0; i < m; ++i)
        set.coherence[ri - set.references.begin()](off + i, oi - set.outputs.begin()) = f.y[k * i];
    }
  }
  return set;
}

namespace {

/// First/last finite line of a column; throws if NaN occurs between them.
bool FiniteRange(const Eigen::VectorXcd& col, const std::string& what, Eigen::Index* first, Eigen::Index* last) {
  *first = -1;
  for (Eigen::Index i = 0; i < col.size(); ++i)
    if (std::isfinite(col[i].real()) && std::isfinite(col[i].imag())) {
      if (*first < 0) *first = i;
      *last = i;
    }
  if (*first < 0) return false;
  for (Eigen::Index i = *first; i <= *last; ++i)
    if (!std::isfinite(col[i].real()) || !std::isfinite(col[i].imag()))
      throw InputError("UFF writer", what + ": non-finite value at line " + std::to_string(i) +
                                         " between finite ones (UFF cannot store NaN)");
  return true;
}

}  // namespace

void WriteFrfSet(const std::filesystem::path& path, const FrfSet& frfs, const WriteOptions& options) {
  uff::WriteFile(path, FrfSetDatasets(frfs), {options.binary});
}

std::vector<Dataset> FrfSetDatasets(const FrfSet& frfs) {
  if (frfs.LineCount() < 2) throw InputError("UFF writer", "an FRF set needs at least 2 frequency lines");
  if (static_cast<int>(frfs.h.size()) != frfs.ReferenceCount())
    throw InputError("UFF writer", "FrfSet: one H matrix per reference expected");
  const double dx = frfs.frequency_hz[1] - frfs.frequency_hz[0];
  const auto [l, fe] = ExponentsOf(frfs.output_quantity);
  // What an FRF and its coherence share: the DOFs (record 6) and the frequency axis of lines
  // first..last.
  auto set_dofs_and_axis = [&](int r, int o, Eigen::Index first, Eigen::Index last, Function58* f) {
    f->response_node = frfs.outputs[o].node;
    f->response_direction = frfs.outputs[o].direction;
    f->reference_node = frfs.references[r].node;
    f->reference_direction = frfs.references[r].direction;
    f->count = last - first + 1;
    f->even = true;
    f->x_min = frfs.frequency_hz[first];
    f->dx = dx;
    f->axes[0] = {18, 0, 0, 0, "Frequency", "Hz"};
  };
  std::vector<Dataset> out;
  int id = 0;
  for (int r = 0; r < frfs.ReferenceCount(); ++r) {
    for (int o = 0; o < frfs.OutputCount(); ++o) {
      const std::string what = "FRF " + DofName(frfs.outputs[o]) + "/" + DofName(frfs.references[r]);
      Eigen::Index first, last;
      if (!FiniteRange(frfs.h[r].col(o), what, &first, &last)) continue;  // not measured
      Function58 f;
      f.id[0] = "ema FRF " + DofName(frfs.outputs[o]) + " / " + DofName(frfs.references[r]);
      f.id[1] = "NONE";
      f.id[2] = Today();
      f.id[3] = o < static_cast<int>(frfs.output_sets.size()) && frfs.output_sets[o] >= 0
                    ? "ema set=" + std::to_string(frfs.output_sets[o])
                    : "NONE";
      // Our metadata: FrfSet fields UFF has no place for, and the full grid (lines that are
      // NaN at the ends are not written).
      std::string meta = "ema window_decay=" + Repr(frfs.window_decay_rate) + " roving_hammer=" +
                         (frfs.roving_hammer ? "1" : "0") + " grid_start=" + Repr(frfs.frequency_hz[0]) +
                         " grid_lines=" + std::to_string(frfs.LineCount());
      if (frfs.averages.rows() == frfs.ReferenceCount() && frfs.averages.cols() == frfs.OutputCount())
        meta += " averages=" + std::to_string(frfs.averages(r, o));
      f.id[4] = meta;
      f.function_type = 4;
      f.function_id = ++id;
      f.load_case = 0;
      set_dofs_and_axis(r, o, first, last, &f);
      f.ordinate_type = 6;
      f.axes[1] = {static_cast<int>(frfs.output_quantity), l, fe, 0, LabelOf(frfs.output_quantity), frfs.response_unit};
      f.axes[2] = {13, 0, 1, 0, "Force", frfs.force_unit};
      f.axes[3] = {0, 0, 0, 0, "NONE", "NONE"};
      f.y.resize(static_cast<size_t>(2 * f.count));
      for (Eigen::Index i = first; i <= last; ++i) {
        f.y[2 * (i - first)] = frfs.h[r](i, o).real();
        f.y[2 * (i - first) + 1] = frfs.h[r](i, o).imag();
      }
      out.push_back(Dataset{58, 0, 0, {}, std::move(f)});
      if (static_cast<int>(frfs.coherence.size()) == frfs.ReferenceCount() && frfs.coherence[r].cols() == frfs.OutputCount()) {
        Eigen::VectorXcd c = frfs.coherence[r].col(o).cast<std::complex<double>>();
        Eigen::Index cf, cl;
        if (!FiniteRange(c, "coherence of " + what, &cf, &cl)) continue;
        Function58 g;
        g.id = {"ema coherence " + DofName(frfs.outputs[o]) + " / " + DofName(frfs.references[r]), "NONE", Today(),
                "NONE", "NONE"};
        g.function_type = 6;
        g.function_id = id;
        set_dofs_and_axis(r, o, cf, cl, &g);
        g.ordinate_type = 4;
        g.axes[1] = {1, 0, 0, 0, "Coherence", "NONE"};
        g.axes[2] = {0, 0, 0, 0, "NONE", "NONE"};
        g.axes[3] = {0, 0, 0, 0, "NONE", "NONE"};
        for (Eigen::Index i = cf; i <= cl; ++i) g.y.push_back(frfs.coherence[r](i, o));
        out.push_back(Dataset{58, 0, 0, {}, std::move(g)});
      }
    }
  }
  if (out.empty()) throw InputError("UFF writer", "the FRF set holds no finite FRF to write");
  return out;
}

// ------------------------------------------------------------------------------------------
// Modes

namespace {

// Axes of a Cartesian dataset-18 system (spec §7) as the columns of a rotation matrix, in the
// reference frame: x = Px - O, y = (Pxz - O) x x, z = x x y.
Eigen::Matrix3d LocalAxes18(const uff::CoordinateSystem18& cs) {
  const auto& q = cs.points;
  const Eigen::Vector3d o(q[0], q[1], q[2]);
  const Eigen::Vector3d ex = (Eigen::Vector3d(q[3], q[4], q[5]) - o).normalized();
  const Eigen::Vector3d ey = (Eigen::Vector3d(q[6], q[7], q[8]) - o).cross(ex).normalized();
  Eigen::Matrix3d axes;
  axes << ex, ey, ex.cross(ey);
  return axes;
}

}  // namespace

ModeSet ReadModeSet(const std::filesystem::path& path) {
  if (LooksLikeJson(path)) return ReadModeSetJson(path);  // MODES.json from `ema fit --json` or another tool
  uff::Reader reader(path);
  std::vector<Dataset> datasets;
  for (Dataset d; reader.Next(&d);) datasets.push_back(std::move(d));
  return ModeSetFromDatasets(path, datasets);
}

ModeSet ModeSetFromDatasets(const std::filesystem::path& path, const std::vector<Dataset>& datasets) {
  struct Shape {
    Mode mode;
    std::map<Dof, std::complex<double>> values;
  };
  std::vector<Shape> shapes;
  std::map<int, std::array<double, 3>> nodes;  // id -> position (file units)
  std::map<int, int> node_def_cs, node_disp_cs;
  std::map<int, uff::CoordinateSystem18> systems;
  std::vector<int> node_order;
  double length_factor = 1.0;
  bool units_stated = false;
  for (const Dataset& d : datasets) {
    const std::string where = path.string() + ":" + std::to_string(d.line);
    if (const auto* u = std::get_if<uff::Units164>(&d.body)) length_factor = u->length, units_stated = true;
    if (const auto* n15 = std::get_if<uff::Nodes15>(&d.body)) {
      for (const auto& n : n15->nodes) {
        if (!nodes.count(static_cast<int>(n.label))) node_order.push_back(static_cast<int>(n.label));
        nodes[static_cast<int>(n.label)] = {n.xyz[0] / length_factor, n.xyz[1] / length_factor, n.xyz[2] / length_factor};
        node_def_cs[static_cast<int>(n.label)] = n.definition_cs;
        node_disp_cs[static_cast<int>(n.label)] = n.displacement_cs;
      }
    }
    if (const auto* n2411 = std::get_if<uff::Nodes2411>(&d.body)) {
      for (const auto& n : n2411->nodes) {
        if (!nodes.count(static_cast<int>(n.label))) node_order.push_back(static_cast<int>(n.label));
        nodes[static_cast<int>(n.label)] = {n.xyz[0] / length_factor, n.xyz[1] / length_factor, n.xyz[2] / length_factor};
      }
    }
    if (const auto* cs = std::get_if<uff::CoordinateSystems18>(&d.body))
      for (const auto& s : cs->systems) systems[s.number] = s;
    const auto* a = std::get_if<uff::Data55>(&d.body);
    uff::Data55 from2414;  // FE modes exported as dataset 2414 (Simcenter/NX, Permas ...)
    if (const auto* raw = std::get_if<uff::RawDataset>(&d.body); raw && d.number == 2414)
      if (uff::Decode2414AsData55(*raw, where, &from2414)) a = &from2414;
    if (!a) continue;
    Shape s;
    Mode& m = s.mode;
    if (a->analysis_type == 3 || a->analysis_type == 7) {
      if (a->reals.size() < 2) throw InputError(where, "dataset 55 record 8: complex eigenvalue needs Re and Im");
      std::complex<double> pole(a->reals[0], a->reals[1]);
      if (pole.imag() < 0.0) pole = std::conj(pole);
      m.pole = pole;
      PoleToFrequencyAndDamping(pole, &m.frequency_hz, &m.damping_ratio);
    } else if (a->analysis_type == 2) {
      if (a->reals.empty()) throw InputError(where, "dataset 55 record 8: normal mode needs its frequency");
      m.frequency_hz = a->reals[0];
      // Field 3 is the viscous damping ratio in the SDRC text; some producers write other
      // things there (spec §11.3), so only a plausible ratio is taken.
      m.damping_ratio = a->reals.size() > 2 && a->reals[2] >= 0.0 && a->reals[2] < 1.0 ? a->reals[2] : 0.0;
      m.pole = FrequencyAndDampingToPole(m.frequency_hz, m.damping_ratio);
    } else {
      continue;  // static, transient, ... results are not modes
    }
    // Our metadata: f, zeta, umm on ID line 5; the complexity on ID line 4 (files written before
    // it moved there carry mpc and mpd on line 5, which wins).
    auto keys = EmaKeys(a->id[4]);
    keys.merge(EmaKeys(a->id[3]));
    double v;
    if (GetDouble(keys, "f", &v)) m.frequency_hz = v;
    if (GetDouble(keys, "zeta", &v)) m.damping_ratio = v;
    if (keys.count("f") || keys.count("zeta")) m.pole = FrequencyAndDampingToPole(m.frequency_hz, m.damping_ratio);
    if (GetDouble(keys, "mpc", &v)) m.mpc = v;
    if (GetDouble(keys, "mpd", &v)) m.mpd = v;
    if (GetDouble(keys, "mcf", &v)) m.mcf = v;
    if (GetDouble(keys, "umm", &v)) m.unit_modal_mass = v != 0.0;
    const bool cplx = a->IsComplex();
    int ndirs = a->ndv;
    if (a->data_characteristic != 1 && a->data_characteristic != 2 && a->data_characteristic != 3)
      throw InputError(where, "dataset 55 record 6 field 3: data characteristic " + std::to_string(a->data_characteristic) +
                                  " is not a displacement-like shape (1, 2 or 3 expected)");
    for (const auto& nv : a->nodes) {
      for (int k = 0; k < ndirs; ++k) {
        const std::complex<double> val = cplx ? std::complex<double>(nv.values[2 * k], nv.values[2 * k + 1])
                                              : std::complex<double>(nv.values[k], 0.0);
        const int dir = a->data_characteristic == 1 ? 0 : k + 1;
        s.values[{static_cast<int>(nv.node), dir}] = val;
      }
    }
    if (a->analysis_type != 2 && a->reals.size() >= 2 && a->reals[1] < 0.0)
      for (auto& [k, val] : s.values) val = std::conj(val);
    shapes.push_back(std::move(s));
  }
  if (shapes.empty()) throw InputError(path.string(), "no mode shapes (dataset 55 or 2414 with analysis type 2, 3 or 7) in the file");
  // Shape values are given in each node's displacement coordinate system (dataset 15 field 3);
  // Test.Lab writes one Cartesian CS per node (dataset 18). Rotate them to the global frame so
  // that every ModeSet is global and the MAC compares like with like.
  for (const auto& [node, cs] : node_disp_cs) {
    if (cs == 0) continue;
    const auto it = systems.find(cs);
    if (it == systems.end())
      throw InputError(path.string(), "dataset 15 node " + std::to_string(node) + ": displacement coordinate system " +
                                          std::to_string(cs) + " is not defined by a dataset 18 in the file");
    if (it->second.type != 0)
      throw InputError(path.string(), "dataset 18 coordinate system " + std::to_string(cs) +
                                          ": only Cartesian (type 0) displacement systems are supported");
    const Eigen::Matrix3d axes = LocalAxes18(it->second);  // columns: local x, y, z in global
    for (auto& shape : shapes)
      for (int first : {1, 4}) {  // translations, then rotations
        Eigen::Vector3cd local = Eigen::Vector3cd::Zero();
        bool any = false;
        for (int k = 0; k < 3; ++k) {
          const auto v = shape.values.find({node, first + k});
          if (v != shape.values.end()) local[k] = v->second, any = true;
        }
        if (!any) continue;
        const Eigen::Vector3cd global = axes.cast<std::complex<double>>() * local;
        for (int k = 0; k < 3; ++k) shape.values[{node, first + k}] = global[k];
      }
  }
  ModeSet set;
  set.source = path.filename().string();
  // DOFs: every (node, direction) that is non-zero in at least one mode (unused slots of a
  // 3-DOF record are written as zero, spec §11.1).
  std::set<Dof> used;
  std::vector<int> shape_nodes;
  for (const auto& s : shapes)
    for (const auto& [dof, val] : s.values) {
      if (val != std::complex<double>(0.0, 0.0)) used.insert(dof);
    }
  for (const auto& s : shapes)
    for (const auto& [dof, val] : s.values)
      if (std::find(shape_nodes.begin(), shape_nodes.end(), dof.node) == shape_nodes.end()) shape_nodes.push_back(dof.node);
  for (int node : shape_nodes)
    for (int dir = 0; dir <= 6; ++dir)
      if (used.count({node, dir})) set.dofs.push_back({node, dir});
  for (auto& s : shapes) {
    s.mode.shape = Eigen::VectorXcd::Zero(static_cast<Eigen::Index>(set.dofs.size()));
    for (size_t i = 0; i < set.dofs.size(); ++i) {
      const auto it = s.values.find(set.dofs[i]);
      if (it != s.values.end()) s.mode.shape[static_cast<Eigen::Index>(i)] = it->second;
    }
    set.modes.push_back(std::move(s.mode));
  }
  for (int id : node_order) {
    std::array<double, 3> p = nodes[id];
    const auto cs_it = systems.find(node_def_cs[id]);
    if (node_def_cs[id] != 0 && cs_it != systems.end() && cs_it->second.type == 0) {
      const auto& q = cs_it->second.points;
      const Eigen::Vector3d o(q[0], q[1], q[2]);
      const Eigen::Vector3d g = o / length_factor + LocalAxes18(cs_it->second) * Eigen::Vector3d(p[0], p[1], p[2]);
      p = {g.x(), g.y(), g.z()};
    }
    set.geometry.push_back(Node{id, Eigen::Vector3d(p[0], p[1], p[2])});
  }
  if (!set.geometry.empty() && !units_stated)
    set.geometry_units_note = path.string() + ": no units dataset (164): node coordinates taken as metres";
  return set;
}

void WriteModeSet(const std::filesystem::path& path, const ModeSet& modes, const WriteOptions& options) {
  uff::WriteFile(path, ModeSetDatasets(modes), {options.binary});
}

std::vector<Dataset> ModeSetDatasets(const ModeSet& modes) {
  std::vector<Dataset> out;
  uff::Header151 h;
  h.model_name = modes.source.empty() ? "ema" : modes.source;
  h.description = "mode shapes";
  h.db_program = "ema";
  const std::string now = Today();
  h.db_created_date = h.db_saved_date = h.uff_written_date = now.substr(0, 9);
  h.db_created_time = h.db_saved_time = h.uff_written_time = now.substr(10);
  h.uff_program = "ema";
  out.push_back(Dataset{151, 0, 0, {}, h});
  if (!modes.geometry.empty()) {
    out.push_back(Dataset{164, 0, 0, {}, uff::Units164{}});  // SI: the positions are metres
    uff::Nodes15 n;
    for (const auto& g : modes.geometry) n.nodes.push_back({g.id, 0, 0, 0, {g.position.x(), g.position.y(), g.position.z()}});
    out.push_back(Dataset{15, 0, 0, {}, n});
  }
  bool six = false;
  for (const auto& d : modes.dofs) six = six || std::abs(d.direction) > 3;
  for (const auto& d : modes.dofs)
    if (d.direction == 0 && modes.dofs.size() > 0)
      throw InputError("UFF writer", "mode set DOF " + DofName(d) + ": scalar DOFs cannot be written as 55 shapes");
  std::vector<int> node_order;
  for (const auto& d : modes.dofs)
    if (std::find(node_order.begin(), node_order.end(), d.node) == node_order.end()) node_order.push_back(d.node);
  const int ndv = six ? 6 : 3;
  int k = 0;
  for (const auto& m : modes.modes) {
    ++k;
    if (m.shape.size() != static_cast<Eigen::Index>(modes.dofs.size()))
      throw InputError("UFF writer", "mode " + std::to_string(k) + ": shape length differs from the DOF count");
    uff::Data55 a;
    char f5[160];
    std::snprintf(f5, sizeof f5, "ema f=%.12g zeta=%.12g", m.frequency_hz, m.damping_ratio);
    std::string id5 = f5;
    if (m.unit_modal_mass) id5 += " umm=1";
    // The complexity has its own ID line: beside f and zeta (12 digits each) it would pass the
    // 80 columns of an ID line. 7 digits: the tables print MPC/MCF to 3 decimals, MPD to 0.1 deg.
    std::string id4 = "ema mode=" + std::to_string(k);
    if (std::isfinite(m.mpc)) id4 += " mpc=" + uff::FormatE(m.mpc, 0, 6);
    if (std::isfinite(m.mpd)) id4 += " mpd=" + uff::FormatE(m.mpd, 0, 6);
    if (std::isfinite(m.mcf)) id4 += " mcf=" + uff::FormatE(m.mcf, 0, 6);
    a.id = {"ema mode " + std::to_string(k), modes.source.empty() ? "NONE" : modes.source, now, id4, id5};
    a.model_type = 1;
    a.analysis_type = 3;
    a.data_characteristic = six ? 3 : 2;
    a.specific_data_type = 8;
    a.data_type = 5;
    a.ndv = ndv;
    a.integers = {1, k};
    const std::complex<double> pole = m.pole == std::complex<double>(0.0, 0.0)
                                          ? FrequencyAndDampingToPole(m.frequency_hz, m.damping_ratio)
                                          : m.pole;
    // Modal A = 1 and B = lambda * A, the relation observed in producer files (spec §11.1).
    a.reals = {pole.real(), pole.imag(), 1.0, 0.0, pole.real(), pole.imag()};
    for (int node : node_order) {
      uff::Data55::NodeValues nv;
      nv.node = node;
      nv.values.assign(static_cast<size_t>(2 * ndv), 0.0);
      for (size_t i = 0; i < modes.dofs.size(); ++i) {
        if (modes.dofs[i].node != node) continue;
        const int dir = modes.dofs[i].direction;
        const int slot = std::abs(dir) - 1;
        const std::complex<double> v = dir < 0 ? -m.shape[static_cast<Eigen::Index>(i)] : m.shape[static_cast<Eigen::Index>(i)];
        nv.values[2 * slot] = v.real();
        nv.values[2 * slot + 1] = v.imag();
      }
      a.nodes.push_back(std::move(nv));
    }
    out.push_back(Dataset{55, 0, 0, {}, std::move(a)});
  }
  return out;
}

}  // namespace ema::formats
