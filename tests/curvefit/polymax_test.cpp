// PolyMAX, stabilisation, automatic selection and LSFD against FRFs generated from known truth.
#include <gtest/gtest.h>

#include <cmath>

#include "curvefit/synthetic.hpp"
#include "ema/core/error.hpp"
#include "ema/curvefit/fit.hpp"

namespace ema::curvefit {
namespace {

using test::MakeFrfSet;
using test::MakeTruth;
using test::Truth;

double ComplexMac(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b) {
  return std::norm(a.dot(b)) / (a.squaredNorm() * b.squaredNorm());
}

/// Index of the fitted mode nearest in frequency to each true mode (-1 if none within 2 %).
std::vector<int> MatchModes(const Truth& truth, const ModeSet& modes) {
  std::vector<int> idx;
  for (const auto& t : truth.modes) {
    int best = -1;
    for (int k = 0; k < static_cast<int>(modes.modes.size()); ++k)
      if (std::abs(modes.modes[k].frequency_hz - t.f_hz) < 0.02 * t.f_hz &&
          (best < 0 || std::abs(modes.modes[k].frequency_hz - t.f_hz) < std::abs(modes.modes[best].frequency_hz - t.f_hz)))
        best = k;
    idx.push_back(best);
  }
  return idx;
}

// The six-mode chain of algorithms.md §7.6: f = 13.0 .. 111.5 Hz, zeta 0.65-0.84 %.
Truth SixModes(int n_dofs) {
  return MakeTruth({13.0, 38.1, 58.8, 78.2, 96.1, 111.5}, {0.0065, 0.0072, 0.0084, 0.0070, 0.0078, 0.0081}, n_dofs);
}

TEST(Polymax, NoiseFreePolesAreExact) {
  const Truth truth = SixModes(8);
  const FrfSet frfs = MakeFrfSet(truth, {1, 6}, 150.0, 0.05, 0.0, 1);
  FitOptions options;
  options.polymax.order_max = 30;  // well above the minimum (6 for 2 refs): the z-domain model converges with order
  const FitResult fit = Fit(frfs, options);
  // algorithms.md §7.5: noise-free, full band: f 1e-7 rel, zeta 1e-5 rel (verified 1e-8 / 1e-6).
  const auto& top = fit.diagram.orders.back();
  for (const auto& t : truth.modes) {
    const Pole* best = nullptr;
    for (const auto& p : top)
      if (!best || std::abs(p.frequency_hz - t.f_hz) < std::abs(best->frequency_hz - t.f_hz)) best = &p;
    ASSERT_NE(best, nullptr);
    EXPECT_NEAR(best->frequency_hz / t.f_hz, 1.0, 1e-7) << t.f_hz;
    EXPECT_NEAR(best->damping_ratio / t.zeta, 1.0, 1e-5) << t.f_hz;
  }
}

// Each stage on its own: PolyMAX + LSFD with the refinement off (a PolyMAX regression cannot hide
// behind the ML refinement), then the whole chain.
TEST(Polymax, OnePercentNoiseSixModes) {
  const Truth truth = SixModes(12);
  const FrfSet frfs = MakeFrfSet(truth, {2, 9}, 150.0, 0.04, 0.01, 7);
  for (const RefineMethod refine : {RefineMethod::kNone, RefineMethod::kMl}) {
    SCOPED_TRACE("refine " + RefineMethodToString(refine));
    FitOptions options;
    options.polymax.order_max = 40;
    options.refine = refine;
    const FitResult fit = Fit(frfs, options);
    ASSERT_EQ(fit.modes.modes.size(), truth.modes.size()) << "automatic selection must find exactly the 6 modes";
    const auto match = MatchModes(truth, fit.modes);
    for (size_t r = 0; r < truth.modes.size(); ++r) {
      ASSERT_GE(match[r], 0);
      const Mode& m = fit.modes.modes[match[r]];
      if (refine == RefineMethod::kNone) {
        EXPECT_EQ(m.frequency_hz, fit.selected[match[r]].pole.frequency_hz);
      }
      // Issue 4 acceptance at 1 % noise: f within 0.05 %, zeta within 2 % (relative), MAC >= 0.995.
      EXPECT_NEAR(m.frequency_hz / truth.modes[r].f_hz, 1.0, 5e-4);
      EXPECT_NEAR(m.damping_ratio / truth.modes[r].zeta, 1.0, 0.02) << truth.modes[r].f_hz;
      EXPECT_GE(ComplexMac(m.shape, truth.modes[r].shape.cast<std::complex<double>>()), 0.995);
      EXPECT_TRUE(m.unit_modal_mass);
    }
  }
}

TEST(Polymax, FivePercentNoiseDamping) {
  const Truth truth = SixModes(12);
  const FrfSet frfs = MakeFrfSet(truth, {2, 9}, 150.0, 0.04, 0.05, 11);
  for (const RefineMethod refine : {RefineMethod::kNone, RefineMethod::kMl}) {
    SCOPED_TRACE("refine " + RefineMethodToString(refine));
    FitOptions options;  // default order: 60 for two references
    options.refine = refine;
    const FitResult fit = Fit(frfs, options);
    EXPECT_EQ(fit.modes.modes.size(), truth.modes.size());
    const auto match = MatchModes(truth, fit.modes);
    for (size_t r = 0; r < truth.modes.size(); ++r) {
      ASSERT_GE(match[r], 0) << truth.modes[r].f_hz;
      const Mode& m = fit.modes.modes[match[r]];
      // Issue 4 acceptance at 5 % noise: zeta within 5 % (relative). The LS bias is negative and
      // shrinks with the order (algorithms.md §2.11: -17 % at p = 40 in the note's runs); the
      // default order and the upper-half representative keep it below 5 % here.
      EXPECT_NEAR(m.damping_ratio / truth.modes[r].zeta, 1.0, 0.05) << truth.modes[r].f_hz;
      EXPECT_NEAR(m.frequency_hz / truth.modes[r].f_hz, 1.0, 5e-4);
      EXPECT_GE(ComplexMac(m.shape, truth.modes[r].shape.cast<std::complex<double>>()), 0.99);
    }
  }
}

TEST(Polymax, CloseModesSeenFromTwoReferences) {
  // Two modes 0.5 % apart (50.0 and 50.25 Hz, half-power width 0.5 Hz: they overlap) with
  // different shapes, plus a neighbour; two references tell them apart by participation.
  Truth truth = MakeTruth({30.0, 50.0, 50.25, 80.0}, {0.005, 0.005, 0.005, 0.006}, 10);
  for (int d = 0; d < 10; ++d) truth.modes[2].shape[d] = 0.5 * std::cos(2.1 * (d + 0.5));
  const FrfSet frfs = MakeFrfSet(truth, {1, 7}, 100.0, 0.02, 0.01, 5);
  FitOptions options;
  options.polymax.order_max = 30;
  const FitResult fit = Fit(frfs, options);
  const auto match = MatchModes(truth, fit.modes);
  ASSERT_GE(match[1], 0);
  ASSERT_GE(match[2], 0);
  EXPECT_NE(match[1], match[2]) << "both close modes must be found";
  EXPECT_EQ(fit.modes.modes.size(), 4u);
  for (int r : {1, 2}) {
    const Mode& m = fit.modes.modes[match[r]];
    // Close modes share the data, so allow 2× the isolated-mode tolerances.
    EXPECT_NEAR(m.frequency_hz / truth.modes[r].f_hz, 1.0, 1e-3);
    EXPECT_NEAR(m.damping_ratio / truth.modes[r].zeta, 1.0, 0.04);
    EXPECT_GE(ComplexMac(m.shape, truth.modes[r].shape.cast<std::complex<double>>()), 0.99);
  }
}

TEST(Polymax, HeavyDamping) {
  // zeta = 5 %: half-power widths of 2-8 Hz, neighbours overlap (modal overlap ~0.5).
  const Truth truth = MakeTruth({20.0, 45.0, 80.0}, {0.05, 0.05, 0.05}, 8);
  const FrfSet frfs = MakeFrfSet(truth, {1, 5}, 150.0, 0.1, 0.01, 9);
  FitOptions options;
  options.polymax.order_max = 30;
  const FitResult fit = Fit(frfs, options);
  EXPECT_EQ(fit.modes.modes.size(), 3u);
  const auto match = MatchModes(truth, fit.modes);
  for (size_t r = 0; r < truth.modes.size(); ++r) {
    ASSERT_GE(match[r], 0);
    const Mode& m = fit.modes.modes[match[r]];
    // 1 % noise tolerances of the issue (f 0.05 %, zeta 2 %) hold for heavy damping too.
    EXPECT_NEAR(m.frequency_hz / truth.modes[r].f_hz, 1.0, 5e-4);
    EXPECT_NEAR(m.damping_ratio / truth.modes[r].zeta, 1.0, 0.02);
    EXPECT_GE(ComplexMac(m.shape, truth.modes[r].shape.cast<std::complex<double>>()), 0.995);
  }
}

TEST(Polymax, SpuriousPolesAreUnstableClearDiagram) {
  // algorithms.md §2.4: with alpha_p = I, basis exp(-jw dt) and the FFTW DFT sign, >= 95 % of the
  // spurious in-band poles come out with negative damping on noisy data. A flipped sign anywhere
  // (basis, constraint, pole mapping) turns this into ~0 % and fails here.
  const Truth truth = SixModes(8);
  for (std::vector<int> refs : {std::vector<int>{2}, std::vector<int>{2, 5}}) {
    const FrfSet frfs = MakeFrfSet(truth, refs, 150.0, 0.04, 0.01, 21);
    FitOptions options;
    options.polymax.order_max = refs.size() == 1 ? 40 : 20;
    const FitResult fit = Fit(frfs, options);
    int spurious = 0, unstable = 0;
    for (const auto& order : fit.diagram.orders)
      for (const auto& p : order) {
        bool physical = false;
        for (const auto& t : truth.modes) physical = physical || std::abs(p.frequency_hz - t.f_hz) < 0.01 * t.f_hz;
        if (physical || p.frequency_hz < 1.0 || p.frequency_hz > 150.0) continue;
        ++spurious;
        unstable += p.damping_ratio < 0.0;
      }
    ASSERT_GT(spurious, 50);
    EXPECT_GE(unstable, 0.95 * spurious) << refs.size() << " reference(s)";
  }
}

TEST(Polymax, ParticipationFactorsGiveExactResidues) {
  // The companion transpose pitfall (§2.7): with right instead of left null vectors the LSFD
  // residues are 30-100 % off; with the left ones they are exact on noise-free data (1e-4, §7.5).
  const Truth truth = MakeTruth({25.0, 60.0, 95.0}, {0.01, 0.012, 0.008}, 6);
  const std::vector<int> refs = {0, 3};
  const FrfSet frfs = MakeFrfSet(truth, refs, 120.0, 0.05, 0.0, 1);
  FitOptions options;
  options.polymax.order_max = 24;
  const FitResult fit = Fit(frfs, options);
  ASSERT_EQ(fit.modes.modes.size(), 3u);
  const FitData data = PrepareFitData(frfs, {});
  const LsfdResult lsfd = EstimateModeShapes(data, fit.selected);
  for (int r = 0; r < 3; ++r) {
    const auto& t = truth.modes[r];
    const std::complex<double> a(0.0, 2.0 * FrequencyAndDampingToPole(t.f_hz, t.zeta).imag());
    double err = 0.0, ref = 0.0;
    for (int o = 0; o < 6; ++o)
      for (int i = 0; i < 2; ++i) {
        const std::complex<double> exact = t.shape[o] * t.shape[refs[i]] / a;
        err = std::max(err, std::abs(lsfd.residues(o * 2 + i, r) - exact));
        ref = std::max(ref, std::abs(exact));
      }
    EXPECT_LT(err / ref, 1e-4) << t.f_hz;
  }
}

TEST(Polymax, UnitModalMassForEveryFrfType) {
  // The shapes are unit-modal-mass scaled from the two driving points whatever the measured
  // quantity (the (jw)^k regressors keep receptance residues): compare with the truth, 0.5 %.
  const Truth truth = MakeTruth({25.0, 60.0, 95.0}, {0.01, 0.012, 0.008}, 6);
  for (int k_pow : {0, 1, 2}) {
    const FrfSet frfs = MakeFrfSet(truth, {0, 3}, 120.0, 0.05, 0.002, 4, k_pow);
    FitOptions options;
    options.polymax.order_max = 24;
    const FitResult fit = Fit(frfs, options);
    ASSERT_EQ(fit.modes.modes.size(), 3u) << "k = " << k_pow;
    EXPECT_TRUE(fit.warnings.empty());
    for (int r = 0; r < 3; ++r) {
      const Mode& m = fit.modes.modes[r];
      EXPECT_TRUE(m.unit_modal_mass);
      int dmax = 0;
      truth.modes[r].shape.cwiseAbs().maxCoeff(&dmax);
      const double sign = truth.modes[r].shape[dmax] * m.shape[dmax].real() > 0 ? 1.0 : -1.0;
      for (int d = 0; d < 6; ++d)
        EXPECT_NEAR(sign * m.shape[d].real(), truth.modes[r].shape[d], 5e-3 * truth.modes[r].shape.cwiseAbs().maxCoeff());
      EXPECT_GT(m.mpc, 0.999);
    }
  }
}

TEST(Polymax, InvertedDrivingPointSignIsReported) {
  // Every FRF negated (an inverted sensor): the driving-point residues imply a negative modal
  // mass, which the fit must say instead of silently returning 90-degree-rotated shapes.
  const Truth truth = MakeTruth({25.0, 60.0, 95.0}, {0.01, 0.012, 0.008}, 6);
  FrfSet frfs = MakeFrfSet(truth, {0, 3}, 120.0, 0.05, 0.002, 4);
  for (auto& h : frfs.h) h = -h;
  FitOptions options;
  options.polymax.order_max = 24;
  const FitResult fit = Fit(frfs, options);
  ASSERT_EQ(fit.modes.modes.size(), 3u);
  ASSERT_EQ(fit.warnings.size(), 3u);
  EXPECT_NE(fit.warnings[0].find("negative modal mass"), std::string::npos) << fit.warnings[0];
}

TEST(Polymax, ExponentialWindowDampingRemoved) {
  // FRFs carrying an exponential window (poles shifted by -1/tau = -2 s^-1, which adds 1.6 %
  // damping at 20 Hz); the fitted poles must be the true ones again (§1.4).
  const Truth truth = MakeTruth({20.0, 48.0, 85.0}, {0.006, 0.007, 0.008}, 6);
  const FrfSet frfs = MakeFrfSet(truth, {1, 4}, 120.0, 0.05, 0.005, 13, 2, 2.0);
  FitOptions options;
  options.polymax.order_max = 24;
  const FitResult fit = Fit(frfs, options);
  ASSERT_EQ(fit.modes.modes.size(), 3u);
  for (int r = 0; r < 3; ++r) {
    EXPECT_NEAR(fit.modes.modes[r].frequency_hz / truth.modes[r].f_hz, 1.0, 2e-4);
    EXPECT_NEAR(fit.modes.modes[r].damping_ratio / truth.modes[r].zeta, 1.0, 0.03);
  }
}

TEST(Polymax, RovingHammerFittedByReciprocity) {
  // One fixed sensor (DOF 3), the hammer at all 8 DOFs: the set says roving_hammer and holds 8
  // references × 1 output. Fitting by reciprocity gives shapes at the 8 hammer points.
  const Truth truth = MakeTruth({22.0, 51.0, 77.0, 104.0}, {0.008, 0.01, 0.009, 0.011}, 8);
  FrfSet all = MakeFrfSet(truth, {3}, 130.0, 0.05, 0.005, 17);
  FrfSet roving;
  roving.frequency_hz = all.frequency_hz;
  roving.outputs = {all.outputs[3]};
  roving.references = all.outputs;
  for (int d = 0; d < 8; ++d) roving.h.push_back(all.h[0].col(d));  // H(3, d) = H(d, 3)
  roving.roving_hammer = true;
  FitOptions options;
  const FitResult fit = Fit(roving, options);
  EXPECT_TRUE(fit.transposed);
  ASSERT_EQ(fit.modes.dofs.size(), 8u);
  ASSERT_EQ(fit.modes.modes.size(), 4u);
  for (int r = 0; r < 4; ++r) {
    EXPECT_NEAR(fit.modes.modes[r].frequency_hz / truth.modes[r].f_hz, 1.0, 5e-4);
    EXPECT_GE(ComplexMac(fit.modes.modes[r].shape, truth.modes[r].shape.cast<std::complex<double>>()), 0.995);
    EXPECT_TRUE(fit.modes.modes[r].unit_modal_mass);  // the sensor DOF is also a hammer point
  }
}

TEST(Polymax, SelectNearGivenFrequencies) {
  const Truth truth = SixModes(8);
  const FrfSet frfs = MakeFrfSet(truth, {2, 6}, 150.0, 0.04, 0.01, 3);
  FitOptions options;
  options.polymax.order_max = 20;
  options.select_frequencies_hz = {38.0, 96.5};
  const FitResult fit = Fit(frfs, options);
  ASSERT_EQ(fit.modes.modes.size(), 2u);
  EXPECT_NEAR(fit.modes.modes[0].frequency_hz, 38.1, 0.02);
  EXPECT_NEAR(fit.modes.modes[1].frequency_hz, 96.1, 0.05);
  options.select_frequencies_hz = {5.0};  // nothing within 10 %
  EXPECT_THROW(Fit(frfs, options), InputError);
}

TEST(Polymax, PeakPickingHalfPower) {
  // Three well separated modes (zeta 1 %, half-power width 0.4-1.6 Hz on a 0.01 Hz grid, i.e.
  // 40-160 lines across each bandwidth): interpolated peak and half-power points give the
  // frequency within 1.4e-4 and the damping within 4.3e-4 relative here (neighbour leakage and the
  // sum over FRFs bias them slightly). Bounds: 3e-4 in f (one line, 0.01 Hz, is 5e-4 at 20 Hz: a peak
  // one line off fails) and 2e-3 in zeta (a bandwidth
  // read between the wrong points, e.g. at 1/2 instead of 1/sqrt(2) of the peak, is 70 % off).
  const Truth truth = MakeTruth({20.0, 50.0, 80.0}, {0.01, 0.01, 0.01}, 6);
  const FrfSet frfs = MakeFrfSet(truth, {1}, 100.0, 0.01, 0.001, 2, 0);
  FitOptions options;
  options.method = FitMethod::kPeak;
  const FitResult fit = Fit(frfs, options);
  ASSERT_EQ(fit.modes.modes.size(), 3u);
  for (int r = 0; r < 3; ++r) {
    EXPECT_NEAR(fit.modes.modes[r].frequency_hz / truth.modes[r].f_hz, 1.0, 3e-4);
    EXPECT_NEAR(fit.modes.modes[r].damping_ratio / truth.modes[r].zeta, 1.0, 2e-3);
  }
}

// ---- bad input -------------------------------------------------------------------------

FrfSet SmallSet() { return MakeFrfSet(MakeTruth({20.0, 48.0}, {0.01, 0.01}, 4), {1}, 80.0, 0.1, 0.01, 1); }

TEST(PolymaxInput, IsolatedNanLinesAreSkippedWithWarning) {
  FrfSet frfs = SmallSet();
  frfs.h[0](0, 0) = kNaN;  // line 0 (DC) is often NaN in exported data; outside the fit anyway
  frfs.h[0](123, 2) = kNaN;
  frfs.h[0](400, 1) = kNaN;
  const FitResult fit = Fit(frfs, FitOptions{});
  ASSERT_EQ(fit.warnings.size(), 1u);
  EXPECT_NE(fit.warnings[0].find("2 of"), std::string::npos) << fit.warnings[0];
  ASSERT_EQ(fit.modes.modes.size(), 2u);
  EXPECT_NEAR(fit.modes.modes[1].frequency_hz, 48.0, 0.05);
}

TEST(PolymaxInput, WidespreadNanIsAnError) {
  FrfSet frfs = SmallSet();
  for (int k = 100; k < 120; ++k) frfs.h[0](k, 1) = kNaN;  // a 20-line hole
  EXPECT_THROW(Fit(frfs, FitOptions{}, "x.unv"), InputError);
  try {
    Fit(frfs, FitOptions{}, "x.unv");
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("x.unv"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("NaN"), std::string::npos);
  }
}

TEST(PolymaxInput, NoLinesInBand) {
  FitOptions options;
  options.data.band_lo_hz = 200.0;
  options.data.band_hi_hz = 300.0;
  EXPECT_THROW(Fit(SmallSet(), options), InputError);
}

TEST(PolymaxInput, TooFewLinesForTheOrder) {
  FitOptions options;
  options.data.band_lo_hz = 40.0;
  options.data.band_hi_hz = 42.0;  // 21 lines
  options.polymax.order_max = 40;
  try {
    Fit(SmallSet(), options);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("lines"), std::string::npos) << e.what();
  }
}

// Every InputError of the fit is placed at its input, once: a stage's ("polymax: ...", "--select:
// ...") and the data's own ("no FRF lines in the band ...") alike, so no caller has to look at an
// error's text to know whether it still needs the file's name.
TEST(PolymaxInput, EveryErrorOfTheFitNamesItsInputOnce) {
  auto error_of = [](const FrfSet& frfs, const FitOptions& options) -> InputError {
    try {
      Fit(frfs, options, "x.unv");
    } catch (const InputError& e) {
      return e;
    }
    ADD_FAILURE() << "expected InputError";
    return InputError("");
  };
  FitOptions stage;
  stage.data.band_lo_hz = 40.0;
  stage.data.band_hi_hz = 42.0;
  stage.polymax.order_max = 40;
  const InputError polymax = error_of(SmallSet(), stage);
  EXPECT_EQ(polymax.Where(), "x.unv");
  EXPECT_EQ(std::string(polymax.what()).rfind("x.unv: polymax: order 40", 0), 0u) << polymax.what();
  FitOptions select;
  select.select_frequencies_hz = {5.0};
  const InputError selected = error_of(SmallSet(), select);
  EXPECT_EQ(selected.Where(), "x.unv");
  EXPECT_EQ(std::string(selected.what()).rfind("x.unv: --select: ", 0), 0u) << selected.what();
  FitOptions band;
  band.data.band_lo_hz = 200.0;
  band.data.band_hi_hz = 300.0;
  const InputError data = error_of(SmallSet(), band);
  EXPECT_EQ(data.Where(), "x.unv");
  EXPECT_EQ(std::string(data.what()).rfind("x.unv: no FRF lines in the band", 0), 0u) << data.what();
}

TEST(PolymaxInput, InconsistentReferences) {
  FrfSet frfs = SmallSet();
  frfs.references.push_back({9, 3});  // a reference without FRFs
  EXPECT_THROW(Fit(frfs, FitOptions{}), InputError);
  FrfSet wrong_shape = SmallSet();
  wrong_shape.h[0].conservativeResize(wrong_shape.h[0].rows() - 5, Eigen::NoChange);
  EXPECT_THROW(Fit(wrong_shape, FitOptions{}), InputError);
  FrfSet unmeasured = MakeFrfSet(MakeTruth({20.0, 48.0}, {0.01, 0.01}, 4), {1, 2}, 80.0, 0.1, 0.01, 1);
  unmeasured.h[1].col(3).setConstant(kNaN);  // output 4 never measured from reference 3
  EXPECT_THROW(Fit(unmeasured, FitOptions{}), InputError);
}

}  // namespace
}  // namespace ema::curvefit
