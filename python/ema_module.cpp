// The `ema` Python module: the library's FRF, fit, correlation and data-quality functions on
// numpy arrays (pybind11). Results are plain dicts of numpy arrays, lists and numbers, with the
// same names and values as the CLI's JSON (python/tests compares them to the last digit).
#include <pybind11/complex.h>
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <Eigen/Core>
#include <cmath>
#include <complex>
#include <string>
#include <vector>

#include "ema/acquisition/hammer_measurement.hpp"
#include "ema/core/error.hpp"
#include "ema/correlation/correlate.hpp"
// The diagnosis moved from correlation/ to its own module (diagnose/); build against either.
#if __has_include("ema/diagnose/diagnose.hpp")
#include "ema/diagnose/diagnose.hpp"
#define EMA_PY_DIAGNOSE_MODULE 1
#else
#include "ema/correlation/diagnose.hpp"
#define EMA_PY_DIAGNOSE_MODULE 0
#endif
#include "ema/correlation/mac.hpp"
#include "ema/curvefit/complexity.hpp"
#include "ema/curvefit/fit.hpp"
#include "ema/curvefit/mode_indicators.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/model/solve.hpp"
#include "ema/frf/hammer_frf.hpp"
#include "ema/frf/quality.hpp"
#include "quality_json.hpp"

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

