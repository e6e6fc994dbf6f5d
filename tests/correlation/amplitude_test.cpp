// Amplitude dependence: pairing across levels and the trend tests, on constructed mode sets
// with known trends plus Gaussian scatter from fixed seeds.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "ema/core/error.hpp"
#include "ema/correlation/amplitude.hpp"

namespace ema::correlation {
namespace {

// Three modes on four DOFs with distinct shapes (so the MAC pairs them), at f0 = 120, 310,
// 545 Hz and ζ0 = 1 %; `df_pct(level)` and `zeta_factor(level)` shape mode 1's trend.
ModeSet ThreeModes(double f1, double zeta1, double f2, double zeta2, std::mt19937* rng, double shape_noise) {
  ModeSet set;
  set.dofs = {{1, 3}, {2, 3}, {3, 3}, {4, 3}};
  const double shapes[3][4] = {{1.0, 0.8, 0.5, 0.2}, {1.0, 0.1, -0.7, -1.0}, {0.5, -1.0, 0.9, -0.3}};
  const double f[3] = {f1, f2, 545.0};
  const double z[3] = {zeta1, zeta2, 0.012};
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int r = 0; r < 3; ++r) {
    Mode m;
    m.frequency_hz = f[r];
    m.damping_ratio = z[r];
    m.pole = FrequencyAndDampingToPole(f[r], z[r]);
    m.shape.resize(4);
    for (int i = 0; i < 4; ++i) m.shape[i] = {shapes[r][i] + shape_noise * normal(*rng), shape_noise * normal(*rng)};
    set.modes.push_back(m);
  }
  return set;
}

TEST(AmplitudeOptions, DefaultsAreValidAndBadValuesAreNamed) {
  std::string why;
  EXPECT_TRUE(AmplitudeOptions{}.IsValid(&why));
  AmplitudeOptions o;
  o.significance = 0.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("significance"), std::string::npos);
}

TEST(AnalyseAmplitude, MicroSlipModeSoftensAndDampingRisesOthersStayNone) {
  // Mode 1 softens by 0.33 % and its damping rises ×1.9 over 6 levels (a saturating micro-slip
  // curve); modes 2 and 3 are linear. Scatter: 0.01 % in f and 2 % in ζ (1σ), below the
  // default floors (0.03 %, 5 %), so "none" must hold for the linear modes.
  std::mt19937 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  const std::vector<double> levels = {0.03, 0.06, 0.12, 0.24, 0.49, 0.8};
  std::vector<AmplitudeLevel> sets;
  for (double lv : levels) {
    const double slip = lv / (lv + 0.15);  // 0 .. ~0.84: share of the joint in slip
    const double f1 = 120.0 * (1.0 - 0.0040 * slip) * (1.0 + 1e-4 * normal(rng));
    const double z1 = 0.01 * (1.0 + 1.2 * slip) * (1.0 + 0.02 * normal(rng));
    const double f2 = 310.0 * (1.0 + 1e-4 * normal(rng));
    const double z2 = 0.008 * (1.0 + 0.02 * normal(rng));
    sets.push_back({lv, ThreeModes(f1, z1, f2, z2, &rng, 0.02), {}});
    sets.back().modes.source = "level " + std::to_string(lv);
  }
  std::shuffle(sets.begin(), sets.end(), rng);  // order of the inputs does not matter
  const AmplitudeResult r = AnalyseAmplitude(sets, LevelKind::kPeakForce);
  ASSERT_EQ(r.modes.size(), 3u);
  EXPECT_EQ(r.modes[0].points.size(), 6u);
  EXPECT_EQ(r.modes[0].frequency_trend, FrequencyTrend::kSoftening);
  EXPECT_EQ(r.modes[0].damping_trend, DampingTrend::kRising);
  // Truth: f(0.8)/f(0.03) - 1 = -0.4 % (0.8/0.95 - 0.03/0.18); 0.02 % allowed for the 0.01 % scatter.
  const double truth = 100.0 * ((1.0 - 0.004 * 0.8 / 0.95) / (1.0 - 0.004 * 0.03 / 0.18) - 1.0);
  EXPECT_NEAR(r.modes[0].frequency_change_pct, truth, 0.02);
  // ζ ratio scatter: 2 % per point, so about 2.8 % (1σ) on the ratio; 3σ of ~1.7 is 0.15.
  EXPECT_NEAR(r.modes[0].damping_ratio_factor, (1.0 + 1.2 * 0.8 / 0.95) / (1.0 + 1.2 * 0.03 / 0.18), 0.15);
  EXPECT_NE(r.modes[0].reading.find("micro-slip in a joint"), std::string::npos) << r.modes[0].reading;
  EXPECT_NE(r.modes[0].reading.find("from 0.03 to 0.8 N"), std::string::npos) << r.modes[0].reading;
  for (int i : {1, 2}) {
    EXPECT_EQ(r.modes[i].frequency_trend, FrequencyTrend::kNone) << i;
    EXPECT_EQ(r.modes[i].damping_trend, DampingTrend::kNone) << i;
  }
}

