#include "ema/acquisition/impact.hpp"

#include "antialias.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <atomic>
#include <map>
#include <thread>

#include "ema/core/parallel.hpp"

namespace ema::acquisition {

namespace {

using internal::kPi;

std::string Format(const char* fmt, double a, double b = 0.0, double c = 0.0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, fmt, a, b, c);
  return buf;
}

double Mean(const std::vector<double>& x, int begin, int end) {
  if (end <= begin) return 0.0;
  double s = 0.0;
  for (int i = begin; i < end; ++i) s += x[i];
  return s / (end - begin);
}

double Rms(const std::vector<double>& x, int begin, int end, double dc) {
  if (end <= begin) return 0.0;
  double s = 0.0;
  for (int i = begin; i < end; ++i) s += (x[i] - dc) * (x[i] - dc);
  return std::sqrt(s / (end - begin));
}

/// Lag-one autocorrelation coefficient of x[begin, end) about dc: near 1 for motion sampled
/// well above its frequency, near 0 for white noise; 0 for a constant stretch.
double LagOneCorrelation(const std::vector<double>& x, int begin, int end, double dc) {
  double ss = 0.0, lag = 0.0;
  for (int i = begin; i < end; ++i) {
    ss += (x[i] - dc) * (x[i] - dc);
    if (i + 1 < end) lag += (x[i] - dc) * (x[i + 1] - dc);
  }
  return ss > 0.0 ? lag / ss : 0.0;
}

}  // namespace

int CountPulses(const std::vector<double>& x, double high, double low) {
  int count = 0;
  bool armed = true;
  for (double v : x) {
    const double a = std::abs(v);
    if (armed && a > high) {
      ++count;
      armed = false;
    } else if (!armed && a < low) {
      armed = true;
    }
  }
  return count;
}

double AutocorrelationSecondaryPeak(const std::vector<double>& x, int begin, int end, int min_lag) {
  begin = std::max(0, begin);
  end = std::min(static_cast<int>(x.size()), end);
  double r0 = 0.0;
  for (int i = begin; i < end; ++i) r0 += x[i] * x[i];
  if (r0 <= 0.0) return 0.0;
  double best = 0.0;
  for (int lag = std::max(1, min_lag); lag < end - begin; ++lag) {
    double r = 0.0;
    for (int i = begin; i + lag < end; ++i) r += x[i] * x[i + lag];
    best = std::max(best, r / r0);
  }
  return best;
}

namespace {

// Running peak of |x| and the run of same-signed samples at it (restarted whenever a larger value
// appears, so at the end `longest` is the longest run at the final peak).
struct FlatTopTracker {
  double peak = 0.0, prev = 0.0;
  int run = 0, longest = 0;
  void Add(double v) {
    const double a = std::abs(v);
    if (a > peak * (1.0 + 1e-9)) {
      peak = a;
      longest = 0;
      run = 1;
    } else if (peak > 0.0 && a >= peak * (1.0 - 1e-9)) {
      run = (run > 0 && (v >= 0) == (prev >= 0)) ? run + 1 : 1;
    } else {
      run = 0;
    }
    longest = std::max(longest, run);
    prev = v;
  }
  std::string Reason(double full_scale, double overload_fraction, int flat_top_run) const {
    if (peak <= 0.0) return "";
    if (std::isfinite(full_scale) && full_scale > 0.0 && peak > overload_fraction * full_scale)
      return Format("overload: peak %.6g exceeds %.0f %% of the full scale %.6g", peak, 100.0 * overload_fraction,
                    full_scale);
    if (longest >= flat_top_run)
      return Format("clipped: flat top of %.0f consecutive samples at the extreme value %.6g", longest, peak);
    return "";
  }
};

}  // namespace

std::string ClippingReason(const std::vector<double>& x, double full_scale, double overload_fraction, int flat_top_run) {
  FlatTopTracker t;
  for (double v : x) t.Add(v);
  return t.Reason(full_scale, overload_fraction, flat_top_run);
}

