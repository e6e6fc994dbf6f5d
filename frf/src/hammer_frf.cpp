#include "ema/frf/hammer_frf.hpp"

#include <algorithm>
#include <memory>
#include <thread>
#include <cstdio>
#include <map>
#include <stdexcept>

#include "ema/core/error.hpp"
#include "ema/core/parallel.hpp"
#include "ema/frf/fft.hpp"

namespace ema::frf {

using acquisition::HammerMeasurement;
using acquisition::Impact;
using acquisition::ImpactAnalysis;

FrfResult EstimateFrfs(const HammerMeasurement& test, const FrfOptions& options, const ProgressCallback& progress) {
  if (test.impacts.empty()) throw InputError("", "the hammer test holds no impact");
  // Progress: the impacts' analysis is the first half, the spectra (to 0.95) and the FRFs from them
  // the second ("FRF"), 1 when done. Every step, from whichever worker thread, is also where a
  // callback that throws (a cancellation) stops the estimation.
  ProgressCallback analysis_progress;
  if (progress)
    analysis_progress = [&progress](double f, std::string_view stage) { progress(0.5 * f, stage); };
  const acquisition::ProcessedTest processed = acquisition::AnalyseImpacts(test, options.impact, analysis_progress);
  const int n = test.samples;
  const int n_refs = static_cast<int>(test.references.size());
  const int n_out = static_cast<int>(test.outputs.size());
  auto ref_index = [&](const Dof& d) {
    return static_cast<int>(std::find(test.references.begin(), test.references.end(), d) - test.references.begin());
  };
  auto out_index = [&](const Dof& d) {
    return static_cast<int>(std::find(test.outputs.begin(), test.outputs.end(), d) - test.outputs.begin());
  };

  // One accumulator per measured (reference, output) FRF, in order of first appearance.
  std::map<std::pair<int, int>, int> bucket_of;
  std::vector<std::pair<int, int>> keys;
  std::vector<Quantity> bucket_quantity;
  std::vector<std::string> bucket_origin;
  std::vector<CrossSpectra> spectra;
  std::vector<std::vector<RejectedImpact>> rejected;
  RealFft force_fft(n), response_fft(n);
  const int lines = force_fft.lines();

  FrfResult result;
  FrfSummary& summary = result.summary;
  summary.estimator = options.estimator;
  summary.window_decay_rate = processed.decay_rate;
  summary.roving_hammer = test.roving_hammer;
  summary.impacts = static_cast<int>(test.impacts.size());
  summary.notes = test.notes;
  summary.notes.insert(summary.notes.end(), processed.notes.begin(), processed.notes.end());

  // Pass 1 (sequential, cheap): buckets, rejections, and the work list of each bucket.
  struct Work {
    int impact, slot;
  };
  std::vector<std::vector<Work>> work;
  std::vector<int> force_slot(test.impacts.size(), -1);  // index into force spectra, -1 = not needed
  int n_forces = 0;
  for (size_t k = 0; k < test.impacts.size(); ++k) {
    if (k % 256 == 255) ReportProgress(progress, 0.5, "FRF");  // tens of thousands of impacts take a while
    const Impact& imp = test.impacts[k];
    const ImpactAnalysis& a = processed.impacts[k];
    const int r = ref_index(imp.reference);
    if (!a.accepted) ++summary.rejected_impacts;
    for (size_t slot = 0; slot < imp.responses.size(); ++slot) {
      const TimeRecord& rec = test.records[imp.responses[slot]];
      const int o = out_index(rec.channel);
      auto [it, fresh] = bucket_of.emplace(std::make_pair(r, o), static_cast<int>(keys.size()));
      if (fresh) {
        keys.push_back({r, o});
        bucket_quantity.push_back(rec.quantity);
        bucket_origin.push_back(rec.origin);
        spectra.emplace_back();
        spectra.back().Resize(lines);
        rejected.emplace_back();
        work.emplace_back();
      }
      const int b = it->second;
      const std::string& why = !a.accepted ? a.reason : a.response_rejections[slot];
      if (!why.empty()) {
        rejected[b].push_back({imp.number, test.set_names[imp.set], why});
        continue;
      }
      if (force_slot[k] < 0) force_slot[k] = n_forces++;
      work[b].push_back({static_cast<int>(k), static_cast<int>(slot)});
    }
  }
  std::size_t spectra_total = static_cast<std::size_t>(n_forces);
  for (const std::vector<Work>& w : work) spectra_total += w.size();
  StepProgress spectra_progress(progress, "FRF", spectra_total, 0.5, 0.95);
  auto spectrum_done = [&] { spectra_progress.Step(); };
  // Force spectra once per used impact.
  std::vector<std::complex<double>> forces(static_cast<size_t>(n_forces) * lines);
  for (size_t k = 0; k < test.impacts.size(); ++k) {
    if (force_slot[k] < 0) continue;
    acquisition::WindowForce(test.records[test.impacts[k].force], processed.impacts[k], processed.decay_rate,
                             force_fft.input());
    const std::complex<double>* fx = force_fft.Execute();
    std::copy(fx, fx + lines, forces.begin() + static_cast<std::ptrdiff_t>(force_slot[k]) * lines);
    spectrum_done();
  }
  // Pass 2: response transforms and accumulation. Each bucket belongs to one thread and is summed
  // in impact order, so the result does not depend on the thread count.
  const int hw = static_cast<int>(std::thread::hardware_concurrency());
  const int threads = std::max(1, std::min<int>(options.threads > 0 ? options.threads : std::max(1, hw),
                                                static_cast<int>(keys.size())));
  auto worker = [&](int t, RealFft* fft, const std::atomic<bool>& stop) {
    for (size_t b = t; b < keys.size(); b += threads) {
      for (const Work& w : work[b]) {
        if (stop.load(std::memory_order_relaxed)) return;
        const Impact& imp = test.impacts[w.impact];
        acquisition::WindowResponse(test.records[imp.responses[w.slot]], processed.impacts[w.impact], w.slot,
                                    processed.decay_rate, fft->input());
        spectra[b].Add(forces.data() + static_cast<std::ptrdiff_t>(force_slot[w.impact]) * lines, fft->Execute());
        spectrum_done();
      }
    }
  };
  {
    std::vector<std::unique_ptr<RealFft>> ffts;
    for (int t = 1; t < threads; ++t) ffts.push_back(std::make_unique<RealFft>(n));
    RunOnThreads(threads, [&](int t, const std::atomic<bool>& stop) {
      worker(t, t == 0 ? &response_fft : ffts[static_cast<size_t>(t - 1)].get(), stop);
    });
  }

  // Every FRF needs at least one accepted impact.
  for (size_t b = 0; b < keys.size(); ++b)
    if (spectra[b].averages == 0) {
      std::string reasons;
      for (const RejectedImpact& ri : rejected[b])
        reasons += "; impact " + std::to_string(ri.impact) + ": " + ri.reason;
      throw InputError(bucket_origin[b], "every impact of FRF " + DofName(test.outputs[keys[b].second]) + " / " +
                                             DofName(test.references[keys[b].first]) + " was rejected" + reasons);
    }

  FrfSet& set = result.frfs;
  const double df = 1.0 / (n * test.sample_interval_s);
  set.frequency_hz = Eigen::VectorXd::LinSpaced(lines, 0.0, df * (lines - 1));
  set.references = test.references;
  set.outputs = test.outputs;
  set.roving_hammer = test.roving_hammer;
  set.window_decay_rate = processed.decay_rate;
  // Roving sets: the impacts of one file that share their response nodes, numbered in order of
  // first appearance; each output belongs to the first set that measured it.
  if (!test.roving_hammer) {
    std::map<std::pair<int, std::vector<int>>, int> set_of;
    set.output_sets.assign(static_cast<size_t>(n_out), -1);
    for (const Impact& imp : test.impacts) {
      std::vector<int> nodes;
      for (int rec : imp.responses) nodes.push_back(test.records[static_cast<size_t>(rec)].channel.node);
      std::sort(nodes.begin(), nodes.end());
      nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
      const int id = set_of.emplace(std::make_pair(imp.set, nodes), static_cast<int>(set_of.size())).first->second;
      for (int rec : imp.responses) {
        int& o = set.output_sets[static_cast<size_t>(out_index(test.records[static_cast<size_t>(rec)].channel))];
        if (o < 0) o = id;
      }
    }
  }
  const Quantity measured = bucket_quantity.empty() ? Quantity::kAcceleration : bucket_quantity.front();
  set.output_quantity = measured;
  set.force_unit = test.records[test.impacts.front().force].unit.empty() ? "N" : test.records[test.impacts.front().force].unit;
  const std::string& ru = test.records[test.impacts.front().responses.front()].unit;
  if (!ru.empty()) set.response_unit = ru;
  else set.response_unit = measured == Quantity::kDisplacement ? "m" : measured == Quantity::kVelocity ? "m/s" : "m/s^2";
  const std::complex<double> nan_c(kNaN, kNaN);
  set.h.assign(n_refs, Eigen::MatrixXcd::Constant(lines, n_out, nan_c));
  set.coherence.assign(n_refs, Eigen::MatrixXd::Constant(lines, n_out, kNaN));
  set.averages = Eigen::MatrixXi::Zero(n_refs, n_out);
  for (size_t b = 0; b < keys.size(); ++b) {
    ReportProgress(progress, 0.95 + 0.04 * static_cast<double>(b) / static_cast<double>(keys.size()), "FRF");
    const auto [r, o] = keys[b];
    Eigen::ArrayXcd h = EstimateFrf(spectra[b], options.estimator);
    // Sets measured with another response quantity join the first one's (spec §1.9).
    h = ConvertFrf(h, set.frequency_hz, bucket_quantity[b], measured);
    set.h[r].col(o) = h.matrix();
    set.coherence[r].col(o) = Coherence(spectra[b]).matrix();
    set.averages(r, o) = spectra[b].averages;
    summary.frfs.push_back({test.outputs[o], test.references[r], spectra[b].averages, rejected[b]});
  }
  if (options.output_quantity != Quantity::kUnknown) ConvertFrfSet(&set, options.output_quantity);
  if (options.band_lo_hz > 0.0 || std::isfinite(options.band_hi_hz)) {
    try {
      set = SelectBand(set, options.band_lo_hz, options.band_hi_hz);
    } catch (const std::invalid_argument&) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "the band %g..%g Hz holds no spectral line (lines 0..%g Hz every %g Hz)",
                    options.band_lo_hz, options.band_hi_hz, set.frequency_hz[lines - 1], df);
      throw InputError(test.set_names.front(), buf);
    }
  }
  ReportProgress(progress, 1.0, "FRF");
  return result;
}

}  // namespace ema::frf
