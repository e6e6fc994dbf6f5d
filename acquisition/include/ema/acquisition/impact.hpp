// Per-impact pre-processing of a hammer test (spec algorithms.md §1.2–1.5): trigger detection
// (the pre-trigger is kept), DC removal from the pre-trigger, force window from the detected
// pulse, exponential window, and the quality gates. Every rejected impact carries a reason.
#pragma once

#include <string>
#include <vector>

#include "ema/acquisition/hammer_measurement.hpp"
#include "ema/core/progress.hpp"

namespace ema::acquisition {

enum class ExpWindowMode {
  kAuto,   ///< none when every response dies out (≤ end level) in the record; else the lightest that reaches it
  kNone,   ///< never
  kFixed,  ///< ImpactOptions::exp_decay_rate
};

struct ImpactOptions {
  double trigger_level = 0.10;         ///< trigger at this fraction of the impact's force peak (rising edge)
  double force_window_pulses = 3.0;    ///< force window = 1 up to (last pulse end + this × T_c) ...
  double force_taper_pulses = 1.0;     ///< ... then a half-cosine taper over this × T_c, then 0
  ExpWindowMode exp_window = ExpWindowMode::kAuto;
  double exp_decay_rate = 0.0;         ///< 1/tau (1/s) for kFixed
  double exp_end_level = 0.01;         ///< kAuto: response envelope at the record end ≤ this × its peak
  double double_hit_high = 0.07;       ///< hysteresis pulse count: a pulse rises above this × peak ...
  double double_hit_low = 0.015;       ///< ... and re-arms below this × peak
  double double_hit_autocorrelation = 0.05;  ///< secondary autocorrelation peak (lags > 1.5 T_c) above this
  bool reject_double_hits = true;      ///< false: keep them, force window spans every pulse
  double overload_fraction = 0.95;     ///< peak above this × full scale (when known) = overload
  int flat_top_run = 3;                ///< this many consecutive samples at the extreme = clipped
  double level_tolerance = 0.5;        ///< reject peak force off the point's median by more than this fraction
  double pretrigger_motion = 0.02;     ///< pre-trigger response rms above this × its peak = still moving ...
  /// ... when the pre-trigger is also slow: its lag-one autocorrelation above this (motion sampled
  /// well above its frequency is near 1; white sensor noise near 0, and a weakly excited channel's
  /// noise alone can pass the rms limit).
  double pretrigger_motion_correlation = 0.5;
};

/// Findings for one impact (aligned with HammerMeasurement::impacts).
struct ImpactAnalysis {
  int trigger_index = 0;          ///< first sample at or above trigger_level × peak
  double force_peak = 0.0;        ///< after DC removal, in the force unit
  double contact_time_s = 0.0;    ///< estimated T_c of the main pulse
  int pulse_count = 0;            ///< hysteresis count over the record
  double autocorrelation_peak = 0.0;
  double force_window_end_s = 0.0;  ///< window 1 up to here (from record start), then the taper
  double force_taper_s = 0.0;
  double force_dc = 0.0;
  std::vector<double> response_dc;  ///< per response record of the impact
  std::vector<double> response_end_level;  ///< envelope at the record end / peak, per response
  bool accepted = true;           ///< false: every FRF of this impact drops it
  std::string reason;             ///< why not accepted
  std::vector<std::string> response_rejections;  ///< per response: "" or why this channel is dropped
};

struct ProcessedTest {
  std::vector<ImpactAnalysis> impacts;
  double decay_rate = 0.0;              ///< exponential window 1/tau applied to all channels (0 = none)
  std::vector<std::string> notes;
};

/// Runs the detectors and gates on every impact and picks the exponential window. `progress` gets
/// the share of records analysed ("impacts"), from the worker threads one call at a time; what it
/// throws (a cancellation) stops the analysis and reaches the caller.
ProcessedTest AnalyseImpacts(const HammerMeasurement& test, const ImpactOptions& options = {},
                             const ProgressCallback& progress = {});

/// Fills out[0..n) with the DC-free force record times the force window and the exponential window.
void WindowForce(const TimeRecord& record, const ImpactAnalysis& analysis, double decay_rate, double* out);
/// Fills out[0..n) with the DC-free response record (slot = position in Impact::responses) times
/// the exponential window.
void WindowResponse(const TimeRecord& record, const ImpactAnalysis& analysis, int slot, double decay_rate,
                    double* out);

// Individual detectors, exposed for tests and tools.

/// Number of pulses in |x|: a pulse starts when |x| rises above high and the detector re-arms
/// only when |x| has fallen below low (both absolute values).
int CountPulses(const std::vector<double>& x, double high, double low);

/// Largest normalised autocorrelation rho(lag) of x[begin, end) for lag ≥ min_lag samples.
double AutocorrelationSecondaryPeak(const std::vector<double>& x, int begin, int end, int min_lag);

/// "" when the record looks unclipped; else the reason (peak vs full scale, or a flat top).
std::string ClippingReason(const std::vector<double>& x, double full_scale, double overload_fraction, int flat_top_run);

}  // namespace ema::acquisition
