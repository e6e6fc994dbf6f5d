#include "ema/acquisition/simulator.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "acquisition/three_dof.hpp"

namespace ema::acquisition {
namespace {

using cd = std::complex<double>;

// DFT of x at bin k with the FFTW sign (spec §0), the test's own reference transform.
cd DftBin(const std::vector<double>& x, int k) {
  cd s = 0.0;
  const double n = static_cast<double>(x.size());
  for (size_t i = 0; i < x.size(); ++i) s += x[i] * std::polar(1.0, -kTwoPi * k * static_cast<double>(i) / n);
  return s;
}

TEST(Simulator, ModalSumIdentities) {
  // §7.3: sum over all 2n state modes of c_r = 0 and of c_r*lambda_r = M^-1 e_i. Exact algebra on
  // mass-normalised shapes, so only rounding remains: 1e-12 relative to M^-1.
  const auto sys = testing::MakeThreeDof();
  const Eigen::Matrix3d minv = sys.m.inverse();
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector3cd sum_c = Eigen::Vector3cd::Zero(), sum_cl = Eigen::Vector3cd::Zero();
    for (int r = 0; r < 3; ++r) {
      const cd a = sys.truth.ModalA(r);
      const cd lambda = sys.truth.poles[r];
      const Eigen::Vector3cd c = sys.truth.shapes[r] * sys.truth.shapes[r][i] / a;
      sum_c += c + c.conjugate();
      sum_cl += c * lambda + (c * lambda).conjugate();
    }
    EXPECT_LT(sum_c.norm(), 1e-12 * minv.norm());
    EXPECT_LT((sum_cl - minv.col(i).cast<cd>()).norm(), 1e-12 * minv.norm());
  }
}

TEST(Simulator, ReceptanceMatchesDirectInverse) {
  // Rayleigh damping C = a M + b K gives zeta_r = a/(2 w_r) + b w_r / 2 exactly, so the pole–residue
  // sum must equal (K + jwC - w^2 M)^-1 to rounding (spec §7.2 reports 1e-13): tolerance 1e-10 rel.
  auto sys = testing::MakeThreeDof();
  const double a = 2.0, b = 2e-5;
  std::vector<double> zeta;
  for (double f : sys.frequency_hz) zeta.push_back(a / (2 * kTwoPi * f) + b * kTwoPi * f / 2);
  sys = testing::MakeThreeDof(zeta);
  const Eigen::Matrix3d c = a * sys.m + b * sys.k;
  for (double f : {5.0, 37.0, sys.frequency_hz[1], 150.0, 400.0}) {
    const double w = kTwoPi * f;
    const Eigen::Matrix3cd dyn = sys.k.cast<cd>() + cd(0, w) * c.cast<cd>() - w * w * sys.m.cast<cd>();
    const Eigen::Matrix3cd direct = dyn.inverse();
    const Eigen::MatrixXcd modal = ReceptanceMatrix(sys.truth, w);
    EXPECT_LT((modal - direct).norm(), 1e-10 * direct.norm()) << "f = " << f;
  }
}

TEST(Simulator, NoiseFreeImpactSpectraRatioIsAnalyticAccelerance) {
  // A noise-free impact whose response dies out inside the record (T = 4 s >> 6 tau): the DFT ratio
  // Y/X must equal the analytic accelerance below 0.4 fs (the anti-alias pass band). Residual
  // errors: truncation e^{-zeta w T} < 1e-3 of the peak, FIR ripple cancels. Tolerance 1e-3 rel.
  const auto sys = testing::MakeThreeDof({0.02, 0.02, 0.02});
  const double fs = 2048.0;
  const int n = 8192;
  const ImpactSignals sig = SimulateImpact(sys.truth, {1, 3}, {{1, 3}, {3, 3}}, {{0.1, 50.0}}, 1e-3, fs, n,
                                           Quantity::kAcceleration);
  for (int k : {20, 100, 160, 300, 452, 700, 1500, 3000}) {
    const double f = k * fs / n;
    const cd ratio = DftBin(sig.responses[1], k) / DftBin(sig.force, k);
    const cd truth = AnalyticFrf(sys.truth, {3, 3}, {1, 3}, Eigen::VectorXd::Constant(1, f))[0];
    EXPECT_LT(std::abs(ratio - truth), 1e-3 * std::abs(truth)) << "f = " << f;
  }
}

TEST(Simulator, PulseShorterThanAFineStepIsNotLost) {
  // A 40 µs half-sine at 2048 Hz is 2/3 of one step of the default fine grid (8 x 2048 Hz): it
  // used to fall between two fine samples and give an all-zero force record. The grid is refined
  // until the pulse spans 16 fine steps, so the force's impulse (sum x dt, the FIR passes DC) is
  // the half-sine's 2 Tc peak / pi within 0.5 % (16-point sampling: at most 0.82/16² = 0.32 %), and
  // the spectra ratio is the accelerance within the same 0.5 % (the force's area error, at every f).
  const auto sys = testing::MakeThreeDof({0.02, 0.02, 0.02});
  const double fs = 2048.0, tc = 40e-6, peak = 50.0;
  const int n = 8192;
  EXPECT_EQ(EffectiveOversampling(tc, fs, 8), 196);  // ceil(16 / (40e-6 x 2048))
  const ImpactSignals sig = SimulateImpact(sys.truth, {1, 3}, {{1, 3}, {3, 3}}, {{0.1, peak}}, tc, fs, n,
                                           Quantity::kAcceleration);
  double impulse = 0.0;
  for (double v : sig.force) impulse += v / fs;
  EXPECT_NEAR(impulse, tc * peak / (kTwoPi / 4.0), 0.005 * tc * peak / (kTwoPi / 4.0));
  for (int k : {20, 100, 160, 300}) {
    const double f = k * fs / n;
    const cd ratio = DftBin(sig.responses[1], k) / DftBin(sig.force, k);
    const cd truth = AnalyticFrf(sys.truth, {3, 3}, {1, 3}, Eigen::VectorXd::Constant(1, f))[0];
    EXPECT_LT(std::abs(ratio - truth), 5e-3 * std::abs(truth)) << "f = " << f;
  }
  // Past the finest grid the simulator makes, it refuses and says the shortest pulse it supports.
  try {
    EffectiveOversampling(1e-6, fs, 8);
    FAIL() << "a 1 µs pulse at 2048 Hz needs a grid 7813 times finer";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("the shortest is 3.05e-05 s"), std::string::npos) << e.what();
  }
}

