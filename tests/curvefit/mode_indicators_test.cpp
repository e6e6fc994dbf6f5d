// CMIF and MMIF (curvefit/mode_indicators.hpp) on exact FRFs with two close modes.
#include <gtest/gtest.h>

#include <vector>

#include "curvefit/synthetic.hpp"
#include "ema/curvefit/fit_data.hpp"
#include "ema/curvefit/mode_indicators.hpp"

namespace ema::curvefit {
namespace {

std::vector<int> LocalMaxima(const Eigen::VectorXd& f, const Eigen::VectorXd& y, double lo, double hi) {
  std::vector<int> peaks;
  for (int k = 1; k + 1 < y.size(); ++k)
    if (f[k] >= lo && f[k] <= hi && y[k] > y[k - 1] && y[k] >= y[k + 1]) peaks.push_back(k);
  return peaks;
}

// Modes at 100 and 102 Hz with 2 % damping (half-power width 4 Hz, wider than their spacing),
// plus a mode at 40 Hz; two references (DOFs 1 and 2) with orthogonal participation of the close
// pair ((1, 1) and (1, -1)), the 102 Hz mode weaker (shape × 0.6), as a second bending mode is
// beside a torsion mode of a symmetric structure.
class ModeIndicatorsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto truth = test::MakeTruth({40.0, 100.0, 102.0}, {0.01, 0.02, 0.02}, 6);
    truth.modes[1].shape << 1.0, 1.0, 0.5, 0.8, 0.3, 0.6;
    truth.modes[2].shape << 1.0, -1.0, 0.7, -0.4, 0.9, -0.2;
    truth.modes[1].shape *= 0.5;
    truth.modes[2].shape *= 0.3;
    FitDataOptions o;
    o.band_lo_hz = 20.0;
    o.band_hi_hz = 140.0;
    data_ = PrepareFitData(test::MakeFrfSet(truth, {0, 1}, 150.0, 0.1, 0.0, 1), o);
    mi_ = ComputeModeIndicators(data_);
  }
  FitData data_;
  ModeIndicators mi_;
};

TEST_F(ModeIndicatorsTest, CmifShowsTwoPeaksWhereTheSumShowsOne) {
  ASSERT_EQ(mi_.cmif.cols(), 2);  // min(6 outputs, 2 references)
  const Eigen::VectorXd sum = data_.h.cwiseAbs().rowwise().sum();
  const auto& f = mi_.frequency_hz;
  // The sum of |H| has a single peak between 90 and 112 Hz ...
  EXPECT_EQ(LocalMaxima(f, sum, 90.0, 112.0).size(), 1u);
  // ... the first singular value peaks at one close mode and the second at the other
  // (within 0.3 Hz: the peak line of a 2 % mode on a 0.1 Hz grid, shifted a little by its neighbour).
  const auto p1 = LocalMaxima(f, mi_.cmif.col(0), 90.0, 112.0);
  const auto p2 = LocalMaxima(f, mi_.cmif.col(1), 90.0, 112.0);
  ASSERT_GE(p1.size(), 1u);
  ASSERT_GE(p2.size(), 1u);
  std::vector<double> found = {f[p1.front()], f[p2.front()]};
  std::sort(found.begin(), found.end());
  EXPECT_NEAR(found[0], 100.0, 0.3);
  EXPECT_NEAR(found[1], 102.0, 0.3);
  // Singular values are ordered at every line.
  EXPECT_TRUE(((mi_.cmif.col(0) - mi_.cmif.col(1)).array() >= 0.0).all());
}

TEST_F(ModeIndicatorsTest, MmifDipsAtEachResonance) {
  ASSERT_EQ(mi_.mmif.cols(), 2);
  const auto& f = mi_.frequency_hz;
  auto at = [&](double hz) { return static_cast<int>(std::lround((hz - f[0]) / 0.1)); };
  // At an isolated resonance the response is in quadrature: Re(H) vanishes, so the smallest
  // eigenvalue dips close to 0 (residual contributions of the other modes keep it above 0).
  EXPECT_LT(mi_.mmif(at(40.0), 0), 0.01);
  // The first MMIF resolves the close pair: a dip at each (values here ~6e-4 and ~2e-4) with a
  // rise between them (0.18 at 101 Hz), where the sum of |H| has a single peak.
  EXPECT_LT(mi_.mmif(at(100.0), 0), 0.01);
  EXPECT_LT(mi_.mmif(at(102.0), 0), 0.01);
  EXPECT_GT(mi_.mmif(at(101.0), 0), 0.1);
  // Far from resonance the response is in phase (Re dominates): near 1.
  EXPECT_GT(mi_.mmif(at(70.0), 0), 0.9);
  EXPECT_TRUE((mi_.mmif.array() >= 0.0).all() && (mi_.mmif.array() <= 1.0).all());
}

}  // namespace
}  // namespace ema::curvefit