ProcessedTest AnalyseImpacts(const HammerMeasurement& test, const ImpactOptions& opt,
                             const ProgressCallback& progress) {
  ProcessedTest out;
  // Progress: the share of records (force and responses) analysed, one call at a time from the
  // worker threads; a call that throws (a cancellation) stops every worker at its next record.
  std::size_t records_total = 0;
  for (const Impact& imp : test.impacts) records_total += 1 + imp.responses.size();
  StepProgress records_progress(progress, "impacts", records_total);
  auto record_done = [&] { records_progress.Step(); };
  const double dt = test.sample_interval_s;
  const int n = test.samples;
  out.impacts.resize(test.impacts.size());
  // Each impact is analysed on its own (it writes only out.impacts[k]), so the impacts are shared
  // out over the cores: this pass reads every sample of the test once and is memory bound.
  auto analyse_impact = [&](size_t k, const std::atomic<bool>& stop) {
    const Impact& imp = test.impacts[k];
    ImpactAnalysis& a = out.impacts[k];
    const std::vector<double>& f = test.records[imp.force].samples;
    // Peak and polarity (a hammer may be wired negative), trigger on the rising edge.
    int p = 0;
    for (int i = 1; i < n; ++i)
      if (std::abs(f[i]) > std::abs(f[p])) p = i;
    const double sign0 = f[p] >= 0 ? 1.0 : -1.0;
    int trig = 0;
    while (trig < p && sign0 * f[trig] < opt.trigger_level * std::abs(f[p])) ++trig;
    int pre_end = std::max(0, trig - 1);
    a.force_dc = Mean(f, 0, pre_end);
    std::vector<double> y(n);
    for (int i = 0; i < n; ++i) y[i] = sign0 * (f[i] - a.force_dc);
    const double peak = y[p];
    a.force_peak = sign0 * peak;
    // Re-trigger on the DC-free signal.
    trig = 0;
    while (trig < p && y[trig] < opt.trigger_level * peak) ++trig;
    a.trigger_index = trig;
    // Contact time of the main pulse: samples above 5 % of the peak span 0.968 T_c of a half-sine.
    int left = p, right = p;
    while (left > 0 && y[left - 1] > 0.05 * peak) --left;
    while (right + 1 < n && y[right + 1] > 0.05 * peak) ++right;
    const double span_to_tc = 1.0 - 2.0 * std::asin(0.05) / kPi;
    a.contact_time_s = std::max(2.0 * dt, (right - left + 1) * dt / span_to_tc);
    const int tc_samples = std::max(1, static_cast<int>(std::ceil(a.contact_time_s / dt)));
    // Double hit: hysteresis pulse count, and the autocorrelation's secondary peak past 1.5 T_c.
    a.pulse_count = CountPulses(y, opt.double_hit_high * peak, opt.double_hit_low * peak);
    const int seg_begin = left - tc_samples;
    const int seg_end = left + std::max(static_cast<int>(std::ceil(0.02 / dt)), 20 * tc_samples);
    a.autocorrelation_peak = AutocorrelationSecondaryPeak(y, seg_begin, seg_end,
                                                          std::max(2, static_cast<int>(std::ceil(1.5 * a.contact_time_s / dt))));
    const bool double_hit = a.pulse_count > 1 || a.autocorrelation_peak > opt.double_hit_autocorrelation;
    int last_pulse_end = right;
    if (double_hit) {
      for (int i = n - 1; i > right; --i)
        if (y[i] > opt.double_hit_high * peak) {
          last_pulse_end = i;
          while (last_pulse_end + 1 < n && y[last_pulse_end + 1] > 0.05 * peak) ++last_pulse_end;
          break;
        }
      if (opt.reject_double_hits) {
        a.accepted = false;
        a.reason = a.pulse_count > 1
                       ? Format("double hit: %.0f force pulses above %.0f %% of the peak", a.pulse_count,
                                100.0 * opt.double_hit_high)
                       : Format("double hit: force autocorrelation secondary peak %.3f > %.3f", a.autocorrelation_peak,
                                opt.double_hit_autocorrelation);
      }
    }
    // Force window: 1 through the last pulse + k T_c (at least 5 ms or 8 samples), cosine taper T_c.
    const double hold = std::max({opt.force_window_pulses * a.contact_time_s, 5e-3, 8 * dt});
    a.force_window_end_s = (last_pulse_end + 1) * dt + hold;
    a.force_taper_s = std::max(opt.force_taper_pulses * a.contact_time_s, 2 * dt);
    const TimeRecord& fr = test.records[imp.force];
    if (a.accepted) {
      const std::string clip = ClippingReason(f, fr.full_scale, opt.overload_fraction, opt.flat_top_run);
      if (!clip.empty()) {
        a.accepted = false;
        a.reason = "force " + clip;
      }
    }
    // Responses: DC from the pre-trigger, clipping, motion before the impact, end level.
    pre_end = std::max(0, trig - 1);
    const int tail = std::max(4, n / 20);
    record_done();
    for (int idx : imp.responses) {
      if (stop.load(std::memory_order_relaxed)) return;
      const TimeRecord& r = test.records[idx];
      const std::vector<double>& x = r.samples;
      const double dc = Mean(x, 0, pre_end);
      // One pass: clipping (raw samples), the peak after DC removal and the energy of each block
      // of 5 % of the record after the trigger (block rms is not fooled by the few-sample
      // acceleration spike at the impact, which would make a ringing mode look small).
      FlatTopTracker clip;
      double rpeak = 0.0, ref_ss = 0.0, block_ss = 0.0;
      int in_block = 0;
      for (int i = 0; i < n; ++i) {
        clip.Add(x[i]);
        const double v = x[i] - dc;
        rpeak = std::max(rpeak, std::abs(v));
        if (i < trig) continue;
        block_ss += v * v;
        if (++in_block == tail) {
          ref_ss = std::max(ref_ss, block_ss);
          block_ss = 0.0;
          in_block = 0;
        }
      }
      std::string why = clip.Reason(r.full_scale, opt.overload_fraction, opt.flat_top_run);
      if (!why.empty()) why = "response " + DofName(r.channel) + " " + why;
      const double pre_rms = Rms(x, 0, pre_end, dc);
      // Motion (a structure still ringing, or moved by hand) is slow against the sampling rate:
      // successive pre-trigger samples follow each other. Sensor noise does not, and a weakly
      // excited channel's noise may well exceed the limit without the structure moving.
      if (why.empty() && pre_end >= 8 && rpeak > 0.0 && pre_rms > opt.pretrigger_motion * rpeak &&
          LagOneCorrelation(x, 0, pre_end, dc) > opt.pretrigger_motion_correlation)
        why = "response " + DofName(r.channel) +
              Format(" was moving before the impact: pre-trigger rms %.1f %% of its peak (limit %.1f %%)",
                     100.0 * pre_rms / rpeak, 100.0 * opt.pretrigger_motion);
      if (why.empty() && rpeak <= 0.0) why = "response " + DofName(r.channel) + " is identically zero";
      // End envelope relative to the strongest block, noise (pre-trigger) rms removed from both.
      const double noise = pre_end >= 8 ? pre_rms : 0.0;
      const double ref_rms = std::sqrt(ref_ss / tail);
      const double end_rms = Rms(x, n - tail, n, dc);
      const double end_amp = std::sqrt(std::max(0.0, end_rms * end_rms - noise * noise));
      const double ref_amp = std::sqrt(std::max(0.0, ref_rms * ref_rms - noise * noise));
      a.response_dc.push_back(dc);
      a.response_end_level.push_back(ref_amp > 0.0 ? end_amp / ref_amp : 0.0);
      a.response_rejections.push_back(why);
      record_done();
    }
  };
  const size_t threads =
      std::max<size_t>(1, std::min<size_t>(test.impacts.size(), std::max(1u, std::thread::hardware_concurrency())));
  RunOnThreads(static_cast<int>(threads), [&](int t, const std::atomic<bool>& stop) {
    for (size_t k = static_cast<size_t>(t); k < test.impacts.size(); k += threads) {
      if (stop.load(std::memory_order_relaxed)) return;
      analyse_impact(k, stop);
    }
  });
  // Impact-level spread: peak force against the median of its point (per set and reference).
  std::map<std::pair<int, Dof>, std::vector<double>> levels;
  for (size_t k = 0; k < test.impacts.size(); ++k)
    if (out.impacts[k].accepted)
      levels[{test.impacts[k].set, test.impacts[k].reference}].push_back(std::abs(out.impacts[k].force_peak));
  // The median of each point once (a test of thousands of impacts at one point took seconds when
  // it was taken again for every impact); NaN: fewer than three levels, a median of two says nothing.
  std::map<std::pair<int, Dof>, double> median_of;
  for (auto& [point, v] : levels) {
    if (v.size() < 3) {
      median_of[point] = kNaN;
      continue;
    }
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    median_of[point] = v[v.size() / 2];
  }
  for (size_t k = 0; k < test.impacts.size(); ++k) {
    ImpactAnalysis& a = out.impacts[k];
    if (!a.accepted) continue;
    const double median = median_of.at({test.impacts[k].set, test.impacts[k].reference});
    if (std::isnan(median)) continue;
    const double dev = (std::abs(a.force_peak) - median) / median;
    if (std::abs(dev) > opt.level_tolerance) {
      a.accepted = false;
      a.reason = Format("impact level %.4g is %.0f %% off the median %.4g of this point", std::abs(a.force_peak),
                        100.0 * dev, median);
    }
  }
  // Exponential window: the lightest decay that brings every kept response to the end level.
  const double record_t = n * dt;
  switch (opt.exp_window) {
    case ExpWindowMode::kNone: out.decay_rate = 0.0; break;
    case ExpWindowMode::kFixed: out.decay_rate = opt.exp_decay_rate; break;
    case ExpWindowMode::kAuto: {
      // Needed when a kept response still rings above the end level; then the window itself
      // falls to the end level at the record end, tau = -(T - t0)/ln(end level) (spec §1.4), so
      // every mode's tail ends at most at that fraction of where it would have ended.
      double worst = 0.0, span = record_t;
      for (size_t k = 0; k < test.impacts.size(); ++k) {
        const ImpactAnalysis& a = out.impacts[k];
        if (!a.accepted) continue;
        span = std::min(span, record_t - a.trigger_index * dt);
        for (size_t j = 0; j < a.response_end_level.size(); ++j)
          if (a.response_rejections[j].empty()) worst = std::max(worst, a.response_end_level[j]);
      }
      out.decay_rate = worst > opt.exp_end_level && span > 0.0 ? -std::log(opt.exp_end_level) / span : 0.0;
      if (out.decay_rate > 0.0)
        out.notes.push_back(Format("responses still ring at up to %.1f %% of their level at the record end: "
                                   "exponential window 1/tau = %.4g 1/s applied (poles shifted left by it; the fit "
                                   "removes it)",
                                   100.0 * worst, out.decay_rate));
      break;
    }
  }
  return out;
}

