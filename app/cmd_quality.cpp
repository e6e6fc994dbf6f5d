// ema quality — can the measurement be trusted? Reciprocity, driving points, coherence map,
// impact-to-impact scatter and (with --modes) the complexity of fitted modes, each with a
// pass/warn verdict and its reason.
#include <iostream>
#include <optional>
#include <sstream>
#include <tuple>

#include "cli.hpp"
#include "ema/core/error.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/quality_json.hpp"
#include "stages.hpp"

namespace ema {

namespace {

/// Human summary: one line per check that warns, counts of those that pass.
std::string QualityText(const frf::FrfQualityReport& q, const std::vector<curvefit::ModeComplexityCheck>& modes) {
  std::ostringstream out;
  auto section = [&](const std::string& name, int n, int warn) {
    out << name << ": " << n << " checked, " << warn << " warn" << (warn == 0 && n > 0 ? " (pass)" : "") << "\n";
  };
  int w = 0;
  for (const auto& c : q.reciprocity) w += c.verdict == frf::Verdict::kWarn;
  section("reciprocity", static_cast<int>(q.reciprocity.size()), w);
  for (const auto& c : q.reciprocity) out << "  " << frf::VerdictToString(c.verdict) << "  " << c.reason << "\n";
  w = 0;
  for (const auto& c : q.driving_points) w += c.verdict == frf::Verdict::kWarn;
  section("driving points", static_cast<int>(q.driving_points.size()), w);
  for (const auto& c : q.driving_points) out << "  " << frf::VerdictToString(c.verdict) << "  " << c.reason << "\n";
  int wc = 0, ws = 0;
  for (const auto& s : q.frfs) {
    wc += s.coherence_verdict == frf::Verdict::kWarn;
    ws += s.scatter_verdict == frf::Verdict::kWarn;
  }
  section("coherence", q.has_coherence ? static_cast<int>(q.frfs.size()) : 0, wc);
  section("impact-to-impact scatter", q.has_averages && q.has_coherence ? static_cast<int>(q.frfs.size()) : 0, ws);
  for (const auto& s : q.frfs)
    if (!s.reason.empty())
      out << "  warn  " << DofName(s.response) << "/" << DofName(s.reference) << ": " << s.reason << "\n";
  if (!modes.empty()) {
    w = 0;
    for (const auto& c : modes) w += c.verdict == frf::Verdict::kWarn;
    section("mode complexity", static_cast<int>(modes.size()), w);
    for (const auto& c : modes) out << "  " << frf::VerdictToString(c.verdict) << "  " << c.reason << "\n";
  }
  for (const auto& n : q.notes) out << "note: " << n << "\n";
  return out.str();
}

}  // namespace

std::optional<app::QualityConfig> app::ParseQualityArgs(const std::vector<std::string>& args) {
  namespace po = cli::po;
  const std::string usage =
      "ema quality FRF.unv [FRF2.unv ...] [--modes MODES.unv] [--json Q.json] [--band LO:HI]\n"
      "ema quality --modes MODES.unv [--json Q.json]\n"
      "        [--reciprocity-tol X] [--coherence-min X] [--scatter-max X] [--mpc-min X] [--mpd-max DEG]";
  po::options_description options(
      "ema quality: data-quality checks before (and after) fitting, each with a pass/warn verdict.\n"
      "Several FRF files of one structure (e.g. roving hammer and roving sensor) are compared for\n"
      "reciprocity (H_ij against H_ji)");
  QualityConfig config;
  std::string band;
  frf::QualityOptions& q = config.quality;
  curvefit::ComplexityOptions& c = config.complexity;
  options.add_options()
      ("input", po::value(&config.inputs)->multitoken(), "FRF files (UFF 58 type 4 + coherence type 6, or FRF tables); "
       "none with --modes: the modes' checks alone")
      ("modes", po::value(&config.modes_path), "fitted modes (UFF 55): MPC, MPD and MCF per mode")
      ("json", po::value(&config.json_path), "numbers and verdicts as JSON (cli.md, ema quality)")
      ("band", po::value(&band), "band LO:HI in Hz of the FRF checks (default: all lines above DC)")
      ("reciprocity-tol", cli::Defaulted(&q.reciprocity_tolerance), "relative difference ||Hij-Hji||/mean norm that passes")
      ("coherence-min", cli::Defaulted(&q.coherence_min), "coherence counted as low below this")
      ("coherence-low-max", cli::Defaulted(&q.coherence_max_low_fraction), "fraction of low-coherence lines that passes")
      ("scatter-max", cli::Defaulted(&q.scatter_max), "median normalised random error of |H| that passes")
      ("mpc-min", cli::Defaulted(&c.mpc_min), "modes with a lower MPC warn")
      ("mpd-max", cli::Defaulted(&c.mpd_max_deg), "modes with a larger MPD [deg] warn");
  cli::AddHelp(&options);
  po::positional_options_description positional;
  positional.add("input", -1);
  po::variables_map vm;
  if (!cli::Parse(args, usage, options, positional, &vm)) return std::nullopt;
  if (config.inputs.empty() && config.modes_path.empty())
    throw UsageError("ema quality needs FRF files (FRF.unv ...), or --modes MODES.unv for the modes' checks alone");
  cli::RefuseOutputsOverInputs(vm, {"input", "modes"}, {"json"});
  if (!band.empty()) std::tie(q.band_lo_hz, q.band_hi_hz) = cli::ParseBand(band);
  std::string error;
  if (!q.IsValid(&error)) throw UsageError(error);
  if (!c.IsValid(&error)) throw UsageError(error);
  return config;
}

app::QualityStageResult app::RunQualityStage(const QualityConfig& config, const std::vector<FrfSet>& sets,
                                             const std::optional<ModeSet>& modes_in, std::ostream& out) {
  const std::vector<std::string>& inputs = config.inputs;
  QualityStageResult stage;
  stage.frfs = frf::CheckFrfQuality(sets, config.quality, inputs);
  if (modes_in) stage.modes = curvefit::CheckModeComplexity(*modes_in, config.complexity);
  stage.json = formats::QualityJson(stage.frfs, stage.modes, config.quality);
  const nlohmann::json& j = stage.json;
  if (!config.json_path.empty()) formats::WriteTextFileAtomically(config.json_path, j.dump(1) + "\n");
  const std::string what = !inputs.empty() ? inputs.front() : config.modes_path;
  out << "data quality of " << what << (inputs.size() > 1 ? " (+" + std::to_string(inputs.size() - 1) + ")" : "")
      << ": " << j["verdict"].get<std::string>() << " (" << j["warnings"].get<int>() << " warning(s))\n"
      << QualityText(stage.frfs, stage.modes);
  return stage;
}

int RunQuality(const std::vector<std::string>& args) {
  const std::optional<app::QualityConfig> config = app::ParseQualityArgs(args);
  if (!config) return 0;
  std::vector<FrfSet> sets;
  for (const auto& path : config->inputs) sets.push_back(formats::ReadFrfSet(path));
  std::optional<ModeSet> modes;
  if (!config->modes_path.empty()) modes = formats::ReadModeSet(config->modes_path);
  app::RunQualityStage(*config, sets, modes, std::cout);
  return 0;
}

}  // namespace ema
