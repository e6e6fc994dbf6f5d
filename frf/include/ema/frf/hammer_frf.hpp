// Hammer test → FRF set: per-impact processing (acquisition/impact.hpp), FFT, spectral averaging
// per (reference, response) FRF, estimator, coherence, quantity conversion, band selection.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "ema/acquisition/hammer_measurement.hpp"
#include "ema/acquisition/impact.hpp"
#include "ema/core/names.hpp"
#include "ema/core/progress.hpp"
#include "ema/core/types.hpp"
#include "ema/frf/estimators.hpp"

namespace ema::frf {

struct FrfOptions {
  Estimator estimator = Estimator::kH1;
  acquisition::ImpactOptions impact;           ///< windows and quality gates
  double band_lo_hz = 0.0;                     ///< keep lines in [band_lo_hz, band_hi_hz]
  double band_hi_hz = std::numeric_limits<double>::infinity();
  Quantity output_quantity = Quantity::kUnknown;  ///< kUnknown: as measured (the first response's quantity)
  int threads = 0;  ///< FFT/accumulation threads; 0 = all cores. Results do not depend on it.

  /// True when every option a user sets is in range; else false with the violated condition in
  /// *why (Ceres style; the CLI option in parentheses).
  bool IsValid(std::string* why) const {
    if (!(band_lo_hz >= 0.0 && band_hi_hz > band_lo_hz)) return *why = "band (--band): expected 0 <= low < high", false;
    if (threads < 0) return *why = "threads (--threads): expected 0 (all cores) or a positive count", false;
    if (!(impact.exp_decay_rate >= 0.0)) return *why = "impact.exp_decay_rate (--exp-window): the decay rate must be >= 0", false;
    if (!(impact.exp_end_level > 0.0 && impact.exp_end_level < 1.0))
      return *why = "impact.exp_end_level (--exp-end-level): expected 0 < level < 1", false;
    if (!(impact.trigger_level > 0.0 && impact.trigger_level < 1.0))
      return *why = "impact.trigger_level (--trigger-level): expected 0 < level < 1", false;
    if (!(impact.double_hit_high > 0.0 && impact.double_hit_high < 1.0))
      return *why = "impact.double_hit_high (--double-hit-ratio): expected 0 < ratio < 1", false;
    return true;
  }
};

/// `ema frf --exp-window` by name (a number there is a fixed decay rate).
inline constexpr EnumName<acquisition::ExpWindowMode> kExpWindowNames[] = {{acquisition::ExpWindowMode::kAuto, "auto"},
                                                                          {acquisition::ExpWindowMode::kNone, "none"}};

/// `ema frf --quantity`: the FRF type to convert to.
inline constexpr EnumName<Quantity> kOutputQuantityNames[] = {
    {Quantity::kAcceleration, "accelerance"}, {Quantity::kVelocity, "mobility"}, {Quantity::kDisplacement, "receptance"}};

struct RejectedImpact {
  int impact = 0;          ///< impact number as read
  std::string set;         ///< file (roving set) the impact came from
  std::string reason;
};

struct FrfSummaryEntry {
  Dof response;
  Dof reference;
  int averages = 0;
  std::vector<RejectedImpact> rejected;
};

struct FrfSummary {
  std::vector<FrfSummaryEntry> frfs;
  Estimator estimator = Estimator::kH1;
  double window_decay_rate = 0.0;   ///< exponential window the FRFs carry (1/s)
  bool roving_hammer = false;
  int impacts = 0;                  ///< impacts in the test
  int rejected_impacts = 0;         ///< impacts rejected for every FRF (force-channel gates)
  std::vector<std::string> notes;
};

struct FrfResult {
  FrfSet frfs;
  FrfSummary summary;
};

/// Estimates every FRF of the test. Throws InputError (file, record, reasons) when every impact
/// of an FRF is rejected. `progress`: the impacts analysed (the first half), the spectra done
/// ("FRF"), 1 at the end; called from the worker threads one call at a time, and what it throws
/// (a cancellation) stops every worker and reaches the caller.
FrfResult EstimateFrfs(const acquisition::HammerMeasurement& test, const FrfOptions& options = {},
                       const ProgressCallback& progress = {});

}  // namespace ema::frf
