// Narrow-band fits (issue 14): a band of few lines around one or two modes, as when each force
// level of an amplitude test is fitted around the mode of interest. PolyMAX must still find the
// mode (low orders suffice there) and so must peak picking; the FRFs come from known truth plus
// 1 % complex noise (synthetic.hpp).
#include <gtest/gtest.h>

#include <random>

#include "ema/core/error.hpp"
#include "ema/curvefit/fit.hpp"
#include "synthetic.hpp"

namespace ema::curvefit {
namespace {

// Accelerance at 4 DOFs, one reference; lines every 0.5 Hz to 400 Hz; modes at 100 Hz (and
// 104 Hz when `two`), 230 Hz and 340 Hz; the band 90..110 Hz holds 41 lines.
FrfSet NarrowBandFrfs(double zeta, bool two, unsigned seed) {
  std::vector<double> f = {100.0, 230.0, 340.0}, z = {zeta, 0.01, 0.01};
  if (two) f.insert(f.begin() + 1, 104.0), z.insert(z.begin() + 1, zeta);
  return test::MakeFrfSet(test::MakeTruth(f, z, 4), {0}, 400.0, 0.5, 0.01, seed);
}

FitOptions Band(double lo, double hi) {
  FitOptions o;
  o.data.band_lo_hz = lo;
  o.data.band_hi_hz = hi;
  return o;
}

TEST(NarrowBand, OneModeIn41LinesIsFoundWithin005PctByPolymax) {
  for (unsigned seed : {1u, 2u, 3u}) {
    for (double zeta : {0.005, 0.01, 0.03}) {
      const FitResult r = Fit(NarrowBandFrfs(zeta, false, seed), Band(90.0, 110.0));
      ASSERT_EQ(r.modes.modes.size(), 1u) << "seed " << seed << " zeta " << zeta;
      // 0.05 % in f (issue 14) for ζ up to 1 %: the fits land within ~0.01 %. The 3 % mode is
      // 6 Hz wide in a 20 Hz band and its peak stands only ~10x above the noise (1 % of the
      // accelerance RMS over 0..400 Hz): the pole scatters by ~0.1 % over the orders; 0.2 %.
      EXPECT_NEAR(r.modes.modes[0].frequency_hz, 100.0, zeta > 0.02 ? 0.2 : 0.05) << "seed " << seed << " zeta " << zeta;
      // Damping within 10 % of the truth: a check that the pole is the physical one.
      EXPECT_NEAR(r.modes.modes[0].damping_ratio, zeta, 0.1 * zeta) << "seed " << seed << " zeta " << zeta;
    }
  }
}

TEST(NarrowBand, TwoModesIn41LinesAreBothFound) {
  const FitResult r = Fit(NarrowBandFrfs(0.005, true, 4), Band(92.0, 112.0));
  ASSERT_EQ(r.modes.modes.size(), 2u);
  EXPECT_NEAR(r.modes.modes[0].frequency_hz, 100.0, 0.05);
  EXPECT_NEAR(r.modes.modes[1].frequency_hz, 104.0, 0.05);
}

TEST(NarrowBand, PeakPickingFindsTheModeIn41Lines) {
  for (double zeta : {0.005, 0.01, 0.03}) {
    FitOptions o = Band(90.0, 110.0);
    o.method = FitMethod::kPeak;
    const FitResult r = Fit(NarrowBandFrfs(zeta, false, 5), o);
    ASSERT_EQ(r.modes.modes.size(), 1u) << zeta;
    // Peak picking on 0.5 Hz lines with a parabola: about a tenth of a line; at 3 % damping the
    // accelerance peak itself sits ζ² = 0.09 % above f_n, plus the noise of a broad peak: 0.2 Hz.
    EXPECT_NEAR(r.modes.modes[0].frequency_hz, 100.0, zeta > 0.02 ? 0.2 : 0.1) << zeta;
    // Half-power damping from interpolated crossings: within 25 % (a 0.5 % mode is 1 Hz wide: two lines).
    EXPECT_NEAR(r.modes.modes[0].damping_ratio, zeta, 0.25 * zeta) << zeta;
  }
}

}  // namespace
}  // namespace ema::curvefit

