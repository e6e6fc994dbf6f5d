// Narrow-band fits (issue 14): a band of few lines around one or two modes, as when each force
// level of an amplitude test is fitted around the mode of interest. PolyMAX must still find the
// mode (low orders suffice there) and so must peak picking; the FRFs come from known truth plus
// 1 % complex noise (synthetic.hpp).
#include <gtest/gtest.h>

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
