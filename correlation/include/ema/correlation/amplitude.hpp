// Amplitude dependence of modes (docs/amplitude.md): the same structure tested at several
// excitation levels, each level fitted to its own mode set. Modes are paired across levels by
// MAC and frequency; per mode the frequency and the damping ratio are followed against the
// level, and a trend test says whether the frequency softens, hardens or does both
// (non-monotonic), and whether the damping rises or falls, judged against each point's 1σ (where
// the fit gives it) combined with a repeatability floor, and against the scatter of the points
// about the trend.
//
// A micro-slipping joint softens and dissipates more as the response grows (frequency falls,
// damping rises); a closing contact or gap hardens. The analysis needs no model.
#pragma once

#include <string>
#include <vector>

#include "ema/core/names.hpp"
#include "ema/core/types.hpp"

namespace ema::correlation {

/// What the level of a mode set measures.
enum class LevelKind { kPeakForce, kRmsForce, kResponse };
inline constexpr EnumName<LevelKind> kLevelKindNames[] = {
    {LevelKind::kPeakForce, "peak_force"}, {LevelKind::kRmsForce, "rms_force"}, {LevelKind::kResponse, "response"}};
/// "peak_force", "rms_force", "response".
std::string LevelKindToString(LevelKind kind);
/// Inverse of LevelKindToString; false for an unknown name.
bool StringToLevelKind(const std::string& name, LevelKind* kind);

/// The 1σ of one mode's estimate (NaN = not known).
struct ModeUncertainty {
  double frequency_std_hz = kNaN;
  double damping_ratio_std = kNaN;
};

/// The modes fitted at one excitation level.
struct AmplitudeLevel {
  double level = kNaN;  ///< > 0: peak force (N), RMS force (N) or response amplitude
  ModeSet modes;
  /// Per mode of `modes` (same order), or empty when the fit gives no σ.
  std::vector<ModeUncertainty> uncertainty;
};

struct AmplitudeOptions {
  /// Pairs need MAC >= mac_min between the shapes on their shared DOFs (sets without shared
  /// DOFs pair by frequency alone).
  double mac_min = 0.8;
  /// Pairs whose frequencies differ by more than this share of the higher one are rejected:
  /// a joint shifts a mode by a few per cent, not by tens.
  double max_relative_frequency_difference = 0.05;
  /// Repeatability floor of a frequency, % of f, added in quadrature to each point's σ. Hammer
  /// tests repeat to about 0.01-0.05 % in frequency (temperature, hammer position, sensor
  /// cables); without a σ from the fit this floor alone judges the change.
  double frequency_floor_pct = 0.03;
  /// Repeatability floor of a damping ratio, relative (0.05 = 5 %), added in quadrature to each
  /// point's relative σ. Damping estimates repeat far worse than frequencies.
  double damping_floor_relative = 0.05;
  /// A change is significant when it exceeds `significance` standard deviations (3 = about
  /// 0.3 % false alarms per test for Gaussian errors).
  double significance = 3.0;
  /// Split poles: an impact on a micro-slipping joint sweeps the amplitude down through one
  /// record, and a curve fit often describes that one mode by two poles with the same shape
  /// (the slipping head, heavily damped, and the stuck tail). Modes of one level whose shapes
  /// agree to MAC >= split_mac and whose frequencies differ by at most
  /// split_max_relative_difference are merged into one point: frequency and damping averaged
  /// with the weight |φ|⁴/ζ (the energy of each pole's free decay when the shapes are scaled to
  /// unit modal mass; 1/ζ otherwise). split_mac > 1 turns merging off.
  double split_mac = 0.95;
  double split_max_relative_difference = 0.03;

  /// False (with the reason in *error) when a field is out of range.
  bool IsValid(std::string* error) const;
};

/// One point of a mode's track.
struct AmplitudePoint {
  double level = kNaN;
  double frequency_hz = kNaN;
  double damping_ratio = kNaN;
  double frequency_std_hz = kNaN;   ///< σ of the fit (NaN when unknown; the floor is not included)
  double damping_ratio_std = kNaN;
  int mode_index = -1;              ///< index of the mode in its level's ModeSet (the heaviest pole if merged)
  int poles = 1;                    ///< poles merged into this point (split poles, see AmplitudeOptions)
};

/// "softening", "hardening", "non-monotonic", "none".
enum class FrequencyTrend { kNone, kSoftening, kHardening, kNonMonotonic };
/// "rising", "falling", "none".
enum class DampingTrend { kNone, kRising, kFalling };
std::string FrequencyTrendToString(FrequencyTrend trend);
std::string DampingTrendToString(DampingTrend trend);

/// One mode followed over the levels.
struct AmplitudeMode {
  std::vector<AmplitudePoint> points;  ///< by increasing level; levels where the mode was found
  FrequencyTrend frequency_trend = FrequencyTrend::kNone;
  DampingTrend damping_trend = DampingTrend::kNone;
  /// 100 (f(target) - f(lowest)) / f(lowest), target = the extreme's level (non-monotonic) or
  /// the highest level.
  double frequency_change_pct = 0.0;
  /// ζ(target) / ζ(lowest) at the same target level (NaN when ζ(lowest) is 0).
  double damping_ratio_factor = kNaN;
  int target_point = 0;               ///< index into points of the target level
  /// Test statistics (docs/amplitude.md): weighted-fit slope over its σ (per log10 of level),
  /// and for a non-monotonic call the smaller of the two one-sided z values of the extreme.
  double frequency_slope_z = 0.0;
  double frequency_extreme_z = 0.0;
  double damping_slope_z = 0.0;
  /// One line, e.g. "micro-slip in a joint: f -0.33 %, ζ ×1.9 from 0.03 to 0.49 N".
  std::string reading;
};

struct AmplitudeResult {
  LevelKind level_kind = LevelKind::kPeakForce;
  std::vector<double> levels;          ///< all levels, increasing
  std::vector<AmplitudeMode> modes;    ///< modes found at >= 2 levels, by frequency
  /// Modes of some level found at no other level: (level index, mode index).
  std::vector<std::pair<int, int>> unpaired;
  std::string summary;                 ///< a few lines for people
};

/// Follows every mode over the levels and tests its trends. Throws InputError (naming the
/// level's source) for fewer than two levels, a level that is not > 0, two equal levels, a level
/// without modes, or when no mode is found at two levels or more.
AmplitudeResult AnalyseAmplitude(std::vector<AmplitudeLevel> levels, LevelKind level_kind = LevelKind::kPeakForce,
                                 const AmplitudeOptions& options = {});

/// The trend test of one series alone (exposed for tests and for callers with their own
/// pairing): points by increasing level. Fills trends, changes, z values and the reading.
void TestAmplitudeTrends(const AmplitudeOptions& options, LevelKind level_kind, AmplitudeMode* mode);

}  // namespace ema::correlation