Dof ToDof(const py::handle& h) {
  if (py::isinstance<py::str>(h)) {
    const std::string t = h.cast<std::string>();
    const auto split = t.find_first_of("+-", 1);
    if (split == std::string::npos) throw py::value_error("DOF '" + t + "': expected e.g. '1+Z'");
    const int dir = ema::ParseDirection(t.substr(split));
    if (dir == 0) throw py::value_error("DOF '" + t + "': unknown direction");
    return {std::stoi(t.substr(0, split)), dir};
  }
  const auto t = h.cast<py::sequence>();
  if (t.size() != 2) throw py::value_error("DOF: expected (node, '+Z')");
  const int dir = py::isinstance<py::str>(t[1]) ? ema::ParseDirection(t[1].cast<std::string>()) : t[1].cast<int>();
  return {t[0].cast<int>(), dir};
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

/// A path (UFF 55/2414) or a dict with "frequency_hz", "dofs", "shapes" (and optionally
/// "damping_ratio").
ModeSet ToModeSet(const py::object& o) {
  if (py::isinstance<py::str>(o) || py::hasattr(o, "__fspath__"))
    return ema::formats::ReadModeSet(py::str(o).cast<std::string>());
  const auto d = o.cast<py::dict>();
  ModeSet set;
  for (auto h : d["dofs"].cast<py::sequence>()) set.dofs.push_back(ToDof(h));
  const auto f = py::array_t<double, py::array::c_style | py::array::forcecast>(d["frequency_hz"]);
  const auto s = py::array_t<std::complex<double>, py::array::c_style | py::array::forcecast>(d["shapes"]);
  if (s.ndim() != 2 || s.shape(0) != static_cast<py::ssize_t>(set.dofs.size()) || s.shape(1) != f.size())
    throw py::value_error("modes['shapes']: expected shape (dofs, modes)");
  py::array_t<double, py::array::c_style | py::array::forcecast> z;
  if (d.contains("damping_ratio")) z = py::array_t<double, py::array::c_style | py::array::forcecast>(d["damping_ratio"]);
  auto sr = s.unchecked<2>();
  for (py::ssize_t r = 0; r < f.size(); ++r) {
    ema::Mode m;
    m.frequency_hz = f.data()[r];
    m.damping_ratio = z.size() == f.size() ? z.data()[r] : 0.0;
    m.pole = ema::FrequencyAndDampingToPole(m.frequency_hz, m.damping_ratio);
    m.shape.resize(static_cast<Eigen::Index>(set.dofs.size()));
    for (py::ssize_t i = 0; i < s.shape(0); ++i) m.shape[i] = sr(i, r);
    set.modes.push_back(std::move(m));
  }
  return set;
}

std::pair<double, double> Band(const py::object& band) {
  if (band.is_none()) return {0.0, 0.0};
  const auto t = band.cast<std::pair<double, double>>();
  if (!(t.second > t.first) || t.first < 0.0) throw py::value_error("band: expected (lo, hi) with 0 <= lo < hi");
  return t;
}

/// nlohmann::json to Python via the json module (plain dict/list/float/None).
py::object FromJson(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

#if EMA_PY_DIAGNOSE_MODULE
namespace dg = ema::diagnose;
#else
namespace dg = ema::correlation;
#endif

py::object Num(double v) { return std::isfinite(v) ? py::object(py::float_(v)) : py::object(py::none()); }

py::dict CandidateDict(const dg::Candidate& c) {
  py::dict d, parameters, uncertainty;
#if EMA_PY_DIAGNOSE_MODULE
  const std::vector<std::string> keys = dg::ParameterKeys(c);
  d["probability"] = Num(c.probability);
  d["mean_agreement_pct"] = Num(c.mean_agreement_pct);
#else
  std::vector<std::string> keys;
  for (const auto& p : c.parameters) keys.push_back(c.effects.size() > 1 ? p.effect_kind + "." + p.name : p.name);
#endif
  for (size_t i = 0; i < c.parameters.size() && i < keys.size(); ++i) {
    parameters[py::str(keys[i])] = c.parameters[i].value;
    uncertainty[py::str(keys[i])] = Num(c.parameters[i].sigma);
  }
  d["rank"] = c.rank;
  d["kind"] = c.kind;
  d["target"] = c.target;
  d["parameters"] = parameters;
  d["uncertainty"] = uncertainty;
  d["mean_abs_frequency_error_pct"] = Num(c.mean_abs_frequency_error_pct);
  d["mean_mac"] = Num(c.mean_mac);
  d["score"] = Num(c.score);
  d["cost"] = Num(c.cost);
  d["explained_pct"] = Num(c.explained_pct);
  d["paired_modes"] = c.paired_modes;
  d["plausible"] = c.plausible;
  d["description"] = dg::DescribeCandidate(c);
  return d;
}

}  // namespace

PYBIND11_MODULE(ema, m) {
  m.doc() =
      "ema: experimental modal analysis (impact-hammer tests -> FRFs -> PolyMAX modes -> correlation with a\n"
      "model -> data quality). The same C++ library as the `ema` command line, on numpy arrays.\n\n"
      "FRF sets are dicts: frequency_hz (n_lines,), outputs/references [(node, '+Z'), ...],\n"
      "h (n_references, n_lines, n_outputs) complex, coherence (same shape) or None, averages\n"
      "(n_references, n_outputs) or None, quantity ('acceleration', 'velocity', 'displacement').\n"
      "Mode sets are dicts: frequency_hz, damping_ratio, pole, mpc, mpd_deg, mcf (n_modes,), dofs\n"
      "[(node, '+Z'), ...], shapes (n_dofs, n_modes) complex, geometry [(id, x, y, z), ...].\n"
      "Functions that take FRFs or modes accept a file path or such a dict.";

  py::register_exception<ema::InputError>(m, "InputError", PyExc_ValueError);
  py::register_exception<ema::UsageError>(m, "UsageError", PyExc_ValueError);

  m.def("read_frfs", [](const py::object& path) { return FrfDict(ToFrfSet(py::str(path))); }, py::arg("path"),
        "Reads FRFs (UFF 58 function type 4 with coherence type 6, or an FRF table/folder) as an FRF dict.");

  m.def("read_modes", [](const py::object& path) { return ModesDict(ToModeSet(py::str(path))); }, py::arg("path"),
        "Reads mode shapes (UFF 55, or FE modes as UFF 2414) with their geometry (15/2411) as a modes dict.");

  m.def(
      "estimate_frfs",
      [](const std::vector<std::string>& paths, const std::string& estimator) {
        std::vector<ema::acquisition::RecordSet> sets;
        for (const auto& p : paths) sets.push_back({p, ema::formats::ReadTimeRecords(p)});
        ema::frf::FrfOptions opt;
        opt.estimator = ema::frf::ParseEstimator(estimator);
        py::gil_scoped_release release;
        const auto result = ema::frf::EstimateFrfs(ema::acquisition::AssembleHammerMeasurement(std::move(sets)), opt);
        py::gil_scoped_acquire acquire;
        return FrfDict(result.frfs);
      },
      py::arg("paths"), py::arg("estimator") = "H1",
      "Hammer time data (UFF 58 type 1, CSV or MATLAB .mat; one file per roving set) to FRFs, as `ema frf`\n"
      "with its default options: impact checks, automatic exponential window, H1/H2/Hv. Returns an FRF dict\n"
      "with coherence and the accepted impacts per FRF ('averages').");

  m.def(
      "fit",
      [](const py::object& frfs, const py::object& band, int order_max, const std::vector<double>& select,
         const std::string& method, const std::string& refine) {
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
        ema::curvefit::FitResult fit;
        {
          py::gil_scoped_release release;
          fit = ema::curvefit::Fit(set, opt, "frfs");
        }
        py::dict d = ModesDict(fit.modes);
        d["synthesis_error"] = fit.synthesis_error;
        d["reciprocity_transposed"] = fit.transposed;
        d["warnings"] = fit.warnings;
        std::vector<int> orders, cluster;
        for (const auto& s : fit.selected) orders.push_back(s.pole.order), cluster.push_back(s.cluster_size);
        d["order"] = orders;
        d["cluster_orders"] = cluster;
        return d;
      },
      py::arg("frfs"), py::arg("band") = py::none(), py::arg("order_max") = 0,
      py::arg("select") = std::vector<double>{}, py::arg("method") = "polymax", py::arg("refine") = "ml",
      "Fits modes to FRFs as `ema fit`: PolyMAX poles for every order up to order_max (0 = automatic),\n"
      "stabilisation, automatic selection (or the poles nearest the frequencies in `select`), LSFD shapes,\n"
      "and the maximum-likelihood refinement (refine='ml', the default; 'none' keeps PolyMAX/LSFD) with the\n"
      "1-sigma frequency_std_hz and damping_ratio_std. band=(lo, hi) in Hz. Returns a modes dict plus\n"
      "synthesis_error, order and cluster_orders.");

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
      [](const std::string& path, const std::string& setup, int max_modes) {
        const ema::model::Model model = ema::formats::ReadModelFile(path);
        ema::model::SolveOptions opt;
        opt.setup = setup;
        opt.max_modes = max_modes;
        py::gil_scoped_release release;
        ModeSet modes = ema::model::Solve(model, opt).modes;
        py::gil_scoped_acquire acquire;
        return ModesDict(modes);
      },
      py::arg("model"), py::arg("setup") = "", py::arg("max_modes") = 0,
      "The model's own modes as `ema model` (a model file, docs/model.md), at the operating point of `setup`\n"
      "(empty: nominal), as a modes dict with the shapes at the model's test points.");

  m.def(
      "mac",
      [](const Eigen::MatrixXcd& a, const Eigen::MatrixXcd& b) { return Mat(ema::correlation::MacMatrix(a, b)); },
      py::arg("a"), py::arg("b"),
      "MAC between every column (mode shape) of a and every column of b (rows/DOFs aligned): |a^H b|^2 / (a^H a b^H b).");

  m.def(
      "correlate",
      [](const py::object& test, const py::object& model, double mac_min) {
        const ModeSet t = ToModeSet(test), mm = ToModeSet(model);
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
        d["unpaired_test"] = r.pairing.unpaired_test;
        d["unpaired_model"] = r.pairing.unpaired_model;
        d["mean_agreement_pct"] = r.mean_agreement_pct;
        d["min_agreement_pct"] = r.min_agreement_pct;
        d["mean_mac"] = r.mean_mac;
        d["shared_dofs"] = r.shared_dof_count;
        d["table"] = ema::correlation::FormatCorrelationTable(r, ema::correlation::TableFormat::kMarkdown);
        return d;
      },
      py::arg("test"), py::arg("model"), py::arg("mac_min") = ema::correlation::CorrelationOptions{}.pairing.mac_min,
      "Test modes against model modes as `ema correlate` (paths or modes dicts): MAC matrix on the shared DOFs,\n"
      "pairing, agreement % = 100 (1 - |f_model - f_test| / f_model); unpaired modes are 0-based indices.");

  m.def(
      "diagnose",
      [](const std::string& model_path, const py::dict& tests, const std::string& criterion) {
        const ema::model::Model model = ema::formats::ReadModelFile(model_path);
        std::vector<dg::SetupModes> sets;
        for (auto item : tests) sets.push_back({item.first.cast<std::string>(), ToModeSet(py::reinterpret_borrow<py::object>(item.second))});
        dg::DiagnoseOptions opt;
#if EMA_PY_DIAGNOSE_MODULE
        if (!criterion.empty() && !dg::StringToCriterion(criterion, &opt.criterion))
          throw py::value_error("criterion: '" + criterion + "' is not one ema diagnose --criterion takes");
#else
        if (criterion == "bic") opt.criterion = dg::InformationCriterion::kBic;
        else if (criterion == "aicc") opt.criterion = dg::InformationCriterion::kAicc;
        else if (!criterion.empty()) throw py::value_error("criterion: expected 'bic' or 'aicc'");
#endif
        dg::Diagnosis d;
        {
          py::gil_scoped_release release;
          d = dg::Diagnose(model, sets, opt);
        }
        py::list candidates;
        for (const auto& c : d.candidates) candidates.append(CandidateDict(c));
        py::dict out;
        out["baseline"] = CandidateDict(d.baseline);
        out["candidates"] = candidates;
        out["explanation"] = d.explanation;
        out["residual_count"] = d.residual_count;
        out["test_modes"] = d.test_mode_count;
        return out;
      },
      py::arg("model"), py::arg("tests"), py::arg("criterion") = "",
      "Which physical effect is the model missing? As `ema diagnose`: `tests` maps a setup name ('' for the\n"
      "nominal model) to its test modes (path or modes dict). Every candidate effect is fitted and ranked by\n"
      "the criterion (criterion='' = the CLI's default); returns {'candidates': [{rank, kind, target, parameters, uncertainty,\n"
      "mean_abs_frequency_error_pct, mean_mac, score, description}, ...] (rank 1 first), 'baseline', ...}.");

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
        return FromJson(ema::QualityJson(report, mc, q));
      },
      py::arg("frfs"), py::arg("modes") = py::none(), py::arg("band") = py::none(),
      "Data-quality checks as `ema quality` (one FRF path/dict or a list of them, e.g. roving hammer and\n"
      "roving sensor): reciprocity, driving points, coherence map, impact-to-impact scatter, and MPC/MPD/MCF\n"
      "of `modes`. Returns the JSON of `ema quality --json` as a dict (verdicts 'pass'/'warn' with reasons).");
}
