// Amplitude dependence of modes: pairing across levels and the trend tests (docs/amplitude.md).
#include "ema/correlation/amplitude.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <sstream>

#include "ema/core/error.hpp"
#include "ema/core/text.hpp"
#include "ema/correlation/dof_match.hpp"
#include "ema/correlation/mac.hpp"
#include "ema/correlation/pairing.hpp"

namespace ema::correlation {
namespace {

std::string Num(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

/// Outcome of the monotone and extreme tests on one series y(x) with 1σ s.
struct SeriesTest {
  double slope_z = 0.0;   ///< weighted LS slope / its σ (σ inflated by the scatter when chi2/dof > 1)
  double end_z = 0.0;     ///< (y_last - y_first) / σ of the difference
  int interior_min = -1;  ///< interior minimum significant on both sides (else -1)
  int interior_max = -1;
  double min_z = 0.0;     ///< the smaller one-sided z of the interior minimum
  double max_z = 0.0;
};

SeriesTest TestSeries(const std::vector<double>& x, const std::vector<double>& y, const std::vector<double>& s,
                      double k) {
  SeriesTest t;
  const size_t n = y.size();
  if (n < 2) return t;
  // Weighted least squares of y on x.
  double sw = 0.0, swx = 0.0, swy = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const double w = 1.0 / (s[i] * s[i]);
    sw += w, swx += w * x[i], swy += w * y[i];
  }
  const double xm = swx / sw, ym = swy / sw;
  double sxx = 0.0, sxy = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const double w = 1.0 / (s[i] * s[i]);
    sxx += w * (x[i] - xm) * (x[i] - xm);
    sxy += w * (x[i] - xm) * (y[i] - ym);
  }
  if (sxx > 0.0) {
    const double b = sxy / sxx;
    double sigma_b = 1.0 / std::sqrt(sxx);
    if (n > 2) {
      double chi2 = 0.0;
      for (size_t i = 0; i < n; ++i) {
        const double r = y[i] - ym - b * (x[i] - xm);
        chi2 += r * r / (s[i] * s[i]);
      }
      const double birge = chi2 / static_cast<double>(n - 2);
      if (birge > 1.0) sigma_b *= std::sqrt(birge);
    }
    t.slope_z = b / sigma_b;
  }
  t.end_z = (y[n - 1] - y[0]) / std::hypot(s[n - 1], s[0]);
  // Interior extremes, each tested one-sided against both ends.
  if (n >= 3) {
    const auto imin = static_cast<size_t>(std::min_element(y.begin(), y.end()) - y.begin());
    const auto imax = static_cast<size_t>(std::max_element(y.begin(), y.end()) - y.begin());
    if (imin > 0 && imin + 1 < n) {
      const double z1 = (y[0] - y[imin]) / std::hypot(s[0], s[imin]);
      const double z2 = (y[n - 1] - y[imin]) / std::hypot(s[n - 1], s[imin]);
      t.min_z = std::min(z1, z2);
      if (t.min_z > k) t.interior_min = static_cast<int>(imin);
    }
    if (imax > 0 && imax + 1 < n) {
      const double z1 = (y[imax] - y[0]) / std::hypot(s[0], s[imax]);
      const double z2 = (y[imax] - y[n - 1]) / std::hypot(s[n - 1], s[imax]);
      t.max_z = std::min(z1, z2);
      if (t.max_z > k) t.interior_max = static_cast<int>(imax);
    }
  }
  return t;
}

/// +1 rising, -1 falling, 0 none: the slope or the end-to-end change beyond k σ, both agreeing
/// in sign when both are significant.
int MonotoneSign(const SeriesTest& t, double k) {
  const bool slope = std::abs(t.slope_z) > k, end = std::abs(t.end_z) > k;
  if (!slope && !end) return 0;
  if (slope && end && (t.slope_z > 0) != (t.end_z > 0)) return 0;
  return (slope ? t.slope_z : t.end_z) > 0.0 ? 1 : -1;
}

std::string Reading(const AmplitudeMode& m, LevelKind kind) {
  const AmplitudePoint& p0 = m.points.front();
  const AmplitudePoint& pt = m.points[static_cast<size_t>(m.target_point)];
  std::string what;
  using F = FrequencyTrend;
  using D = DampingTrend;
  if (m.frequency_trend == F::kSoftening && m.damping_trend == D::kRising) what = "micro-slip in a joint";
  else if (m.frequency_trend == F::kSoftening) what = "softening stiffness (a contact or joint losing stiffness)";
  else if (m.frequency_trend == F::kHardening && m.damping_trend == D::kRising)
    what = "hardening with more dissipation (a contact closing, with friction)";
  else if (m.frequency_trend == F::kHardening) what = "hardening stiffness (a gap closing or a Hertz-type contact)";
  else if (m.frequency_trend == F::kNonMonotonic) {
    const bool soft_first = pt.frequency_hz < p0.frequency_hz;
    what = soft_first ? "micro-slip at low levels, then contact stiffening"
                      : "stiffening at low levels, then softening (slip)";
  } else if (m.damping_trend == D::kRising)
    what = "amplitude-dependent damping (friction) without a stiffness change";
  else if (m.damping_trend == D::kFalling)
    what = "damping falling with level";
  else
    what = "linear within the scatter";
  const std::string unit = kind == LevelKind::kResponse ? "" : " N";
  const double dpct = m.frequency_change_pct;
  std::string f = std::string("f ") + (dpct < 0 ? "\u2212" : "+") + FixedPoint(std::abs(dpct), 2, "nan") + " %";
  std::string z = std::isfinite(m.damping_ratio_factor) ? ", \u03b6 \u00d7" + Num(m.damping_ratio_factor, 2) : "";
  return what + ": " + f + z + " from " + Num(p0.level, 3) + " to " + Num(pt.level, 3) + unit;
}

/// Merges the split poles of one level in place (AmplitudeOptions::split_mac); `count` gets,
/// per remaining mode, how many poles it stands for.
void MergeSplitPoles(const AmplitudeOptions& options, AmplitudeLevel* level, std::vector<int>* count) {
  ModeSet& set = level->modes;
  const size_t n = set.modes.size();
  count->assign(n, 1);
  if (options.split_mac > 1.0 || n < 2) return;
  std::vector<int> group(n);
  for (size_t i = 0; i < n; ++i) group[i] = static_cast<int>(i);
  std::function<int(int)> find = [&](int i) { return group[i] == i ? i : group[i] = find(group[i]); };
  bool any = false;
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j) {
      const Mode& a = set.modes[i];
      const Mode& b = set.modes[j];
      if (a.shape.size() == 0 || a.shape.size() != b.shape.size() || a.shape.norm() == 0.0 || b.shape.norm() == 0.0)
        continue;
      const double df = std::abs(a.frequency_hz - b.frequency_hz) / std::max(a.frequency_hz, b.frequency_hz);
      if (df <= options.split_max_relative_difference && Mac(a.shape, b.shape) >= options.split_mac) {
        group[static_cast<size_t>(find(static_cast<int>(j)))] = find(static_cast<int>(i));
        any = true;
      }
    }
  if (!any) return;
  ModeSet merged = set;
  merged.modes.clear();
  std::vector<ModeUncertainty> sigma;
  count->clear();
  for (size_t root = 0; root < n; ++root) {
    if (find(static_cast<int>(root)) != static_cast<int>(root)) continue;
    double sw = 0.0, f = 0.0, z = 0.0, vf = 0.0, vz = 0.0, heaviest = -1.0;
    bool sf = true, sz = true;
    int members = 0;
    size_t best = root;
    for (size_t i = 0; i < n; ++i) {
      if (find(static_cast<int>(i)) != static_cast<int>(root)) continue;
      const Mode& m = set.modes[i];
      const double amp = m.unit_modal_mass ? std::pow(m.shape.squaredNorm(), 2) : 1.0;
      const double w = amp / std::max(m.damping_ratio, 1e-6);
      sw += w, f += w * m.frequency_hz, z += w * m.damping_ratio, ++members;
      if (w > heaviest) heaviest = w, best = i;
      const ModeUncertainty u = level->uncertainty.empty() ? ModeUncertainty{} : level->uncertainty[i];
      sf = sf && std::isfinite(u.frequency_std_hz), sz = sz && std::isfinite(u.damping_ratio_std);
      vf += w * w * (std::isfinite(u.frequency_std_hz) ? u.frequency_std_hz * u.frequency_std_hz : 0.0);
      vz += w * w * (std::isfinite(u.damping_ratio_std) ? u.damping_ratio_std * u.damping_ratio_std : 0.0);
    }
    Mode m = set.modes[best];
    m.frequency_hz = f / sw;
    m.damping_ratio = z / sw;
    m.pole = FrequencyAndDampingToPole(m.frequency_hz, m.damping_ratio);
    merged.modes.push_back(m);
    sigma.push_back({sf ? std::sqrt(vf) / sw : kNaN, sz ? std::sqrt(vz) / sw : kNaN});
    count->push_back(members);
  }
  set = std::move(merged);
  if (!level->uncertainty.empty()) level->uncertainty = std::move(sigma);
}

}  // namespace

