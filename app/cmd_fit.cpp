// ema fit — FRFs to modes (PolyMAX + stabilisation + automatic selection + LSFD, or peak picking).
#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <optional>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli.hpp"
#include "ema/core/error.hpp"
#include "ema/curvefit/fit.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/json_codecs.hpp"
#include "ema/formats/mode_indicators_json.hpp"
#include "ema/pipeline/json.hpp"
#include "stages.hpp"
#include "plot_stabilisation.hpp"

namespace ema {

std::optional<app::FitConfig> app::ParseFitArgs(const std::vector<std::string>& args, bool require_input,
                                                const curvefit::FitOptions& base, const std::string& usage_given) {
  namespace po = cli::po;
  const std::string usage = !usage_given.empty() ? usage_given :
      "ema fit FRF.unv -o MODES.unv [--band LO:HI] [--order-max N] [--select auto|F1,F2,...]\n"
      "        [--json MODES.json] [--stabilisation STAB.json] [--plot STAB.svg|STAB.png] [--method polymax|peak]\n"
      "        [--refine ml|none]";
  po::options_description options("ema fit: FRFs to modes (PolyMAX, stabilisation diagram, automatic selection, LSFD)");
  FitConfig config;
  config.options = base;
  std::string band, select = "auto", method = "polymax", refine = "ml";
  int order_max = 0, threads = 0;
  curvefit::FitOptions& fit_options = config.options;
  auto input = po::value(&config.input), output = po::value(&config.output);
  if (require_input) input->required(), output->required();
  options.add_options()
      ("input", input, "FRFs: UFF 58 (function type 4), an FRF table or a folder\n"
                       "of FRF columns with its frfs.csv index (docs/formats.md)")
      ("output,o", output, "mode shapes out (UFF 55 complex modes)")
      ("band", po::value(&band), "analysis band LO:HI in Hz (default: all lines above DC)")
      ("order-max", po::value(&order_max), "highest PolyMAX order (default: ceil(120/references), limited by the lines)")
      ("select", po::value(&select), "auto (default) or a comma-separated list of frequencies in Hz")
      ("json", po::value(&config.json_path), "modes as JSON (cli.md layout)")
      ("stabilisation", po::value(&config.stabilisation_path), "stabilisation diagram as JSON")
      ("plot", po::value(&config.plot_path), "stabilisation diagram picture (.svg or .png)")
      ("method", po::value(&method), "polymax (default) or peak (peak picking, half-power damping)")
      ("refine", po::value(&refine), "ml (default): maximum-likelihood refinement of the poles and residues with\n"
                                     "1-sigma uncertainties; none: PolyMAX/LSFD values (sigma still estimated)")
      ("freq-tol", cli::Defaulted(&fit_options.stability.frequency_tol), "frequency stability tolerance")
      ("damping-tol", cli::Defaulted(&fit_options.stability.damping_tol), "damping stability tolerance")
      ("mac-min", cli::Defaulted(&fit_options.stability.mac_min), "vector stability: minimum MAC")
      ("threads", po::value(&threads), "threads for the per-order stage (default: all cores)");
  cli::AddHelp(&options);
  po::positional_options_description positional;
  positional.add("input", 1);
  po::variables_map vm;
  if (!cli::Parse(args, usage, options, positional, &vm)) return std::nullopt;
  cli::RefuseOutputsOverInputs(vm, {"input"}, {"output", "json", "stabilisation", "plot"});

  // Only what the arguments give replaces `base`.
  if (vm.count("refine") && !curvefit::StringToRefineMethod(refine, &fit_options.refine))
    throw UsageError("--refine: expected ml or none, got '" + refine + "'");
  if (vm.count("method") && !FromName(curvefit::kFitMethodNames, method, &fit_options.method))
    throw UsageError("--method: expected " + NameList(curvefit::kFitMethodNames) + ", got '" + method + "'");
  if (!band.empty()) std::tie(fit_options.data.band_lo_hz, fit_options.data.band_hi_hz) = cli::ParseBand(band);
  if (vm.count("order-max") && order_max < 1) throw UsageError("--order-max: expected a positive order");
  if (vm.count("order-max")) fit_options.polymax.order_max = order_max;
  if (vm.count("threads")) fit_options.polymax.threads = threads;
  if (vm.count("select")) fit_options.select_frequencies_hz = ParseSelect(select);
  if (std::string why; !fit_options.IsValid(&why)) throw UsageError(why);
  if (!config.plot_path.empty() && !IsSupportedPlotPath(config.plot_path))
    throw UsageError("--plot: expected a .svg or .png file name, got '" + config.plot_path + "'");
  if (fit_options.method == curvefit::FitMethod::kPeak && (!config.stabilisation_path.empty() || !config.plot_path.empty()))
    throw UsageError("--stabilisation and --plot need --method polymax");

  return config;
}

std::vector<double> app::ParseSelect(const std::string& select) {
  std::vector<double> frequencies_hz;
  if (select == "auto") return frequencies_hz;
  std::stringstream ss(select);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const double f = cli::ParseNumber(item, "--select");
    if (f <= 0.0) throw UsageError("--select: frequencies must be positive");
    frequencies_hz.push_back(f);
  }
  if (frequencies_hz.empty()) throw UsageError("--select: expected auto or F1,F2,...");
  return frequencies_hz;
}

