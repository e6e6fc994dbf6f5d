// MPC, MPD and MCF of shapes with a known complexity (curvefit/complexity.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <complex>

#include "ema/curvefit/complexity.hpp"

namespace ema::curvefit {
namespace {

TEST(Complexity, TwoComponentShapeWithKnownPhase) {
  // phi = [1, e^{j a}]: Sxx = 1 + cos^2 a, Syy = sin^2 a, Sxy = cos a sin a, so
  // MPC = cos^2 a, MCF = sin^2 a, and the principal axis bisects the two components: MPD = a/2.
  const double a = 30.0 * M_PI / 180.0;
  const std::complex<double> global = std::polar(2.5, 0.7);  // amplitude and phase do not matter
  ModeSet set;
  set.dofs = {{1, 3}, {2, 3}};
  Mode m;
  m.frequency_hz = 12.0;
  m.shape = Eigen::VectorXcd(2);
  m.shape << global, global * std::polar(1.0, a);
  set.modes.push_back(m);
  Mode real = m;
  real.shape << 1.0, -0.4;
  real.shape *= global;
  set.modes.push_back(real);

  const auto checks = CheckModeComplexity(set);
  ASSERT_EQ(checks.size(), 2u);
  EXPECT_NEAR(checks[0].mpc, 0.75, 1e-14);  // rounding of a few sums
  EXPECT_NEAR(checks[0].mcf, 0.25, 1e-14);
  EXPECT_NEAR(checks[0].mpd_deg, 15.0, 1e-9);  // SVD-based axis: a few ulps of acos near 1
  EXPECT_EQ(checks[0].verdict, frf::Verdict::kWarn);
  EXPECT_NE(checks[0].reason.find("MPC 0.750"), std::string::npos) << checks[0].reason;

  EXPECT_NEAR(checks[1].mpc, 1.0, 1e-14);
  EXPECT_NEAR(checks[1].mcf, 0.0, 1e-14);
  EXPECT_NEAR(checks[1].mpd_deg, 0.0, 1e-6);  // acos(1 - ulp) ~ 1e-8 rad
  EXPECT_EQ(checks[1].verdict, frf::Verdict::kPass);
}

TEST(Complexity, CircularShapeHasMcfOne) {
  // A travelling wave: phi_k = e^{j 2 pi k / 4}; phi^T phi = sum e^{j pi k} = 0.
  Eigen::VectorXcd phi(4);
  for (int k = 0; k < 4; ++k) phi[k] = std::polar(1.0, M_PI * k / 2.0);
  EXPECT_NEAR(ModeComplexityFactor(phi), 1.0, 1e-15);
  EXPECT_TRUE(std::isnan(ModeComplexityFactor(Eigen::VectorXcd::Zero(3))));
}

TEST(Complexity, ThresholdsAreOptions) {
  ComplexityOptions o;
  o.mpc_min = 0.7;
  o.mpd_max_deg = 20.0;
  ModeSet set;
  Mode m;
  m.shape = Eigen::VectorXcd(2);
  m.shape << 1.0, std::polar(1.0, 30.0 * M_PI / 180.0);  // MPC 0.75, MPD 15 deg
  set.modes.push_back(m);
  EXPECT_EQ(CheckModeComplexity(set, o)[0].verdict, frf::Verdict::kPass);
  o.mpc_min = 2.0;
  std::string error;
  EXPECT_FALSE(o.IsValid(&error));
}

}  // namespace
}  // namespace ema::curvefit
