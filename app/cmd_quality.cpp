// ema quality — can the measurement be trusted? Reciprocity, driving points, coherence map,
// impact-to-impact scatter and (with --modes) the complexity of fitted modes, each with a
// pass/warn verdict and its reason.
#include <iostream>

#include "cli.hpp"
#include "ema/core/error.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/io.hpp"
#include "quality_json.hpp"

namespace ema {

int RunQuality(const std::vector<std::string>& args) {
  namespace po = cli::po;
  const std::string usage =
      "ema quality FRF.unv [FRF2.unv ...] [--modes MODES.unv] [--json Q.json] [--band LO:HI]\n"
      "        [--reciprocity-tol X] [--coherence-min X] [--scatter-max X] [--mpc-min X] [--mpd-max DEG]";
  po::options_description options(
      "ema quality: data-quality checks before (and after) fitting, each with a pass/warn verdict.\n"
      "Several FRF files of one structure (e.g. roving hammer and roving sensor) are compared for\n"
      "reciprocity (H_ij against H_ji)");
  std::vector<std::string> inputs;
  std::string modes_path, json_path, band;
  frf::QualityOptions q;
  curvefit::ComplexityOptions c;
  options.add_options()
      ("input", po::value(&inputs)->required()->multitoken(), "FRF files (UFF 58 type 4 + coherence type 6, or FRF tables)")
      ("modes", po::value(&modes_path), "fitted modes (UFF 55): MPC, MPD and MCF per mode")
      ("json", po::value(&json_path), "numbers and verdicts as JSON (cli.md, ema quality)")
      ("band", po::value(&band), "band LO:HI in Hz of the FRF checks (default: all lines above DC)")
      ("reciprocity-tol", po::value(&q.reciprocity_tolerance), "relative difference ||Hij-Hji||/mean norm that passes (default 0.05)")
      ("coherence-min", po::value(&q.coherence_min), "coherence counted as low below this (default 0.9)")
      ("coherence-low-max", po::value(&q.coherence_max_low_fraction), "fraction of low-coherence lines that passes (default 0.2)")
      ("scatter-max", po::value(&q.scatter_max), "median normalised random error of |H| that passes (default 0.1)")
      ("mpc-min", po::value(&c.mpc_min), "modes with a lower MPC warn (default 0.9)")
      ("mpd-max", po::value(&c.mpd_max_deg), "modes with a larger MPD [deg] warn (default 10)");
  cli::AddHelp(&options);
  po::positional_options_description positional;
  positional.add("input", -1);
  po::variables_map vm;
  if (!cli::Parse(args, usage, options, positional, &vm)) return 0;
  cli::RefuseOutputsOverInputs(vm, {"input", "modes"}, {"json"});
  if (!band.empty()) {
    const auto colon = band.find(':');
    try {
      if (colon == std::string::npos) throw std::invalid_argument(band);
      q.band_lo_hz = std::stod(band.substr(0, colon));
      q.band_hi_hz = std::stod(band.substr(colon + 1));
    } catch (const std::exception&) {
      throw UsageError("--band: expected LO:HI in Hz, got '" + band + "'");
    }
  }
  std::string error;
  if (!q.IsValid(&error)) throw UsageError(error);
  if (!c.IsValid(&error)) throw UsageError(error);

  std::vector<FrfSet> sets;
  for (const auto& path : inputs) sets.push_back(formats::ReadFrfSet(path));
  const frf::FrfQualityReport report = frf::CheckFrfQuality(sets, q, inputs);
  std::vector<curvefit::ModeComplexityCheck> modes;
  if (!modes_path.empty()) modes = curvefit::CheckModeComplexity(formats::ReadModeSet(modes_path), c);

  const nlohmann::json j = QualityJson(report, modes, q);
  if (!json_path.empty()) formats::WriteTextFileAtomically(json_path, j.dump(1) + "\n");
  std::cout << "data quality of " << inputs.front() << (inputs.size() > 1 ? " (+" + std::to_string(inputs.size() - 1) + ")" : "")
            << ": " << j["verdict"].get<std::string>() << " (" << j["warnings"].get<int>() << " warning(s))\n"
            << QualityText(report, modes);
  return 0;
}

}  // namespace ema
