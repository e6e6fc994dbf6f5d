// MAC, AutoMAC, COMAC, agreement: hand-computed values and invariances.
#include <gtest/gtest.h>

#include <stdexcept>

#include <cmath>
#include <complex>
#include <random>

#include "ema/correlation/mac.hpp"

namespace ema::correlation {
namespace {

using cd = std::complex<double>;

TEST(Mac, RealVectorsByHand) {
  // a = (1, 2, 0), b = (1, 0, 1): a·b = 1, |a|² = 5, |b|² = 2 → MAC = 1/10.
  Eigen::VectorXcd a(3), b(3);
  a << 1.0, 2.0, 0.0;
  b << 1.0, 0.0, 1.0;
  EXPECT_NEAR(Mac(a, b), 0.1, 1e-15);  // exact arithmetic up to rounding
  EXPECT_NEAR(Mac(a, a), 1.0, 1e-15);
  Eigen::VectorXcd c(3);
  c << 2.0, -1.0, 5.0;  // orthogonal to a
  EXPECT_NEAR(Mac(a, c), 0.0, 1e-15);
}

TEST(Mac, ComplexVectorsByHand) {
  // a = (1, j), b = (1, 1): a^H b = 1 − j, |.|² = 2; |a|² = 2, |b|² = 2 → MAC = 0.5.
  Eigen::VectorXcd a(2), b(2);
  a << cd(1, 0), cd(0, 1);
  b << cd(1, 0), cd(1, 0);
  EXPECT_NEAR(Mac(a, b), 0.5, 1e-15);
  // a = (1+j, 2), b = (1, 1−j): a^H b = (1−j)·1 + 2(1−j) = 3 − 3j, |.|² = 18;
  // |a|² = 2 + 4 = 6, |b|² = 1 + 2 = 3 → MAC = 1.
  Eigen::VectorXcd p(2), q(2);
  p << cd(1, 1), cd(2, 0);
  q << cd(1, 0), cd(1, -1);
  EXPECT_NEAR(Mac(p, q), 1.0, 1e-14);
  // A naive transpose (no conjugate) would give |(1+j)+2(1−j)|² = |3 − j|² = 10 → 10/18: make
  // sure we are not doing that.
  EXPECT_GT(std::abs(Mac(p, q) - 10.0 / 18.0), 0.1);
}

TEST(Mac, InvariantToComplexScaling) {
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  Eigen::VectorXcd a(8), b(8);
  for (int i = 0; i < 8; ++i) {
    a(i) = cd(g(rng), g(rng));
    b(i) = cd(g(rng), g(rng));
  }
  const double reference = Mac(a, b);
  const cd s1(-3.2, 1.7), s2(0.0, -0.004);
  EXPECT_NEAR(Mac(s1 * a, b), reference, 1e-13);  // relative rounding of a few ulps
  EXPECT_NEAR(Mac(a, s2 * b), reference, 1e-13);
  EXPECT_NEAR(Mac(s1 * a, s2 * b), reference, 1e-13);
  EXPECT_NEAR(Mac(s1 * a, a), 1.0, 1e-13);
}

TEST(Mac, ZeroVectorGivesZeroNotNaN) {
  Eigen::VectorXcd a = Eigen::VectorXcd::Zero(3), b = Eigen::VectorXcd::Ones(3);
  EXPECT_EQ(Mac(a, b), 0.0);
}

TEST(Mac, AutoMacSymmetricUnitDiagonal) {
  Eigen::MatrixXcd shapes(3, 3);
  shapes << 1, 0, 1,  //
      0, 1, 1,        //
      0, 0, 1;
  const Eigen::MatrixXd auto_mac = AutoMac(shapes);
  EXPECT_TRUE(auto_mac.isApprox(auto_mac.transpose(), 0.0));
  for (int i = 0; i < 3; ++i) EXPECT_DOUBLE_EQ(auto_mac(i, i), 1.0);
  EXPECT_NEAR(auto_mac(0, 1), 0.0, 1e-15);
  EXPECT_NEAR(auto_mac(0, 2), 1.0 / 3.0, 1e-15);  // (1)² / (1 · 3)
}

TEST(Mac, ModalScaleFactorRecoversScale) {
  Eigen::VectorXcd x(3);
  x << cd(1, 2), cd(-0.5, 0), cd(0.3, 0.1);
  const cd scale(2.5, -1.0);
  EXPECT_NEAR(std::abs(ModalScaleFactor(x, scale * x) - scale), 0.0, 1e-14);
}

TEST(Comac, IdenticalSetsGiveOneAndABadDofDips) {
  Eigen::MatrixXcd model(4, 3);
  model << 1.0, 0.5, 0.2,  //
      0.8, -0.4, 1.0,      //
      0.3, 1.0, -0.7,      //
      -0.6, 0.2, 0.9;
  // Test = model scaled differently per mode (COMAC must scale first).
  Eigen::MatrixXcd test = model;
  test.col(0) *= cd(-2.0, 0.0);
  test.col(1) *= cd(0.0, 3.0);
  test.col(2) *= 0.1;
  Eigen::VectorXd comac = Comac(test, model);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(comac(i), 1.0, 1e-12);
  // Corrupt DOF 2 (a sensor with the wrong sign in one mode): its COMAC must fall below the rest.
  test(2, 1) *= -1.0;
  comac = Comac(test, model);
  int worst = 0;
  comac.minCoeff(&worst);
  EXPECT_EQ(worst, 2);
  EXPECT_LT(comac(2), 0.9);
}

TEST(Comac, ValuesByHand) {
  // COMAC_i = (Σ_r |t_ir m_ir|)² / (Σ_r t_ir² Σ_r m_ir²), test modes first scaled to the model by
  // their modal scale factor. Model m1 = (1, 2, 3), m2 = (1, -1, 1); test t1 = m1, t2 = (1, -1, 2)
  // with MSF (1 + 1 + 2) / 6 = 2/3, so t2 scaled = (2/3, -2/3, 4/3). By hand:
  //   DOF 1: (1 + 2/3)² / ((1 + 4/9)(1 + 1)) = 25/26
  //   DOF 2: (4 + 2/3)² / ((4 + 4/9)(4 + 1)) = 196/200
  //   DOF 3: (9 + 4/3)² / ((9 + 16/9)(9 + 1)) = 961/970
  Eigen::MatrixXcd model(3, 2), test(3, 2);
  model << 1, 1, 2, -1, 3, 1;
  test << 1, 1, 2, -1, 3, 2;
  const Eigen::VectorXd comac = Comac(test, model);
  ASSERT_EQ(comac.size(), 3);
  EXPECT_NEAR(comac(0), 25.0 / 26.0, 1e-12);
  EXPECT_NEAR(comac(1), 196.0 / 200.0, 1e-12);
  EXPECT_NEAR(comac(2), 961.0 / 970.0, 1e-12);
}

TEST(Agreement, DefinitionAndSign) {
  EXPECT_DOUBLE_EQ(AgreementPct(100.0, 100.0), 100.0);
  EXPECT_NEAR(AgreementPct(200.0, 150.0), 75.0, 1e-12);
  EXPECT_NEAR(AgreementPct(200.0, 250.0), 75.0, 1e-12);  // relative to the model, both sides
  EXPECT_NEAR(FrequencyErrorPct(110.0, 100.0), 10.0, 1e-12);
  EXPECT_NEAR(FrequencyErrorPct(90.0, 100.0), -10.0, 1e-12);
}

// Thesis tables: model frequency, test frequency, printed percentage agreement. The printed
// values are integers, so the recomputed value must round to the printed one (tolerance 0.5),
// with one exception: Table 7.7 mode 7 (430 vs 429 Hz) is printed 99 % but is 99.77 %, a
// rounding slip in the thesis (it reads as truncation).
struct ThesisRow {
  const char* table;
  int mode;
  double model_hz, test_hz, printed_pct;
};

TEST(Agreement, ReproducesThesisTables) {
  const ThesisRow rows[] = {
      {"6.1", 1, 2257, 1260, 56}, {"6.1", 2, 3218, 2200, 68}, {"6.1", 3, 2483, 2269, 91}, {"6.1", 4, 2811, 2549, 91},
      {"6.2", 1, 1067, 806, 76}, {"6.2", 2, 1577, 1514, 96}, {"6.2", 3, 2483, 2262, 91}, {"6.2", 4, 2782, 2533, 91},
      {"7.6", 1, 333, 294, 88},  {"7.6", 2, 347, 324, 93},   {"7.6", 3, 429, 425, 99},
      {"7.7", 1, 193, 207, 93},  {"7.7", 2, 261, 254, 97},   {"7.7", 3, 281, 263, 94},   {"7.7", 4, 297, 312, 95},
      {"7.7", 5, 343, 391, 86},  {"7.7", 7, 430, 429, 99},
      {"7.8", 1, 153, 137, 90},  {"7.8", 2, 234, 180, 77},   {"7.8", 3, 236, 222, 94},   {"7.8", 4, 242, 244, 99},
      {"7.8", 5, 271, 305, 87},  {"7.8", 6, 347, 319, 92},   {"7.8", 7, 429, 425, 99},
  };
  for (const ThesisRow& r : rows) {
    const double pct = AgreementPct(r.model_hz, r.test_hz);
    const bool slip = std::string(r.table) == "7.7" && r.mode == 7;
    if (slip) {
      EXPECT_NEAR(pct, 99.77, 0.01) << "Table 7.7 mode 7";
      EXPECT_NE(std::round(pct), r.printed_pct) << "the thesis's rounding slip is expected to remain visible";
    } else {
      EXPECT_EQ(std::round(pct), r.printed_pct) << "Table " << r.table << " mode " << r.mode << ": " << pct;
    }
  }
  // The agreement is normalised by the model frequency, not symmetric: Table 7.7 mode 5 with the
  // roles swapped would read 87.7 %, which the thesis does not print.
  EXPECT_NEAR(AgreementPct(343.0, 391.0), 100.0 * (1.0 - 48.0 / 343.0), 1e-12);
  EXPECT_NEAR(AgreementPct(391.0, 343.0), 100.0 * (1.0 - 48.0 / 391.0), 1e-12);
}

TEST(Mac, ShapesOfDifferentLengthsAreRefused) {
  // Comparing a 2-DOF shape with a 50000-DOF one read past the shorter (the Python binding crashed
  // the interpreter; issue 41): no MAC exists between them.
  EXPECT_THROW(MacMatrix(Eigen::MatrixXcd::Ones(2, 2), Eigen::MatrixXcd::Ones(50000, 2)), std::invalid_argument);
  EXPECT_THROW(MacMatrix(Eigen::MatrixXcd::Ones(3, 2), Eigen::MatrixXcd::Ones(4, 2)), std::invalid_argument);
  EXPECT_EQ(MacMatrix(Eigen::MatrixXcd::Ones(3, 2), Eigen::MatrixXcd::Ones(3, 1)).rows(), 2);
}

}  // namespace
}  // namespace ema::correlation