void WindowForce(const TimeRecord& record, const ImpactAnalysis& a, double decay_rate, double* out) {
  const int n = static_cast<int>(record.samples.size());
  const double dt = record.sample_interval_s;
  const double t_trig = a.trigger_index * dt;
  for (int i = 0; i < n; ++i) {
    const double t = i * dt;
    double w = 1.0;
    if (t > a.force_window_end_s) {
      const double u = (t - a.force_window_end_s) / a.force_taper_s;
      w = u >= 1.0 ? 0.0 : 0.5 * (1.0 + std::cos(kPi * u));
    }
    if (decay_rate > 0.0 && t > t_trig) w *= std::exp(-decay_rate * (t - t_trig));
    out[i] = w == 0.0 ? 0.0 : w * (record.samples[i] - a.force_dc);
  }
}

void WindowResponse(const TimeRecord& record, const ImpactAnalysis& a, int slot, double decay_rate, double* out) {
  const int n = static_cast<int>(record.samples.size());
  const double dc = a.response_dc[slot];
  if (decay_rate <= 0.0) {
    for (int i = 0; i < n; ++i) out[i] = record.samples[i] - dc;
    return;
  }
  const double dt = record.sample_interval_s;
  const double step = std::exp(-decay_rate * dt);
  double w = 1.0;
  for (int i = 0; i < n; ++i) {
    if (i > a.trigger_index) w *= step;  // e^{-rate (t - t_trig)}
    out[i] = w * (record.samples[i] - dc);
  }
}

}  // namespace ema::acquisition
