// Hammer test → FRFs against analytic truth (issue 3, item 6). Every test states its tolerance.
#include "ema/frf/hammer_frf.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "ema/core/error.hpp"
#include "ema/frf/fft.hpp"
#include "frf/frf_test_util.hpp"

namespace ema::frf {
namespace {

using acquisition::AnalyticFrf;
using acquisition::HammerTestPlan;
using cd = std::complex<double>;
using ::testing::HasSubstr;

// Bendat & Piersol normalised random error of |H1| (spec §1.8).
double RandomError(double coherence, int averages) {
  return std::sqrt(std::max(0.0, 1.0 - coherence)) / (std::sqrt(coherence) * std::sqrt(2.0 * averages));
}

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// Longer records than ThreeDofPlan (4 s = 11 tau of the slowest mode) keep truncation leakage
// below 0.1 % of the accelerance above 10 Hz, so what remains is the estimator's own error.
HammerTestPlan LongPlan() {
  HammerTestPlan plan = testing::ThreeDofPlan();
  plan.samples_per_record = 16384;
  return plan;
}

TEST(HammerFrf, NoiseFreeEstimatorsAgreeWithAnalyticAccelerance) {
  // Noise-free time-domain simulation: H1, H2, Hv agree within 5e-3 and equal the analytic
  // accelerance within 5e-3 over 10–1000 Hz. Not 1e-10 as for FRF-domain data (that is checked on
  // exact spectra in estimators_test): each impact's trigger jitter moves the truncation point of
  // the not-quite-decayed tail (e^{-zeta w T} ~ 1e-5 of the peak), which shows up relative to the
  // small accelerance near anti-resonances. A sign, scale or phase-convention error fails by far.
  const auto sys = testing::MakeThreeDof();
  const HammerTestPlan plan = LongPlan();
  const auto test = acquisition::AssembleHammerMeasurement(testing::ToRecordSets(acquisition::SimulateHammerTestSets({sys.truth}, plan)));
  FrfOptions opt;
  const FrfResult h1 = EstimateFrfs(test, opt);
  opt.estimator = Estimator::kH2;
  const FrfResult h2 = EstimateFrfs(test, opt);
  opt.estimator = Estimator::kHv;
  const FrfResult hv = EstimateFrfs(test, opt);
  const FrfSet& s = h1.frfs;
  EXPECT_EQ(s.window_decay_rate, 0.0);
  EXPECT_EQ(s.output_quantity, Quantity::kAcceleration);
  ASSERT_EQ(s.OutputCount(), 3);
  for (int o = 0; o < 3; ++o) {
    const Eigen::VectorXcd truth = AnalyticFrf(sys.truth, s.outputs[o], s.references[0], s.frequency_hz);
    EXPECT_EQ(s.averages(0, o), 5);
    double worst = 0.0, worst_est = 0.0;
    for (int i = 0; i < s.LineCount(); ++i) {
      if (s.frequency_hz[i] < 10.0 || s.frequency_hz[i] > 1000.0) continue;
      const cd a = s.h[0](i, o);
      worst_est = std::max({worst_est, std::abs(h2.frfs.h[0](i, o) - a) / std::abs(a),
                            std::abs(hv.frfs.h[0](i, o) - a) / std::abs(a)});
      worst = std::max(worst, std::abs(a - truth[i]) / std::abs(truth[i]));
    }
    EXPECT_LT(worst_est, 5e-3) << "output " << o;
    EXPECT_LT(worst, 5e-3) << "output " << o;
  }
}

TEST(HammerFrf, H1WithinTwoPercentWhereCoherenceIsHigh) {
  // Issue 3 item 6: 1 % noise (rms, relative to each channel's rms) on force and responses, 5
  // impacts, H1 against the analytic accelerance, complex difference (so phase included).
  // (a) Around every resonance (±2 half-power bandwidths, the lines a fit lives on) every line has
  //     coherence > 0.95 and H1 within 2 %.
  // (b) Over all lines of 10–1000 Hz with coherence > 0.95, the median error is below 2 % and the
  //     errors are what the noise explains: median of err / ε(γ², 5) below 2 (ε = Bendat–Piersol
  //     random error; the theoretical median is ≈ 1.4). A line-by-line 2 % bound cannot hold at
  //     γ² ≈ 0.95 with 5 averages (ε ≈ 7 % there), but any bias or phase error ≥ 2 % at the many
  //     high-coherence lines pushes the normalised median far above 2.
  const auto sys = testing::MakeThreeDof();
  HammerTestPlan plan = LongPlan();
  plan.force_noise = 0.01;
  plan.response_noise = 0.01;
  const FrfResult res = testing::SimulateAndEstimate(sys.truth, plan);
  const FrfSet& s = res.frfs;
  for (int o = 0; o < 3; ++o) {
    const Eigen::VectorXcd truth = AnalyticFrf(sys.truth, s.outputs[o], s.references[0], s.frequency_hz);
    int checked = 0, near_resonance = 0;
    std::vector<double> errors, zs;
    for (int i = 0; i < s.LineCount(); ++i) {
      const double f = s.frequency_hz[i];
      if (f < 10.0 || f > 1000.0) continue;
      const double coh = s.coherence[0](i, o);
      const double err = std::abs(s.h[0](i, o) - truth[i]) / std::abs(truth[i]);
      bool near = false;
      for (int r = 0; r < 3; ++r)
        near = near || std::abs(f - sys.frequency_hz[r]) < 2.0 * 2.0 * sys.damping[r] * sys.frequency_hz[r];
      if (near) {
        ++near_resonance;
        EXPECT_GT(coh, 0.95) << "output " << o << " at " << f << " Hz";
        EXPECT_LT(err, 0.02) << "output " << o << " at " << f << " Hz";
      }
      if (coh <= 0.95) continue;
      ++checked;
      errors.push_back(err);
      zs.push_back(err / RandomError(coh, 5));
    }
    EXPECT_LT(Median(errors), 0.02) << "output " << o;
    EXPECT_LT(Median(zs), 2.0) << "output " << o << ": errors larger than the noise explains (a bias)";
    EXPECT_GT(near_resonance, 10);
    EXPECT_GT(checked, 500) << "too few high-coherence lines to say anything";
  }
}

TEST(HammerFrf, H1LowWithForceNoiseH2HighWithResponseNoise) {
  // H1 = Gxy/Gxx is biased low by force (input) noise, H2 = Gyy/Gyx high by response (output)
  // noise; the other estimator stays unbiased (spec §1.7). 20 impacts. Force noise is 1 % of the force peak
  // with the force window opened over the whole record, so the noise reaches Gxx (response noise:
  // 20 % of the response rms, expected H2/H ≈ 1 + 1/SNR, 1.3 in the median): expected
  // H1/H ≈ 1/(1 + Gnn/Gxx) ≈ 0.8 here. Tolerances on the median of Re(H/H_true) over 10–1000 Hz: biased
  // estimator off by > 5 %, unbiased one within 2 %, and |H1| ≤ |Hv| ≤ |H2|, γ² = |H1|/|H2|
  // (1e-12) at every line (spec §7.5).
  const auto sys = testing::MakeThreeDof();
  for (const bool force_noise : {true, false}) {
    HammerTestPlan plan = LongPlan();
    plan.noise_relative_to_peak = force_noise;
    plan.force_noise = force_noise ? 0.01 : 0.0;
    plan.response_noise = force_noise ? 0.0 : 0.2;
    plan.impacts_per_reference = 20;  // the bias stays, the random part averages down
    FrfOptions opt;
    opt.impact.force_window_pulses = 1e6;  // window open: the force noise stays in Gxx
    const auto test = acquisition::AssembleHammerMeasurement(testing::ToRecordSets(acquisition::SimulateHammerTestSets({sys.truth}, plan)));
    const FrfResult h1 = EstimateFrfs(test, opt);
    opt.estimator = Estimator::kH2;
    const FrfResult h2 = EstimateFrfs(test, opt);
    opt.estimator = Estimator::kHv;
    const FrfResult hv = EstimateFrfs(test, opt);
    const FrfSet& s = h1.frfs;
    std::vector<double> r1, r2;
    for (int o = 0; o < 3; ++o) {
      const Eigen::VectorXcd truth = AnalyticFrf(sys.truth, s.outputs[o], s.references[0], s.frequency_hz);
      for (int i = 0; i < s.LineCount(); ++i) {
        const double f = s.frequency_hz[i];
        if (f < 10.0 || f > 1000.0) continue;
        const double a1 = std::abs(s.h[0](i, o)), a2 = std::abs(h2.frfs.h[0](i, o)), av = std::abs(hv.frfs.h[0](i, o));
        // Re(H/H_true): the magnitude |H| of a noisy estimate is biased up by the noise alone,
        // the in-phase component is not; the estimator bias shows in it.
        r1.push_back((s.h[0](i, o) / truth[i]).real());
        r2.push_back((h2.frfs.h[0](i, o) / truth[i]).real());
        EXPECT_LE(a1, av * (1 + 1e-12));
        EXPECT_LE(av, a2 * (1 + 1e-12));
        EXPECT_NEAR(s.coherence[0](i, o), a1 / a2, 1e-12);
      }
    }
    if (force_noise) {
      EXPECT_LT(Median(r1), 0.95) << "H1 should be biased low by force noise";
      EXPECT_NEAR(Median(r2), 1.0, 0.02) << "H2 should be unbiased with force noise";
    } else {
      EXPECT_GT(Median(r2), 1.05) << "H2 should be biased high by response noise";
      EXPECT_NEAR(Median(r1), 1.0, 0.02) << "H1 should be unbiased with response noise";
    }
  }
}

// Levy fit of a 3-mode rational receptance model alpha(s) = N(s)/D(s), D monic of degree 6, N of
// degree 5, over [f_lo, f_hi] (all three modes inside, so the model is exact and only noise
// biases it). `decay_rate`: the data are accelerance at s = jw + rate, so alpha = A / (jw + rate)^2.
// s is scaled by s0 for conditioning. Returns the poles with Im > 0, sorted by frequency.
std::vector<cd> FitPoles(const FrfSet& s, int o, double f_lo, double f_hi, double decay_rate) {
  constexpr int kOrder = 6;
  const double s0 = kTwoPi * 100.0;
  std::vector<int> lines;
  for (int i = 0; i < s.LineCount(); ++i)
    if (s.frequency_hz[i] >= f_lo && s.frequency_hz[i] <= f_hi) lines.push_back(i);
  // Unknowns: d_0..d_5 (D = x^6 + sum d_k x^k) and n_0..n_5, x = jw / s0. Sanathanan–Koerner
  // iterations (rows weighted by 1/|D_previous|) remove Levy's bias toward large |D|.
  Eigen::VectorXd sol = Eigen::VectorXd::Zero(2 * kOrder);
  for (int iteration = 0; iteration < 8; ++iteration) {
    Eigen::MatrixXd a(2 * lines.size(), 2 * kOrder);
    Eigen::VectorXd b(2 * lines.size());
    for (size_t k = 0; k < lines.size(); ++k) {
      const cd jw(0, kTwoPi * s.frequency_hz[lines[k]]);
      const cd x = jw / s0;
      const cd alpha = s.h[0](lines[k], o) / ((jw + decay_rate) * (jw + decay_rate)) * (s0 * s0);
      cd d_prev = std::pow(x, kOrder);
      for (int c = 0; c < kOrder; ++c) d_prev += sol[c] * std::pow(x, c);
      const double w = iteration == 0 ? 1.0 : 1.0 / std::abs(d_prev);
      cd xp = 1.0;
      for (int c = 0; c < kOrder; ++c) {
        const cd d_term = w * alpha * xp, n_term = -w * xp;
        a(2 * k, c) = d_term.real();
        a(2 * k + 1, c) = d_term.imag();
        a(2 * k, kOrder + c) = n_term.real();
        a(2 * k + 1, kOrder + c) = n_term.imag();
        xp *= x;
      }
      const cd rhs = -w * alpha * xp;  // xp = x^6 here
      b(2 * k) = rhs.real();
      b(2 * k + 1) = rhs.imag();
    }
    sol = a.colPivHouseholderQr().solve(b);
  }
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(kOrder, kOrder);
  for (int c = 0; c < kOrder; ++c) companion(0, c) = -sol[kOrder - 1 - c];
  for (int c = 1; c < kOrder; ++c) companion(c, c - 1) = 1.0;
  const Eigen::VectorXcd roots = Eigen::EigenSolver<Eigen::MatrixXd>(companion).eigenvalues();
  std::vector<cd> poles;
  for (const cd& r : roots)
    if (r.imag() > 0) poles.push_back(r * s0);
  std::sort(poles.begin(), poles.end(), [](cd p, cd q) { return p.imag() < q.imag(); });
  return poles;
}

TEST(HammerFrf, ExponentialWindowCorrectionRestoresDamping) {
  // 0.5 s records: the slowest mode still rings at ~25 % of its peak at the end, so the automatic
  // exponential window is applied and recorded. The windowed FRF must match the analytic FRF at
  // s = jw + 1/tau (3 % within ±3 windowed half-power bandwidths of each mode; away from the
  // modes random error dominates, see the H1 test), and a 3-mode rational fit (the test's own
  // Sanathanan–Koerner fit), corrected by lambda += 1/tau (spec §1.4), must give the true damping
  // within 2 % (issue 3 item 6) while the uncorrected damping is far off (> 20 %). Noise 0.2 %
  // and 5 impacts as in spec §7.5; measured errors 0.7 %, 0.1 %, 0.1 % (at 1 % noise: 2.0 %).
  const auto sys = testing::MakeThreeDof();
  HammerTestPlan plan = testing::ThreeDofPlan();
  plan.samples_per_record = 2048;
  plan.force_noise = 0.002;  // the noise of spec §7.5's hammer-pipeline check
  plan.response_noise = 0.002;
  const FrfResult res = testing::SimulateAndEstimate(sys.truth, plan);
  const FrfSet& s = res.frfs;
  const double rate = s.window_decay_rate;
  ASSERT_GT(rate, 1.0);
  EXPECT_EQ(res.summary.window_decay_rate, rate);
  for (int o = 0; o < 3; ++o) {
    const Eigen::VectorXcd shifted = acquisition::AnalyticFrfShifted(sys.truth, s.outputs[o], s.references[0], s.frequency_hz, rate);
    for (int i = 0; i < s.LineCount(); ++i) {
      const double f = s.frequency_hz[i];
      for (int r = 0; r < 3; ++r) {
        const double half_band = (sys.damping[r] + rate / (kTwoPi * sys.frequency_hz[r])) * sys.frequency_hz[r];
        if (std::abs(f - sys.frequency_hz[r]) < 3 * half_band) {
          EXPECT_LT(std::abs(s.h[0](i, o) - shifted[i]), 0.03 * std::abs(shifted[i])) << f << " Hz, output " << o;
        }
      }
    }
  }
  const std::vector<cd> measured = FitPoles(s, 0, 10.0, 400.0, rate);
  ASSERT_EQ(measured.size(), 3u);
  for (int r = 0; r < 3; ++r) {
    double f_fit, zeta_fit, f_raw, zeta_raw;
    PoleToFrequencyAndDamping(measured[r] + rate, &f_fit, &zeta_fit);
    PoleToFrequencyAndDamping(measured[r], &f_raw, &zeta_raw);
    EXPECT_NEAR(zeta_fit / sys.damping[r], 1.0, 0.02) << "mode " << r;
    EXPECT_NEAR(f_fit / sys.frequency_hz[r], 1.0, 1e-3) << "mode " << r;
    EXPECT_GT(zeta_raw / sys.damping[r], 1.2) << "mode " << r << ": the window must visibly add damping";
  }
}

TEST(HammerFrf, DoubleHitAndClippingRejectedWithReasons) {
  // A double hit (second pulse 30 % after 3 ms) on impact 2 and a response clipped at 40 % of
  // its peak on impact 4 (3+Z only). Expected: impact 2 rejected for every FRF with a double-hit
  // reason, impact 4 rejected for 3+Z only with a clipping reason, nothing else rejected (no
  // false positives on clean impacts at 1 % noise).
  const auto sys = testing::MakeThreeDof();
  HammerTestPlan plan = LongPlan();
  plan.force_noise = 0.01;
  plan.response_noise = 0.01;
  const auto clean = acquisition::SimulateHammerTestSets({sys.truth}, plan);
  double peak3 = 0.0;
  for (double v : clean[0].records[3].samples) peak3 = std::max(peak3, std::abs(v));  // impact 1, 3+Z
  plan.double_hits.push_back({0, 0, 2, 3e-3, 0.3});
  plan.clipping.push_back({0, 0, 4, {3, 3}, false, 0.4 * peak3});
  const FrfResult res = testing::SimulateAndEstimate(sys.truth, plan);
  ASSERT_EQ(res.summary.frfs.size(), 3u);
  for (const FrfSummaryEntry& e : res.summary.frfs) {
    const bool clipped = e.response == Dof{3, 3};
    EXPECT_EQ(e.averages, clipped ? 3 : 4) << DofName(e.response);
    ASSERT_EQ(e.rejected.size(), clipped ? 2u : 1u) << DofName(e.response);
    EXPECT_EQ(e.rejected[0].impact, 2);
    EXPECT_THAT(e.rejected[0].reason, HasSubstr("double hit"));
    if (clipped) {
      EXPECT_EQ(e.rejected[1].impact, 4);
      EXPECT_THAT(e.rejected[1].reason, ::testing::AnyOf(HasSubstr("clipped"), HasSubstr("overload")));
    }
  }
  EXPECT_EQ(res.summary.rejected_impacts, 1);
  // A force channel with a 100 N range: impacts peaking above 95 N (the spread is ±10 %) are
  // overloads, the others are kept.
  plan.clipping.clear();
  plan.double_hits.clear();
  plan.roving_sets = {{{1, 3}}};
  plan.force_full_scale = 100.0;
  const FrfResult over = testing::SimulateAndEstimate(sys.truth, plan);
  EXPECT_GT(over.summary.frfs[0].rejected.size(), 0u);
  EXPECT_GT(over.summary.frfs[0].averages, 0);
  for (const RejectedImpact& ri : over.summary.frfs[0].rejected) EXPECT_THAT(ri.reason, HasSubstr("force overload"));
}

TEST(HammerFrf, TwoRovingSetsMergeIntoOneFrfSet) {
  // Two files, reference 1+Z in both: set 1 measures 1+Z and 2+Z, set 2 measures 3+Z. The merged
  // set holds three outputs from one reference, every FRF within 2 % of the analytic accelerance
  // near the resonances (noise 0.5 %; same reasoning as the H1 test).
  const auto sys = testing::MakeThreeDof();
  HammerTestPlan plan = LongPlan();
  plan.roving_sets = {{{1, 3}, {2, 3}}, {{3, 3}}};
  plan.force_noise = 0.005;
  plan.response_noise = 0.005;
  const FrfResult res = testing::SimulateAndEstimate(sys.truth, plan);
  const FrfSet& s = res.frfs;
  ASSERT_EQ(s.ReferenceCount(), 1);
  ASSERT_EQ(s.OutputCount(), 3);
  EXPECT_FALSE(s.roving_hammer);
  EXPECT_EQ(s.outputs[2], (Dof{3, 3}));
  for (int o = 0; o < 3; ++o) {
    EXPECT_EQ(s.averages(0, o), 5);
    const Eigen::VectorXcd truth = AnalyticFrf(sys.truth, s.outputs[o], s.references[0], s.frequency_hz);
    for (int r = 0; r < 3; ++r) {
      const int i = static_cast<int>(std::lround(sys.frequency_hz[r] / s.frequency_hz[1]));
      EXPECT_LT(std::abs(s.h[0](i, o) - truth[i]), 0.02 * std::abs(truth[i])) << "output " << o << " mode " << r;
    }
  }
}

TEST(HammerFrf, SetWithDifferentReferenceIsAnError) {
  const auto sys = testing::MakeThreeDof();
  HammerTestPlan plan = testing::ThreeDofPlan();
  plan.samples_per_record = 1024;
  plan.roving_sets = {{{2, 3}}};
  auto set1 = testing::ToRecordSets(acquisition::SimulateHammerTestSets({sys.truth}, plan));
  plan.references = {{2, 3}};
  plan.roving_sets = {{{3, 3}}};
  auto set2 = testing::ToRecordSets(acquisition::SimulateHammerTestSets({sys.truth}, plan));
  set2[0].name = "set2.unv";
  std::vector<acquisition::RecordSet> both{set1[0], set2[0]};
  try {
    acquisition::AssembleHammerMeasurement(both);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("set2.unv"));
    EXPECT_THAT(e.what(), HasSubstr("2+Z"));
    EXPECT_THAT(e.what(), HasSubstr("1+Z"));
    EXPECT_THAT(e.what(), HasSubstr("must share the reference"));
  }
}

TEST(HammerFrf, RovingHammerIsRecognisedAndKeptAsSuch) {
  // Hammer at 1, 2, 3; one fixed accelerometer at 3+Z. The set keeps the physical orientation
  // (references = hammer points) and flags roving_hammer; H(3, j) matches the analytic accelerance
  // within 2 % at the resonances (noise-free apart from FIR/truncation effects of 1e-3).
  const auto sys = testing::MakeThreeDof();
  HammerTestPlan plan = LongPlan();
  plan.references = {{1, 3}, {2, 3}, {3, 3}};
  plan.roving_sets = {{{3, 3}}};
  plan.impacts_per_reference = 3;
  const FrfResult res = testing::SimulateAndEstimate(sys.truth, plan);
  const FrfSet& s = res.frfs;
  EXPECT_TRUE(s.roving_hammer);
  EXPECT_TRUE(res.summary.roving_hammer);
  ASSERT_EQ(s.ReferenceCount(), 3);
  ASSERT_EQ(s.OutputCount(), 1);
  for (int r = 0; r < 3; ++r) {
    const Eigen::VectorXcd truth = AnalyticFrf(sys.truth, s.outputs[0], s.references[r], s.frequency_hz);
    const int i = static_cast<int>(std::lround(sys.frequency_hz[1] / s.frequency_hz[1]));
    EXPECT_LT(std::abs(s.h[r](i, 0) - truth[i]), 0.02 * std::abs(truth[i]));
  }
}

TEST(HammerFrf, BadInputNamesFileRecordAndReason) {
  const auto sys = testing::MakeThreeDof();
  HammerTestPlan plan = testing::ThreeDofPlan();
  plan.samples_per_record = 1024;
  plan.impacts_per_reference = 3;
  plan.roving_sets = {{{2, 3}, {3, 3}}};
  const auto good = testing::ToRecordSets(acquisition::SimulateHammerTestSets({sys.truth}, plan));
  {  // a response of one impact with another length
    auto sets = good;
    sets[0].records[2].samples.resize(1000);
    sets[0].records[2].origin = "t.unv, dataset 58 #3";
    try {
      acquisition::AssembleHammerMeasurement(sets);
      FAIL();
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr("t.unv, dataset 58 #3"));
      EXPECT_THAT(e.what(), HasSubstr("expected 1024 samples"));
    }
  }
  {  // a different sample rate
    auto sets = good;
    sets[0].records[4].sample_interval_s *= 2;
    EXPECT_THROW(acquisition::AssembleHammerMeasurement(sets), InputError);
  }
  {  // a response with no impact (its force record missing), even by record order
    auto sets = good;
    sets[0].records.erase(sets[0].records.begin());
    try {
      acquisition::AssembleHammerMeasurement(sets);
      FAIL();
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr("no force record"));
    }
  }
  {  // every impact rejected (all double hits)
    auto p = plan;
    for (int k = 1; k <= 3; ++k) p.double_hits.push_back({0, 0, k, 4e-3, 0.4});
    const auto sets = testing::ToRecordSets(acquisition::SimulateHammerTestSets({sys.truth}, p));
    try {
      EstimateFrfs(acquisition::AssembleHammerMeasurement(sets));
      FAIL();
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr("every impact"));
      EXPECT_THAT(e.what(), HasSubstr("double hit"));
      EXPECT_THAT(e.what(), HasSubstr("set1.unv"));
    }
  }
}