std::string LevelKindToString(LevelKind kind) { return NameOf(kLevelKindNames, kind); }

bool StringToLevelKind(const std::string& name, LevelKind* kind) { return FromName(kLevelKindNames, name, kind); }

std::string FrequencyTrendToString(FrequencyTrend trend) {
  switch (trend) {
    case FrequencyTrend::kNone: return "none";
    case FrequencyTrend::kSoftening: return "softening";
    case FrequencyTrend::kHardening: return "hardening";
    case FrequencyTrend::kNonMonotonic: return "non-monotonic";
  }
  return "none";
}

std::string DampingTrendToString(DampingTrend trend) {
  switch (trend) {
    case DampingTrend::kNone: return "none";
    case DampingTrend::kRising: return "rising";
    case DampingTrend::kFalling: return "falling";
  }
  return "none";
}

bool AmplitudeOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (!(mac_min >= 0.0 && mac_min <= 1.0)) return fail("mac_min (" + Num(mac_min, 6) + ") must be in [0, 1]");
  if (!(max_relative_frequency_difference > 0.0))
    return fail("max_relative_frequency_difference (" + Num(max_relative_frequency_difference, 6) + ") must be > 0");
  if (!(frequency_floor_pct > 0.0)) return fail("frequency_floor_pct (" + Num(frequency_floor_pct, 6) + ") must be > 0");
  if (!(damping_floor_relative > 0.0))
    return fail("damping_floor_relative (" + Num(damping_floor_relative, 6) + ") must be > 0");
  if (!(significance > 0.0)) return fail("significance (" + Num(significance, 6) + ") must be > 0");
  if (!(split_mac >= 0.0)) return fail("split_mac (" + Num(split_mac, 6) + ") must be >= 0");
  if (!(split_max_relative_difference >= 0.0))
    return fail("split_max_relative_difference (" + Num(split_max_relative_difference, 6) + ") must be >= 0");
  return true;
}

