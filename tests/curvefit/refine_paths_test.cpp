// The ML refinement's other paths: per-roving-set poles, a pole that the data pull away (stopped at
// the edge of its neighbourhood and rejected), a pole that cannot be evaluated (failure in ema's own
// words, no solver log lines), a misfit far above the measured noise (rejected), a pole near the
// band edge (stays in the band), and modes reported in frequency order.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "curvefit/synthetic.hpp"
#include "ema/curvefit/fit.hpp"
#include "ema/curvefit/fit_data.hpp"
#include "ema/curvefit/ml_refine.hpp"

namespace ema::curvefit {
namespace {

using test::MakeFrfSet;
using test::MakeTruth;
using test::Truth;

SelectedPole PoleAt(double f_hz, double zeta) {
  SelectedPole p;
  p.pole.lambda = p.pole.lambda_fitted = FrequencyAndDampingToPole(f_hz, zeta);
  p.pole.frequency_hz = f_hz;
  p.pole.damping_ratio = zeta;
  p.pole.physical = true;
  p.pole.label = 's';
  return p;
}

// Three modes 30/50/80 Hz, ζ 1 %, 12 outputs, references 2 and 9, 0.05 Hz lines to 120 Hz.
FrfSet ThreeModes(double noise, unsigned seed) {
  return MakeFrfSet(MakeTruth({30.0, 50.0, 80.0}, {0.01, 0.01, 0.01}, 12), {1, 8}, 120.0, 0.05, noise, seed);
}

// Outputs 1-6 in roving set 0 and 7-12 in set 1, the 50 Hz mode at 50.4 Hz in set 1 (its
// sensors' mass). With the sets known, each set's FRFs get their own poles: the mode is reported
// once, with both sets' frequencies, each within a few of its σ of the truth.
TEST(RefinePerSet, EachRovingSetGetsItsOwnPoles) {
  FrfSet frfs = test::TwoRovingSetsWithShiftedMode(50.4);
  frfs.output_sets = {0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1};
  FitOptions options;
  options.polymax.order_max = 40;
  const FitResult fit = Fit(frfs, options);
  ASSERT_TRUE(fit.refine.IsSolutionUsable()) << fit.refine.BriefReport();
  ASSERT_EQ(fit.modes.modes.size(), 3u);
  const Mode& shifted = fit.modes.modes[1];
  ASSERT_EQ(shifted.set_frequency_hz.size(), 2u) << "one frequency per roving set";
  // 1 % noise, ζ 1 %: σ_f ~ 2e-3 Hz per set; 0.02 Hz is 10 σ and 5 % of the 0.4 Hz shift.
  EXPECT_NEAR(shifted.set_frequency_hz[0], 50.0, 0.02);
  EXPECT_NEAR(shifted.set_frequency_hz[1], 50.4, 0.02);
  // The unshifted modes agree between the sets.
  for (int k : {0, 2}) {
    ASSERT_EQ(fit.modes.modes[k].set_frequency_hz.size(), 2u);
    EXPECT_NEAR(fit.modes.modes[k].set_frequency_hz[0], fit.modes.modes[k].set_frequency_hz[1], 0.02);
  }
  // Without the sets' names the same data give one pole per mode for every FRF.
  options.per_set_poles = false;
  const FitResult pooled = Fit(frfs, options);
  ASSERT_EQ(pooled.modes.modes.size(), 3u);
  EXPECT_TRUE(pooled.modes.modes[1].set_frequency_hz.empty());
}

// A pole started at 46 Hz (ζ 1 %: half-power bandwidth 0.92 Hz) where the data hold the 50 Hz
// mode and no other pole models it: the likelihood pulls the pole 4.3 bandwidths to 50 Hz. The
// box (2 bandwidths) stops it; the refinement is rejected with the reason, the start kept.
TEST(RefineBounds, PoleThatWandersOffIsStoppedAndRejected) {
  const FitData data = PrepareFitData(ThreeModes(0.01, 41), FitDataOptions{});
  const std::vector<SelectedPole> poles = {PoleAt(30.0, 0.01), PoleAt(46.0, 0.01), PoleAt(80.0, 0.01)};
  const MlRefineResult r = RefineModalModel(data, poles, MlRefineOptions{});
  EXPECT_EQ(r.summary.termination, RefineTermination::kRejected) << r.summary.BriefReport();
  EXPECT_NE(r.summary.message.find("edge of its neighbourhood"), std::string::npos) << r.summary.message;
  ASSERT_EQ(r.poles.size(), 3u);
  EXPECT_NEAR(r.poles[1].frequency_hz, 46.0, 1e-9) << "the starting pole is kept";
  // With a box wide enough (6 bandwidths) the same pole reaches the mode and is accepted.
  MlRefineOptions wide;
  wide.max_pole_shift_bandwidths = 6.0;
  const MlRefineResult reached = RefineModalModel(data, poles, wide);
  ASSERT_TRUE(reached.summary.IsSolutionUsable()) << reached.summary.BriefReport();
  EXPECT_NEAR(reached.poles[1].frequency_hz, 50.0, 0.01);
}

// A pole 0.3 bandwidths inside the upper band edge (mode at 119.9 Hz, band to 120 Hz): its
// neighbourhood is cut at the band edge, so the refined pole stays in the band, and near the truth.
TEST(RefineBounds, PoleNearTheBandEdgeStaysInTheBand) {
  const Truth truth = MakeTruth({40.0, 119.5}, {0.01, 0.005}, 10);
  const FitData data = PrepareFitData(MakeFrfSet(truth, {2}, 120.0, 0.05, 0.01, 43), FitDataOptions{});
  const MlRefineResult r = RefineModalModel(data, {PoleAt(40.02, 0.011), PoleAt(119.52, 0.0055)}, MlRefineOptions{});
  ASSERT_EQ(r.poles.size(), 2u);
  EXPECT_LE(r.poles[1].frequency_hz, data.frequency_hz[data.LineCount() - 1] + 1e-9);
  ASSERT_TRUE(r.summary.IsSolutionUsable()) << r.summary.BriefReport();
  // 1 % noise: σ_f ~ 1e-3 Hz; 0.01 Hz allows for the truncated half-power band.
  EXPECT_NEAR(r.poles[1].frequency_hz, 119.5, 0.01);
  EXPECT_NEAR(r.poles[0].frequency_hz, 40.0, 0.01);
}

// An unstable starting pole (Re λ > 0) cannot be refined: the summary says so in ema's words and
// nothing from the solver's log reaches stderr.
TEST(RefineFailure, UnstablePoleFailsInPlainWordsWithoutSolverLog) {
  const FitData data = PrepareFitData(ThreeModes(0.01, 44), FitDataOptions{});
  SelectedPole bad = PoleAt(50.0, 0.01);
  bad.pole.lambda = bad.pole.lambda_fitted = std::conj(-bad.pole.lambda_fitted);  // mirrored: Re > 0
  testing::internal::CaptureStderr();
  const MlRefineResult r = RefineModalModel(data, {PoleAt(30.0, 0.01), bad, PoleAt(80.0, 0.01)}, MlRefineOptions{});
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_FALSE(r.summary.IsSolutionUsable()) << r.summary.BriefReport();
  EXPECT_FALSE(r.summary.message.empty());
  EXPECT_EQ(r.summary.message.find("trust_region"), std::string::npos) << r.summary.message;
  EXPECT_EQ(err, "") << "solver log lines on stderr";
}

// A measured noise level far below the misfit (a coherence of 1 - 1e-12 everywhere, say): the modal
// model cannot reach it, the refinement is rejected and the PolyMAX poles are kept.
TEST(RefineAdequacy, MisfitFarAboveTheMeasuredNoiseIsRejected) {
  FitData data = PrepareFitData(ThreeModes(0.01, 45), FitDataOptions{});
  // The FRFs' noise is 1 % of their RMS; claim a variance 1e-6 of that.
  data.noise_variance = Eigen::MatrixXd::Constant(data.LineCount(), data.h.cols(), 0.0);
  for (Eigen::Index c = 0; c < data.h.cols(); ++c)
    data.noise_variance.col(c).setConstant(1e-10 * data.h.col(c).squaredNorm() / data.LineCount());
  const std::vector<SelectedPole> poles = {PoleAt(30.01, 0.0101), PoleAt(50.01, 0.0101), PoleAt(80.01, 0.0101)};
  const MlRefineResult r = RefineModalModel(data, poles, MlRefineOptions{});
  EXPECT_EQ(r.summary.noise_source, NoiseSource::kCoherence);
  EXPECT_EQ(r.summary.termination, RefineTermination::kRejected) << r.summary.BriefReport();
  EXPECT_GT(r.summary.reduced_chi2, 1e3);
  EXPECT_NEAR(r.poles[1].frequency_hz, 50.01, 1e-9);
  // With the truthful noise level (1 % of RMS) the same fit is accepted, χ² near 1.
  for (Eigen::Index c = 0; c < data.h.cols(); ++c)
    data.noise_variance.col(c).setConstant(1e-4 * data.h.col(c).squaredNorm() / data.LineCount());
  const MlRefineResult ok = RefineModalModel(data, poles, MlRefineOptions{});
  ASSERT_TRUE(ok.summary.IsSolutionUsable()) << ok.summary.BriefReport();
  EXPECT_NEAR(ok.summary.reduced_chi2, 1.0, 0.3);
  EXPECT_NEAR(ok.poles[1].frequency_hz, 50.0, 0.01);
}

// Two close modes given in reverse order: the fit reports them by frequency, each shape with its
// own mode (the permutation applies to modes and selection alike).
TEST(FitOrder, ModesComeOutSortedByFrequency) {
  FitOptions options;
  options.select_frequencies_hz = {80.0, 30.0, 50.0};
  const FitResult fit = Fit(ThreeModes(0.01, 46), options);
  ASSERT_EQ(fit.modes.modes.size(), 3u);
  ASSERT_EQ(fit.selected.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(fit.modes.modes[k].frequency_hz, (std::vector<double>{30.0, 50.0, 80.0})[k], 0.05);
    EXPECT_NEAR(fit.selected[k].pole.frequency_hz, fit.modes.modes[k].frequency_hz, 0.05);
  }
}

}  // namespace
}  // namespace ema::curvefit