TEST(HammerFrf, ImpactsGroupedByRecordOrderWhenLoadCasesDoNotNumberThem) {
  // Another tool's file: every record has its own load case id. Rule 2 (record order) must give
  // the same FRFs as the conventional numbering, bit for bit.
  const auto sys = testing::MakeThreeDof();
  HammerTestPlan plan = testing::ThreeDofPlan();
  plan.samples_per_record = 2048;
  plan.response_noise = 0.01;
  auto sets = testing::ToRecordSets(acquisition::SimulateHammerTestSets({sys.truth}, plan));
  const FrfResult conventional = EstimateFrfs(acquisition::AssembleHammerMeasurement(sets));
  for (size_t i = 0; i < sets[0].records.size(); ++i) sets[0].records[i].impact = static_cast<int>(i) + 100;
  const auto test = acquisition::AssembleHammerMeasurement(sets);
  EXPECT_TRUE(test.grouped_by_record_order);
  const FrfResult by_order = EstimateFrfs(test);
  EXPECT_EQ((by_order.frfs.h[0] - conventional.frfs.h[0]).norm(), 0.0);
}

TEST(HammerFrf, ThreadCountDoesNotChangeTheResult) {
  // Each FRF is accumulated by one thread in impact order: bit-identical for 1 and 3 threads.
  const auto sys = testing::MakeThreeDof();
  HammerTestPlan plan = testing::ThreeDofPlan();
  plan.samples_per_record = 2048;
  plan.response_noise = 0.01;
  const auto test = acquisition::AssembleHammerMeasurement(testing::ToRecordSets(acquisition::SimulateHammerTestSets({sys.truth}, plan)));
  FrfOptions one, three;
  one.threads = 1;
  three.threads = 3;
  const FrfResult a = EstimateFrfs(test, one), b = EstimateFrfs(test, three);
  EXPECT_EQ((a.frfs.h[0] - b.frfs.h[0]).norm(), 0.0);
  EXPECT_EQ((a.frfs.coherence[0] - b.frfs.coherence[0]).norm(), 0.0);
}