TEST(AnalyseAmplitude, SofteningThenHardeningIsNonMonotonic) {
  // The case: f falls by 0.3 % up to the middle levels and rises above; comparing the
  // lowest with the highest level alone (+0.15 %) would call it hardening.
  const std::vector<double> levels = {0.5, 1, 2, 4, 8, 16, 32, 64};
  const std::vector<double> df_pct = {0.0, -0.08, -0.2, -0.3, -0.28, -0.1, 0.05, 0.15};
  std::mt19937 rng(3);
  std::vector<AmplitudeLevel> sets;
  for (size_t i = 0; i < levels.size(); ++i)
    sets.push_back({levels[i], ThreeModes(120.0 * (1 + df_pct[i] / 100), 0.01, 310.0, 0.008, &rng, 0.0), {}});
  const AmplitudeResult r = AnalyseAmplitude(sets, LevelKind::kRmsForce);
  ASSERT_EQ(r.modes.size(), 3u);
  EXPECT_EQ(r.modes[0].frequency_trend, FrequencyTrend::kNonMonotonic);
  EXPECT_EQ(r.modes[0].target_point, 3);
  EXPECT_NEAR(r.modes[0].frequency_change_pct, -0.3, 1e-9);  // to the extreme's level, exactly
  EXPECT_DOUBLE_EQ(r.modes[0].damping_ratio_factor, 1.0);
  EXPECT_EQ(r.modes[0].damping_trend, DampingTrend::kNone);
  EXPECT_NE(r.modes[0].reading.find("then contact stiffening"), std::string::npos) << r.modes[0].reading;
  EXPECT_EQ(r.level_kind, LevelKind::kRmsForce);
}

TEST(AnalyseAmplitude, TheFitSigmaDecidesWhenLargerThanTheFloor) {
  // f falls 0.2 % over three levels: significant against the 0.03 % floor, but not when the
  // fit says each frequency is only known to 0.1 %.
  std::mt19937 rng(1);
  std::vector<AmplitudeLevel> sets;
  for (int i = 0; i < 3; ++i) {
    AmplitudeLevel l{std::pow(2.0, i), ThreeModes(120.0 * (1 - 0.001 * i), 0.01, 310.0, 0.008, &rng, 0.0), {}};
    sets.push_back(l);
  }
  EXPECT_EQ(AnalyseAmplitude(sets).modes[0].frequency_trend, FrequencyTrend::kSoftening);
  for (AmplitudeLevel& l : sets) l.uncertainty.assign(3, ModeUncertainty{0.12, 0.0005});
  EXPECT_EQ(AnalyseAmplitude(sets).modes[0].frequency_trend, FrequencyTrend::kNone);
}

TEST(AnalyseAmplitude, LinearStructureIsNoneInNearlyAllMonteCarloRuns) {
  // 200 runs of 5 linear levels with scatter at the floors (0.03 % in f, 5 % in ζ): a test at 3σ
  // (slope or end-to-end change, both directions) should false-alarm in a few % of runs at most.
  std::mt19937 rng(11);
  std::normal_distribution<double> normal(0.0, 1.0);
  int alarms = 0;
  for (int run = 0; run < 200; ++run) {
    std::vector<AmplitudeLevel> sets;
    for (int i = 0; i < 5; ++i)
      sets.push_back({std::pow(2.0, i),
                      ThreeModes(120.0 * (1 + 3e-4 * normal(rng)), 0.01 * (1 + 0.05 * normal(rng)),
                                 310.0 * (1 + 3e-4 * normal(rng)), 0.008 * (1 + 0.05 * normal(rng)), &rng, 0.01),
                      {}});
    const AmplitudeResult r = AnalyseAmplitude(sets);
    for (const AmplitudeMode& m : r.modes)
      alarms += (m.frequency_trend != FrequencyTrend::kNone) + (m.damping_trend != DampingTrend::kNone);
  }
  EXPECT_LT(alarms, 0.03 * 200 * 3 * 2);  // 3 modes x 2 trends per run
}

TEST(AnalyseAmplitude, FewerThanTwoLevelsOrNoPairIsAnInputError) {
  std::mt19937 rng(1);
  std::vector<AmplitudeLevel> one = {{1.0, ThreeModes(120, 0.01, 310, 0.008, &rng, 0.0), {}}};
  EXPECT_THROW(AnalyseAmplitude(one), InputError);
  // Second level: modes far from the first level's in frequency (no pair within 5 %).
  std::vector<AmplitudeLevel> two = one;
  ModeSet other = ThreeModes(200, 0.01, 400, 0.008, &rng, 0.0);
  other.modes.pop_back();
  two.push_back({2.0, other, {}});
  two[0].modes.modes.pop_back();
  EXPECT_THROW(AnalyseAmplitude(two), InputError);
  std::vector<AmplitudeLevel> same = one;
  same.push_back(one.front());
  EXPECT_THROW(AnalyseAmplitude(same), InputError);
}

}  // namespace
}  // namespace ema::correlation
