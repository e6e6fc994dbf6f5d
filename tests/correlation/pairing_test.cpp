// Hungarian assignment and mode pairing: swapped order, missing and extra modes, ties.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

#include "ema/correlation/mac.hpp"
#include "ema/correlation/pairing.hpp"

namespace ema::correlation {
namespace {

// Brute force over all permutations, for checking the assignment on small matrices.
double BruteForceMinCost(const Eigen::MatrixXd& cost) {
  std::vector<int> perm(cost.cols());
  std::iota(perm.begin(), perm.end(), 0);
  double best = 1e300;
  do {
    double sum = 0.0;
    for (int i = 0; i < cost.rows(); ++i) sum += cost(i, perm[i]);
    best = std::min(best, sum);
  } while (std::next_permutation(perm.begin(), perm.end()));
  return best;
}

TEST(Assignment, MatchesBruteForceOnRandomSquareMatrices) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 30; ++trial) {
    const int n = 2 + trial % 5;
    Eigen::MatrixXd cost(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) cost(i, j) = u(rng);
    const std::vector<int> a = SolveAssignment(cost);
    std::vector<int> seen(n, 0);
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
      ASSERT_GE(a[i], 0);
      ++seen[a[i]];
      sum += cost(i, a[i]);
    }
    for (int j = 0; j < n; ++j) EXPECT_EQ(seen[j], 1);
    EXPECT_NEAR(sum, BruteForceMinCost(cost), 1e-12);  // exact optimum up to rounding
  }
}

TEST(Assignment, RectangularLeavesRowsOut) {
  Eigen::MatrixXd cost(3, 2);
  cost << 0.0, -1.0,  //
      -1.0, 0.0,      //
      -0.5, -0.5;
  const std::vector<int> a = SolveAssignment(cost);
  EXPECT_EQ(a[0], 1);
  EXPECT_EQ(a[1], 0);
  EXPECT_EQ(a[2], -1);
}

// A set of orthonormal-ish random shapes and frequencies; test = model permuted + noise.
struct Sets {
  Eigen::MatrixXcd model;
  Eigen::VectorXd model_hz;
};

Sets MakeModel(int dofs, int modes, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  Sets s;
  s.model.resize(dofs, modes);
  for (int i = 0; i < dofs; ++i)
    for (int j = 0; j < modes; ++j) s.model(i, j) = g(rng);
  s.model_hz.resize(modes);
  for (int j = 0; j < modes; ++j) s.model_hz(j) = 100.0 + 37.0 * j;
  return s;
}

TEST(Pairing, RecoversSwappedOrderAndComplexScaling) {
  const Sets s = MakeModel(12, 5, 3);
  const std::vector<int> order = {3, 0, 4, 1, 2};  // test mode i is model mode order[i]
  Eigen::MatrixXcd test(12, 5);
  Eigen::VectorXd test_hz(5);
  for (int i = 0; i < 5; ++i) {
    test.col(i) = std::complex<double>(0.0, -2.0 - i) * s.model.col(order[i]);
    test_hz(i) = s.model_hz(order[i]) * 1.03;
  }
  const Pairing p = PairModes(MacMatrix(test, s.model), test_hz, s.model_hz);
  ASSERT_EQ(p.pairs.size(), 5u);
  for (const ModePair& pair : p.pairs) {
    EXPECT_EQ(pair.model, order[pair.test]);
    EXPECT_NEAR(pair.mac, 1.0, 1e-12);
  }
  EXPECT_TRUE(p.unpaired_test.empty());
  EXPECT_TRUE(p.unpaired_model.empty());
}

TEST(Pairing, MissingTestModeLeavesModelOnly) {
  const Sets s = MakeModel(12, 5, 5);
  // Test misses model mode 2.
  const std::vector<int> order = {0, 1, 3, 4};
  Eigen::MatrixXcd test(12, 4);
  Eigen::VectorXd test_hz(4);
  for (int i = 0; i < 4; ++i) {
    test.col(i) = s.model.col(order[i]);
    test_hz(i) = s.model_hz(order[i]);
  }
  const Pairing p = PairModes(MacMatrix(test, s.model), test_hz, s.model_hz);
  ASSERT_EQ(p.pairs.size(), 4u);
  for (const ModePair& pair : p.pairs) EXPECT_EQ(pair.model, order[pair.test]);
  EXPECT_EQ(p.unpaired_model, std::vector<int>{2});
  EXPECT_TRUE(p.unpaired_test.empty());
}

TEST(Pairing, ExtraTestModeLeavesTestOnly) {
  const Sets s = MakeModel(12, 4, 9);
  // Test: the 4 model modes plus a spurious one (random shape, MAC well below 0.6 with all).
  const Sets extra = MakeModel(12, 1, 99);
  Eigen::MatrixXcd test(12, 5);
  Eigen::VectorXd test_hz(5);
  for (int i = 0; i < 4; ++i) {
    test.col(i) = s.model.col(i);
    test_hz(i) = s.model_hz(i);
  }
  test.col(4) = extra.model.col(0);
  test_hz(4) = 150.0;
  const Eigen::MatrixXd mac = MacMatrix(test, s.model);
  ASSERT_LT(mac.row(4).maxCoeff(), 0.6) << "the spurious shape must be distinct for this test to mean anything";
  const Pairing p = PairModes(mac, test_hz, s.model_hz);
  ASSERT_EQ(p.pairs.size(), 4u);
  EXPECT_EQ(p.unpaired_test, std::vector<int>{4});
  EXPECT_TRUE(p.unpaired_model.empty());
}

TEST(Pairing, MaximisesTotalMacNotGreedy) {
  // Greedy by row takes (0,0)=0.9 and leaves row 1 with 0.61; the optimum is (0,1)+(1,0).
  Eigen::MatrixXd mac(2, 2);
  mac << 0.90, 0.85,  //
      0.88, 0.10;
  Eigen::VectorXd f(2);
  f << 100.0, 200.0;
  const Pairing p = PairModes(mac, f, f);
  ASSERT_EQ(p.pairs.size(), 2u);
  EXPECT_EQ(p.pairs[0].model, 1);
  EXPECT_EQ(p.pairs[1].model, 0);
}

TEST(Pairing, TieBrokenByFrequency) {
  // Two model modes identical on the shared DOFs (MAC tie): the closer frequency wins.
  Eigen::MatrixXd mac(1, 2);
  mac << 0.95, 0.95;
  Eigen::VectorXd test_hz(1), model_hz(2);
  test_hz << 210.0;
  model_hz << 150.0, 205.0;
  const Pairing p = PairModes(mac, test_hz, model_hz);
  ASSERT_EQ(p.pairs.size(), 1u);
  EXPECT_EQ(p.pairs[0].model, 1);
  EXPECT_EQ(p.unpaired_model, std::vector<int>{0});
}

TEST(Pairing, BelowThresholdIsNeverPaired) {
  Eigen::MatrixXd mac(1, 1);
  mac << 0.59;
  Eigen::VectorXd f(1);
  f << 100.0;
  const Pairing p = PairModes(mac, f, f);
  EXPECT_TRUE(p.pairs.empty());
  EXPECT_EQ(p.unpaired_test.size(), 1u);
  EXPECT_EQ(p.unpaired_model.size(), 1u);
}

}  // namespace
}  // namespace ema::correlation