pipeline::FitStage app::RunFitStage(const FitConfig& config, const FrfSet& frfs, std::ostream& out) {
  pipeline::FitStage stage = pipeline::FitModes(frfs, config.options, config.input, config.output,
                                                [](double f, std::string_view stage) { cli::DrawProgress(f, std::string(stage)); });
  WriteFit(config, stage, frfs);
  PrintFit(config, stage, out);
  return stage;
}

void app::WriteFit(const FitConfig& config, const pipeline::FitStage& stage, const FrfSet& frfs) {
  // Everything is computed before the first file is written.
  const nlohmann::json modes_json = config.json_path.empty() ? nlohmann::json() : pipeline::FitModesJson(stage, frfs);
  const nlohmann::json stabilisation_json =
      config.stabilisation_path.empty() ? nlohmann::json() : pipeline::FitStabilisationJson(stage, frfs, config.input);
  formats::WriteModeSet(config.output, stage.fit.modes);
  if (!config.json_path.empty()) formats::WriteTextFileAtomically(config.json_path, modes_json.dump(2) + "\n");
  if (!config.stabilisation_path.empty())
    formats::WriteTextFileAtomically(config.stabilisation_path, stabilisation_json.dump(1) + "\n");
  if (!config.plot_path.empty()) PlotStabilisation(config.plot_path, stage.fit.diagram, stage.fit.selected);
}

void app::PrintFit(const FitConfig& config, const pipeline::FitStage& stage, std::ostream& out) {
  const curvefit::FitResult& fit = stage.fit;
  const curvefit::FitOptions& fit_options = stage.options;
  for (const auto& w : fit.warnings) std::cerr << "warning: " << w << "\n";
  // What the fit handled itself is said, not warned about: nothing is left for the user to do.
  for (const auto& d : fit.dropped) {
    char hz[32];
    std::snprintf(hz, sizeof hz, "%.2f", d.frequency_hz);
    out << "note: " << config.input << ": pole at " << hz << " Hz dropped: " << d.reason << "\n";
  }
  out << fit.modes.modes.size() << " mode(s) from " << config.input << " ("
      << (fit_options.method == curvefit::FitMethod::kPeak ? "peak picking" : "PolyMAX");
  if (fit.transposed) out << ", roving hammer fitted by reciprocity";
  out << ")\n";
  if (fit_options.method != curvefit::FitMethod::kPeak)
    out << "  orders " << fit.diagram.order_min << ".." << fit.diagram.order_max
        << (fit.diagram.zoom_mapped ? " (zoom band: its lines spread over the unit circle)" : "") << ", selection "
        << fit.selection_rule << "\n";
  const bool any_std = std::any_of(fit.modes.modes.begin(), fit.modes.modes.end(),
                                   [](const Mode& m) { return std::isfinite(m.frequency_std_hz); });
  if (any_std) out << "  " << fit.refine.BriefReport() << "\n";
  out << "  #   f [Hz]               zeta [%]         spread f [Hz]  spread zeta [%]  MPC     MPD [deg]\n";
  const auto flags = out.flags();
  const auto precision = out.precision();
  for (size_t r = 0; r < fit.modes.modes.size(); ++r) {
    const Mode& m = fit.modes.modes[r];
    std::ostringstream f, z;
    f << std::fixed << std::setprecision(3) << m.frequency_hz;
    z << std::fixed << std::setprecision(3) << 100.0 * m.damping_ratio;
    f.unsetf(std::ios::floatfield);
    z.unsetf(std::ios::floatfield);
    if (std::isfinite(m.frequency_std_hz)) f << " ± " << std::setprecision(2) << m.frequency_std_hz;
    if (std::isfinite(m.damping_ratio_std)) z << " ± " << std::setprecision(2) << 100.0 * m.damping_ratio_std;
    out << std::setw(3) << r + 1 << "  " << std::left << std::setw(21) << f.str() << std::setw(17) << z.str()
        << std::right << std::fixed << std::setprecision(3) << std::setw(12) << m.frequency_spread_hz
        << std::setw(16) << 100.0 * m.damping_spread << std::setw(10) << m.mpc << std::setw(11)
        << std::setprecision(1) << m.mpd << "\n";
  }
  out.flags(flags);
  out.precision(precision);
}

int RunFit(const std::vector<std::string>& args) {
  const std::optional<app::FitConfig> config = app::ParseFitArgs(args);
  if (!config) return 0;
  // UFF 58, or an FRF table / a folder of FRF columns (formats::ReadFrfSet).
  const FrfSet frfs = formats::ReadFrfSet(config->input);
  app::RunFitStage(*config, frfs, std::cout);
  return 0;
}

}  // namespace ema
