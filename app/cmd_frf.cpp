// ema frf TIME.unv [TIME2.unv ...] -o FRF.unv [--estimator H1|H2|Hv] [--json SUMMARY.json] (cli.md):
// hammer time records to FRFs + coherences (UFF 58), several files = several roving sets.
#include <cmath>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli.hpp"
#include "ema/acquisition/hammer_test.hpp"
#include "ema/core/error.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/io.hpp"
#include "ema/frf/hammer_frf.hpp"

namespace ema {

namespace {

double ParseNumber(const std::string& text, const std::string& option) {
  try {
    size_t used = 0;
    const double v = std::stod(text, &used);
    if (used == text.size() && std::isfinite(v)) return v;
  } catch (const std::exception&) {
  }
  throw UsageError(option + ": expected a number, got '" + text + "'");
}

nlohmann::json SummaryJson(const frf::FrfResult& result) {
  const frf::FrfSummary& s = result.summary;
  const FrfSet& set = result.frfs;
  nlohmann::json frfs = nlohmann::json::array();
  for (const frf::FrfSummaryEntry& e : s.frfs) {
    nlohmann::json rejected = nlohmann::json::array();
    for (const frf::RejectedImpact& r : e.rejected)
      rejected.push_back({{"impact", r.impact}, {"reason", r.reason}, {"file", r.set}});
    frfs.push_back({{"response_node", e.response.node},
                    {"response_dir", DirectionName(e.response.direction)},
                    {"reference_node", e.reference.node},
                    {"reference_dir", DirectionName(e.reference.direction)},
                    {"averages", e.averages},
                    {"rejected", rejected}});
  }
  const int lines = set.LineCount();
  return {{"frfs", frfs},
          {"estimator", frf::EstimatorName(s.estimator)},
          {"window_decay_rate", s.window_decay_rate},
          {"roving_hammer", s.roving_hammer},
          {"impacts", s.impacts},
          {"rejected_impacts", s.rejected_impacts},
          {"lines", lines},
          {"frequency_min_hz", lines > 0 ? set.frequency_hz[0] : 0.0},
          {"frequency_max_hz", lines > 0 ? set.frequency_hz[lines - 1] : 0.0},
          {"notes", s.notes}};
}

}  // namespace

int RunFrf(const std::vector<std::string>& args) {
  namespace po = cli::po;
  const std::string usage =
      "ema frf TIME.unv [TIME2.unv ...] -o FRF.unv [--estimator H1|H2|Hv] [--json SUMMARY.json]\n"
      "        [--band LO:HI] [--exp-window auto|none|RATE] [--quantity accelerance|mobility|receptance] ...";
  po::options_description options(
      "ema frf: hammer time records (UFF 58 function type 1, or CSV) to FRFs and coherences (UFF 58).\n"
      "Several files are several roving sets of one test and share the reference");
  std::vector<std::string> inputs;
  std::string output, estimator = "H1", json_path, band, exp_window = "auto", quantity;
  frf::FrfOptions opt;
  acquisition::ImpactOptions& imp = opt.impact;
  bool accept_double_hits = false, binary = false;
  options.add_options()
      ("input", po::value(&inputs)->required()->multitoken(), "time-data files (one per roving set)")
      ("output,o", po::value(&output)->required(), "FRFs out (UFF 58: function type 4 FRFs, type 6 coherences)")
      ("estimator", po::value(&estimator), "H1 (default), H2 or Hv")
      ("json", po::value(&json_path), "summary as JSON (cli.md layout)")
      ("band", po::value(&band), "keep lines in LO:HI Hz (default: 0 to Nyquist)")
      ("exp-window", po::value(&exp_window),
       "auto (default: only when a response still rings at the record end), none, or a decay rate 1/tau in 1/s")
      ("exp-end-level", po::value(&imp.exp_end_level), "auto window: end level as a fraction (default 0.01)")
      ("quantity", po::value(&quantity), "output FRF type: accelerance, mobility or receptance (default: as measured)")
      ("trigger-level", po::value(&imp.trigger_level), "trigger as a fraction of the force peak (default 0.10)")
      ("force-window", po::value(&imp.force_window_pulses), "force window: pulse end + this many contact times (default 3)")
      ("double-hit-ratio", po::value(&imp.double_hit_high),
       "double hit: a second pulse above this fraction of the first (default 0.07)")
      ("double-hit-autocorrelation", po::value(&imp.double_hit_autocorrelation),
       "double hit: force autocorrelation secondary peak above this (default 0.05)")
      ("accept-double-hits", po::bool_switch(&accept_double_hits), "keep double hits (force window spans every pulse)")
      ("overload-fraction", po::value(&imp.overload_fraction), "overload: peak above this fraction of full scale (default 0.95)")
      ("level-tolerance", po::value(&imp.level_tolerance),
       "reject impacts whose peak force is off the point's median by more than this fraction (default 0.5)")
      ("threads", po::value(&opt.threads), "threads for the transforms (default: all cores; results do not depend on it)")
      ("binary", po::bool_switch(&binary), "write 58b (binary) records");
  cli::AddHelp(&options);
  po::positional_options_description positional;
  positional.add("input", -1);
  po::variables_map vm;
  if (!cli::Parse(args, usage, options, positional, &vm)) return 0;
  cli::RefuseOutputsOverInputs(vm, {"input"}, {"output", "json"});

  try {
    opt.estimator = frf::ParseEstimator(estimator);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--estimator: ") + e.what());
  }
  if (!band.empty()) {
    const auto colon = band.find(':');
    if (colon == std::string::npos) throw UsageError("--band: expected LO:HI in Hz, got '" + band + "'");
    opt.band_lo_hz = ParseNumber(band.substr(0, colon), "--band");
    opt.band_hi_hz = ParseNumber(band.substr(colon + 1), "--band");
    if (!(opt.band_hi_hz > opt.band_lo_hz) || opt.band_lo_hz < 0.0)
      throw UsageError("--band: expected 0 <= LO < HI, got '" + band + "'");
  }
  if (exp_window == "auto") {
    imp.exp_window = acquisition::ExpWindowMode::kAuto;
  } else if (exp_window == "none") {
    imp.exp_window = acquisition::ExpWindowMode::kNone;
  } else {
    imp.exp_window = acquisition::ExpWindowMode::kFixed;
    imp.exp_decay_rate = ParseNumber(exp_window, "--exp-window");
    if (imp.exp_decay_rate < 0.0) throw UsageError("--exp-window: the decay rate must be >= 0");
  }
  if (!(imp.exp_end_level > 0.0 && imp.exp_end_level < 1.0)) throw UsageError("--exp-end-level: expected 0 < level < 1");
  if (!(imp.trigger_level > 0.0 && imp.trigger_level < 1.0)) throw UsageError("--trigger-level: expected 0 < level < 1");
  if (!(imp.double_hit_high > 0.0 && imp.double_hit_high < 1.0))
    throw UsageError("--double-hit-ratio: expected 0 < ratio < 1");
  imp.double_hit_low = std::min(imp.double_hit_low, 0.5 * imp.double_hit_high);
  imp.reject_double_hits = !accept_double_hits;
  if (!quantity.empty()) {
    if (quantity == "accelerance") opt.output_quantity = Quantity::kAcceleration;
    else if (quantity == "mobility") opt.output_quantity = Quantity::kVelocity;
    else if (quantity == "receptance") opt.output_quantity = Quantity::kDisplacement;
    else throw UsageError("--quantity: expected accelerance, mobility or receptance, got '" + quantity + "'");
  }

  std::vector<acquisition::RecordSet> sets;
  for (const std::string& path : inputs) {
    for (const auto& s : sets)
      if (s.name == path) throw UsageError("file given twice: " + path);
    sets.push_back({path, formats::ReadTimeRecords(path)});
  }
  const acquisition::HammerTest test = acquisition::AssembleHammerTest(std::move(sets));
  const frf::FrfResult result =
      frf::EstimateFrfs(test, opt, [](double f, std::string_view stage) { cli::DrawProgress(f, std::string(stage)); });
  cli::DrawProgress(1.0, "");

  // Nothing is written unless everything above succeeded; each file goes through a temp + rename.
  formats::WriteOptions write_options;
  write_options.binary = binary;
  formats::WriteFrfSet(output, result.frfs, write_options);
  if (!json_path.empty()) formats::WriteTextFileAtomically(json_path, SummaryJson(result).dump(2) + "\n");

  const frf::FrfSummary& s = result.summary;
  const FrfSet& set = result.frfs;
  std::cout << s.frfs.size() << " FRF(s) (" << frf::EstimatorName(s.estimator) << ") from " << s.impacts
            << " impact(s) in " << inputs.size() << " file(s)";
  if (s.roving_hammer) std::cout << ", roving hammer (fixed sensors; the fit uses reciprocity)";
  std::cout << "\n  " << set.LineCount() << " lines, " << set.frequency_hz[0] << " to "
            << set.frequency_hz[set.LineCount() - 1] << " Hz; exponential window: ";
  if (s.window_decay_rate > 0.0) std::cout << "1/tau = " << s.window_decay_rate << " 1/s (recorded for the fit)\n";
  else std::cout << "none\n";
  for (const std::string& n : s.notes) std::cout << "  note: " << n << "\n";
  std::cout << "  response   reference  averages  rejected\n";
  for (const frf::FrfSummaryEntry& e : s.frfs) {
    std::cout << "  " << std::left << std::setw(11) << DofName(e.response) << std::setw(11) << DofName(e.reference)
              << std::right << std::setw(8) << e.averages << "  " << e.rejected.size() << "\n" << std::left;
    for (const frf::RejectedImpact& r : e.rejected)
      std::cout << "      impact " << r.impact << " (" << r.set << "): " << r.reason << "\n";
  }
  std::cout << std::right;
  return 0;
}

}  // namespace ema