void TestAmplitudeTrends(const AmplitudeOptions& options, LevelKind level_kind, AmplitudeMode* mode) {
  AmplitudeMode& m = *mode;
  const size_t n = m.points.size();
  const double k = options.significance;
  m.frequency_trend = FrequencyTrend::kNone;
  m.damping_trend = DampingTrend::kNone;
  m.target_point = n > 0 ? static_cast<int>(n - 1) : 0;
  if (n < 2) {
    m.reading = "found at one level only";
    return;
  }
  // Frequency in % of the lowest level's, σ = fit σ (+) floor.
  const double f0 = m.points.front().frequency_hz;
  std::vector<double> x, y, s;
  for (const AmplitudePoint& p : m.points) {
    x.push_back(std::log10(p.level));
    y.push_back(100.0 * (p.frequency_hz - f0) / f0);
    const double fit = std::isfinite(p.frequency_std_hz) ? 100.0 * p.frequency_std_hz / f0 : 0.0;
    s.push_back(std::hypot(fit, options.frequency_floor_pct));
  }
  const SeriesTest ft = TestSeries(x, y, s, k);
  m.frequency_slope_z = ft.slope_z;
  // Non-monotonic wins when an interior extreme stands out on both sides; the stronger one.
  int extreme = -1;
  if (ft.interior_min >= 0 && (ft.interior_max < 0 || ft.min_z >= ft.max_z)) extreme = ft.interior_min;
  else if (ft.interior_max >= 0) extreme = ft.interior_max;
  if (extreme >= 0) {
    m.frequency_trend = FrequencyTrend::kNonMonotonic;
    m.frequency_extreme_z = extreme == ft.interior_min ? ft.min_z : ft.max_z;
    m.target_point = extreme;
  } else {
    const int sign = MonotoneSign(ft, k);
    m.frequency_trend = sign < 0 ? FrequencyTrend::kSoftening : sign > 0 ? FrequencyTrend::kHardening : FrequencyTrend::kNone;
  }
  const AmplitudePoint& target = m.points[static_cast<size_t>(m.target_point)];
  m.frequency_change_pct = 100.0 * (target.frequency_hz - f0) / f0;

  // Damping: ln(ζ / ζ_lowest), σ = relative fit σ (+) floor; points with ζ <= 0 are left out.
  const double z0 = m.points.front().damping_ratio;
  m.damping_ratio_factor = z0 > 0.0 ? target.damping_ratio / z0 : kNaN;
  std::vector<double> dx, dy, ds;
  for (const AmplitudePoint& p : m.points) {
    if (!(p.damping_ratio > 0.0)) continue;
    dx.push_back(std::log10(p.level));
    dy.push_back(std::log(p.damping_ratio));
    const double fit = std::isfinite(p.damping_ratio_std) ? p.damping_ratio_std / p.damping_ratio : 0.0;
    ds.push_back(std::hypot(fit, options.damping_floor_relative));
  }
  if (dy.size() >= 2) {
    const SeriesTest dt = TestSeries(dx, dy, ds, k);
    m.damping_slope_z = dt.slope_z;
    const int sign = MonotoneSign(dt, k);
    m.damping_trend = sign > 0 ? DampingTrend::kRising : sign < 0 ? DampingTrend::kFalling : DampingTrend::kNone;
  }
  m.reading = Reading(m, level_kind);
}