namespace ema::curvefit {
namespace {

// A stepped-sine measurement (issue 28): one driving-point FRF, 41 lines over 2 Hz around one
// mode, nothing else in the file (the axis starts at the first line, not at 0 Hz). The band is
// 79.3..81.3 Hz; the mode at f0 (ζ), complex noise of `noise` × the peak magnitude.
FrfSet SteppedSine(double f0, double zeta, double noise, unsigned seed, int k_pow = 2) {
  FrfSet set;
  set.frequency_hz = Eigen::VectorXd::LinSpaced(41, 79.3, 81.3);
  set.outputs = {{1, 3}};
  set.references = {{1, 3}};
  set.output_quantity = k_pow == 2 ? Quantity::kAcceleration : Quantity::kDisplacement;
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const std::complex<double> lam = FrequencyAndDampingToPole(f0, zeta);
  const std::complex<double> res = 0.3 / std::complex<double>(0.0, 2.0 * lam.imag());
  Eigen::MatrixXcd h(41, 1);
  for (int k = 0; k < 41; ++k) {
    const std::complex<double> jw(0.0, kTwoPi * set.frequency_hz[k]);
    h(k, 0) = (res / (jw - lam) + std::conj(res) / (jw - std::conj(lam))) * std::pow(jw, k_pow);
  }
  const double peak = h.cwiseAbs().maxCoeff();
  for (int k = 0; k < 41; ++k) h(k, 0) += noise * peak * std::complex<double>(gauss(rng), gauss(rng)) / std::sqrt(2.0);
  set.h.push_back(h);
  return set;
}

// Before the zoom map the normal equations of this band turned singular above order 4 and no
// pole stayed stable ("no pole stayed stable over the PolyMAX orders 1..4"); with `--select 80.3`
// the mode was fitted. Now the automatic fit finds exactly that mode, within 0.05 % of the
// `--select` fit (issue 28), for light to moderate damping and 20 noise draws each.
TEST(NarrowBand, SteppedSineSingleModeIsFoundWithoutSelect) {
  for (double zeta : {0.001, 0.003, 0.01}) {
    for (unsigned seed = 1; seed <= 20; ++seed) {
      const FrfSet frfs = SteppedSine(80.3, zeta, 0.005, seed);
      const FitResult r = Fit(frfs, FitOptions{});
      EXPECT_TRUE(r.diagram.zoom_mapped);
      EXPECT_GE(r.diagram.order_max, 30) << "the band supports high orders on the zoom map";
      ASSERT_EQ(r.modes.modes.size(), 1u) << "zeta " << zeta << " seed " << seed;
      FitOptions hint;
      hint.select_frequencies_hz = {80.3};
      const FitResult s = Fit(frfs, hint);
      ASSERT_EQ(s.modes.modes.size(), 1u);
      EXPECT_NEAR(r.modes.modes[0].frequency_hz / s.modes.modes[0].frequency_hz, 1.0, 5e-4) << zeta << " " << seed;
      // The 0.05 % (0.04 Hz); the fits land within 0.006 Hz (0.5 % noise of the peak).
      EXPECT_NEAR(r.modes.modes[0].frequency_hz, 80.3, 5e-4 * 80.3) << zeta << " " << seed;
      // Damping within 10 %: the pole is the physical one, not a noise pole at the same place.
      EXPECT_NEAR(r.modes.modes[0].damping_ratio, zeta, 0.1 * zeta) << zeta << " " << seed;
    }
  }
}

// The same band read as receptance (k = 0) and a mode off-centre (80.9 Hz in 79.3..81.3 Hz).
TEST(NarrowBand, SteppedSineOffCentreReceptance) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const FrfSet frfs = SteppedSine(80.9, 0.002, 0.005, seed, 0);
    const FitResult r = Fit(frfs, FitOptions{});
    ASSERT_EQ(r.modes.modes.size(), 1u) << seed;
    EXPECT_NEAR(r.modes.modes[0].frequency_hz, 80.9, 5e-4 * 80.9) << seed;
    EXPECT_NEAR(r.modes.modes[0].damping_ratio, 0.002, 0.1 * 0.002) << seed;
  }
}

}  // namespace
}  // namespace ema::curvefit
