// Amplitude dependence of modes over impact force levels (algorithms.md §6.7, `ema diagnose
// --force-level`). The missing-effect diagnosis itself moved to its own module:
// ema/diagnose/diagnose.hpp.
#pragma once

#include <string>
#include <vector>

#include "ema/core/progress.hpp"
#include "ema/core/types.hpp"

namespace ema::correlation {

// ---- Amplitude dependence (§6.7, issue 7 item 4) ----

/// Modes fitted from the impacts of one force level.
struct ForceLevelModes {
  double force_n = kNaN;  ///< peak (or RMS) impact force of the level
  ModeSet modes;
};

struct NonlinearityOptions {
  /// Flag a mode when |f(max force) − f(min force)| / f > max(repeatability_factor × the
  /// repeatability, min_change). Repeatability: the modes' frequency_spread_hz when known.
  double repeatability_factor = 3.0;
  double min_change = 0.002;
  double mac_min = 0.6;
};

struct AmplitudeTrend {
  int reference_mode = -1;               ///< index in the lowest force level's modes
  std::vector<double> force_n;           ///< levels where the mode was found
  std::vector<double> frequency_hz;
  double change_pct = 0.0;               ///< (f(max F) − f(min F)) / f(min F) · 100
  double slope_pct_per_decade = 0.0;     ///< least-squares slope of f vs log10 F, % of f per decade
  double threshold_pct = 0.0;
  bool flagged = false;
  std::string trend;                     ///< "softening", "hardening" or "none"
};

struct NonlinearityReport {
  std::vector<AmplitudeTrend> modes;
  bool any_flagged = false;
  std::string summary;
};

/// Tracks each mode over the force levels (paired by MAC with the lowest level) and flags a
/// stiffness that depends on amplitude, with the trend. Throws InputError with < 2 levels.
NonlinearityReport DetectAmplitudeDependence(std::vector<ForceLevelModes> levels, const NonlinearityOptions& options = {});

}  // namespace ema::correlation