AmplitudeResult AnalyseAmplitude(std::vector<AmplitudeLevel> levels, LevelKind level_kind,
                                 const AmplitudeOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("amplitude options", why);
  if (levels.size() < 2)
    throw InputError(levels.empty() ? "amplitude" : levels.front().modes.source,
                     "amplitude dependence needs mode sets from at least 2 levels, got " + std::to_string(levels.size()));
  for (const AmplitudeLevel& l : levels) {
    if (!(l.level > 0.0) || !std::isfinite(l.level))
      throw InputError(l.modes.source, "level must be a positive number, got " + Num(l.level, 6));
    if (l.modes.modes.empty()) throw InputError(l.modes.source, "no modes at level " + Num(l.level, 6));
    if (!l.uncertainty.empty() && l.uncertainty.size() != l.modes.modes.size())
      throw InputError(l.modes.source, "uncertainty given for " + std::to_string(l.uncertainty.size()) +
                                           " modes but the set holds " + std::to_string(l.modes.modes.size()));
  }
  std::stable_sort(levels.begin(), levels.end(), [](const auto& a, const auto& b) { return a.level < b.level; });
  for (size_t i = 1; i < levels.size(); ++i)
    if (levels[i].level == levels[i - 1].level)
      throw InputError(levels[i].modes.source, "same level " + Num(levels[i].level, 6) + " as " +
                                                   levels[i - 1].modes.source + ": give each level once");

  std::vector<std::vector<int>> merged_count(levels.size());
  for (std::size_t l = 0; l < levels.size(); ++l) MergeSplitPoles(options, &levels[l], &merged_count[l]);

  AmplitudeResult result;
  result.level_kind = level_kind;
  for (const AmplitudeLevel& l : levels) result.levels.push_back(l.level);

  // Reference: the level with the most modes (the lowest such), so every mode has a home.
  size_t ref = 0;
  for (size_t i = 1; i < levels.size(); ++i)
    if (levels[i].modes.modes.size() > levels[ref].modes.modes.size()) ref = i;
  const ModeSet& ref_set = levels[ref].modes;
  auto point = [&](size_t level, int mode) {
    const Mode& md = levels[level].modes.modes[static_cast<size_t>(mode)];
    AmplitudePoint p;
    p.level = levels[level].level;
    p.frequency_hz = md.frequency_hz;
    p.damping_ratio = md.damping_ratio;
    if (!levels[level].uncertainty.empty()) {
      p.frequency_std_hz = levels[level].uncertainty[static_cast<size_t>(mode)].frequency_std_hz;
      p.damping_ratio_std = levels[level].uncertainty[static_cast<size_t>(mode)].damping_ratio_std;
    }
    p.mode_index = mode;
    p.poles = merged_count[level][static_cast<size_t>(mode)];
    return p;
  };
  std::vector<AmplitudeMode> tracks(ref_set.modes.size());
  for (size_t j = 0; j < ref_set.modes.size(); ++j) tracks[j].points.push_back(point(ref, static_cast<int>(j)));

  Eigen::VectorXd f_ref(static_cast<Eigen::Index>(ref_set.modes.size()));
  for (size_t j = 0; j < ref_set.modes.size(); ++j) f_ref(static_cast<Eigen::Index>(j)) = ref_set.modes[j].frequency_hz;
  for (size_t l = 0; l < levels.size(); ++l) {
    if (l == ref) continue;
    const ModeSet& set = levels[l].modes;
    Eigen::VectorXd f_set(static_cast<Eigen::Index>(set.modes.size()));
    for (size_t i = 0; i < set.modes.size(); ++i) f_set(static_cast<Eigen::Index>(i)) = set.modes[i].frequency_hz;
    PairingOptions popt;
    popt.mac_min = options.mac_min;
    popt.max_relative_frequency_difference = options.max_relative_frequency_difference;
    const DofMatch match = MatchDofs(set, ref_set);
    Eigen::MatrixXd mac;
    bool shapes = match.Count() > 0;
    if (shapes) {
      mac = MacMatrix(match.TestShapes(set), match.ModelShapes(ref_set));
      // Shapes that are all zero on the shared DOFs (e.g. peak picking without shapes) cannot
      // be compared: pair those sets by frequency alone.
      shapes = mac.size() > 0 && mac.maxCoeff() > 0.0;
    }
    if (!shapes) {
      mac = Eigen::MatrixXd::Ones(f_set.size(), f_ref.size());
      popt.mac_min = 0.0;
    }
    popt.frequency_weight = shapes ? 0.2 : 1.0;
    const Pairing pairing = PairModes(mac, f_set, f_ref, popt);
    for (const ModePair& p : pairing.pairs) tracks[static_cast<size_t>(p.model)].points.push_back(point(l, p.test));
    for (int u : pairing.unpaired_test) result.unpaired.push_back({static_cast<int>(l), u});
  }
  for (AmplitudeMode& t : tracks) {
    if (t.points.size() < 2) {
      result.unpaired.push_back({static_cast<int>(ref), t.points.front().mode_index});
      continue;
    }
    std::sort(t.points.begin(), t.points.end(), [](const auto& a, const auto& b) { return a.level < b.level; });
    TestAmplitudeTrends(options, level_kind, &t);
    result.modes.push_back(std::move(t));
  }
  if (result.modes.empty()) {
    std::string sources;
    for (const AmplitudeLevel& l : levels) sources += (sources.empty() ? "" : ", ") + l.modes.source;
    throw InputError(sources, "no mode pairs across the levels (MAC >= " + Num(options.mac_min, 3) +
                                  " and frequencies within " + Num(100.0 * options.max_relative_frequency_difference, 3) +
                                  " %): nothing to follow over the levels");
  }
  std::sort(result.modes.begin(), result.modes.end(),
            [](const auto& a, const auto& b) { return a.points.front().frequency_hz < b.points.front().frequency_hz; });
  std::ostringstream s;
  for (size_t i = 0; i < result.modes.size(); ++i) {
    const AmplitudeMode& m = result.modes[i];
    s << "mode " << i + 1 << " (" << Num(m.points.front().frequency_hz, 6) << " Hz, " << m.points.size()
      << " levels): frequency " << FrequencyTrendToString(m.frequency_trend) << ", damping "
      << DampingTrendToString(m.damping_trend) << "; " << m.reading << "\n";
  }
  result.summary = s.str();
  return result;
}

}  // namespace ema::correlation