TEST(Simulator, RecordsFollowTheFileConvention) {
  const auto sys = testing::MakeThreeDof();
  HammerTestPlan plan;
  plan.references = {{1, 3}};
  plan.roving_sets = {{{2, 3}}, {{3, 3}}};
  plan.impacts_per_reference = 2;
  plan.samples_per_record = 1024;
  plan.force_noise = 0.01;
  const auto sets = SimulateHammerTestSets({sys.truth}, plan);
  ASSERT_EQ(sets.size(), 2u);
  ASSERT_EQ(sets[1].records.size(), 4u);  // 2 impacts x (force + 1 response)
  EXPECT_EQ(sets[1].records[0].quantity, Quantity::kForce);
  EXPECT_EQ(sets[1].records[0].channel, (Dof{1, 3}));
  EXPECT_EQ(sets[1].records[1].channel, (Dof{3, 3}));
  EXPECT_EQ(sets[1].records[1].reference, (Dof{1, 3}));
  EXPECT_EQ(sets[1].records[3].impact, 2);
  // The flat list numbers impacts across sets so one list can hold both sets unambiguously.
  const auto flat = SimulateHammerTest({sys.truth}, plan);
  EXPECT_EQ(flat.back().impact, 4);
  // Peak force within the requested spread (100 N ± 10 %, plus 1 % rms noise: margin 5 N).
  for (const auto& r : flat)
    if (r.quantity == Quantity::kForce) {
      double peak = 0;
      for (double v : r.samples) peak = std::max(peak, v);
      EXPECT_GT(peak, 85.0);
      EXPECT_LT(peak, 115.0);
    }
}

}  // namespace
}  // namespace ema::acquisition
