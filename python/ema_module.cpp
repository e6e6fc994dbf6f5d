// The `ema` Python module: the library's FRF, fit, correlation, diagnosis and data-quality
// functions on numpy arrays (pybind11). Results are plain dicts of numpy arrays, lists and numbers,
// with the same names and values as the CLI's JSON (python/tests compares them to the last digit).
// Built as `ema._ema`, the compiled core of the `ema` package (python/ema/: __init__.py re-exports
// it, _ema.pyi types it; docs/python.md).
#include <pybind11/complex.h>
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <unistd.h>

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <complex>
#include <cstdlib>
#include <filesystem>
#include <future>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <pthread.h>
#include <set>
#include <signal.h>
#include <string>
#include <type_traits>
#include <vector>

#include "ema/acquisition/hammer_measurement.hpp"
#include "ema/core/error.hpp"
#include "ema/core/progress.hpp"
#include "ema/correlation/correlate.hpp"
#include "ema/correlation/mac.hpp"
#include "ema/curvefit/complexity.hpp"
#include "ema/curvefit/fit.hpp"
#include "ema/curvefit/mode_indicators.hpp"
#include "ema/diagnose/diagnose.hpp"
#include "ema/formats/diagnosis_readings.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/json_codecs.hpp"
#include "ema/formats/uff.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/formats/modes_sidecar.hpp"
#include "ema/formats/output_guard.hpp"
#include "ema/formats/plan_file.hpp"
#include "ema/formats/plan_json.hpp"
#include "ema/formats/quality_json.hpp"
#include "ema/frf/hammer_frf.hpp"
#include "ema/frf/quality.hpp"
#include "ema/model/effects.hpp"
#include "ema/model/solve.hpp"
#include "ema/formats/project_file.hpp"
#include "ema/pipeline/json.hpp"
#include "ema/pipeline/run.hpp"
#include "ema/pipeline/stages.hpp"
#include "ema/planning/plan.hpp"

#ifndef EMA_VERSION
#define EMA_VERSION "unknown"
#endif

namespace py = pybind11;

namespace {

using ema::Dof;
using ema::FrfSet;
using ema::ModeSet;

py::array_t<double> Vec(const Eigen::VectorXd& v) {
  py::array_t<double> a(v.size());
  std::copy(v.data(), v.data() + v.size(), a.mutable_data());
  return a;
}

py::array_t<double> Vec(const std::vector<double>& v) {
  py::array_t<double> a(v.size());
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

/// Row-major numpy copy of an Eigen matrix.
template <class Matrix>
py::array_t<typename Matrix::Scalar> Mat(const Matrix& m) {
  py::array_t<typename Matrix::Scalar> a({m.rows(), m.cols()});
  auto r = a.template mutable_unchecked<2>();
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j) r(i, j) = m(i, j);
  return a;
}

py::tuple DofTuple(const Dof& d) { return py::make_tuple(d.node, ema::DirectionName(d.direction)); }

py::list DofList(const std::vector<Dof>& dofs) {
  py::list out;
  for (const auto& d : dofs) out.append(DofTuple(d));
  return out;
}

// A direction code is ±1..±6 (X, Y, Z, RX, RY, RZ); anything else is refused with the DOF's text.
int CheckedDirection(int dir, const std::string& what) {
  if (dir == 0 || dir < -6 || dir > 6)
    throw py::value_error(what + ": unknown direction (expected one of +X +Y +Z +RX +RY +RZ, with + or -)");
  return dir;
}

Dof ToDof(const py::handle& h) {
  if (py::isinstance<py::str>(h)) {
    const std::string t = h.cast<std::string>();
    const auto split = t.find_first_of("+-", 1);
    if (split == std::string::npos) throw py::value_error("DOF '" + t + "': expected e.g. '1+Z'");
    const int dir = CheckedDirection(ema::ParseDirection(t.substr(split)), "DOF '" + t + "'");
    int node = 0;
    try {
      size_t used = 0;
      node = std::stoi(t.substr(0, split), &used);
      if (used != split) throw std::invalid_argument(t);
    } catch (const std::exception&) {
      throw py::value_error("DOF '" + t + "': expected a node number before the direction, e.g. '1+Z'");
    }
    return {node, dir};
  }
  if (!py::isinstance<py::sequence>(h))
    throw py::type_error("DOF: expected '1+Z' or (node, '+Z'), got " + std::string(py::str(py::type::of(h).attr("__name__"))));
  const auto t = h.cast<py::sequence>();
  if (t.size() != 2) throw py::value_error("DOF: expected (node, '+Z')");
  if (!py::isinstance<py::int_>(t[0])) throw py::type_error("DOF: the node must be an int, as in (101, '+Z')");
  const std::string what = "DOF (" + std::string(py::str(t[0])) + ", " + std::string(py::repr(t[1])) + ")";
  int dir = 0;
  if (py::isinstance<py::str>(t[1])) dir = ema::ParseDirection(t[1].cast<std::string>());
  else if (py::isinstance<py::int_>(t[1])) dir = t[1].cast<int>();
  else throw py::type_error(what + ": the direction must be '+Z' or a code ±1..±6");
  return {t[0].cast<int>(), CheckedDirection(dir, what)};
}

std::string QuantityName(ema::Quantity q) {
  switch (q) {
    case ema::Quantity::kDisplacement: return "displacement";
    case ema::Quantity::kVelocity: return "velocity";
    default: return "acceleration";
  }
}

py::dict FrfDict(const FrfSet& s) {
  const py::ssize_t nr = s.ReferenceCount(), nl = s.LineCount(), no = s.OutputCount();
  py::array_t<std::complex<double>> h({nr, nl, no});
  auto hr = h.mutable_unchecked<3>();
  for (py::ssize_t r = 0; r < nr; ++r)
    for (py::ssize_t k = 0; k < nl; ++k)
      for (py::ssize_t o = 0; o < no; ++o) hr(r, k, o) = s.h[r](k, o);
  py::dict d;
  d["frequency_hz"] = Vec(s.frequency_hz);
  d["outputs"] = DofList(s.outputs);
  d["references"] = DofList(s.references);
  d["h"] = h;
  if (static_cast<py::ssize_t>(s.coherence.size()) == nr && nr > 0) {
    py::array_t<double> c({nr, nl, no});
    auto cr = c.mutable_unchecked<3>();
    for (py::ssize_t r = 0; r < nr; ++r)
      for (py::ssize_t k = 0; k < nl; ++k)
        for (py::ssize_t o = 0; o < no; ++o) cr(r, k, o) = s.coherence[r](k, o);
    d["coherence"] = c;
  } else {
    d["coherence"] = py::none();
  }
  d["averages"] = s.averages.size() ? py::object(Mat(s.averages)) : py::object(py::none());
  d["quantity"] = QuantityName(s.output_quantity);
  d["roving_hammer"] = s.roving_hammer;
  d["window_decay_rate"] = s.window_decay_rate;
  // Per output, the roving set it was measured in (empty when unknown): ema.fit gives each set its
  // own poles and reports the sets, which diagnose(..., sensor_mass=...) needs.
  d["output_sets"] = s.output_sets;
  return d;
}

/// A path (UFF 58 or FRF table) or a dict as FrfDict makes.
FrfSet ToFrfSet(const py::object& o) {
  if (py::isinstance<py::str>(o) || py::hasattr(o, "__fspath__"))
    return ema::formats::ReadFrfSet(py::str(o).cast<std::string>());
  const auto d = o.cast<py::dict>();
  FrfSet s;
  const auto f = py::array_t<double, py::array::c_style | py::array::forcecast>(d["frequency_hz"]);
  s.frequency_hz = Eigen::Map<const Eigen::VectorXd>(f.data(), f.size());
  for (auto h : d["outputs"].cast<py::sequence>()) s.outputs.push_back(ToDof(h));
  for (auto h : d["references"].cast<py::sequence>()) s.references.push_back(ToDof(h));
  // Complex FRFs only: a real array (magnitudes, or real parts alone) would be taken as FRFs with
  // no phase and fit to nonsense without a word.
  if (!d.contains("h")) throw py::value_error("frfs: expected a dict with 'h' (complex, references × lines × outputs)");
  {
    const py::array raw = py::array::ensure(d["h"]);
    if (!raw || raw.dtype().kind() != 'c')
      throw py::type_error("frfs['h']: expected a complex array (references, lines, outputs), got dtype " +
                           (raw ? std::string(py::str(raw.dtype())) : std::string("none")));
  }
  const auto h = py::array_t<std::complex<double>, py::array::c_style | py::array::forcecast>(d["h"]);
  if (h.ndim() != 3 || h.shape(0) != s.ReferenceCount() || h.shape(1) != s.LineCount() || h.shape(2) != s.OutputCount())
    throw py::value_error("frfs['h']: expected shape (references, lines, outputs)");
  auto hr = h.unchecked<3>();
  for (int r = 0; r < s.ReferenceCount(); ++r) {
    Eigen::MatrixXcd m(s.LineCount(), s.OutputCount());
    for (int k = 0; k < s.LineCount(); ++k)
      for (int o = 0; o < s.OutputCount(); ++o) m(k, o) = hr(r, k, o);
    s.h.push_back(std::move(m));
  }
  if (d.contains("coherence") && !d["coherence"].is_none()) {
    const auto c = py::array_t<double, py::array::c_style | py::array::forcecast>(d["coherence"]);
    if (c.ndim() != 3 || c.shape(0) != h.shape(0) || c.shape(1) != h.shape(1) || c.shape(2) != h.shape(2))
      throw py::value_error("frfs['coherence']: expected the shape of frfs['h']");
    auto cr = c.unchecked<3>();
    for (int r = 0; r < s.ReferenceCount(); ++r) {
      Eigen::MatrixXd m(s.LineCount(), s.OutputCount());
      for (int k = 0; k < s.LineCount(); ++k)
        for (int o = 0; o < s.OutputCount(); ++o) m(k, o) = cr(r, k, o);
      s.coherence.push_back(std::move(m));
    }
  }
  if (d.contains("averages") && !d["averages"].is_none()) {
    const auto a = py::array_t<int, py::array::c_style | py::array::forcecast>(d["averages"]);
    if (a.ndim() != 2 || a.shape(0) != s.ReferenceCount() || a.shape(1) != s.OutputCount())
      throw py::value_error("frfs['averages']: expected shape (references, outputs)");
    s.averages.resize(s.ReferenceCount(), s.OutputCount());
    auto ar = a.unchecked<2>();
    for (int r = 0; r < s.ReferenceCount(); ++r)
      for (int o = 0; o < s.OutputCount(); ++o) s.averages(r, o) = ar(r, o);
  }
  if (d.contains("quantity")) {
    const std::string q = d["quantity"].cast<std::string>();
    s.output_quantity = q == "displacement" ? ema::Quantity::kDisplacement
                        : q == "velocity"   ? ema::Quantity::kVelocity
                                            : ema::Quantity::kAcceleration;
  }
  if (d.contains("roving_hammer")) s.roving_hammer = d["roving_hammer"].cast<bool>();
  if (d.contains("window_decay_rate")) s.window_decay_rate = d["window_decay_rate"].cast<double>();
  if (d.contains("output_sets") && !d["output_sets"].is_none()) {
    s.output_sets = d["output_sets"].cast<std::vector<int>>();
    if (!s.output_sets.empty() && s.output_sets.size() != s.outputs.size())
      throw py::value_error("frfs['output_sets']: expected one roving-set number per output (" +
                            std::to_string(s.outputs.size()) + "), got " + std::to_string(s.output_sets.size()));
  }
  return s;
}

py::dict ModesDict(const ModeSet& set) {
  const size_t n = set.modes.size();
  std::vector<double> f(n), z(n), mpc(n), mpd(n), mcf(n), f_std(n), z_std(n);
  Eigen::MatrixXcd shapes(static_cast<Eigen::Index>(set.dofs.size()), static_cast<Eigen::Index>(n));
  py::array_t<std::complex<double>> poles(n);
  for (size_t r = 0; r < n; ++r) {
    const auto& m = set.modes[r];
    f[r] = m.frequency_hz;
    z[r] = m.damping_ratio;
    mpc[r] = m.mpc;
    mpd[r] = m.mpd;
    mcf[r] = m.mcf;
    f_std[r] = m.frequency_std_hz;
    z_std[r] = m.damping_ratio_std;
    poles.mutable_data()[r] = m.pole;
    if (m.shape.size() == shapes.rows()) shapes.col(static_cast<Eigen::Index>(r)) = m.shape;
  }
  py::dict d;
  d["frequency_hz"] = Vec(f);
  d["damping_ratio"] = Vec(z);
  d["frequency_std_hz"] = Vec(f_std);
  d["damping_ratio_std"] = Vec(z_std);
  d["pole"] = poles;
  d["mpc"] = Vec(mpc);
  d["mpd_deg"] = Vec(mpd);
  d["mcf"] = Vec(mcf);
  d["dofs"] = DofList(set.dofs);
  d["shapes"] = Mat(shapes);
  py::list geometry;
  for (const auto& node : set.geometry)
    geometry.append(py::make_tuple(node.id, node.position.x(), node.position.y(), node.position.z()));
  d["geometry"] = geometry;
  return d;
}

// ------------------------------------------------------------------------------------------------
// Arguments: paths, mappings, objects.

/// str, bytes or os.PathLike.
bool IsPath(const py::handle& o) {
  return py::isinstance<py::str>(o) || py::isinstance<py::bytes>(o) || py::hasattr(o, "__fspath__");
}

std::string PathOf(const py::handle& o) { return py::module_::import("os").attr("fsdecode")(o).cast<std::string>(); }

bool IsMapping(const py::handle& o) {
  return py::isinstance(o, py::module_::import("collections.abc").attr("Mapping"));
}

std::string TypeName(const py::handle& o) { return py::str(py::type::handle_of(o).attr("__name__")).cast<std::string>(); }

template <class T>
T Cast(const py::handle& o, const std::string& label, const char* expected) {
  try {
    return o.cast<T>();
  } catch (const py::cast_error&) {
    throw py::type_error(label + ": expected " + expected + ", found " + TypeName(o));
  }
}

/// The keys of a dict — or the attributes of any other object (a dataclass, a SimpleNamespace) —
/// that describes a model or a part. A dict with a key outside `keys` is an error, as an unknown
/// key of the model file is.
class Fields {
 public:
  Fields(const py::handle& o, std::string label, std::vector<std::string> keys)
      : o_(py::reinterpret_borrow<py::object>(o)), label_(std::move(label)), keys_(std::move(keys)), mapping_(IsMapping(o)) {
    if (!mapping_) return;
    for (const auto& k : o_.attr("keys")()) {
      const std::string key = py::str(k).cast<std::string>();
      if (std::find(keys_.begin(), keys_.end(), key) != keys_.end()) continue;
      std::string allowed;
      for (const auto& a : keys_) allowed += (allowed.empty() ? "'" : ", '") + a + "'";
      throw ema::InputError(label_, "unknown key '" + key + "'; expected " + allowed);
    }
  }
  /// The value, or None when it is not given.
  py::object Get(const std::string& key) const {
    if (mapping_) return o_.attr("get")(key);
    return py::getattr(o_, key.c_str(), py::none());
  }
  std::string At(const std::string& key) const { return label_ + "['" + key + "']"; }
  const std::string& label() const { return label_; }

