// Estimators, coherence, MIMO H1 / multiple coherence and conversions on exact spectra.
#include "ema/frf/estimators.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

namespace ema::frf {
namespace {

using cd = std::complex<double>;

CrossSpectra Accumulate(const std::vector<Eigen::ArrayXcd>& x, const std::vector<Eigen::ArrayXcd>& y) {
  CrossSpectra s;
  s.Resize(x[0].size());
  for (size_t k = 0; k < x.size(); ++k) s.Add(x[k].data(), y[k].data());
  return s;
}

TEST(Estimators, NoiseFreeAllEqualTruth) {
  // Y = H X exactly: H1 = H2 = Hv = H and coherence 1 to rounding (spec §7.5: 1e-10 rel).
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0, 1);
  const int lines = 64;
  Eigen::ArrayXcd h(lines);
  for (int i = 0; i < lines; ++i) h[i] = cd(n(rng), n(rng));
  std::vector<Eigen::ArrayXcd> x, y;
  for (int k = 0; k < 5; ++k) {
    Eigen::ArrayXcd xk(lines);
    for (int i = 0; i < lines; ++i) xk[i] = cd(n(rng), n(rng));
    x.push_back(xk);
    y.push_back(h * xk);
  }
  const CrossSpectra s = Accumulate(x, y);
  for (Estimator e : {Estimator::kH1, Estimator::kH2, Estimator::kHv})
    EXPECT_LT(((EstimateFrf(s, e) - h).abs() / h.abs()).maxCoeff(), 1e-10) << EstimatorName(e);
  EXPECT_LT((Coherence(s) - 1.0).abs().maxCoeff(), 1e-12);
}

TEST(Estimators, OrderingAndCoherenceIdentityWithNoise) {
  // Spec §7.5: |H1| ≤ |Hv| ≤ |H2| and γ² = H1/H2 (1e-12) with noise on both channels.
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0, 1);
  const int lines = 200;
  std::vector<Eigen::ArrayXcd> x, y;
  for (int k = 0; k < 5; ++k) {
    Eigen::ArrayXcd xk(lines), yk(lines);
    for (int i = 0; i < lines; ++i) {
      const cd xt(n(rng), n(rng));
      xk[i] = xt + 0.3 * cd(n(rng), n(rng));
      yk[i] = cd(2.0, -1.0) * xt + 0.3 * cd(n(rng), n(rng));
    }
    x.push_back(xk);
    y.push_back(yk);
  }
  const CrossSpectra s = Accumulate(x, y);
  const Eigen::ArrayXcd h1 = EstimateFrf(s, Estimator::kH1), h2 = EstimateFrf(s, Estimator::kH2),
                        hv = EstimateFrf(s, Estimator::kHv);
  const Eigen::ArrayXd coh = Coherence(s);
  for (int i = 0; i < lines; ++i) {
    EXPECT_LE(std::abs(h1[i]), std::abs(hv[i]) * (1 + 1e-12));
    EXPECT_LE(std::abs(hv[i]), std::abs(h2[i]) * (1 + 1e-12));
    EXPECT_NEAR(std::abs(h1[i] / h2[i]), coh[i], 1e-12);
    EXPECT_NEAR(std::arg(hv[i] / h1[i]), 0.0, 1e-12);  // phase(Hv) = phase(H1)
  }
}

TEST(Estimators, MimoH1AndMultipleCoherence) {
  // Two simultaneous inputs, 3 outputs, 8 averages, Y = H X exactly: H1 = S_yx S_xx^-1 recovers H
  // (1e-10) and the multiple coherence is 1; with output noise it drops below 1. For one input it
  // equals the ordinary coherence (1e-12).
  std::mt19937 rng(9);
  std::normal_distribution<double> n(0, 1);
  Eigen::MatrixXcd h(3, 2);
  for (int i = 0; i < 6; ++i) h(i % 3, i / 3) = cd(n(rng), n(rng));
  Eigen::MatrixXcd sxx = Eigen::MatrixXcd::Zero(2, 2), syx = Eigen::MatrixXcd::Zero(3, 2),
                   syx_noisy = Eigen::MatrixXcd::Zero(3, 2);
  Eigen::VectorXd syy = Eigen::VectorXd::Zero(3), syy_noisy = Eigen::VectorXd::Zero(3);
  for (int k = 0; k < 8; ++k) {
    Eigen::VectorXcd xk(2);
    xk << cd(n(rng), n(rng)), cd(n(rng), n(rng));
    const Eigen::VectorXcd yk = h * xk;
    Eigen::VectorXcd noisy = yk;
    for (int o = 0; o < 3; ++o) noisy[o] += 0.2 * cd(n(rng), n(rng));
    sxx += xk * xk.adjoint();
    syx += yk * xk.adjoint();
    syx_noisy += noisy * xk.adjoint();
    syy += yk.cwiseAbs2();
    syy_noisy += noisy.cwiseAbs2();
  }
  EXPECT_LT((MimoH1(syx, sxx) - h).norm(), 1e-10 * h.norm());
  for (int o = 0; o < 3; ++o) {
    EXPECT_NEAR(MultipleCoherence(syx.row(o), sxx, syy[o]), 1.0, 1e-10);
    EXPECT_LT(MultipleCoherence(syx_noisy.row(o), sxx, syy_noisy[o]), 0.999);
  }
  // m = 1: reduces to |Gxy|^2 / (Gxx Gyy).
  Eigen::MatrixXcd s1(1, 1);
  s1(0, 0) = 2.0;
  Eigen::RowVectorXcd so(1);
  so(0) = cd(1.0, 0.5);
  EXPECT_NEAR(MultipleCoherence(so, s1, 0.8), std::norm(so(0)) / (2.0 * 0.8), 1e-12);
}

TEST(Estimators, ConversionsFollowJOmegaPowers) {
  // Mobility = jw α leads receptance by +90°, accelerance = −w² α by 180° (spec §1.9); DC line of
  // a division is NaN.
  Eigen::VectorXd f(3);
  f << 0.0, 10.0, 50.0;
  Eigen::ArrayXcd alpha(3);
  alpha << cd(1, 0), cd(0.5, -0.2), cd(-0.1, 0.3);
  const Eigen::ArrayXcd mob = ConvertFrf(alpha, f, Quantity::kDisplacement, Quantity::kVelocity);
  const Eigen::ArrayXcd acc = ConvertFrf(alpha, f, Quantity::kDisplacement, Quantity::kAcceleration);
  for (int i = 1; i < 3; ++i) {
    const double w = kTwoPi * f[i];
    EXPECT_LT(std::abs(mob[i] - cd(0, w) * alpha[i]), 1e-12 * std::abs(mob[i]));
    EXPECT_LT(std::abs(acc[i] + w * w * alpha[i]), 1e-12 * std::abs(acc[i]));
  }
  const Eigen::ArrayXcd back = ConvertFrf(acc, f, Quantity::kAcceleration, Quantity::kDisplacement);
  EXPECT_TRUE(std::isnan(back[0].real()));
  EXPECT_LT(std::abs(back[2] - alpha[2]), 1e-12);
  EXPECT_EQ(ParseEstimator("hv"), Estimator::kHv);
  EXPECT_THROW(ParseEstimator("H3"), std::invalid_argument);
}

}  // namespace
}  // namespace ema::frf
