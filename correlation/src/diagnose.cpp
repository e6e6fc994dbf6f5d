// Amplitude dependence over force levels (the diagnosis moved to diagnose/).
#include "ema/correlation/diagnose.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <map>
#include <memory>
#include <set>
#include <sstream>

#include "ema/core/error.hpp"
#include "ema/correlation/mac.hpp"
#include "ema/correlation/dof_match.hpp"
#include "ema/correlation/pairing.hpp"

namespace ema::correlation {
namespace {

std::string FormatNumber(double v, int significant = 3) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*g", significant, v);
  return buffer;
}

std::string Join(const std::vector<std::string>& parts, const std::string& sep) {
  std::string out;
  for (size_t i = 0; i < parts.size(); ++i) out += (i ? sep : "") + parts[i];
  return out;
}

}  // namespace

NonlinearityReport DetectAmplitudeDependence(std::vector<ForceLevelModes> levels, const NonlinearityOptions& options) {
  if (levels.size() < 2)
    throw InputError("", "amplitude dependence needs modes from at least 2 force levels, found " +
                             std::to_string(levels.size()));
  for (const auto& l : levels) {
    if (!(l.force_n > 0.0)) throw InputError(l.modes.source, "force level must be a positive force in N");
    if (l.modes.modes.empty()) throw InputError(l.modes.source, "no modes found at force level " + FormatNumber(l.force_n));
  }
  std::sort(levels.begin(), levels.end(), [](const auto& a, const auto& b) { return a.force_n < b.force_n; });
  const ModeSet& ref = levels.front().modes;
  NonlinearityReport report;
  for (size_t m = 0; m < ref.modes.size(); ++m) {
    AmplitudeTrend t;
    t.reference_mode = static_cast<int>(m);
    t.force_n.push_back(levels.front().force_n);
    t.frequency_hz.push_back(ref.modes[m].frequency_hz);
    double spread = std::isfinite(ref.modes[m].frequency_spread_hz) ? ref.modes[m].frequency_spread_hz : 0.0;
    report.modes.push_back(t);
    report.modes.back().threshold_pct = spread;  // holds the largest spread (Hz) until the end
  }
  PairingOptions popt;
  popt.mac_min = options.mac_min;
  popt.frequency_weight = 0.2;
  for (size_t l = 1; l < levels.size(); ++l) {
    const ModeSet& set = levels[l].modes;
    const DofMatch match = MatchDofs(set, ref);
    if (match.Count() == 0)
      throw InputError(set.source, "shares no DOF with the lowest force level's modes " + ref.source);
    const Eigen::MatrixXd mac = MacMatrix(match.TestShapes(set), match.ModelShapes(ref));
    Eigen::VectorXd f_set(set.modes.size()), f_ref(ref.modes.size());
    for (size_t i = 0; i < set.modes.size(); ++i) f_set(i) = set.modes[i].frequency_hz;
    for (size_t j = 0; j < ref.modes.size(); ++j) f_ref(j) = ref.modes[j].frequency_hz;
    for (const ModePair& p : PairModes(mac, f_set, f_ref, popt).pairs) {
      AmplitudeTrend& t = report.modes[p.model];
      t.force_n.push_back(levels[l].force_n);
      t.frequency_hz.push_back(set.modes[p.test].frequency_hz);
      if (std::isfinite(set.modes[p.test].frequency_spread_hz))
        t.threshold_pct = std::max(t.threshold_pct, set.modes[p.test].frequency_spread_hz);
    }
  }
  std::vector<std::string> flagged;
  for (AmplitudeTrend& t : report.modes) {
    const double f0 = t.frequency_hz.front();
    const double spread_hz = t.threshold_pct;
    t.threshold_pct = 100.0 * std::max(options.repeatability_factor * spread_hz / f0, options.min_change);
    if (t.frequency_hz.size() < 2) {
      t.trend = "none";
      continue;
    }
    t.change_pct = 100.0 * (t.frequency_hz.back() - f0) / f0;
    // Least squares of f on log10 F.
    const size_t n = t.force_n.size();
    double mx = 0.0, my = 0.0;
    for (size_t i = 0; i < n; ++i) {
      mx += std::log10(t.force_n[i]) / n;
      my += t.frequency_hz[i] / n;
    }
    double sxx = 0.0, sxy = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const double dx = std::log10(t.force_n[i]) - mx;
      sxx += dx * dx;
      sxy += dx * (t.frequency_hz[i] - my);
    }
    t.slope_pct_per_decade = sxx > 0.0 ? 100.0 * (sxy / sxx) / f0 : 0.0;
    t.flagged = std::abs(t.change_pct) > t.threshold_pct;
    t.trend = !t.flagged ? "none" : (t.change_pct < 0.0 ? "softening" : "hardening");
    if (t.flagged)
      flagged.push_back("mode at " + FormatNumber(f0, 4) + " Hz " + t.trend + " by " +
                        FormatNumber(std::abs(t.change_pct), 2) + " % from " + FormatNumber(t.force_n.front(), 3) +
                        " N to " + FormatNumber(t.force_n.back(), 3) + " N (" +
                        FormatNumber(t.slope_pct_per_decade, 2) + " % per decade of force)");
  }
  report.any_flagged = !flagged.empty();
  report.summary = flagged.empty()
                       ? "No amplitude-dependent frequency: every mode stays within its repeatability across the "
                         "force levels, so a linear model is adequate."
                       : "Amplitude-dependent stiffness: " + Join(flagged, "; ") +
                             ". A linear model holds only at the amplitude it was fitted at.";
  return report;
}

}  // namespace ema::correlation