TEST(HammerFrf, PlansAreCreatedOnceAndReused) {
  const auto sys = testing::MakeThreeDof();
  HammerTestPlan plan = testing::ThreeDofPlan();
  plan.samples_per_record = 3000;  // a length no other test uses
  plan.impacts_per_reference = 2;
  testing::SimulateAndEstimate(sys.truth, plan);
  const int plans = PlanCount();
  testing::SimulateAndEstimate(sys.truth, plan);
  EXPECT_EQ(PlanCount(), plans);
}

TEST(HammerFrf, BandSelectionAndQuantityConversion) {
  // Receptance = accelerance / (jw)^2 exactly (1e-12 rel), band keeps [lo, hi] only.
  const auto sys = testing::MakeThreeDof();
  HammerTestPlan plan = testing::ThreeDofPlan();
  plan.samples_per_record = 2048;
  const FrfResult acc = testing::SimulateAndEstimate(sys.truth, plan);
  FrfOptions opt;
  opt.output_quantity = Quantity::kDisplacement;
  opt.band_lo_hz = 20.0;
  opt.band_hi_hz = 300.0;
  const FrfResult rec = testing::SimulateAndEstimate(sys.truth, plan, opt);
  const FrfSet& s = rec.frfs;
  EXPECT_GE(s.frequency_hz[0], 20.0);
  EXPECT_LE(s.frequency_hz[s.LineCount() - 1], 300.0);
  EXPECT_EQ(s.output_quantity, Quantity::kDisplacement);
  EXPECT_EQ(s.response_unit, "m");
  const Eigen::Index first = std::lround(s.frequency_hz[0] / acc.frfs.frequency_hz[1]);
  for (int i = 0; i < s.LineCount(); ++i) {
    const double w = kTwoPi * s.frequency_hz[i];
    const cd expected = acc.frfs.h[0](first + i, 1) / (-w * w);
    EXPECT_LT(std::abs(s.h[0](i, 1) - expected), 1e-12 * std::abs(expected));
  }
}

}  // namespace
}  // namespace ema::frf
