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

TEST(Polymax, OnePercentNoiseSixModes) {
  const Truth truth = SixModes(12);
  const FrfSet frfs = MakeFrfSet(truth, {2, 9}, 150.0, 0.04, 0.01, 7);
  FitOptions options;
  options.polymax.order_max = 40;
  const FitResult fit = Fit(frfs, options);
  ASSERT_EQ(fit.modes.modes.size(), truth.modes.size()) << "automatic selection must find exactly the 6 modes";
  const auto match = MatchModes(truth, fit.modes);
  for (size_t r = 0; r < truth.modes.size(); ++r) {
    ASSERT_GE(match[r], 0);
    const Mode& m = fit.modes.modes[match[r]];
    // Issue 4 acceptance at 1 % noise: f within 0.05 %, zeta within 2 % (relative), MAC >= 0.995.
    EXPECT_NEAR(m.frequency_hz / truth.modes[r].f_hz, 1.0, 5e-4);
    EXPECT_NEAR(m.damping_ratio / truth.modes[r].zeta, 1.0, 0.02) << truth.modes[r].f_hz;
    EXPECT_GE(ComplexMac(m.shape, truth.modes[r].shape.cast<std::complex<double>>()), 0.995);
    EXPECT_TRUE(m.unit_modal_mass);
  }
}

}  // namespace
}  // namespace ema::curvefit
