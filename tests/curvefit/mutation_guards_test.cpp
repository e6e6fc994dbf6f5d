// Tests added after the mutation check (docs/testing.md): each pins down a piece of curvefit that
// a small deliberate bug changed without any other test noticing.
#include <gtest/gtest.h>

#include <cmath>

#include "curvefit/synthetic.hpp"
#include "ema/curvefit/fit.hpp"
#include "ema/curvefit/ml_refine.hpp"

namespace ema::curvefit {
namespace {

using test::MakeFrfSet;
using test::MakeTruth;
using test::Truth;

TEST(Uncertainty, PoleCovarianceToFrequencyAndDampingByHand) {
  // f = |λ|/2π, ζ = −Re λ/|λ|; first-order propagation σ² = gᵀ C g with, for λ = u + iv, a = |λ|:
  //   ∂f/∂(u, v) = (u, v) / (2π a),   ∂ζ/∂(u, v) = (−v², u v) / a³.
  // λ = −1 + 10i, C = diag(4, 0.01) (anisotropic, so a swapped gradient shows):
  //   σ_f² = (1·4 + 100·0.01) / (4π² · 101) = 5 / (4π² · 101)
  //   σ_ζ² = (100² · 4 + 10² · 0.01) / 101³ = 40001 / 101³
  double sf = 0.0, sz = 0.0;
  Eigen::Matrix2d c = Eigen::Vector2d(4.0, 0.01).asDiagonal();
  PoleStdToFrequencyAndDamping({-1.0, 10.0}, c, &sf, &sz);
  EXPECT_NEAR(sf, std::sqrt(5.0 / (4.0 * M_PI * M_PI * 101.0)), 1e-14);
  EXPECT_NEAR(sz, std::sqrt(40001.0 / std::pow(101.0, 3)), 1e-14);
}

TEST(Residuals, OutOfBandModesAreAbsorbedByTheResidualTerms) {
  // Modes at 15 Hz (below the 40..100 Hz band) and 250 Hz (above) shape the in-band FRFs like a
  // mass line and a stiffness line: for accelerance, the lower residual LR/(jω)² · (jω)² is a
  // constant and the upper residual UR · (jω)² grows like ω². With both terms the noise-free
  // data are reproduced to 1.2e-3 relative (the out-of-band modes are not exactly such lines over
  // the band); a lower residual with the wrong power of jω leaves 3.2e-2. Bound: 3e-3.
  const Truth truth = MakeTruth({15.0, 60.0, 80.0, 250.0}, {0.01, 0.01, 0.01, 0.01}, 6);
  const FrfSet frfs = MakeFrfSet(truth, {1}, 300.0, 0.05, 0.0, 1);
  FitOptions options;
  options.data.band_lo_hz = 40.0;
  options.data.band_hi_hz = 100.0;
  options.polymax.order_max = 30;
  options.refine = RefineMethod::kNone;
  const FitResult fit = Fit(frfs, options);
  ASSERT_EQ(fit.modes.modes.size(), 2u);
  EXPECT_NEAR(fit.modes.modes[0].frequency_hz, 60.0, 1e-4 * 60.0);
  EXPECT_NEAR(fit.modes.modes[1].frequency_hz, 80.0, 1e-4 * 80.0);
  EXPECT_LT(fit.synthesis_error, 3e-3);
}

TEST(Polymax, NegativelyDampedPolesAreNeverPhysical) {
  // Noise brings PolyMAX poles with negative damping at high orders; none of them may count as
  // physical (label 'o'), or the selection could pick an unstable pole.
  const Truth truth = MakeTruth({20.0, 50.0, 80.0}, {0.01, 0.02, 0.01}, 6);
  const FrfSet frfs = MakeFrfSet(truth, {1}, 100.0, 0.1, 0.05, 7);
  FitOptions options;
  options.polymax.order_max = 60;
  options.refine = RefineMethod::kNone;
  const FitResult fit = Fit(frfs, options);
  int negative = 0;
  for (const auto& order : fit.diagram.orders)
    for (const auto& pole : order)
      if (pole.damping_ratio <= 0.0) {
        ++negative;
        EXPECT_FALSE(pole.physical) << pole.frequency_hz << " Hz, ζ " << pole.damping_ratio;
        EXPECT_EQ(pole.label, 'o');
      }
  EXPECT_GT(negative, 0) << "the test needs negatively damped poles to check";
}

TEST(SplitPoles, MergedWhenTheShiftIsWithinBothHalfPowerBandsTogether) {
  // As SplitPoles.RovingSetInconsistencyGivesOneMode, with the second set's mode 0.8 Hz higher:
  // more than one half-power half-width (ζ f = 0.5 Hz) but less than the two together (1.0 Hz),
  // so the two poles' bands still overlap and they are one mode.
  const FrfSet frfs = test::TwoRovingSetsWithShiftedMode(50.8);
  FitOptions options;
  options.polymax.order_max = 40;
  const FitResult fit = Fit(frfs, options);
  EXPECT_EQ(fit.modes.modes.size(), 3u) << "one pole per physical mode";
  ASSERT_EQ(fit.dropped.size(), 1u);
  EXPECT_NEAR(fit.dropped[0].merged_into_hz, 50.4, 0.5);
}

}  // namespace
}  // namespace ema::curvefit