 private:
  py::object o_;
  std::string label_;
  std::vector<std::string> keys_;
  bool mapping_;
};

// ------------------------------------------------------------------------------------------------
// Mode sets: a path (UFF 55/2414 or MODES.json), a dict in `ema fit --json`'s layout, or a dict of
// arrays as ModesDict makes.

/// Per-mode numbers of a modes dict (`key`: one per mode), or empty when the key is absent or None.
std::vector<double> OptionalPerMode(const py::dict& d, const char* key, py::ssize_t modes, const std::string& label) {
  if (!d.contains(key) || d[key].is_none()) return {};
  const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>(d[key]);
  if (a.ndim() != 1 || a.size() != modes)
    throw py::value_error(label + "['" + key + "']: expected one value per mode (" + std::to_string(modes) + ")");
  return {a.data(), a.data() + a.size()};
}

/// A dict of arrays (ModesDict's layout): "frequency_hz", "dofs", "shapes"; optionally
/// "damping_ratio", the 1σ "frequency_std_hz" and "damping_ratio_std", "pole", "mpc", "mpd_deg",
/// "mcf", "geometry".
ModeSet ModeSetFromArrays(const py::dict& d, const std::string& label) {
  for (const char* key : {"frequency_hz", "dofs", "shapes"})
    if (!d.contains(key)) throw py::value_error(label + ": missing '" + key + "' (a modes dict as ema.fit returns it)");
  ModeSet set;
  for (auto h : d["dofs"].cast<py::sequence>()) set.dofs.push_back(ToDof(h));
  const auto f = py::array_t<double, py::array::c_style | py::array::forcecast>(d["frequency_hz"]);
  const auto s = py::array_t<std::complex<double>, py::array::c_style | py::array::forcecast>(d["shapes"]);
  if (s.ndim() != 2 || s.shape(0) != static_cast<py::ssize_t>(set.dofs.size()) || s.shape(1) != f.size())
    throw py::value_error(label + "['shapes']: expected shape (dofs, modes)");
  const py::ssize_t n = f.size();
  const std::vector<double> z = OptionalPerMode(d, "damping_ratio", n, label);
  const std::vector<double> f_std = OptionalPerMode(d, "frequency_std_hz", n, label);
  const std::vector<double> z_std = OptionalPerMode(d, "damping_ratio_std", n, label);
  const std::vector<double> mpc = OptionalPerMode(d, "mpc", n, label);
  const std::vector<double> mpd = OptionalPerMode(d, "mpd_deg", n, label);
  const std::vector<double> mcf = OptionalPerMode(d, "mcf", n, label);
  std::vector<std::complex<double>> poles;
  if (d.contains("pole") && !d["pole"].is_none()) {
    const auto p = py::array_t<std::complex<double>, py::array::c_style | py::array::forcecast>(d["pole"]);
    if (p.ndim() != 1 || p.size() != n) throw py::value_error(label + "['pole']: expected one pole per mode");
    poles.assign(p.data(), p.data() + p.size());
  }
  auto sr = s.unchecked<2>();
  for (py::ssize_t r = 0; r < n; ++r) {
    ema::Mode m;
    const auto i = static_cast<size_t>(r);
    m.frequency_hz = f.data()[r];
    m.damping_ratio = z.empty() ? 0.0 : z[i];
    // The fit's own pole when the dict carries it (ema.fit), else the one of (f, ζ).
    m.pole = poles.empty() ? ema::FrequencyAndDampingToPole(m.frequency_hz, m.damping_ratio) : poles[i];
    if (!f_std.empty()) m.frequency_std_hz = f_std[i];
    if (!z_std.empty()) m.damping_ratio_std = z_std[i];
    if (!mpc.empty()) m.mpc = mpc[i];
    if (!mpd.empty()) m.mpd = mpd[i];
    if (!mcf.empty()) m.mcf = mcf[i];
    m.shape.resize(static_cast<Eigen::Index>(set.dofs.size()));
    for (py::ssize_t k = 0; k < s.shape(0); ++k) m.shape[k] = sr(k, r);
    set.modes.push_back(std::move(m));
  }
  if (d.contains("geometry") && !d["geometry"].is_none())
    for (auto g : d["geometry"].cast<py::sequence>()) {
      const auto t = g.cast<py::sequence>();
      if (t.size() != 4) throw py::value_error(label + "['geometry']: expected [(node, x, y, z), ...]");
      set.geometry.push_back({t[0].cast<int>(), {t[1].cast<double>(), t[2].cast<double>(), t[3].cast<double>()}});
    }
  set.source = label;
  return set;
}

/// A dict as strict JSON text (numpy numbers and arrays as plain numbers and lists); InputError
/// naming `label` and `layout` (the layout expected) for what JSON cannot hold.
std::string JsonText(const py::handle& d, const std::string& label, const std::string& layout) {
  const py::module_ json = py::module_::import("json");
  const py::cpp_function plain([](const py::object& o) -> py::object {
    if (py::hasattr(o, "tolist")) return o.attr("tolist")();
    throw py::type_error("a " + TypeName(o) + " is not a number, list or dict");
  });
  try {
    return json.attr("dumps")(d, py::arg("allow_nan") = false, py::arg("default") = plain).cast<std::string>();
  } catch (py::error_already_set& e) {
    if (!e.matches(PyExc_ValueError) && !e.matches(PyExc_TypeError)) throw;
    throw ema::InputError(label, "not in " + layout + " (" + py::str(e.value()).cast<std::string>() +
                                     "); numbers must be finite: None for a value not known");
  }
}

/// A dict in `ema fit --json`'s layout ({"modes": [{"frequency_hz", "frequency_std_hz",
/// "damping_ratio", "shape": [{"node", "dir", "value"}]}]}, model-format.md): read by the reader of
/// MODES.json files itself, so a dict means what the same JSON in a file means to `ema diagnose`
/// and fails with the same messages (naming `label` instead of a file). The roving sets, when the
/// dict lists them ("roving_sets", "reference"), go to *roving_sets / *reference.
ModeSet ModeSetFromJsonLayout(const py::handle& d, const std::string& label, std::vector<std::vector<int>>* roving_sets,
                              Dof* reference) {
  const std::string text = JsonText(d, label, "`ema fit --json`'s layout");
  ModeSet set = ema::formats::ReadModeSetJsonText(text, label);  // its messages name `label`
  if (roving_sets && reference) ema::formats::ReadTestSets(nlohmann::json::parse(text), roving_sets, reference);
  return set;
}

/// True for a dict in `ema fit --json`'s layout: a "modes" list.
bool IsJsonLayout(const py::handle& o) {
  return IsMapping(o) && o.attr("__contains__")("modes").cast<bool>() && !py::isinstance<py::str>(o.attr("get")("modes")) &&
         py::isinstance<py::sequence>(o.attr("get")("modes"));
}

/// A path (UFF 55/2414 or MODES.json), a dict in `ema fit --json`'s layout, or a modes dict of arrays.
ModeSet ToModeSet(const py::object& o, const std::string& label = "modes") {
  if (IsPath(o)) return ema::formats::ReadModeSet(PathOf(o));
  if (IsJsonLayout(o)) return ModeSetFromJsonLayout(o, label, nullptr, nullptr);
  if (!IsMapping(o)) throw py::type_error(label + ": expected a path or a modes dict, found " + TypeName(o));
  return ModeSetFromArrays(py::dict(o), label);
}

std::pair<double, double> Band(const py::object& band) {
  if (band.is_none()) return {0.0, 0.0};
  if (!py::isinstance<py::sequence>(band) || py::isinstance<py::str>(band) || py::len(band) != 2)
    throw py::type_error("band: expected (lo, hi) in Hz or None, got " + std::string(py::repr(band)));
  std::pair<double, double> t;
  try {
    t = band.cast<std::pair<double, double>>();
  } catch (const py::cast_error&) {
    throw py::type_error("band: expected two numbers (lo, hi) in Hz, got " + std::string(py::repr(band)));
  }
  if (!(t.second > t.first) || t.first < 0.0) throw py::value_error("band: expected (lo, hi) with 0 <= lo < hi");
  return t;
}

// ------------------------------------------------------------------------------------------------
// Ctrl-C in a computation whose progress callback the core calls from worker threads (ema.fit,
// ema.estimate_frfs, ema.run). Python runs a signal's handler on the main thread only, and only when that
// thread asks (PyErr_CheckSignals); asked from a worker thread it does nothing. So the computation
// runs on a thread of its own with the GIL released, the asynchronous signals blocked there (and in
// the threads it starts, which inherit the mask: a signal goes to the main thread, and no system
// call of the computation is interrupted by one). The main thread waits for it in slices of 50 ms
// and between two takes the GIL for a moment to ask Python whether a signal is pending. When the
// handler raised (SIGINT: KeyboardInterrupt), the cancel flag goes up: the computation's progress
// callback throws ema::Cancelled at its next step, from whichever thread calls it, the core stops
// its other workers and unwinds (core/parallel.hpp), and once the computation's thread has
// finished the handler's exception is raised here. A computation that ends otherwise returns its
// result or raises its own error as before.

void BlockAsynchronousSignals() {
  sigset_t set;
  sigemptyset(&set);
  for (const int signal : {SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGALRM, SIGUSR1, SIGUSR2, SIGCHLD, SIGWINCH})
    sigaddset(&set, signal);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

/// `compute(progress)` (C++ only: it must not touch a Python object) on a thread of its own, stopped
/// by Ctrl-C as above. Called with the GIL held.
template <class Compute>
auto RunInterruptibly(Compute&& compute) -> std::invoke_result_t<Compute&, const ema::ProgressCallback&> {
  using Result = std::invoke_result_t<Compute&, const ema::ProgressCallback&>;
  ema::CancelFlag cancel;
  const ema::ProgressCallback progress = cancel.Callback();
  std::optional<py::error_already_set> interrupted;
  std::future<Result> done;
  {
    py::gil_scoped_release release;
    done = std::async(std::launch::async, [&]() -> Result {
      BlockAsynchronousSignals();
      return compute(progress);
    });
    // Whatever leaves this block, the computation is stopped and waited for first: it uses
    // `cancel`, `progress` and the caller's inputs.
    struct StopAndWait {
      ema::CancelFlag& cancel;
      std::future<Result>& done;
      ~StopAndWait() {
        if (done.valid() && done.wait_for(std::chrono::seconds(0)) != std::future_status::ready) {
          cancel.Cancel();
          done.wait();
        }
      }
    } stop_and_wait{cancel, done};
    while (done.wait_for(std::chrono::milliseconds(50)) != std::future_status::ready) {
      if (interrupted) continue;  // asked once; now waiting for the computation to unwind
      py::gil_scoped_acquire acquire;
      if (PyErr_CheckSignals() != 0) {
        interrupted.emplace();  // takes the handler's exception (KeyboardInterrupt) off the indicator
        cancel.Cancel();
      }
    }
  }
  if (interrupted) throw *interrupted;
  return done.get();
}

/// nlohmann::json to Python via the json module (plain dict/list/float/None).
py::object FromJson(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

// ------------------------------------------------------------------------------------------------
// Models: a model file, or an FE model built from parts given in Python (model-format.md "FE
// models built from parts"): the same ema::model::Model the model file makes.

using SparseMatrix = Eigen::SparseMatrix<double>;

/// A scipy.sparse matrix or array (anything with .tocoo()) or a dense 2-D array, n × n.
SparseMatrix ToSparse(const py::handle& o, Eigen::Index n, const std::string& label) {
  std::vector<Eigen::Triplet<double>> entries;
  long long rows = 0, cols = 0;
  auto add = [&](long long i, long long j, double v) {
    if (!std::isfinite(v))
      throw ema::InputError(label, "entry [" + std::to_string(i) + ", " + std::to_string(j) + "] is not a finite number");
    if (v != 0.0) entries.emplace_back(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j), v);
  };
  if (py::hasattr(o, "tocoo")) {
    const py::object coo = o.attr("tocoo")();
    const auto shape = Cast<std::pair<long long, long long>>(coo.attr("shape"), label, "a 2-D matrix");
    rows = shape.first, cols = shape.second;
    const auto r = py::array_t<long long, py::array::c_style | py::array::forcecast>(coo.attr("row"));
    const auto c = py::array_t<long long, py::array::c_style | py::array::forcecast>(coo.attr("col"));
    const auto v = py::array_t<double, py::array::c_style | py::array::forcecast>(coo.attr("data"));
    if (rows == n && cols == n) {
      entries.reserve(static_cast<size_t>(v.size()));
      for (py::ssize_t k = 0; k < v.size(); ++k) add(r.data()[k], c.data()[k], v.data()[k]);
    }
  } else {
    const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(o);
    if (!a || a.ndim() != 2)
      throw py::type_error(label + ": expected a scipy.sparse matrix or a 2-D numpy array, found " + TypeName(o));
    rows = a.shape(0), cols = a.shape(1);
    if (rows == n && cols == n) {
      auto ar = a.unchecked<2>();
      for (py::ssize_t i = 0; i < rows; ++i)
        for (py::ssize_t j = 0; j < cols; ++j) add(i, j, ar(i, j));
    }
  }
  if (rows != n || cols != n)
    throw ema::InputError(label, "is " + std::to_string(rows) + "x" + std::to_string(cols) + " but model['dofs'] lists " +
                                     std::to_string(n) + " DOFs: expected a " + std::to_string(n) + "x" + std::to_string(n) +
                                     " matrix in the order of model['dofs']");
  SparseMatrix m(n, n);
  m.setFromTriplets(entries.begin(), entries.end());  // duplicates (COO) add up
  m.makeCompressed();
  return m;
}

/// Mass and stiffness matrices are symmetric: the full matrix, not one triangle.
void RequireSymmetric(const SparseMatrix& a, const std::string& label) {
  double scale = 0.0;
  for (int c = 0; c < a.outerSize(); ++c)
    for (SparseMatrix::InnerIterator it(a, c); it; ++it) scale = std::max(scale, std::abs(it.value()));
  const SparseMatrix difference = a - SparseMatrix(a.transpose());
  for (int c = 0; c < difference.outerSize(); ++c)
    for (SparseMatrix::InnerIterator it(difference, c); it; ++it) {
      if (!(std::abs(it.value()) > 1e-9 * scale)) continue;
      auto i = it.row(), j = it.col();
      if (std::abs(a.coeff(i, j)) < std::abs(a.coeff(j, i))) std::swap(i, j);  // name the entry given
      char text[200];
      std::snprintf(text, sizeof text, "entry [%ld, %ld] = %.6g but [%ld, %ld] = %.6g", static_cast<long>(i),
                    static_cast<long>(j), a.coeff(i, j), static_cast<long>(j), static_cast<long>(i), a.coeff(j, i));
      throw ema::InputError(label, std::string(text) + ": expected a symmetric matrix (the full matrix, not one triangle: "
                                                       "A + A.T - diag(A) makes it from a triangle)");
    }
}

/// A part's matrix is a sum of element matrices, each positive semi-definite
/// (ema::model::FirstNegativePivotRow, as the model file's reader checks [[fe.part]] matrices).
void RequirePositiveSemiDefinite(const SparseMatrix& a, const ema::model::FeMatrices& fe, const std::string& label,
                                 const char* what) {
  const int row = ema::model::FirstNegativePivotRow(a);
  if (row < 0) return;
  static const char* kDofNames[] = {"ux", "uy", "uz", "rx", "ry", "rz"};
  const auto& dof = fe.dofs[static_cast<size_t>(row)];
  throw ema::InputError(label, std::string("the part's ") + what + " is not positive semi-definite (a negative pivot at node " +
                                   std::to_string(dof.node) + " " + kDofNames[std::clamp(dof.dof, 1, 6) - 1] + ", row " +
                                   std::to_string(row) + "): expected the sum of the part's element matrices, which adds " +
                                   "no negative stiffness or mass");
}

int DofCode(const py::handle& h, const std::string& label) {
  static const char* kNames[] = {"ux", "uy", "uz", "rx", "ry", "rz"};
  if (py::isinstance<py::str>(h)) {
    const std::string s = h.cast<std::string>();
    for (int i = 0; i < 6; ++i)
      if (s == kNames[i]) return i + 1;
    throw ema::InputError(label, "dof '" + s + "': expected 1..6 or 'ux', 'uy', 'uz', 'rx', 'ry', 'rz'");
  }
  const int code = Cast<int>(h, label, "a dof 1..6 or 'ux'..'rz'");
  if (code < 1 || code > 6) throw ema::InputError(label, "dof " + std::to_string(code) + ": expected 1..6 (ux uy uz rx ry rz)");
  return code;
}

double Uncertainty(const py::handle& h, const std::string& label) {
  const double v = Cast<double>(h, label, "a number");
  if (!(v > 0.0) || !std::isfinite(v))
    throw ema::InputError(label, "uncertainty must be a relative 1σ > 0 (0.02 = 2 %), found " + std::to_string(v));
  return v;
}

/// A part or part-group name: non-empty, without '/' or '+' (they join targets), and not '*' (what
/// "GROUP/*", any member of a group, would hold).
std::string PartName(const py::handle& h, const std::string& label) {
  const std::string name = Cast<std::string>(h, label, "a name (str)");
  if (name.empty() || name.find('/') != std::string::npos || name.find('+') != std::string::npos || name == "*")
    throw ema::InputError(label, "'" + name + "': expected a non-empty name without '/' or '+', and not '*'");
  return name;
}

/// An FE model given in Python (a dict, or any object with these attributes):
///   dofs      [(node, dof), ...] one per matrix row, dof 1..6 or 'ux'..'rz' (required)
///   mass, stiffness   n × n, scipy.sparse or numpy (optional once parts carry them)
///   parts     [{"name", "group", "stiffness", "mass", "uncertainty"}, ...]
///   nodes     {node: (x, y, z)} or [(node, x, y, z), ...]
///   points    [{"id", "node"}, ...] or [node, ...] (the test point ids are then the node ids)
///   damping   a ratio, a list of ratios per mode, or {"ratio"} / {"ratios"}
///   priors    {effect kind: relative 1σ}
///   name      the model's name
ema::model::Model BuildModel(const py::handle& o) {
  namespace md = ema::model;
  const Fields f(o, "model", {"name", "mass", "stiffness", "dofs", "nodes", "parts", "points", "damping", "priors"});
  md::Model m;
  m.origin = "model";
  if (const py::object name = f.Get("name"); !name.is_none()) m.name = Cast<std::string>(name, f.At("name"), "a str");

  const py::object dofs = f.Get("dofs");
  if (dofs.is_none()) throw ema::InputError("model", "missing 'dofs': [(node, dof), ...], one per matrix row");
  int row = 0;
  for (const auto& d : Cast<py::sequence>(dofs, f.At("dofs"), "a list of (node, dof)")) {
    const std::string at = f.At("dofs") + "[" + std::to_string(row++) + "]";
    const auto pair = Cast<py::sequence>(d, at, "(node, dof)");
    if (pair.size() != 2) throw ema::InputError(at, "expected (node, dof)");
    const int node = Cast<int>(pair[0], at, "an integer node id");
    if (node <= 0) throw ema::InputError(at, "node " + std::to_string(node) + ": expected a positive node id");
    m.fe.dofs.push_back({node, DofCode(pair[1], at)});
  }
  const auto n = static_cast<Eigen::Index>(m.fe.dofs.size());
  if (n == 0) throw ema::InputError(f.At("dofs"), "is empty: expected one (node, dof) per matrix row");
  m.fe.origin = f.At("dofs");

  const py::object mass = f.Get("mass"), stiffness = f.Get("stiffness"), parts = f.Get("parts");
  if (!mass.is_none()) {
    m.fe.mass = ToSparse(mass, n, f.At("mass"));
    RequireSymmetric(m.fe.mass, f.At("mass"));
    m.fe.mass_file = f.At("mass");
  }
  if (!stiffness.is_none()) {
    m.fe.stiffness = ToSparse(stiffness, n, f.At("stiffness"));
    RequireSymmetric(m.fe.stiffness, f.At("stiffness"));
    m.fe.stiffness_file = f.At("stiffness");
  }
  const bool has_parts = !parts.is_none() && py::len(parts) > 0;
  if (!has_parts && (mass.is_none() || stiffness.is_none()))
    throw ema::InputError("model", "expected 'mass' and 'stiffness', or 'parts' that carry them");

  if (has_parts) {
    std::set<std::string> names;
    std::map<std::string, bool> targets;  // group or lone part name -> is a group
    int index = 0;
    for (const auto& p : Cast<py::sequence>(parts, f.At("parts"), "a list of parts")) {
      const Fields pf(p, f.At("parts") + "[" + std::to_string(index++) + "]",
                      {"name", "group", "stiffness", "mass", "uncertainty"});
      md::FePart part;
      const py::object name = pf.Get("name");
      if (name.is_none()) throw ema::InputError(pf.label(), "missing 'name'");
      part.name = PartName(name, pf.At("name"));
      const std::string ctx = pf.label() + " (part '" + part.name + "')";
      if (!names.insert(part.name).second) throw ema::InputError(ctx, "duplicate part name '" + part.name + "'");
      if (const py::object g = pf.Get("group"); !g.is_none()) part.group = PartName(g, pf.At("group"));
      const std::string target = part.group.empty() ? part.name : part.group;
      if (const auto it = targets.find(target); it != targets.end() && (part.group.empty() || !it->second))
        throw ema::InputError(ctx, "name '" + target + "' is already used by another part or part group");
      targets[target] = !part.group.empty();
      for (const char* key : {"stiffness", "mass"}) {
        const py::object a = pf.Get(key);
        if (a.is_none()) continue;
        auto matrix = std::make_shared<const SparseMatrix>(ToSparse(a, n, pf.At(key)));
        RequireSymmetric(*matrix, pf.At(key));
        RequirePositiveSemiDefinite(*matrix, m.fe, pf.At(key), key);
        if (std::string(key) == "stiffness") part.stiffness = matrix, part.stiffness_file = pf.At(key);
        else part.mass = matrix, part.mass_file = pf.At(key);
      }
      if (!part.stiffness && !part.mass)
        throw ema::InputError(ctx, "expected 'stiffness' (and optionally 'mass'): the part's own matrices");
      if (const py::object u = pf.Get("uncertainty"); !u.is_none()) part.uncertainty = Uncertainty(u, pf.At("uncertainty"));
      m.fe.parts.push_back(std::move(part));
    }
  }

  if (const py::object nodes = f.Get("nodes"); !nodes.is_none()) {
    auto position = [&](const py::handle& xyz, const std::string& at) {
      const auto v = Cast<std::vector<double>>(xyz, at, "(x, y, z)");
      if (v.size() != 3) throw ema::InputError(at, "expected (x, y, z)");
      return Eigen::Vector3d(v[0], v[1], v[2]);
    };
    if (IsMapping(nodes)) {
      for (const auto& item : nodes.attr("items")()) {
        const auto kv = item.cast<py::tuple>();
        const int id = Cast<int>(kv[0], f.At("nodes"), "integer node ids as keys");
        m.fe.node_positions[id] = position(kv[1], f.At("nodes") + "[" + std::to_string(id) + "]");
      }
    } else {
      int k = 0;
      for (const auto& e : Cast<py::sequence>(nodes, f.At("nodes"), "{node: (x, y, z)} or [(node, x, y, z), ...]")) {
        const std::string at = f.At("nodes") + "[" + std::to_string(k++) + "]";
        const auto v = Cast<std::vector<double>>(e, at, "(node, x, y, z)");
        if (v.size() != 4) throw ema::InputError(at, "expected (node, x, y, z)");
        m.fe.node_positions[static_cast<int>(v[0])] = {v[1], v[2], v[3]};
      }
    }
  }

  if (const py::object points = f.Get("points"); !points.is_none()) {
    std::set<int> ids;
    int k = 0;
    for (const auto& e : Cast<py::sequence>(points, f.At("points"), "[{'id', 'node'}, ...] or [node, ...]")) {
      const std::string at = f.At("points") + "[" + std::to_string(k++) + "]";
      md::TestPoint p;
      if (py::isinstance<py::int_>(e) || py::hasattr(e, "__index__")) {  // a node id (numpy integers too)
        p.id = p.where.node = e.cast<int>();
      } else {
        const Fields pf(e, at, {"id", "node"});
        if (pf.Get("node").is_none()) throw ema::InputError(at, "missing 'node': the FE node the test point sits on");
        p.where.node = Cast<int>(pf.Get("node"), pf.At("node"), "an integer node id");
        p.id = pf.Get("id").is_none() ? p.where.node : Cast<int>(pf.Get("id"), pf.At("id"), "an integer point id");
      }
      if (p.id <= 0 || p.where.node <= 0) throw ema::InputError(at, "expected a positive point id and node id");
      if (!ids.insert(p.id).second) throw ema::InputError(at, "point id " + std::to_string(p.id) + " appears twice");
      m.points.push_back(p);
    }
  }

  if (const py::object damping = f.Get("damping"); !damping.is_none()) {
    const std::string at = f.At("damping");
    if (IsMapping(damping)) {
      const Fields df(damping, at, {"ratio", "ratios"});
      if (!df.Get("ratio").is_none()) m.damping.ratio = Cast<double>(df.Get("ratio"), df.At("ratio"), "a number");
      if (!df.Get("ratios").is_none())
        m.damping.ratios = Cast<std::vector<double>>(df.Get("ratios"), df.At("ratios"), "a list of numbers");
    } else if (py::isinstance<py::sequence>(damping)) {
      m.damping.ratios = Cast<std::vector<double>>(damping, at, "a list of numbers");
    } else {
      m.damping.ratio = Cast<double>(damping, at, "a damping ratio, a list of them or {'ratio'}/{'ratios'}");
    }
    for (double r : m.damping.ratios)
      if (!(r >= 0.0 && r < 1.0)) throw ema::InputError(at, "ratios must lie in [0, 1) (0.01 = 1 %)");
    if (!(m.damping.ratio >= 0.0 && m.damping.ratio < 1.0)) throw ema::InputError(at, "ratio must lie in [0, 1) (0.01 = 1 %)");
  }

  if (const py::object priors = f.Get("priors"); !priors.is_none()) {
    const auto& kinds = md::EffectKinds();
    std::vector<std::string> keys(kinds.begin(), kinds.end());
    keys.push_back("stiffness_fault_share");  // model-format.md [priors], added turn 4
    keys.push_back("stiffness_fault_width");
    const Fields pf(priors, f.At("priors"), keys);
    for (const md::EffectKindInfo& info : md::EffectKindTable())
      if (const py::object v = pf.Get(info.name); !v.is_none()) m.priors[info.kind] = Uncertainty(v, pf.At(info.name));
    if (const py::object v = pf.Get("stiffness_fault_share"); !v.is_none()) {
      const double share = py::cast<double>(v);
      if (!(share >= 0.0 && share < 1.0)) throw ema::InputError(pf.At("stiffness_fault_share"), "expected a share in [0, 1)");
      m.stiffness_fault_share = share;
    }
    if (const py::object v = pf.Get("stiffness_fault_width"); !v.is_none()) {
      const double width = py::cast<double>(v);
      if (!(width > 0.0 && std::isfinite(width))) throw ema::InputError(pf.At("stiffness_fault_width"), "expected a number > 0");
      m.stiffness_fault_width = width;
    }
  }
  return m;
}

/// A model file path, or an FE model given in Python (BuildModel).
ema::model::Model ToModel(const py::object& o) {
  if (IsPath(o)) return ema::formats::ReadModelFile(PathOf(o));
  return BuildModel(o);
}

/// One setup's test modes for the diagnosis, as `ema diagnose --test SETUP=PATH` reads them: a path
/// (UFF 55 with the σ and roving sets of the `ema fit --json` file beside it, or MODES.json), a
/// dict in `ema fit --json`'s layout, or a modes dict of arrays (ema.fit's; "roving_sets" and
/// "reference" when known).
ema::diagnose::SetupModes ToSetupModes(const std::string& setup, const py::object& o, double sensor_mass) {
  const std::string label = "tests['" + setup + "']";
  ema::diagnose::SetupModes test;
  test.setup = setup;
  test.sensor_mass = sensor_mass;
  if (IsPath(o)) {
    const std::string path = PathOf(o);
    test.modes = ema::formats::ReadModeSet(path);
    if (test.modes.source.empty()) test.modes.source = path;
    ema::formats::AttachSidecarUncertainty(path, &test.modes);
    if (sensor_mass > 0.0) ema::formats::ReadSidecarTestSets(path, test.modes, &test.roving_sets, &test.reference);
  } else if (IsJsonLayout(o)) {
    test.modes = ModeSetFromJsonLayout(o, label, &test.roving_sets, &test.reference);
  } else if (IsMapping(o)) {
    const py::dict d(o);
    test.modes = ModeSetFromArrays(d, label);
    if (d.contains("roving_sets") && !d["roving_sets"].is_none())
      test.roving_sets = Cast<std::vector<std::vector<int>>>(d["roving_sets"], label + "['roving_sets']", "[[node, ...], ...]");
    if (d.contains("reference") && !d["reference"].is_none()) test.reference = ToDof(d["reference"]);
  } else {
    throw py::type_error(label + ": expected a path or a modes dict, found " + TypeName(o));
  }
  return test;
}

// ------------------------------------------------------------------------------------------------
// Test planning (`ema plan`, docs/plan.md).

/// A diagnosis as JSON: a DIAG.json path (read once), or the dict ema.diagnose returns (any mapping
/// in DIAG.json's layout) — then read by the DIAG.json readers themselves, so that it means what
/// the same JSON in a file means to `ema plan --candidates`. *origin: the name messages give it
/// (the path, or "candidates"); *base_dir: where a law's relative curve files resolve (the file's
/// folder, or the working folder).
nlohmann::json DiagnosisJsonOf(const py::object& o, std::string* origin, std::filesystem::path* base_dir) {
  if (IsPath(o)) {
    const std::string path = PathOf(o);
    std::error_code ec;
    if (!std::filesystem::exists(path, ec))
      throw ema::InputError(path, "diagnosis file not found; expected the DIAG.json of `ema diagnose --json`");
    *origin = path;
    *base_dir = std::filesystem::path(path).parent_path();
    return ema::formats::ReadDiagnosisJson(path);
  }
  if (!IsMapping(o))
    throw py::type_error("candidates: expected None, a DIAG.json path or the dict ema.diagnose returns, found " + TypeName(o));
  *origin = "candidates";
  *base_dir = std::filesystem::current_path();
  return nlohmann::json::parse(
      JsonText(py::dict(o), "candidates", "the layout of `ema diagnose --json` (what ema.diagnose returns)"));
}

/// None, or the path `o` names; TypeError naming the argument otherwise.
std::string PathOrNone(const py::object& o, const std::string& name, const std::string& what) {
  if (o.is_none()) return "";
  if (!IsPath(o)) throw py::type_error(name + ": expected None or the path of " + what + ", found " + TypeName(o));
  return PathOf(o);
}

}  // namespace

PYBIND11_MODULE(_ema, m) {
  m.doc() =
      "ema: experimental modal analysis (impact-hammer tests -> FRFs -> PolyMAX modes -> correlation with a\n"
      "model -> which physics the model misses -> data quality -> the next test's plan). The same C++ library\n"
      "as the `ema` command line, on numpy arrays.\n\n"
      "FRF sets are dicts: frequency_hz (n_lines,), outputs/references [(node, '+Z'), ...],\n"
      "h (n_references, n_lines, n_outputs) complex, coherence (same shape) or None, averages\n"
      "(n_references, n_outputs) or None, quantity ('acceleration', 'velocity', 'displacement').\n"
      "Mode sets are dicts: frequency_hz, damping_ratio, frequency_std_hz, damping_ratio_std, pole, mpc,\n"
      "mpd_deg, mcf (n_modes,), dofs [(node, '+Z'), ...], shapes (n_dofs, n_modes) complex, geometry\n"
      "[(id, x, y, z), ...]. Functions that take FRFs or modes accept a file path or such a dict; those\n"
      "that take test modes also accept a dict in `ema fit --json`'s layout (MODES.json:\n"
      "{'modes': [{'frequency_hz', 'frequency_std_hz', 'damping_ratio', 'shape': [{'node', 'dir', 'value'}]}]}).\n"
      "Models are a model file (docs/model.md) or an FE model built from parts in Python: a dict with dofs,\n"
      "mass, stiffness, parts (scipy.sparse or numpy matrices), nodes, points, damping (see model_modes).\n"
      "Bad input raises ema.InputError (a ValueError) naming the file or the argument.";
  m.attr("__version__") = EMA_VERSION;

  py::register_exception<ema::InputError>(m, "InputError", PyExc_ValueError);
  py::register_exception<ema::UsageError>(m, "UsageError", PyExc_ValueError);

  m.def("read_frfs", [](const py::object& path) { return FrfDict(ema::formats::ReadFrfSet(PathOf(path))); }, py::arg("path"),
        "Reads FRFs (UFF 58 function type 4 with coherence type 6, or an FRF table/folder) as an FRF dict.");

  m.def("read_modes", [](const py::object& path) { return ModesDict(ema::formats::ReadModeSet(PathOf(path))); },
        py::arg("path"),
        "Reads mode shapes (UFF 55, FE modes as UFF 2414, or MODES.json in `ema fit --json`'s layout) with\n"
        "their geometry (15/2411) as a modes dict.");

  // Every dataset of a UFF file, as the library reads it (issue 41): the geometry, units, trace
  // lines, mode shapes, functions (time records, FRFs, PSDs, coherences ...) that the typed readers
  // above turn into FRF and mode dicts, here each as its own dict.
  m.def(
      "read_uff",
      [](const py::object& path) {
        if (!IsPath(path)) throw py::type_error("path: expected the path of a UFF file, found " + TypeName(path));
        namespace uff = ema::formats::uff;
        const std::vector<uff::Dataset> datasets = uff::ReadFile(PathOf(path));
        py::list out;
        auto strings = [](const auto& a) {
          py::list l;
          for (const auto& x : a) l.append(ema::formats::JsonText(x));
          return l;
        };
        auto nodes = [](const std::vector<uff::NodeRecord>& records) {
          py::array_t<std::int64_t> label(static_cast<py::ssize_t>(records.size()));
          py::array_t<double> xyz({static_cast<py::ssize_t>(records.size()), py::ssize_t(3)});
          py::array_t<int> cs({static_cast<py::ssize_t>(records.size()), py::ssize_t(2)});
          auto l = label.mutable_unchecked<1>();
          auto x = xyz.mutable_unchecked<2>();
          auto c = cs.mutable_unchecked<2>();
          for (size_t i = 0; i < records.size(); ++i) {
            const auto k = static_cast<py::ssize_t>(i);
            l(k) = records[i].label;
            for (int d = 0; d < 3; ++d) x(k, d) = records[i].xyz[static_cast<size_t>(d)];
            c(k, 0) = records[i].definition_cs, c(k, 1) = records[i].displacement_cs;
          }
          py::dict d;
          d["label"] = label, d["xyz"] = xyz, d["coordinate_systems"] = cs;
          return d;
        };
        for (const uff::Dataset& ds : datasets) {
          py::dict d;
          d["number"] = ds.number;
          d["line"] = ds.line;
          d["notes"] = strings(ds.notes);
          std::visit(
              [&](const auto& b) {
                using T = std::decay_t<decltype(b)>;
                if constexpr (std::is_same_v<T, uff::Header151>) {
                  d["model_name"] = ema::formats::JsonText(b.model_name), d["description"] = ema::formats::JsonText(b.description);
                  d["db_program"] = ema::formats::JsonText(b.db_program), d["uff_program"] = ema::formats::JsonText(b.uff_program);
                } else if constexpr (std::is_same_v<T, uff::Units164>) {
                  d["code"] = b.code, d["description"] = ema::formats::JsonText(b.description);
                  d["length"] = b.length, d["force"] = b.force, d["temperature"] = b.temperature;
                  d["temperature_offset"] = b.temperature_offset, d["temperature_mode"] = b.temperature_mode;
                } else if constexpr (std::is_same_v<T, uff::Nodes15> || std::is_same_v<T, uff::Nodes2411>) {
                  d["nodes"] = nodes(b.nodes);
                } else if constexpr (std::is_same_v<T, uff::CoordinateSystems18>) {
                  py::list l;
                  for (const auto& c : b.systems)
                    l.append(py::dict(py::arg("number") = c.number, py::arg("type") = c.type, py::arg("reference") = c.reference,
                                      py::arg("name") = ema::formats::JsonText(c.name),
                                      py::arg("points") = std::vector<double>(c.points.begin(), c.points.end())));
                  d["systems"] = l;
                } else if constexpr (std::is_same_v<T, uff::CoordinateSystems2420>) {
                  py::list l;
                  for (const auto& c : b.systems)
                    l.append(py::dict(py::arg("label") = c.label, py::arg("type") = c.type, py::arg("name") = ema::formats::JsonText(c.name),
                                      py::arg("matrix") = std::vector<double>(c.matrix.begin(), c.matrix.end())));
                  d["part_name"] = ema::formats::JsonText(b.part_name), d["systems"] = l;
                } else if constexpr (std::is_same_v<T, uff::TraceLine82>) {
                  d["trace_number"] = b.number, d["id"] = ema::formats::JsonText(b.id), d["nodes"] = b.nodes;
                } else if constexpr (std::is_same_v<T, uff::Data55>) {
                  d["id"] = strings(b.id);
                  d["analysis_type"] = b.analysis_type, d["data_characteristic"] = b.data_characteristic;
                  d["specific_data_type"] = b.specific_data_type, d["values_per_node"] = b.ndv;
                  d["integers"] = b.integers, d["reals"] = b.reals;
                  std::vector<std::int64_t> node_ids;
                  py::array_t<std::complex<double>> values({static_cast<py::ssize_t>(b.nodes.size()), static_cast<py::ssize_t>(b.ndv)});
                  auto v = values.mutable_unchecked<2>();
                  for (size_t i = 0; i < b.nodes.size(); ++i) {
                    node_ids.push_back(b.nodes[i].node);
                    for (int k = 0; k < b.ndv; ++k) {
                      const auto& x = b.nodes[i].values;
                      const size_t re = b.IsComplex() ? 2 * static_cast<size_t>(k) : static_cast<size_t>(k);
                      v(static_cast<py::ssize_t>(i), k) = {re < x.size() ? x[re] : ema::kNaN,
                                                          b.IsComplex() && re + 1 < x.size() ? x[re + 1] : 0.0};
                    }
                  }
                  d["node"] = node_ids, d["values"] = values, d["complex"] = b.IsComplex();
                } else if constexpr (std::is_same_v<T, uff::Function58>) {
                  d["id"] = strings(b.id);
                  d["function_type"] = b.function_type, d["load_case"] = b.load_case;
                  d["response_node"] = b.response_node, d["response_direction"] = b.response_direction;
                  d["reference_node"] = b.reference_node, d["reference_direction"] = b.reference_direction;
                  d["binary"] = b.binary;
                  const auto n = static_cast<py::ssize_t>(b.count);
                  py::array_t<double> x(n);
                  auto xv = x.mutable_unchecked<1>();
                  for (py::ssize_t i = 0; i < n; ++i) xv(i) = b.X(i);
                  d["x"] = x;
                  if (b.IsComplex()) {
                    py::array_t<std::complex<double>> y(n);
                    auto yv = y.mutable_unchecked<1>();
                    for (py::ssize_t i = 0; i < n && static_cast<size_t>(2 * i + 1) < b.y.size(); ++i) yv(i) = {b.y[2 * i], b.y[2 * i + 1]};
                    d["y"] = y;
                  } else {
                    py::array_t<double> y(n);
                    auto yv = y.mutable_unchecked<1>();
                    for (py::ssize_t i = 0; i < n && static_cast<size_t>(i) < b.y.size(); ++i) yv(i) = b.y[static_cast<size_t>(i)];
                    d["y"] = y;
                  }
                  py::list axes;
                  for (const auto& a : b.axes)
                    axes.append(py::dict(py::arg("specific_data_type") = a.specific_data_type,
                                         py::arg("label") = ema::formats::JsonText(a.label), py::arg("units") = ema::formats::JsonText(a.units)));
                  d["axes"] = axes;
                } else {
                  d["lines"] = strings(b.lines);  // a dataset the library does not decode, verbatim
                }
              },
              ds.body);
          out.append(d);
        }
        return out;
      },
      py::arg("path"),
      "Every dataset of a UFF file (15, 18, 55, 58/58b, 82, 151, 164, 2411, 2420; others verbatim as\n"
      "'lines') as a list of dicts, each with 'number' (the dataset type), 'line' (where it starts) and its\n"
      "fields: 58 gives function_type (1 time, 4 FRF, 6 coherence, 12 spectrum, ...), response/reference\n"
      "node and direction, 'x' and 'y' (complex when the data are); 55 gives 'node' and 'values' (nodes x\n"
      "values per node, complex); 15/2411 'nodes' with label and xyz.");

  // The writers of the CLI's files: what `ema fit -o` / `--json` and `ema frf -o` write, from the
  // dicts the readers and ema.fit return (issue 41). An output naming the input is refused.
  auto output_path = [](const py::object& path, const py::object& input, const std::string& what) {
    if (!IsPath(path)) throw py::type_error("path: expected the path of the " + what + " to write, found " + TypeName(path));
    const std::string out = PathOf(path);
    if (IsPath(input)) {
      try {
        ema::formats::RefuseOutputsOverInputs({{"input", PathOf(input)}}, {{"path", out}});
      } catch (const ema::UsageError& e) {
        throw ema::UsageError(std::string("path: ") + e.what());
      }
    }
    return out;
  };
  m.def(
      "write_modes",
      [output_path](const py::object& modes, const py::object& path, bool binary) {
        const std::string out = output_path(path, modes, "modes file");
        const ModeSet set = ToModeSet(modes, "modes");
        if (std::filesystem::path(out).extension() == ".json")
          ema::formats::WriteTextFileAtomically(out, ema::formats::ModeSetJson(set).dump(2) + "\n");
        else
          ema::formats::WriteModeSet(out, set, {binary});
      },
      py::arg("modes"), py::arg("path"), py::kw_only(), py::arg("binary") = false,
      "Writes modes (a path, a modes dict, or what ema.fit returns) as UFF 55 with their geometry, or as\n"
      "JSON in `ema fit --json`'s mode layout when `path` ends in .json; read back by ema.read_modes.\n"
      "Written atomically; `path` naming the input is refused.");
  m.def(
      "write_frfs",
      [output_path](const py::object& frfs, const py::object& path, bool binary) {
        const std::string out = output_path(path, frfs, "FRF file");
        if (!IsPath(frfs) && !IsMapping(frfs))
          throw py::type_error("frfs: expected a path or an FRF dict (ema.read_frfs), found " + TypeName(frfs));
        ema::formats::WriteFrfSet(out, ToFrfSet(frfs), {binary});
      },
      py::arg("frfs"), py::arg("path"), py::kw_only(), py::arg("binary") = false,
      "Writes FRFs (a path or an FRF dict as ema.read_frfs returns) as UFF 58 (58b with binary=True),\n"
      "as `ema frf -o` writes them; read back by ema.read_frfs. Written atomically; `path` naming the\n"
      "input is refused.");

  m.def(
      "estimate_frfs",
      [](const py::object& paths, const std::string& estimator, const py::object& band, const py::object& exp_window,
         double exp_end_level, const std::string& quantity, double trigger_level, double force_window,
         double double_hit_ratio, double double_hit_autocorrelation, bool accept_double_hits, double overload_fraction,
         double level_tolerance, const py::object& force, const py::object& response, const py::object& fs,
         const py::object& dofs, const py::object& reference, const std::string& response_quantity) {
        // One path or a sequence of paths (str or os.PathLike), one per roving set; or the records
        // as arrays (force=, response=, fs=, dofs=, reference=): one roving set.
        std::vector<std::string> files;
        const bool arrays = !force.is_none() || !response.is_none();
        if (arrays) {
          if (!paths.is_none()) throw py::type_error("paths: give paths or arrays (force=, response=), not both");
        } else if (paths.is_none()) {
          throw py::type_error("paths: expected a path or a list of paths of time data, or force= and response= arrays");
        } else if (IsPath(paths)) {
          files.push_back(PathOf(paths));
        } else if (py::isinstance<py::sequence>(paths) && !py::isinstance<py::bytes>(paths)) {
          for (const py::handle& p : py::reinterpret_borrow<py::sequence>(paths)) {
            if (!IsPath(p)) throw py::type_error("paths: expected paths of time data, found " + TypeName(p) + " in the list");
            files.push_back(PathOf(p));
          }
        } else {
          throw py::type_error("paths: expected a path or a list of paths of time data, found " + TypeName(paths));
        }
        if (!arrays && files.empty()) throw py::value_error("paths: expected at least one time-data file");
        // The options of `ema frf`, by the same names (app/cmd_frf.cpp).
        ema::frf::FrfOptions opt;
        try {
          opt.estimator = ema::frf::ParseEstimator(estimator);
        } catch (const std::invalid_argument& e) {
          throw py::value_error(std::string("estimator: ") + e.what());
        }
        if (!band.is_none()) {
          std::tie(opt.band_lo_hz, opt.band_hi_hz) = Band(band);
        }
        ema::acquisition::ImpactOptions& imp = opt.impact;
        if (py::isinstance<py::str>(exp_window)) {
          if (!ema::FromName(ema::frf::kExpWindowNames, exp_window.cast<std::string>(), &imp.exp_window))
            throw py::value_error("exp_window: expected 'auto', 'none' or a decay rate 1/tau in 1/s, got '" +
                                  exp_window.cast<std::string>() + "'");
        } else if (py::isinstance<py::float_>(exp_window) || py::isinstance<py::int_>(exp_window)) {
          imp.exp_window = ema::acquisition::ExpWindowMode::kFixed;
          imp.exp_decay_rate = exp_window.cast<double>();
        } else {
          throw py::type_error("exp_window: expected 'auto', 'none' or a number, found " + TypeName(exp_window));
        }
        imp.exp_end_level = exp_end_level;
        imp.trigger_level = trigger_level;
        imp.force_window_pulses = force_window;
        imp.double_hit_high = double_hit_ratio;
        imp.double_hit_low = std::min(imp.double_hit_low, 0.5 * imp.double_hit_high);
        imp.double_hit_autocorrelation = double_hit_autocorrelation;
        imp.reject_double_hits = !accept_double_hits;
        imp.overload_fraction = overload_fraction;
        imp.level_tolerance = level_tolerance;
        if (!quantity.empty() && !ema::FromName(ema::frf::kOutputQuantityNames, quantity, &opt.output_quantity))
          throw py::value_error("quantity: expected " + ema::NameList(ema::frf::kOutputQuantityNames) + ", got '" + quantity + "'");
        if (std::string why; !opt.IsValid(&why)) throw py::value_error(why);
        std::vector<ema::acquisition::RecordSet> sets;  // from the arrays; the files are read below
        if (arrays) {
          // force: (impacts, samples); response: (impacts, channels, samples), or (channels,
          // samples) for one impact; the records as a file of them would hold (formats.md).
          if (force.is_none() || response.is_none() || fs.is_none() || dofs.is_none() || reference.is_none())
            throw py::type_error("arrays: force=, response=, fs=, dofs= and reference= are all needed");
          auto f = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(force);
          auto r = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(response);
          if (!f || !r || py::isinstance<py::str>(force) || py::isinstance<py::str>(response))
            throw py::type_error("force, response: expected real numeric arrays");
          if (f.ndim() == 1) f = f.reshape({py::ssize_t(1), f.shape(0)});
          if (r.ndim() == 2 && f.shape(0) == 1) r = r.reshape({py::ssize_t(1), r.shape(0), r.shape(1)});
          if (f.ndim() != 2 || r.ndim() != 3)
            throw py::value_error("force: expected (impacts, samples); response: (impacts, channels, samples) or (channels, samples)");
          const auto impacts = f.shape(0), samples = f.shape(1), channels = r.shape(1);
          if (r.shape(0) != impacts || r.shape(2) != samples || samples < 2)
            throw py::value_error("response: expected shape (" + std::to_string(impacts) + ", channels, " + std::to_string(samples) +
                                  ") to match force's (impacts, samples) = (" + std::to_string(impacts) + ", " +
                                  std::to_string(samples) + "), found " + std::string(py::str(py::tuple(r.attr("shape")))));
          double rate = 0.0;
          try {
            rate = fs.cast<double>();
          } catch (const py::cast_error&) {
            throw py::type_error("fs: expected the sample rate in Hz, found " + TypeName(fs));
          }
          if (!(rate > 0.0) || !std::isfinite(rate)) throw py::value_error("fs: expected a sample rate > 0 Hz");
          if (!py::isinstance<py::sequence>(dofs) || py::isinstance<py::str>(dofs) || static_cast<py::ssize_t>(py::len(dofs)) != channels)
            throw py::value_error("dofs: expected one DOF per response channel (" + std::to_string(channels) + "), e.g. [(101, '+Z'), ...]");
          std::vector<Dof> channel_dofs;
          for (const py::handle& d : py::reinterpret_borrow<py::sequence>(dofs)) channel_dofs.push_back(ToDof(d));
          const Dof hammer = ToDof(reference);
          ema::Quantity q = ema::Quantity::kUnknown;
          const std::string unit = response_quantity == "acceleration" ? "m/s^2" : response_quantity == "velocity" ? "m/s" : "m";
          if (response_quantity == "acceleration") q = ema::Quantity::kAcceleration;
          else if (response_quantity == "velocity") q = ema::Quantity::kVelocity;
          else if (response_quantity == "displacement") q = ema::Quantity::kDisplacement;
          else throw py::value_error("response_quantity: expected 'acceleration', 'velocity' or 'displacement'");
          ema::acquisition::RecordSet set{"arrays", {}};
          const auto fv = f.unchecked<2>();
          const auto rv = r.unchecked<3>();
          for (py::ssize_t i = 0; i < impacts; ++i) {
            ema::TimeRecord force_record;
            force_record.channel = hammer, force_record.reference = hammer, force_record.impact = static_cast<int>(i + 1);
            force_record.quantity = ema::Quantity::kForce, force_record.sample_interval_s = 1.0 / rate, force_record.unit = "N";
            force_record.origin = "force[" + std::to_string(i) + "]";
            force_record.samples.assign(&fv(i, 0), &fv(i, 0) + samples);
            set.records.push_back(std::move(force_record));
            for (py::ssize_t c = 0; c < channels; ++c) {
              ema::TimeRecord rec;
              rec.channel = channel_dofs[static_cast<size_t>(c)], rec.reference = hammer, rec.impact = static_cast<int>(i + 1);
              rec.quantity = q, rec.sample_interval_s = 1.0 / rate, rec.unit = unit;
              rec.origin = "response[" + std::to_string(i) + ", " + std::to_string(c) + "]";
              rec.samples.assign(&rv(i, c, 0), &rv(i, c, 0) + samples);
              set.records.push_back(std::move(rec));
            }
          }
          sets.push_back(std::move(set));
        }
        // The files read, the impacts analysed and the spectra taken with Ctrl-C stopping them at the
        // next file, record or spectrum.
        const ema::frf::FrfResult result = RunInterruptibly([&](const ema::ProgressCallback& progress) {
          std::vector<ema::acquisition::RecordSet> read;
          for (const auto& p : files) {
            ema::ReportProgress(progress, 0.0, "reading");
            read.push_back({p, ema::formats::ReadTimeRecords(p)});
          }
          for (auto& s : sets) read.push_back(std::move(s));
          return ema::frf::EstimateFrfs(ema::acquisition::AssembleHammerMeasurement(std::move(read)), opt, progress);
        });
        py::dict d = FrfDict(result.frfs);
        // What `ema frf --json` writes: per FRF its averages and rejections, and every rejected
        // impact with its file and reason.
        d["summary"] = FromJson(ema::formats::FrfSummaryJson(result));
        return d;
      },
      py::arg("paths") = py::none(), py::arg("estimator") = "H1", py::kw_only(), py::arg("band") = py::none(),
      py::arg("exp_window") = "auto", py::arg("exp_end_level") = ema::acquisition::ImpactOptions{}.exp_end_level,
      py::arg("quantity") = "", py::arg("trigger_level") = ema::acquisition::ImpactOptions{}.trigger_level,
      py::arg("force_window") = ema::acquisition::ImpactOptions{}.force_window_pulses,
      py::arg("double_hit_ratio") = ema::acquisition::ImpactOptions{}.double_hit_high,
      py::arg("double_hit_autocorrelation") = ema::acquisition::ImpactOptions{}.double_hit_autocorrelation,
      py::arg("accept_double_hits") = false,
      py::arg("overload_fraction") = ema::acquisition::ImpactOptions{}.overload_fraction,
      py::arg("level_tolerance") = ema::acquisition::ImpactOptions{}.level_tolerance, py::arg("force") = py::none(),
      py::arg("response") = py::none(), py::arg("fs") = py::none(), py::arg("dofs") = py::none(),
      py::arg("reference") = py::none(), py::arg("response_quantity") = "acceleration",
      "Hammer time data (UFF 58 type 1, CSV or MATLAB .mat; a path or a list of paths, one per roving set)\n"
      "to FRFs, as `ema frf` with the same options by the same names (band=(lo, hi), exp_window='auto',\n"
      "'none' or a decay rate, quantity='accelerance'|'mobility'|'receptance', trigger_level, force_window,\n"
      "double_hit_ratio, double_hit_autocorrelation, accept_double_hits, overload_fraction, level_tolerance).\n"
      "Returns an FRF dict with coherence and the accepted impacts per FRF ('averages'), and 'summary': what\n"
      "`ema frf --json` writes (per FRF its 'rejected' impacts with their file and reason).\n"
      "Or the records as numpy arrays, one roving set: force (impacts, samples) in N, response (impacts,\n"
      "channels, samples), fs in Hz, dofs (one per channel, e.g. (101, '+Z')), reference (the hammer DOF),\n"
      "response_quantity ('acceleration' in m/s^2, 'velocity', 'displacement').\n"
      "Ctrl-C stops the estimation at its next file, record or spectrum (KeyboardInterrupt).");

  m.def(
      "fit",
      [](const py::object& frfs, const py::object& band, int order_max, const std::vector<double>& select,
         const std::string& method, const std::string& refine, bool stabilisation) {
        const FrfSet set = ToFrfSet(frfs);
        ema::curvefit::FitOptions opt;
        std::tie(opt.data.band_lo_hz, opt.data.band_hi_hz) = Band(band);
        if (order_max < 0) throw py::value_error("order_max: expected 0 (automatic) or a positive order");
        opt.polymax.order_max = order_max;
        opt.select_frequencies_hz = select;
        if (method == "peak") opt.method = ema::curvefit::FitMethod::kPeak;
        else if (method != "polymax") throw py::value_error("method: expected 'polymax' or 'peak'");
        if (!ema::curvefit::StringToRefineMethod(refine, &opt.refine))
          throw py::value_error("refine: expected 'ml' or 'none', got '" + refine + "'");
        // Ctrl-C stops the fit at its next step (a PolyMAX order, a refinement iteration).
        const ema::curvefit::FitResult fit = RunInterruptibly(
            [&](const ema::ProgressCallback& progress) { return ema::curvefit::Fit(set, opt, "frfs", progress); });
        // As `ema fit` exits 1: a fit that finds nothing is an error, not an empty result.
        if (fit.modes.modes.empty())
          throw py::value_error(
              "fit: no mode found" +
              std::string(method == "peak" ? ": no resonance peak in the band (try another band)"
                                           : ": no pole stayed stable over the PolyMAX orders " +
                                                 std::to_string(fit.diagram.order_min) + "–" +
                                                 std::to_string(fit.diagram.order_max) +
                                                 " (try a wider band or a higher order_max; an all-zero FRF has none)"));
        // Each warning through Python's warnings (filterable, and an error under -W error); the
        // list stays in the result for scripts that read it.
        for (const std::string& w : fit.warnings)
          // Stack level 2: the line that called the Python wrapper ema.fit, not the wrapper.
          if (PyErr_WarnEx(PyExc_RuntimeWarning, ("ema.fit: " + w).c_str(), 2) != 0) throw py::error_already_set();
        py::dict d = ModesDict(fit.modes);
        d["synthesis_error"] = fit.synthesis_error;
        d["reciprocity_transposed"] = fit.transposed;
        d["warnings"] = fit.warnings;
        std::vector<int> orders, cluster;
        for (const auto& s : fit.selected) orders.push_back(s.pole.order), cluster.push_back(s.cluster_size);
        d["order"] = orders;
        d["cluster_orders"] = cluster;
        // The roving sets and the hammer DOF when the FRFs know them (diagnose's sensor_mass).
        const nlohmann::json sets = ema::formats::TestSetsJson(set);
        if (sets.contains("roving_sets")) d["roving_sets"] = FromJson(sets["roving_sets"]);
        if (sets.contains("reference")) d["reference"] = DofTuple(set.references[0]);
        if (stabilisation) {
          // Why each mode is there and why others are not: the diagram as `ema fit --stabilisation`
          // writes it (poles per order with their stability), the modal model behind the shapes
          // (poles, residues and residual terms per measured FRF) and the dropped poles with reasons,
          // as `ema fit --json` gives them.
          const nlohmann::json fit_json = ema::formats::FitModesJson(fit, opt.refine);
          d["stabilisation"] = opt.method == ema::curvefit::FitMethod::kPeak
                                   ? py::object(py::none())
                                   : FromJson(ema::formats::StabilisationJson(fit, opt.stability));
          d["modal_model"] = fit_json.contains("modal_model") ? FromJson(fit_json["modal_model"]) : py::object(py::none());
          d["dropped"] = fit_json.contains("dropped") ? FromJson(fit_json["dropped"]) : FromJson(nlohmann::json::array());
        }
        return d;
      },
      py::arg("frfs"), py::arg("band") = py::none(), py::arg("order_max") = 0,
      py::arg("select") = std::vector<double>{}, py::arg("method") = "polymax", py::arg("refine") = "ml",
      py::arg("stabilisation") = false,
      "Fits modes to FRFs as `ema fit`: PolyMAX poles for every order up to order_max (0 = automatic),\n"
      "stabilisation, automatic selection (or the poles nearest the frequencies in `select`), LSFD shapes,\n"
      "and the maximum-likelihood refinement (refine='ml', the default; 'none' keeps PolyMAX/LSFD) with the\n"
      "1-sigma frequency_std_hz and damping_ratio_std. band=(lo, hi) in Hz. Returns a modes dict plus\n"
      "synthesis_error, order and cluster_orders (and roving_sets/reference when the FRFs know them).\n"
      "The result goes straight into correlate() and diagnose() (the sigmas weigh each mode there).\n"
      "Raises ValueError when no mode is found (as `ema fit` exits 1), for an unknown direction or a bad band,\n"
      "TypeError for a real-valued 'h' or a band that is not (lo, hi); each fit warning is also issued\n"
      "through warnings.warn (RuntimeWarning) and kept in the result's 'warnings'.\n"
      "stabilisation=True adds 'stabilisation' (the diagram as `ema fit --stabilisation` writes it: poles per\n"
      "order with their stability), 'modal_model' (poles, residues and residual terms per measured FRF, as in\n"
      "`ema fit --json`) and 'dropped' (poles the fit dropped, each with its reason).\n"
      "Ctrl-C stops the fit at its next step (KeyboardInterrupt).");

  m.def(
      "synthesize",
      [](const py::object& fit_result, const py::object& frequency_hz) {
        // The modal model as ema.fit(..., stabilisation=True) returns it (or that dict's
        // 'modal_model' alone): poles as the FRFs carry them, residues and residual terms per
        // measured FRF (`ema fit --json`'s modal_model).
        if (!IsMapping(fit_result)) throw py::type_error("synthesize: fit_result must be what ema.fit(..., stabilisation=True) returns");
        // A copy as a real dict: any Mapping is accepted (a MappingProxyType borrowed as a dict
        // crashed the interpreter in PyDict_Contains).
        py::dict given = py::dict(fit_result);
        if (given.contains("modal_model")) {
          if (given["modal_model"].is_none())
            throw py::value_error("synthesize: this fit has no modal model (the peak method, or no mode)");
          if (!IsMapping(given["modal_model"])) throw py::type_error("synthesize: fit_result['modal_model'] must be a dict");
          given = py::dict(given["modal_model"]);
        } else if (!given.contains("poles") || !given.contains("frfs")) {
          throw py::value_error("synthesize: fit_result has no 'modal_model': fit with stabilisation=True");
        }
        nlohmann::json j;
        try {
          j = nlohmann::json::parse(py::module_::import("json").attr("dumps")(given).cast<std::string>());
          // The layout `ema fit --json` writes: checked here, so a wrong dict is a ValueError naming it.
          for (const auto& p : j.at("poles")) (void)p.at(1).get<double>();
          for (const auto& frf : j.at("frfs"))
            for (const char* key : {"response_node", "response_dir", "reference_node", "reference_dir", "residues"})
              (void)frf.at(key);
        } catch (const nlohmann::json::exception& e) {
          throw py::value_error(std::string("synthesize: modal_model is not in `ema fit --json`'s layout: ") + e.what());
        }
        const auto f = py::array_t<double, py::array::c_style | py::array::forcecast>(frequency_hz);
        if (f.ndim() != 1 || f.size() == 0) throw py::value_error("synthesize: frequency_hz must be a 1-D array of Hz");
        const Eigen::VectorXd hz = Eigen::Map<const Eigen::VectorXd>(f.data(), f.size());
        ema::curvefit::ModalModel mm;
        const std::string type = j.value("frf_type", "accelerance");
        mm.frf_type = type == "receptance" ? ema::FrfType::kReceptance
                      : type == "mobility" ? ema::FrfType::kMobility
                                           : ema::FrfType::kAccelerance;
        // Without a band the model is evaluated at every line above 0 Hz.
        const auto band = j.value("band_hz", std::vector<double>{});
        mm.band_hi_hz = std::numeric_limits<double>::infinity();
        if (band.size() == 2 && band[1] > band[0]) mm.band_lo_hz = band[0], mm.band_hi_hz = band[1];
        for (const auto& p : j.at("poles")) mm.poles_fitted.emplace_back(p.at(0).get<double>(), p.at(1).get<double>());
        auto dof = [](const nlohmann::json& e, const char* node, const char* dir) {
          const int d = ema::ParseDirection(e.at(dir).get<std::string>());
          if (d == 0) throw py::value_error("synthesize: modal_model: unknown direction " + e.at(dir).dump());
          return Dof{e.at(node).get<int>(), d};
        };
        auto index_of = [](std::vector<Dof>* list, const Dof& d) {
          for (size_t i = 0; i < list->size(); ++i)
            if ((*list)[i] == d) return static_cast<int>(i);
          list->push_back(d);
          return static_cast<int>(list->size()) - 1;
        };
        struct Entry { int o, i; const nlohmann::json* frf; };
        std::vector<Entry> entries;
        for (const auto& frf : j.at("frfs"))
          entries.push_back({index_of(&mm.outputs, dof(frf, "response_node", "response_dir")),
                             index_of(&mm.references, dof(frf, "reference_node", "reference_dir")), &frf});
        const int l = static_cast<int>(mm.outputs.size()), m = static_cast<int>(mm.references.size());
        const int n = static_cast<int>(mm.poles_fitted.size());
        mm.residues = Eigen::MatrixXcd::Zero(l * m, n);
        mm.lower_residual = Eigen::VectorXd::Zero(l * m);
        mm.upper_residual = Eigen::VectorXd::Zero(l * m);
        std::vector<bool> held(static_cast<size_t>(l * m), false);
        for (const Entry& e : entries) {
          const int c = e.o * m + e.i;
          const auto& residues = e.frf->at("residues");
          if (static_cast<int>(residues.size()) != n)
            throw py::value_error("synthesize: modal_model: each FRF needs one residue per pole (" + std::to_string(n) + ")");
          for (int r = 0; r < n; ++r) mm.residues(c, r) = {residues[r].at(0).get<double>(), residues[r].at(1).get<double>()};
          mm.lower_residual(c) = e.frf->value("lower_residual", 0.0);
          mm.upper_residual(c) = e.frf->value("upper_residual", 0.0);
          held[static_cast<size_t>(c)] = true;
        }
        // (references, lines, outputs) as every FRF dict, through the synthesis the report draws
        // (SynthesiseMeasuredFrf: NaN outside the band it was fitted in, nothing extrapolated);
        // NaN for an FRF the dict does not hold.
        py::array_t<std::complex<double>> h({static_cast<py::ssize_t>(m), static_cast<py::ssize_t>(hz.size()),
                                             static_cast<py::ssize_t>(l)});
        auto hr = h.mutable_unchecked<3>();
        const std::complex<double> nan(std::nan(""), std::nan(""));
        for (int o = 0; o < l; ++o)
          for (int i = 0; i < m; ++i) {
            const bool have = held[static_cast<size_t>(o * m + i)];
            const Eigen::VectorXcd v =
                have ? ema::curvefit::SynthesiseMeasuredFrf(mm, mm.outputs[o], mm.references[i], hz) : Eigen::VectorXcd();
            for (Eigen::Index k = 0; k < hz.size(); ++k) hr(i, k, o) = have ? v(k) : nan;
          }
        py::dict d;
        d["frequency_hz"] = Vec(hz);
        d["outputs"] = DofList(mm.outputs);
        d["references"] = DofList(mm.references);
        d["h"] = h;
        d["quantity"] = type == "receptance" ? "displacement" : type == "mobility" ? "velocity" : "acceleration";
        return d;
      },
      py::arg("fit_result"), py::arg("frequency_hz"),
      "FRFs of a fitted modal model: what ema.fit(..., stabilisation=True) returns (or its 'modal_model'),\n"
      "evaluated at frequency_hz (1-D, Hz) — the synthesis a fit is judged by. Returns an FRF dict\n"
      "(frequency_hz, outputs, references, h of shape (references, lines, outputs)) for the measured FRFs the\n"
      "model holds; NaN outside the band it was fitted in and for FRFs it does not hold.");

  m.def(
      "mode_indicators",
      [](const py::object& frfs, const py::object& band) {
        ema::curvefit::FitDataOptions opt;
        std::tie(opt.band_lo_hz, opt.band_hi_hz) = Band(band);
        const auto data = ema::curvefit::PrepareFitData(ToFrfSet(frfs), opt, "frfs");
        const auto mi = ema::curvefit::ComputeModeIndicators(data);
        py::dict d;
        d["frequency_hz"] = Vec(mi.frequency_hz);
        d["cmif"] = Mat(mi.cmif);
        d["mmif"] = Mat(mi.mmif);
        return d;
      },
      py::arg("frfs"), py::arg("band") = py::none(),
      "CMIF (singular values of the FRF matrix per line, largest first: (n_lines, min(outputs, references)))\n"
      "and MMIF (eigenvalues of the real-part energy ratio, smallest first: (n_lines, references)) in the band.");

  m.def(
      "model_modes",
      [](const py::object& model_arg, const std::string& setup, int max_modes) {
        const ema::model::Model model = ToModel(model_arg);
        ema::model::SolveOptions opt;
        opt.setup = setup;
        opt.max_modes = max_modes;
        if (std::string why; !opt.IsValid(&why)) throw ema::UsageError(why);
        py::gil_scoped_release release;
        ModeSet modes = ema::model::Solve(model, opt).modes;
        py::gil_scoped_acquire acquire;
        return ModesDict(modes);
      },
      py::arg("model"), py::arg("setup") = "", py::arg("max_modes") = 0,
      "The model's own modes as `ema model`, at the operating point of `setup` ('' = nominal), as a modes dict\n"
      "with the shapes at the model's test points (+X, +Y, +Z each; unit modal mass). max_modes: elastic modes\n"
      "kept (0 = all for small models, 30 from 1000 DOFs on).\n\n"
      "model: a model file (TOML, docs/model.md), or an FE model built from parts in Python (model-format.md,\n"
      "'FE models built from parts'): a dict, or any object with these attributes:\n"
      "  dofs       [(node, dof), ...] one per matrix row; dof 1..6 or 'ux', 'uy', 'uz', 'rx', 'ry', 'rz'\n"
      "  mass       n x n scipy.sparse matrix or numpy array (optional when parts carry the mass)\n"
      "  stiffness  n x n, whatever is in no part (optional)\n"
      "  parts      [{'name', 'group' (optional), 'stiffness', 'mass' (optional), 'uncertainty' (optional,\n"
      "             relative 1-sigma)}, ...]: each part's own contribution, K = stiffness + sum of parts'\n"
      "  nodes      {node: (x, y, z)} (m)\n"
      "  points     [{'id': 101, 'node': 1003}, ...] or [node, ...]: where the test's sensors sit\n"
      "  damping    a modal damping ratio, or a list of them per mode\n"
      "  priors     {effect kind: relative 1-sigma}, name  (optional)\n"
      "Matrices are symmetric (full storage); parts' positive semi-definite. A model built in Python has no\n"
      "setups: use setup=''.");

  m.def(
      "mac",
      // Shapes of different lengths: MacMatrix's std::invalid_argument, a ValueError in Python.
      [](const Eigen::MatrixXcd& a, const Eigen::MatrixXcd& b) { return Mat(ema::correlation::MacMatrix(a, b)); },
      py::arg("a"), py::arg("b"),
      "MAC between every column (mode shape) of a and every column of b (rows/DOFs aligned): |a^H b|^2 / (a^H a b^H b).");

  m.def(
      "correlate",
      [](const py::object& test, const py::object& model, double mac_min) {
        const ModeSet t = ToModeSet(test, "test"), mm = ToModeSet(model, "model");
        ema::correlation::CorrelationOptions opt;
        opt.pairing.mac_min = mac_min;
        const auto r = ema::correlation::Correlate(t, mm, opt);
        py::list pairs;
        for (const auto& row : r.rows) {
          if (!row.paired()) continue;
          py::dict p;
          p["test_mode"] = row.test_mode + 1;
          p["model_mode"] = row.model_mode + 1;
          p["test_frequency_hz"] = row.test_frequency_hz;
          p["model_frequency_hz"] = row.model_frequency_hz;
          p["agreement_pct"] = row.agreement_pct;
          p["frequency_error_pct"] = row.frequency_error_pct;
          p["mac"] = row.mac;
          p["remark"] = row.remark;
          pairs.append(p);
        }
        py::dict d;
        d["pairs"] = pairs;
        d["mac"] = Mat(r.mac);
        // Mode numbers are 1-based everywhere (as pairs[] and `ema correlate --json`): the array
        // indices of the MAC matrix are those numbers minus one.
        std::vector<int> unpaired_test, unpaired_model;
        for (int i : r.pairing.unpaired_test) unpaired_test.push_back(i + 1);
        for (int i : r.pairing.unpaired_model) unpaired_model.push_back(i + 1);
        d["unpaired_test"] = unpaired_test;
        d["unpaired_model"] = unpaired_model;
        d["mean_agreement_pct"] = r.mean_agreement_pct;
        d["min_agreement_pct"] = r.min_agreement_pct;
        d["mean_mac"] = r.mean_mac;
        d["shared_dofs"] = r.shared_dof_count;
        d["table"] = ema::correlation::FormatCorrelationTable(r, ema::correlation::TableFormat::kMarkdown);
        return d;
      },
      py::arg("test"), py::arg("model"), py::arg("mac_min") = ema::correlation::CorrelationOptions{}.pairing.mac_min,
      "Test modes against model modes as `ema correlate` (paths, modes dicts or dicts in `ema fit --json`'s\n"
      "layout): MAC matrix on the shared DOFs, pairing, agreement % = 100 (1 - |f_model - f_test| / f_model);\n"
      "mode numbers (pairs[].test_mode, model_mode, unpaired_test, unpaired_model) are 1-based as in\n"
      "`ema correlate --json`; the MAC matrix is indexed by those numbers minus one.");

  const ema::diagnose::DiagnoseOptions defaults;
  m.def(
      "diagnose",
      [](const py::object& model_arg, const py::object& tests, const std::string& criterion, int max_effects, bool members,
         double frequency_floor, double shape_sigma, double mac_min, double sensor_mass, double effect_prior_odds,
         bool exact_form, const std::string& shape_residual, double shape_dof_sigma) {
        namespace dg = ema::diagnose;
        const ema::model::Model model = ToModel(model_arg);
        if (!(sensor_mass >= 0.0) || !std::isfinite(sensor_mass))
          throw ema::UsageError("sensor_mass must be a mass in kg >= 0 (0.0112 for an 11.2 g accelerometer)");
        std::vector<dg::SetupModes> sets;
        // One mode set alone (a path, MODES.json's layout, ema.fit's dict): the nominal setup's.
        const bool single = IsPath(tests) || IsJsonLayout(tests) ||
                            (IsMapping(tests) && py::dict(tests).contains("frequency_hz") && py::dict(tests).contains("shapes"));
        if (single) {
          sets.push_back(ToSetupModes("", tests, sensor_mass));
        } else if (IsMapping(tests)) {
          for (const auto& item : tests.attr("items")()) {
            const auto kv = item.cast<py::tuple>();
            sets.push_back(ToSetupModes(Cast<std::string>(kv[0], "tests", "setup names (str) as keys"),
                                        py::reinterpret_borrow<py::object>(kv[1]), sensor_mass));
          }
        } else {
          throw py::type_error("tests: expected {setup: modes, ...} ('' for the nominal model) or one mode set, found " +
                               TypeName(tests));
        }
        if (sets.empty()) throw ema::UsageError("tests: expected the test modes of at least one setup");
        dg::DiagnoseOptions opt;
        if (!criterion.empty() && !dg::StringToCriterion(criterion, &opt.criterion))
          throw ema::UsageError("criterion: '" + criterion + "' is not one ema diagnose --criterion takes "
                                "(evidence, bic, aicc)");
        opt.max_effects = max_effects;
        opt.members = members;
        opt.frequency_floor = frequency_floor;
        opt.shape_sigma = shape_sigma;
        if (!dg::StringToShapeResidual(shape_residual, &opt.shape_residual))
          throw ema::UsageError("shape_residual: '" + shape_residual + "' is not one ema diagnose --shape-residual "
                                "takes (per-dof, mac)");
        opt.shape_dof_sigma = shape_dof_sigma;
        opt.pairing.mac_min = mac_min;
        opt.effect_prior_odds = effect_prior_odds;
        opt.model_error = !exact_form;
        if (std::string why; !opt.IsValid(&why)) throw ema::UsageError(why);
        // Ctrl-C: at every progress step (each candidate screened or fitted) the diagnosis takes the
        // GIL back for a moment and asks Python whether a signal is pending; KeyboardInterrupt
        // unwinds the search (single-threaded) instead of waiting for the whole call.
        opt.progress = [](double, std::string_view) {
          py::gil_scoped_acquire acquire;
          if (PyErr_CheckSignals() != 0) throw py::error_already_set();
        };
        // The stage `ema diagnose` runs, and its JSON: DIAG.json's every key, rank 1's findings included.
        std::optional<ema::pipeline::DiagnoseStage> stage;
        {
          py::gil_scoped_release release;
          stage = ema::pipeline::DiagnoseModel(model, sets, opt);
        }
        return FromJson(ema::pipeline::DiagnosisJson(*stage));
      },
      py::arg("model"), py::arg("tests"), py::arg("criterion") = "", py::kw_only(),
      py::arg("max_effects") = defaults.max_effects, py::arg("members") = defaults.members,
      py::arg("frequency_floor") = defaults.frequency_floor, py::arg("shape_sigma") = defaults.shape_sigma,
      py::arg("mac_min") = defaults.pairing.mac_min, py::arg("sensor_mass") = 0.0,
      py::arg("effect_prior_odds") = defaults.effect_prior_odds, py::arg("exact_form") = false,
      py::arg("shape_residual") = ema::diagnose::ShapeResidualToString(defaults.shape_residual),
      py::arg("shape_dof_sigma") = defaults.shape_dof_sigma,
      "Which physical effect is the model missing, where, and how sure? As `ema diagnose`.\n\n"
      "model: a model file, or an FE model built from parts in Python (a dict with dofs, mass, stiffness, parts\n"
      "  as scipy.sparse or numpy matrices, nodes, points, damping: see help(ema.model_modes)).\n"
      "tests: {setup: modes} ('' = the model's nominal operating points), modes being\n"
      "  - a path: UFF 55 (with the sigmas of the `ema fit --json` file beside it, as the CLI reads it) or MODES.json;\n"
      "  - what ema.fit returns (its frequency_std_hz weighs each mode);\n"
      "  - a dict in `ema fit --json`'s layout: {'modes': [{'frequency_hz': 41.2, 'frequency_std_hz': 0.03,\n"
      "    'damping_ratio': 0.01, 'shape': [{'node': 101, 'dir': '+Z', 'value': [re, im] or re}, ...]}, ...]},\n"
      "    the shapes at the measured DOFs only (every mode the same DOFs).\n"
      "  One mode set alone (a path or a dict) means {'': modes}.\n"
      "criterion: 'evidence' (default: '' = the CLI's), 'bic' or 'aicc'. Keyword options as the CLI's:\n"
      "max_effects (1..3), members (False = --no-members), frequency_floor, shape_sigma, mac_min, sensor_mass (kg\n"
      "per measured node, the test's own sensors), effect_prior_odds (--effect-prior-odds, 0 < odds <= 1),\n"
      "exact_form (--exact-form: no model error in the likelihood), shape_residual ('per-dof' or 'mac',\n"
      "--shape-residual), shape_dof_sigma (--shape-dof-sigma).\n\n"
      "Returns `ema diagnose --json`'s layout (DIAG.json, cli.md) as a dict: 'candidates' ranked (rank 1 first;\n"
      "each with kind, target, parameters, uncertainty, probability, mean_abs_frequency_error_pct, mean_mac,\n"
      "score, description, effects, the evidence per test mode), 'baseline', 'effect_probabilities', 'groups',\n"
      "'steps', 'explanation', 'modes' (every test mode before/after rank 1) and the options used.");

  m.def(
      "run",
      [](const py::object& project_path, const py::object& output) {
        ema::formats::Project project = ema::formats::ReadProjectFile(PathOf(project_path));
        if (!project.fit_extra.empty() || !project.diagnose_extra.empty())
          throw ema::UsageError(project.file.string() + ": [fit] args / [diagnose] args (the old form of the keys) are "
                                "read by `ema run` only; give each option as a key (docs/project-file.md)");
        const ema::pipeline::RunPlan plan = ema::pipeline::PlanFromProject(std::move(project), PathOf(output));
        // Ctrl-C stops the run at its next progress step (a step, an impact record, a PolyMAX order, a
        // refinement iteration, a candidate of the diagnosis), as ema.fit. ema::Cancelled is no
        // std::exception, so no step takes it for its own failure and the run goes no further (a
        // KeyboardInterrupt thrown inside a step was recorded as that step's error and the run went on).
        const ema::pipeline::RunResult run = RunInterruptibly(
            [&](const ema::ProgressCallback& progress) { return ema::pipeline::Run(plan, progress); });
        return FromJson(ema::pipeline::RunResultJson(run));
      },
      py::arg("project"), py::arg("output") = "ema-run",
      "The whole story of a project file, as `ema run` computes it: per test frf -> fit -> correlate with the\n"
      "nominal model, the diagnosis over all tests, the correlation with the updated model. Writes no file.\n\n"
      "project: a project file (docs/project-file.md; its [fit]/[diagnose] keys, not the old `args`).\n"
      "output: the folder `ema run -o` would write to; it only names the results' sources (nothing is written).\n\n"
      "Returns {'project', 'model', 'tests': [{'name', 'setup', 'frf' (`ema frf --json`, None when the project\n"
      "gives FRFs), 'modes' (`ema fit --json`), 'select_hz', 'picked_by_hand', 'correlation_before',\n"
      "'correlation_after' (`ema correlate --json`)}], 'diagnosis' (DIAG.json, as ema.diagnose), 'steps':\n"
      "[{'step', 'test', 'status' ('done', 'failed', 'skipped', 'given'), 'error'}], 'problems',\n"
      "'mean_agreement_pct_before', 'mean_mac_before', 'mean_agreement_pct_after', 'mean_mac_after'}; None where\n"
      "a stage gave nothing (a failed step is in 'steps' with its error, as `ema run` reports it).\n"
      "Ctrl-C stops the run at its next step, record, order, iteration or candidate (KeyboardInterrupt).");

  const ema::planning::PlanOptions plan_defaults;
  m.def(
      "plan",
      [](const py::object& model_arg, const std::string& setup, const py::object& band, int sensors, int sets, bool triaxial,
         int references, double sensor_mass, int impacts, const py::object& candidates, const py::object& keep,
         const py::object& output) {
        namespace fm = ema::formats;
        // The arguments first, as `ema plan` parses its options: nothing is read or written after a bad one.
        ema::planning::PlanOptions o;
        o.setup = setup;
        std::tie(o.band_lo_hz, o.band_hi_hz) = Band(band);
        auto at_least_one = [](int value, const std::string& name, const std::string& what) {
          if (value < 1) throw ema::UsageError(name + ": expected >= 1 (" + what + "), got " + std::to_string(value));
        };
        at_least_one(sensors, "sensors", "the sensors mounted at once (test points with triaxial=True, else DOFs)");
        at_least_one(sets, "sets", "the number of roving sets");
        at_least_one(references, "references", "the number of hammer DOFs");
        at_least_one(impacts, "impacts", "the impacts per reference and set");
        if (!(sensor_mass >= 0.0) || !std::isfinite(sensor_mass))
          throw ema::UsageError("sensor_mass: expected a mass in kg >= 0 per sensor point (0.0112 for an 11.2 g accelerometer)");
        o.sensors_per_set = sensors;
        o.sets = sets;
        o.triaxial = triaxial;
        o.references = references;
        o.sensor_mass_kg = sensor_mass;
        o.impacts = impacts;
        if (std::string why; !o.IsValid(&why)) throw ema::UsageError(why);
        if (!candidates.is_none() && !IsPath(candidates) && !IsMapping(candidates))
          throw py::type_error("candidates: expected None, a DIAG.json path or the dict ema.diagnose returns, found " +
                               TypeName(candidates));
        const std::string model_path = IsPath(model_arg) ? PathOf(model_arg) : "";
        const std::string candidates_path = !candidates.is_none() && IsPath(candidates) ? PathOf(candidates) : "";
        const std::string keep_path = PathOrNone(keep, "keep", "an earlier plan (TOML)");
        const std::string output_path = PathOrNone(output, "output", "the plan file to write (TOML)");
        if (!output_path.empty()) {
          try {
            ema::formats::RefuseOutputsOverInputs({{"model", model_path}, {"candidates", candidates_path}, {"keep", keep_path}},
                                                  {{"output", output_path}});
          } catch (const ema::UsageError& e) {
            throw ema::UsageError(std::string("output: ") + e.what());
          }
        }

        const ema::model::Model model = ToModel(model_arg);
        std::vector<ema::planning::Reading> readings;
        std::string candidates_origin;
        if (!candidates.is_none()) {
          std::filesystem::path base_dir;
          const nlohmann::json diagnosis = DiagnosisJsonOf(candidates, &candidates_origin, &base_dir);
          readings = fm::LookAlikeReadings(fm::ReadDiagnosisReadings(diagnosis, candidates_origin, base_dir), candidates_origin);
          // As `ema plan --candidates`: the separations in the noise and the model's own error.
          ema::pipeline::SeparateInModelError(fm::ReadDiagnosisModelError(diagnosis, candidates_origin), &o);
        }
        std::optional<fm::Plan> kept;
        if (!keep_path.empty()) {
          std::error_code ec;
          if (!std::filesystem::exists(keep_path, ec)) throw ema::InputError(keep_path, "plan file not found");
          kept = fm::ReadPlanFile(keep_path);
        }

        // What `ema plan` does with them (formats::PlanFileOf, as app/cmd_plan.cpp): the plan, then
        // the plan file — a kept plan's settings and sets as they were, new sets after.
        std::vector<std::vector<Dof>> kept_sets;
        if (kept)
          for (const fm::RovingSet& s : kept->sets) kept_sets.push_back(s.sensors);
        if (kept && o.setup.empty()) o.setup = kept->setup;  // the kept test's setup
        ema::planning::TestPlan plan =
            ema::planning::PlanTest(model, o, readings, kept_sets, kept ? kept->hammer.references : std::vector<Dof>{});
        if (kept) fm::AdoptKeptSettings(*kept, &plan);
        const fm::Plan file = fm::PlanFileOf(plan, kept, o.setup);

        std::string comment = "Test plan of " + (model_path.empty() ? std::string("a model built in Python") : model_path) +
                              " made by ema.plan (docs/plan.md).";
        if (kept)
          comment += "\nExtends " + keep_path + ": its settings and first " + std::to_string(kept_sets.size()) + " set(s) as they were.";
        if (!candidates.is_none()) comment += "\nSensors placed to tell apart the look-alike readings of " + candidates_origin + ".";
        py::dict d(FromJson(fm::TestPlanJson(plan, !candidates.is_none())));
        d["plan_toml"] = fm::PlanToToml(file, comment);
        if (!output_path.empty()) fm::WritePlanFile(output_path, file, comment);
        return d;
      },
      py::arg("model"), py::kw_only(), py::arg("setup") = "", py::arg("band") = py::none(),
      py::arg("sensors") = plan_defaults.sensors_per_set, py::arg("sets") = plan_defaults.sets,
      py::arg("triaxial") = plan_defaults.triaxial, py::arg("references") = plan_defaults.references,
      py::arg("sensor_mass") = plan_defaults.sensor_mass_kg, py::arg("impacts") = plan_defaults.impacts,
      py::arg("candidates") = py::none(), py::arg("keep") = py::none(), py::arg("output") = py::none(),
      "The test to run next, as `ema plan` (docs/plan.md): sensors that see the band's modes distinctly\n"
      "(effective independence, then exchange; AutoMAC kept below 0.1), hammer references that excite them\n"
      "all, acquisition settings from band and damping — and with `candidates` the sensors that tell a\n"
      "diagnosis's look-alike readings apart.\n\n"
      "model: a model file (TOML), or an FE model built from parts in Python (see help(ema.model_modes)).\n"
      "Keyword options as the CLI's: setup (the model setup the test is made in, '' = nominal), band ((lo, hi)\n"
      "in Hz; None: up to 1.25 x the 6th mode, or the last below a gap of 3x), sensors (mounted at once: test\n"
      "points with triaxial=True, else DOFs), sets (roving sets), triaxial (each sensor measures X, Y and Z at\n"
      "one point), references (hammer DOFs), sensor_mass (kg per sensor point, written to the plan), impacts\n"
      "(per reference and set).\n"
      "candidates: None, the path of a DIAG.json (`ema diagnose --json`), or the dict ema.diagnose returns:\n"
      "  rank 1 and every other candidate within a factor 20 of its probability (at least 0.001; 'none' left\n"
      "  out; at most 10) are the readings the plan separates. A law's relative `file =` path in a dict's\n"
      "  effects resolves against the working folder (ema.diagnose writes laws inline, without files).\n"
      "keep: None or the path of an earlier plan (TOML): its settings and sets stay, `sets` new ones are added.\n"
      "output: None or the path to write the plan file (PLAN.toml, what `ema simulate --plan` reads); an\n"
      "  output naming an input (model, candidates, keep) is refused (ValueError).\n\n"
      "Returns PLAN.json's layout (`ema plan --json`) as a dict: sensors, references, sets [{name, sensors}],\n"
      "modes [{frequency_hz, observability, damping_ratio, reference_participation, excited}],\n"
      "automac_max_offdiagonal, automac, band_hz, acquisition {sample_rate_hz, samples, record_length_s,\n"
      "pulse_duration_s, impacts, sensor_mass_kg}, notes, with candidates separations [{a, b, sigma_before,\n"
      "sigma_after}]; and plan_toml, the text of the plan file. ValueError (ema.InputError / ema.UsageError)\n"
      "for a band holding no model mode, more sensor points than the model has, a diagnosis of another model,\n"
      "an option out of range; TypeError for a band that is not (lo, hi) or an argument of the wrong type.");

  m.def(
      "quality",
      [](const py::object& frfs, const py::object& modes, const py::object& band) {
        std::vector<FrfSet> sets;
        std::vector<std::string> names;
        if (py::isinstance<py::list>(frfs) || py::isinstance<py::tuple>(frfs)) {
          for (auto f : frfs.cast<py::sequence>()) {
            sets.push_back(ToFrfSet(py::reinterpret_borrow<py::object>(f)));
            names.push_back(py::isinstance<py::str>(f) ? f.cast<std::string>() : "frfs " + std::to_string(names.size() + 1));
          }
        } else {
          sets.push_back(ToFrfSet(frfs));
          names.push_back(py::isinstance<py::str>(frfs) ? frfs.cast<std::string>() : "frfs");
        }
        ema::frf::QualityOptions q;
        std::tie(q.band_lo_hz, q.band_hi_hz) = Band(band);
        const auto report = ema::frf::CheckFrfQuality(sets, q, names);
        std::vector<ema::curvefit::ModeComplexityCheck> mc;
        if (!modes.is_none()) mc = ema::curvefit::CheckModeComplexity(ToModeSet(modes));
        return FromJson(ema::formats::QualityJson(report, mc, q));
      },
      py::arg("frfs"), py::arg("modes") = py::none(), py::arg("band") = py::none(),
      "Data-quality checks as `ema quality` (one FRF path/dict or a list of them, e.g. roving hammer and\n"
      "roving sensor): reciprocity, driving points, coherence map, impact-to-impact scatter, and MPC/MPD/MCF\n"
      "of `modes`. Returns the JSON of `ema quality --json` as a dict (verdicts 'pass'/'warn' with reasons).");
}
