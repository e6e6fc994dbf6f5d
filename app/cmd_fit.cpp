// ema fit — FRFs to modes (PolyMAX + stabilisation + automatic selection + LSFD, or peak picking).
#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli.hpp"
#include "ema/core/error.hpp"
#include "ema/curvefit/fit.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/io.hpp"
#include "mode_indicators_json.hpp"
#include "plot_stabilisation.hpp"

namespace ema {

namespace {

double ParseNumber(const std::string& text, const std::string& option) {
  try {
    size_t used = 0;
    const double v = std::stod(text, &used);
    if (used != text.size() || !std::isfinite(v)) throw std::invalid_argument(text);
    return v;
  } catch (const std::exception&) {
    throw UsageError(option + ": expected a number, got '" + text + "'");
  }
}

nlohmann::json Complex(std::complex<double> v) { return nlohmann::json::array({v.real(), v.imag()}); }

nlohmann::json NumberOrNull(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json RefinementJson(const curvefit::FitResult& fit, curvefit::RefineMethod method) {
  const auto& r = fit.refine;
  return {{"method", curvefit::RefineMethodToString(method)},
          {"termination", curvefit::RefineTerminationToString(r.termination)},
          {"noise_source", curvefit::NoiseSourceToString(r.noise_source)},
          {"iterations", r.iterations},
          {"initial_cost", NumberOrNull(r.initial_cost)},
          {"final_cost", NumberOrNull(r.final_cost)},
          {"reduced_chi2", NumberOrNull(r.reduced_chi2)},
          {"message", r.message}};
}

// The fitted modal model (docs/curvefit.md "modal_model"): what the report synthesises FRFs from.
nlohmann::json ModalModelJson(const curvefit::ModalModel& model) {
  nlohmann::json poles = nlohmann::json::array();
  for (const auto& p : model.poles_fitted) poles.push_back(Complex(p));
  nlohmann::json frfs = nlohmann::json::array();
  const int m = static_cast<int>(model.references.size());
  for (int o = 0; o < static_cast<int>(model.outputs.size()); ++o)
    for (int i = 0; i < m; ++i) {
      const int c = o * m + i;
      // Measured orientation: the response is the output unless the fit used reciprocity.
      const Dof& response = model.transposed ? model.references[i] : model.outputs[o];
      const Dof& reference = model.transposed ? model.outputs[o] : model.references[i];
      nlohmann::json residues = nlohmann::json::array();
      for (int r = 0; r < model.residues.cols(); ++r) residues.push_back(Complex(model.residues(c, r)));
      frfs.push_back({{"response_node", response.node},
                      {"response_dir", DirectionName(response.direction)},
                      {"reference_node", reference.node},
                      {"reference_dir", DirectionName(reference.direction)},
                      {"residues", residues},
                      {"lower_residual", c < model.lower_residual.size() ? model.lower_residual[c] : 0.0},
                      {"upper_residual", c < model.upper_residual.size() ? model.upper_residual[c] : 0.0}});
    }
  const char* type = model.frf_type == FrfType::kReceptance ? "receptance"
                     : model.frf_type == FrfType::kMobility ? "mobility"
                                                             : "accelerance";
  return {{"frf_type", type}, {"band_hz", {model.band_lo_hz, model.band_hi_hz}}, {"poles", poles}, {"frfs", frfs}};
}

nlohmann::json ModesJson(const ModeSet& set, const curvefit::FitResult& fit, curvefit::RefineMethod refine) {
  nlohmann::json modes = nlohmann::json::array();
  for (size_t r = 0; r < set.modes.size(); ++r) {
    const Mode& m = set.modes[r];
    nlohmann::json shape = nlohmann::json::array();
    for (size_t d = 0; d < set.dofs.size(); ++d) {
      nlohmann::json entry = {{"node", set.dofs[d].node}, {"dir", DirectionName(set.dofs[d].direction)}, {"value", Complex(m.shape[d])}};
      if (m.shape_std.size() == m.shape.size()) entry["std"] = NumberOrNull(m.shape_std[d]);
      shape.push_back(entry);
    }
    nlohmann::json participation = nlohmann::json::array();
    for (int i = 0; i < m.participation.size(); ++i) participation.push_back(Complex(m.participation[i]));
    nlohmann::json j = {{"frequency_hz", m.frequency_hz},
                        {"damping_ratio", m.damping_ratio},
                        {"frequency_std_hz", NumberOrNull(m.frequency_std_hz)},
                        {"damping_ratio_std", NumberOrNull(m.damping_ratio_std)},
                        {"mpc", NumberOrNull(m.mpc)},
                        {"mpd_deg", NumberOrNull(m.mpd)},
                        {"mcf", NumberOrNull(m.mcf)},
                        {"pole", Complex(m.pole)},
                        {"frequency_spread_hz", NumberOrNull(m.frequency_spread_hz)},
                        {"damping_spread", NumberOrNull(m.damping_spread)},
                        {"unit_modal_mass", m.unit_modal_mass},
                        {"participation", participation},
                        {"shape", shape}};
    if (r < fit.selected.size()) {
      j["order"] = fit.selected[r].pole.order;
      j["cluster_orders"] = fit.selected[r].cluster_size;
    }
    modes.push_back(j);
  }
  nlohmann::json out = {{"modes", modes}, {"synthesis_error", fit.synthesis_error}, {"reciprocity_transposed", fit.transposed}};
  if (!fit.dropped.empty()) {
    nlohmann::json dropped = nlohmann::json::array();
    for (const auto& d : fit.dropped)
      dropped.push_back({{"frequency_hz", d.frequency_hz},
                         {"damping_ratio", d.damping_ratio},
                         {"merged_into_hz", NumberOrNull(d.merged_into_hz)},
                         {"reason", d.reason}});
    out["dropped"] = dropped;
  }
  if (!fit.selected.empty()) {
    out["refinement"] = RefinementJson(fit, refine);
    out["modal_model"] = ModalModelJson(fit.model);
  }
  return out;
}

nlohmann::json StabilisationJson(const curvefit::FitResult& fit, const curvefit::StabilityOptions& stab) {
  const auto& d = fit.diagram;
  nlohmann::json orders = nlohmann::json::array();
  for (size_t k = 0; k < d.orders.size(); ++k) {
    const auto& order = d.orders[k];
    nlohmann::json poles = nlohmann::json::array();
    for (const auto& p : order) {
      nlohmann::json part = nlohmann::json::array();
      for (int i = 0; i < p.participation.size(); ++i) part.push_back(Complex(p.participation[i]));
      poles.push_back({{"frequency_hz", p.frequency_hz},
                       {"damping_ratio", p.damping_ratio},
                       {"pole", Complex(p.lambda)},
                       {"label", std::string(1, p.label)},
                       {"physical", p.physical},
                       {"participation", part}});
    }
    orders.push_back({{"order", d.order_min + static_cast<int>(k)}, {"poles", poles}});
  }
  nlohmann::json selected = nlohmann::json::array();
  for (const auto& s : fit.selected)
    selected.push_back({{"order", s.pole.order},
                        {"frequency_hz", s.pole.frequency_hz},
                        {"damping_ratio", s.pole.damping_ratio},
                        {"frequency_spread_hz", NumberOrNull(s.frequency_spread_hz)},
                        {"damping_spread", NumberOrNull(s.damping_spread)},
                        {"cluster_orders", s.cluster_size}});
  nlohmann::json mif = nlohmann::json::array();
  for (int k = 0; k < d.frequency_hz.size(); ++k) mif.push_back({d.frequency_hz[k], d.sum_frf[k]});
  return {{"band_hz", {d.band_lo_hz, d.band_hi_hz}},
          {"references", d.references},
          {"order_min", d.order_min},
          {"order_max", d.order_max},
          {"criteria", {{"frequency_tol", stab.frequency_tol}, {"damping_tol", stab.damping_tol}, {"mac_min", stab.mac_min}}},
          {"labels", {{"s", "stable (frequency, damping, vector)"}, {"d", "frequency and damping"},
                      {"v", "frequency and vector"}, {"f", "frequency"}, {"o", "new or unstable"}}},
          {"orders", orders},
          {"selected", selected},
          {"sum_frf", mif}};
}

}  // namespace

// Why a fit found no mode (exit 1, nothing written): said in terms of the options to change.
static std::string NoModeReason(const curvefit::FitResult& fit, const curvefit::FitOptions& options, const std::string& select) {
  if (options.method == curvefit::FitMethod::kPeak) return "no mode found: no resonance peak in the band (try --band)";
  const int orders = fit.diagram.order_max;
  std::string why = "no mode found: no pole stayed stable over the PolyMAX orders " + std::to_string(fit.diagram.order_min) +
                    ".." + std::to_string(orders);
  if (orders < 4) why += " (--order-max " + std::to_string(orders) + " is too low: a stable pole must repeat over several orders)";
  return why + "; try a higher --order-max, another --band" + (select == "auto" ? " or --select F1,F2,..." : "");
}

int RunFit(const std::vector<std::string>& args) {
  namespace po = cli::po;
  const std::string usage =
      "ema fit FRF.unv -o MODES.unv [--band LO:HI] [--order-max N] [--select auto|F1,F2,...]\n"
      "        [--json MODES.json] [--stabilisation STAB.json] [--plot STAB.svg|STAB.png] [--method polymax|peak]\n"
      "        [--refine ml|none]";
  po::options_description options("ema fit: FRFs to modes (PolyMAX, stabilisation diagram, automatic selection, LSFD)");
  std::string input, output, band, select = "auto", json_path, stab_path, plot_path, method = "polymax", refine = "ml";
  int order_max = 0, threads = 0;
  curvefit::FitOptions fit_options;
  options.add_options()
      ("input", po::value(&input)->required(), "FRFs: UFF 58 (function type 4), an FRF table or a folder\n"
                                               "of FRF columns with its frfs.csv index (docs/formats.md)")
      ("output,o", po::value(&output)->required(), "mode shapes out (UFF 55 complex modes)")
      ("band", po::value(&band), "analysis band LO:HI in Hz (default: all lines above DC)")
      ("order-max", po::value(&order_max), "highest PolyMAX order (default: ceil(120/references), limited by the lines)")
      ("select", po::value(&select), "auto (default) or a comma-separated list of frequencies in Hz")
      ("json", po::value(&json_path), "modes as JSON (cli.md layout)")
      ("stabilisation", po::value(&stab_path), "stabilisation diagram as JSON")
      ("plot", po::value(&plot_path), "stabilisation diagram picture (.svg or .png)")
      ("method", po::value(&method), "polymax (default) or peak (peak picking, half-power damping)")
      ("refine", po::value(&refine), "ml (default): maximum-likelihood refinement of the poles and residues with\n"
                                     "1-sigma uncertainties; none: PolyMAX/LSFD values (sigma still estimated)")
      ("freq-tol", po::value(&fit_options.stability.frequency_tol), "frequency stability tolerance (default 0.01)")
      ("damping-tol", po::value(&fit_options.stability.damping_tol), "damping stability tolerance (default 0.05)")
      ("mac-min", po::value(&fit_options.stability.mac_min), "vector stability: minimum MAC (default 0.98)")
      ("threads", po::value(&threads), "threads for the per-order stage (default: all cores)");
  cli::AddHelp(&options);
  po::positional_options_description positional;
  positional.add("input", 1);
  po::variables_map vm;
  if (!cli::Parse(args, usage, options, positional, &vm)) return 0;
  cli::RefuseOutputsOverInputs(vm, {"input"}, {"output", "json", "stabilisation", "plot"});

  if (!curvefit::StringToRefineMethod(refine, &fit_options.refine))
    throw UsageError("--refine: expected ml or none, got '" + refine + "'");
  if (method == "peak") fit_options.method = curvefit::FitMethod::kPeak;
  else if (method != "polymax") throw UsageError("--method: expected polymax or peak, got '" + method + "'");
  if (!band.empty()) {
    const auto colon = band.find(':');
    if (colon == std::string::npos) throw UsageError("--band: expected LO:HI in Hz, got '" + band + "'");
    fit_options.data.band_lo_hz = ParseNumber(band.substr(0, colon), "--band");
    fit_options.data.band_hi_hz = ParseNumber(band.substr(colon + 1), "--band");
    if (!(fit_options.data.band_hi_hz > fit_options.data.band_lo_hz) || fit_options.data.band_lo_hz < 0.0)
      throw UsageError("--band: expected 0 <= LO < HI, got '" + band + "'");
  }
  if (vm.count("order-max") && order_max < 1) throw UsageError("--order-max: expected a positive order");
  fit_options.polymax.order_max = order_max;
  if (threads < 0) throw UsageError("--threads: expected 0 (all cores) or a positive count");
  fit_options.polymax.threads = threads;
  if (select != "auto") {
    std::stringstream ss(select);
    std::string item;
    while (std::getline(ss, item, ',')) {
      const double f = ParseNumber(item, "--select");
      if (f <= 0.0) throw UsageError("--select: frequencies must be positive");
      fit_options.select_frequencies_hz.push_back(f);
    }
    if (fit_options.select_frequencies_hz.empty()) throw UsageError("--select: expected auto or F1,F2,...");
  }
  if (!plot_path.empty() && !IsSupportedPlotPath(plot_path))
    throw UsageError("--plot: expected a .svg or .png file name, got '" + plot_path + "'");
  if (fit_options.method == curvefit::FitMethod::kPeak && (!stab_path.empty() || !plot_path.empty()))
    throw UsageError("--stabilisation and --plot need --method polymax");

  // UFF 58, or an FRF table / a folder of FRF columns (formats::ReadFrfTable).
  const FrfSet frfs = formats::ReadFrfSet(input);
  curvefit::FitResult fit;
  try {
    fit = curvefit::Fit(frfs, fit_options, input, [](double f, std::string_view stage) {
      cli::DrawProgress(f, std::string(stage));
    });
  } catch (const InputError& e) {
    const std::string what = e.what();
    if (what.rfind(input, 0) == 0) throw;
    throw InputError(input, what);
  }
  for (const auto& w : fit.warnings) std::cerr << "warning: " << w << "\n";
  if (fit.modes.modes.empty()) throw InputError(input, NoModeReason(fit, fit_options, select));

  fit.modes.source = input;
  if (fit.modes.modes.empty()) {
    // Never a success without a mode (issue 14): say why, keep the diagram for a look.
    if (!stab_path.empty())
      formats::WriteTextFileAtomically(stab_path, StabilisationJson(fit, fit_options.stability).dump(1) + "\n");
    if (!plot_path.empty()) PlotStabilisation(plot_path, fit.diagram, fit.selected);
    std::ostringstream why;
    why << "no mode found";
    if (fit_options.method == curvefit::FitMethod::kPeak)
      why << ": no peak of the summed FRF stands " << fit_options.peak.prominence
          << "x above its valleys with a half-power point in the band";
    else
      why << ": no pole is stable over enough orders " << fit.diagram.order_min << ".." << fit.diagram.order_max
          << " of the stabilisation diagram (" << fit.diagram.frequency_hz.size() << " lines)";
    why << (fit_options.method == curvefit::FitMethod::kPeak
                ? "; widen the band"
                : "; widen the band, raise --order-max, or pick poles with --select F1,F2,...");
    throw InputError(input, why.str());
  }
  formats::WriteModeSet(output, fit.modes);
  if (!json_path.empty()) formats::WriteTextFileAtomically(json_path, ModesJson(fit.modes, fit, fit_options.refine).dump(2) + "\n");
  if (!stab_path.empty()) {
    nlohmann::json stab = StabilisationJson(fit, fit_options.stability);
    AddModeIndicatorsJson(&stab, frfs, fit_options.data, input);  // CMIF/MMIF (docs/quality.md)
    formats::WriteTextFileAtomically(stab_path, stab.dump(1) + "\n");
  }
  if (!plot_path.empty()) PlotStabilisation(plot_path, fit.diagram, fit.selected);

  std::cout << fit.modes.modes.size() << " mode(s) from " << input << " ("
            << (fit_options.method == curvefit::FitMethod::kPeak ? "peak picking" : "PolyMAX");
  if (fit.transposed) std::cout << ", roving hammer fitted by reciprocity";
  std::cout << ")\n";
  const bool any_std = std::any_of(fit.modes.modes.begin(), fit.modes.modes.end(),
                                   [](const Mode& m) { return std::isfinite(m.frequency_std_hz); });
  if (any_std) std::cout << "  " << fit.refine.BriefReport() << "\n";
  std::cout << "  #   f [Hz]               zeta [%]         spread f [Hz]  spread zeta [%]  MPC     MPD [deg]\n";
  for (size_t r = 0; r < fit.modes.modes.size(); ++r) {
    const Mode& m = fit.modes.modes[r];
    std::ostringstream f, z;
    f << std::fixed << std::setprecision(3) << m.frequency_hz;
    z << std::fixed << std::setprecision(3) << 100.0 * m.damping_ratio;
    f.unsetf(std::ios::floatfield);
    z.unsetf(std::ios::floatfield);
    if (std::isfinite(m.frequency_std_hz)) f << " ± " << std::setprecision(2) << m.frequency_std_hz;
    if (std::isfinite(m.damping_ratio_std)) z << " ± " << std::setprecision(2) << 100.0 * m.damping_ratio_std;
    std::cout << std::setw(3) << r + 1 << "  " << std::left << std::setw(21) << f.str() << std::setw(17) << z.str()
              << std::right << std::fixed << std::setprecision(3) << std::setw(12) << m.frequency_spread_hz
              << std::setw(16) << 100.0 * m.damping_spread << std::setw(10) << m.mpc << std::setw(11)
              << std::setprecision(1) << m.mpd << "\n";
  }
  return 0;
}

}  // namespace ema
