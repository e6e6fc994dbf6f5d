// ema frf TIME.unv [TIME2.unv ...] -o FRF.unv [--estimator H1|H2|Hv] [--json SUMMARY.json] (cli.md):
// hammer time records to FRFs + coherences (UFF 58), several files = several roving sets.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <optional>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <tuple>

#include "cli.hpp"
#include "ema/acquisition/hammer_measurement.hpp"
#include "ema/core/error.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/json_codecs.hpp"
#include "stages.hpp"
#include "ema/frf/hammer_frf.hpp"

namespace ema {

namespace {

/// One force-level bin of `ema frf --force-bins/--force-bin-edges`.
struct ForceBin {
  double lo = 0.0, hi = 0.0;          ///< peak-force limits of the bin, N
  std::vector<double> peaks;          ///< peak forces of its impacts
  std::vector<double> rms;            ///< RMS force over each impact's contact
  std::set<std::tuple<std::size_t, int, int, int>> impacts;  ///< (file, reference node, dir, impact)
};

std::string BinPath(const std::string& output, std::size_t bin) {
  std::filesystem::path p(output);
  const std::string ext = p.extension().string();
  p.replace_extension();
  return p.string() + ".bin" + std::to_string(bin + 1) + (ext.empty() ? ".unv" : ext);
}

double Median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Splits the impacts of every file by the peak of their force record: `count` bins of equal
/// numbers of impacts (by rank of the peak force), or the bins between consecutive `edges`
/// (impacts outside the first and last edge are left out).
std::vector<ForceBin> MakeForceBins(const std::vector<acquisition::RecordSet>& sets, int count,
                                    const std::vector<double>& edges, int* left_out) {
  struct Peak {
    double force;
    std::tuple<std::size_t, int, int, int> key;
    double rms = 0.0;  ///< over the contact: the samples around the peak above 10 % of it
  };
  std::vector<Peak> peaks;
  for (std::size_t f = 0; f < sets.size(); ++f)
    for (const TimeRecord& r : sets[f].records) {
      if (r.quantity != Quantity::kForce) continue;
      double peak = 0.0;
      std::size_t at = 0;
      for (std::size_t i = 0; i < r.samples.size(); ++i)
        if (std::abs(r.samples[i]) > peak) peak = std::abs(r.samples[i]), at = i;
      std::size_t lo = at, hi = at;
      while (lo > 0 && std::abs(r.samples[lo - 1]) >= 0.1 * peak) --lo;
      while (hi + 1 < r.samples.size() && std::abs(r.samples[hi + 1]) >= 0.1 * peak) ++hi;
      double ss = 0.0;
      for (std::size_t i = lo; i <= hi; ++i) ss += r.samples[i] * r.samples[i];
      const double rms = r.samples.empty() ? 0.0 : std::sqrt(ss / static_cast<double>(hi - lo + 1));
      peaks.push_back({peak, {f, r.reference.node, r.reference.direction, r.impact}, rms});
    }
  if (peaks.empty()) throw InputError(sets.front().name, "no force records (specific data type 13): nothing to bin by force");
  std::sort(peaks.begin(), peaks.end(), [](const Peak& a, const Peak& b) { return a.force < b.force; });
  std::vector<ForceBin> bins;
  *left_out = 0;
  if (count > 0) {
    if (static_cast<std::size_t>(count) > peaks.size())
      throw InputError(sets.front().name, "--force-bins " + std::to_string(count) + ": only " +
                                              std::to_string(peaks.size()) + " impacts to share out");
    bins.resize(static_cast<std::size_t>(count));
    for (std::size_t i = 0; i < peaks.size(); ++i) {
      ForceBin& b = bins[i * static_cast<std::size_t>(count) / peaks.size()];
      b.peaks.push_back(peaks[i].force);
      b.rms.push_back(peaks[i].rms);
      b.impacts.insert(peaks[i].key);
    }
    for (ForceBin& b : bins) b.lo = b.peaks.front(), b.hi = b.peaks.back();
  } else {
    bins.resize(edges.size() - 1);
    for (std::size_t i = 0; i + 1 < edges.size(); ++i) bins[i].lo = edges[i], bins[i].hi = edges[i + 1];
    for (const Peak& p : peaks) {
      bool placed = false;
      for (std::size_t i = 0; i < bins.size() && !placed; ++i)
        if (p.force >= bins[i].lo && (p.force < bins[i].hi || (i + 1 == bins.size() && p.force <= bins[i].hi))) {
          bins[i].peaks.push_back(p.force);
          bins[i].rms.push_back(p.rms);
          bins[i].impacts.insert(p.key);
          placed = true;
        }
      if (!placed) ++*left_out;
    }
    for (std::size_t i = 0; i < bins.size(); ++i)
      if (bins[i].peaks.empty())
        throw InputError(sets.front().name, "force bin " + std::to_string(i + 1) + " [" + std::to_string(bins[i].lo) +
                                                ", " + std::to_string(bins[i].hi) + "] N holds no impact");
  }
  return bins;
}

void RunFrfBins(const std::vector<acquisition::RecordSet>& sets, const frf::FrfOptions& opt, const std::string& output,
                const std::string& json_path, bool binary, int count, const std::vector<double>& edges, std::ostream& out) {
  int left_out = 0;
  const std::vector<ForceBin> bins = MakeForceBins(sets, count, edges, &left_out);
  std::vector<frf::FrfResult> results;
  for (std::size_t b = 0; b < bins.size(); ++b) {
    std::vector<acquisition::RecordSet> subset;
    for (std::size_t f = 0; f < sets.size(); ++f) {
      acquisition::RecordSet part{sets[f].name, {}};
      for (const TimeRecord& r : sets[f].records)
        if (bins[b].impacts.count({f, r.reference.node, r.reference.direction, r.impact})) part.records.push_back(r);
      if (!part.records.empty()) subset.push_back(std::move(part));
    }
    const acquisition::HammerMeasurement test = acquisition::AssembleHammerMeasurement(std::move(subset));
    results.push_back(frf::EstimateFrfs(test, opt, [&](double f, std::string_view stage) {
      cli::DrawProgress((static_cast<double>(b) + f) / bins.size(), std::string(stage));
    }));
  }
  cli::DrawProgress(1.0, "");
  // Nothing is written unless every bin succeeded.
  formats::WriteOptions write_options;
  write_options.binary = binary;
  nlohmann::json all_frfs = nlohmann::json::array(), bin_json = nlohmann::json::array();
  out << bins.size() << " force-level bin(s) by peak force";
  if (left_out > 0) out << " (" << left_out << " impact(s) outside the edges left out)";
  out << "\n";
  for (std::size_t b = 0; b < bins.size(); ++b) {
    const std::string path = BinPath(output, b);
    formats::WriteFrfSet(path, results[b].frfs, write_options);
    nlohmann::json summary = formats::FrfSummaryJson(results[b]);
    for (auto& e : summary["frfs"]) {
      e["bin"] = b + 1;
      all_frfs.push_back(e);
    }
    const double median = Median(bins[b].peaks);
    bin_json.push_back({{"bin", b + 1},
                        {"file", path},
                        {"level_kind", "peak_force"},
                        {"level", median},
                        {"peak_force_n", median},
                        {"rms_force_n", Median(bins[b].rms)},
                        {"peak_force_min_n", *std::min_element(bins[b].peaks.begin(), bins[b].peaks.end())},
                        {"peak_force_max_n", *std::max_element(bins[b].peaks.begin(), bins[b].peaks.end())},
                        {"lower_edge_n", bins[b].lo},
                        {"upper_edge_n", bins[b].hi},
                        {"impacts", bins[b].peaks.size()},
                        {"summary", summary}});
    out << "  bin " << b + 1 << ": " << bins[b].peaks.size() << " impact(s), peak force " << bins[b].peaks.front()
              << " to " << bins[b].peaks.back() << " N (median " << median << " N), "
              << results[b].summary.frfs.size() << " FRF(s) -> " << path << "\n";
  }
  if (!json_path.empty())
    formats::WriteTextFileAtomically(json_path,
                                     nlohmann::json{{"frfs", all_frfs}, {"bins", bin_json}, {"left_out_impacts", left_out}}
                                             .dump(2) +
                                         "\n");
}

}  // namespace

std::optional<app::FrfConfig> app::ParseFrfArgs(const std::vector<std::string>& args) {
  namespace po = cli::po;
  const std::string usage =
      "ema frf TIME.unv [TIME2.unv ...] -o FRF.unv [--estimator H1|H2|Hv] [--json SUMMARY.json]\n"
      "        [--band LO:HI] [--exp-window auto|none|RATE] [--quantity accelerance|mobility|receptance] ...";
  po::options_description options(
      "ema frf: hammer time records (UFF 58 function type 1, or CSV) to FRFs and coherences (UFF 58).\n"
      "Several files are several roving sets of one test and share the reference");
  FrfConfig config;
  std::string estimator = "H1", band, exp_window = "auto", quantity;
  frf::FrfOptions& opt = config.options;
  acquisition::ImpactOptions& imp = opt.impact;
  bool accept_double_hits = false;
  std::string force_bin_edges;
  options.add_options()
      ("input", po::value(&config.inputs)->required()->multitoken(), "time-data files (one per roving set)")
      ("output,o", po::value(&config.output)->required(), "FRFs out (UFF 58: function type 4 FRFs, type 6 coherences)")
      ("estimator", po::value(&estimator)->default_value(estimator), "H1, H2 or Hv")
      ("json", po::value(&config.json_path), "summary as JSON (cli.md layout)")
      ("band", po::value(&band), "keep lines in LO:HI Hz (default: 0 to Nyquist)")
      ("exp-window", po::value(&exp_window)->default_value(exp_window),
       "auto (only when a response still rings at the record end), none, or a decay rate 1/tau in 1/s")
      ("exp-end-level", cli::Defaulted(&imp.exp_end_level), "auto window: end level as a fraction")
      ("quantity", po::value(&quantity), "output FRF type: accelerance, mobility or receptance (default: as measured)")
      ("trigger-level", cli::Defaulted(&imp.trigger_level), "trigger as a fraction of the force peak")
      ("force-window", cli::Defaulted(&imp.force_window_pulses), "force window: pulse end + this many contact times")
      ("double-hit-ratio", cli::Defaulted(&imp.double_hit_high),
       "double hit: a second pulse above this fraction of the first")
      ("double-hit-autocorrelation", cli::Defaulted(&imp.double_hit_autocorrelation),
       "double hit: force autocorrelation secondary peak above this")
      ("accept-double-hits", po::bool_switch(&accept_double_hits), "keep double hits (force window spans every pulse)")
      ("overload-fraction", cli::Defaulted(&imp.overload_fraction), "overload: peak above this fraction of full scale")
      ("level-tolerance", cli::Defaulted(&imp.level_tolerance),
       "reject impacts whose peak force is off the point's median by more than this fraction")
      ("threads", po::value(&opt.threads), "threads for the transforms (default: all cores; results do not depend on it)")
      ("binary", po::bool_switch(&config.binary), "write 58b (binary) records")
      ("force-bins", po::value(&config.force_bins),
       "split the impacts into N force-level bins of equal counts by the peak of their force record, one FRF\n"
       "set per bin: FRF.bin1.unv (lowest forces), FRF.bin2.unv, ...; levels listed in the JSON summary")
      ("force-bin-edges", po::value(&force_bin_edges),
       "as --force-bins with explicit peak-force edges in N, a,b,c: bins [a,b), [b,c]; impacts outside are left out");
  cli::AddHelp(&options);
  po::positional_options_description positional;
  positional.add("input", -1);
  po::variables_map vm;
  if (!cli::Parse(args, usage, options, positional, &vm)) return std::nullopt;
  cli::RefuseOutputsOverInputs(vm, {"input"}, {"output", "json"});

  try {
    opt.estimator = frf::ParseEstimator(estimator);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--estimator: ") + e.what());
  }
  if (!band.empty()) std::tie(opt.band_lo_hz, opt.band_hi_hz) = cli::ParseBand(band);
  // --exp-window: a mode's name (frf::kExpWindowNames), else a fixed decay rate.
  if (!FromName(frf::kExpWindowNames, exp_window, &imp.exp_window)) {
    imp.exp_window = acquisition::ExpWindowMode::kFixed;
    imp.exp_decay_rate = cli::ParseNumber(exp_window, "--exp-window");
  }
  imp.double_hit_low = std::min(imp.double_hit_low, 0.5 * imp.double_hit_high);
  imp.reject_double_hits = !accept_double_hits;
  if (!quantity.empty() && !FromName(frf::kOutputQuantityNames, quantity, &opt.output_quantity))
    throw UsageError("--quantity: expected " + NameList(frf::kOutputQuantityNames) + ", got '" + quantity + "'");
  if (std::string why; !opt.IsValid(&why)) throw UsageError(why);

  if (vm.count("force-bins") && !force_bin_edges.empty()) throw UsageError("give --force-bins or --force-bin-edges, not both");
  if (vm.count("force-bins") && config.force_bins < 1) throw UsageError("--force-bins: expected a positive number of bins");
  std::vector<double>& edges = config.force_bin_edges;
  if (!force_bin_edges.empty()) {
    std::stringstream ss(force_bin_edges);
    std::string item;
    while (std::getline(ss, item, ',')) edges.push_back(cli::ParseNumber(item, "--force-bin-edges"));
    if (edges.size() < 2) throw UsageError("--force-bin-edges: expected at least two edges a,b[,c...] in N");
    for (std::size_t i = 1; i < edges.size(); ++i)
      if (!(edges[i] > edges[i - 1])) throw UsageError("--force-bin-edges: edges must increase");
  }
  // The bin files are outputs too: none may replace an input (cli.md).
  const std::size_t bin_count = config.force_bins > 0 ? static_cast<std::size_t>(config.force_bins) : edges.empty() ? 0 : edges.size() - 1;
  if (bin_count > 0) {
    std::vector<cli::PathArg> in_args, bin_args;
    for (const std::string& path : config.inputs) in_args.push_back({"input", path});
    for (std::size_t b = 0; b < bin_count; ++b) bin_args.push_back({"-o (bin " + std::to_string(b + 1) + ")", BinPath(config.output, b)});
    cli::RefuseOutputsOverInputs(in_args, bin_args);
  }
  return config;
}

pipeline::FrfStage app::RunFrfStage(const FrfConfig& config, std::ostream& out) {
  const auto progress = [](double f, std::string_view stage) { cli::DrawProgress(f, std::string(stage)); };
  if (config.force_bins > 0 || !config.force_bin_edges.empty()) {
    std::vector<acquisition::RecordSet> sets;
    for (const std::string& path : config.inputs) {
      for (const auto& s : sets)
        if (s.name == path) throw UsageError("file given twice: " + path);
      sets.push_back({path, formats::ReadTimeRecords(path)});
    }
    RunFrfBins(sets, config.options, config.output, config.json_path, config.binary, config.force_bins,
               config.force_bin_edges, out);
    return {};
  }
  pipeline::FrfStage stage = pipeline::EstimateFrfs(config.inputs, config.options, config.binary, progress);
  cli::DrawProgress(1.0, "");
  // Nothing is written unless everything above succeeded; each file goes through a temp + rename.
  WriteFrf(config, stage);
  PrintFrf(stage, out);
  return stage;
}

void app::WriteFrf(const FrfConfig& config, const pipeline::FrfStage& stage) {
  formats::WriteOptions write_options;
  write_options.binary = config.binary;
  formats::WriteFrfSet(config.output, stage.result.frfs, write_options);
  if (!config.json_path.empty())
    formats::WriteTextFileAtomically(config.json_path, formats::FrfSummaryJson(stage.result).dump(2) + "\n");
}

void app::PrintFrf(const pipeline::FrfStage& stage, std::ostream& out) {
  const frf::FrfSummary& s = stage.result.summary;
  const FrfSet& set = stage.result.frfs;
  out << s.frfs.size() << " FRF(s) (" << frf::EstimatorName(s.estimator) << ") from " << s.impacts
      << " impact(s) in " << stage.file_count << " file(s)";
  if (s.roving_hammer) out << ", roving hammer (fixed sensors; the fit uses reciprocity)";
  out << "\n  " << set.LineCount() << " lines, " << set.frequency_hz[0] << " to "
      << set.frequency_hz[set.LineCount() - 1] << " Hz; exponential window: ";
  if (s.window_decay_rate > 0.0) out << "1/tau = " << s.window_decay_rate << " 1/s (recorded for the fit)\n";
  else out << "none\n";
  for (const std::string& n : s.notes) out << "  note: " << n << "\n";
  out << "  response   reference  averages  rejected\n";
  for (const frf::FrfSummaryEntry& e : s.frfs) {
    out << "  " << std::left << std::setw(11) << DofName(e.response) << std::setw(11) << DofName(e.reference)
        << std::right << std::setw(8) << e.averages << "  " << e.rejected.size() << "\n" << std::left;
    for (const frf::RejectedImpact& r : e.rejected)
      out << "      impact " << r.impact << " (" << r.set << "): " << r.reason << "\n";
  }
  out << std::right;
}

int RunFrf(const std::vector<std::string>& args) {
  const std::optional<app::FrfConfig> config = app::ParseFrfArgs(args);
  if (!config) return 0;
  app::RunFrfStage(*config, std::cout);
  return 0;
}

}  // namespace ema
