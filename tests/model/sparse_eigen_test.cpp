// The sparse path of Solve (model/src/solve.cpp): block Lanczos for FE-sized models, Spectra's
// Lanczos for the few hundred DOFs below that — against spectra known in closed form.
#include "ema/model/solve.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "ema/core/types.hpp"

namespace ema::model {
namespace {

// `chains` uncoupled free chains of n unit masses on springs of kSpring (both ends free): each
// has a rigid-body mode (λ = 0) and λ_k = kSpring 4 sin²(kπ/(2n)), k = 1..n − 1.
Model FreeChains(int n, int chains);

// `chains` uncoupled chains of n unit masses on springs of kSpring, each fixed at one end: the
// stiffness kSpring tridiag(−1, 2, −1) with the free end's diagonal 1, M = I. Eigenvalues
// kSpring 4 sin²((2k − 1)π/(4n + 2)), k = 1..n, each `chains` times (kSpring keeps the lowest,
// 0.2 Hz at n = 1 200, above the rigid-body limit of 1 mHz).
constexpr double kSpring = 1e6;
Model FixedChains(int n, int chains) {
  Model m;
  const int size = n * chains;
  std::vector<Eigen::Triplet<double>> k, mass;
  for (int c = 0; c < chains; ++c)
    for (int i = 0; i < n; ++i) {
      const int r = c * n + i;
      k.emplace_back(r, r, kSpring * (i + 1 < n ? 2.0 : 1.0));
      if (i + 1 < n) k.emplace_back(r + 1, r, -kSpring), k.emplace_back(r, r + 1, -kSpring);
      mass.emplace_back(r, r, 1.0);
    }
  m.fe.stiffness.resize(size, size);
  m.fe.stiffness.setFromTriplets(k.begin(), k.end());
  m.fe.mass.resize(size, size);
  m.fe.mass.setFromTriplets(mass.begin(), mass.end());
  for (int r = 0; r < size; ++r) m.fe.dofs.push_back({r / 3 + 1, r % 3 + 1});
  return m;
}

Model FreeChains(int n, int chains) {
  Model m = FixedChains(n, chains);
  for (int c = 0; c < chains; ++c) m.fe.stiffness.coeffRef(c * n, c * n) = kSpring;  // the fixed end freed
  return m;
}

double ChainEigenvalue(int n, int k) { return kSpring * 4.0 * std::pow(std::sin((2 * k - 1) * M_PI / (4.0 * n + 2.0)), 2); }

std::vector<double> Eigenvalues(const Solution& sol) {
  std::vector<double> out;
  for (const Mode& mode : sol.modes.modes) out.push_back(std::pow(kTwoPi * mode.frequency_hz, 2));
  return out;
}

// 1 200 DOFs, 12 modes: the block Lanczos (the basis, 18 pairs wanted in blocks of 6, is far below
// the model). Every eigenvalue to 1e-10 relative — the solver's tolerance is on the residual,
// which bounds a symmetric eigenvalue's error by its square over the gap — and the shapes
// M-orthonormal.
TEST(SparseEigen, BlockLanczosFindsTheChainsSpectrum) {
  const int n = 1200;
  const Model model = FixedChains(n, 1);
  SolveOptions options;
  options.max_modes = 12;
  const Solution sol = Solve(model, options);
  ASSERT_TRUE(sol.sparse);
  const std::vector<double> lambda = Eigenvalues(sol);
  ASSERT_EQ(lambda.size(), 12u);
  for (int k = 1; k <= 12; ++k)
    EXPECT_NEAR(lambda[k - 1], ChainEigenvalue(n, k), 1e-10 * ChainEigenvalue(n, k)) << "mode " << k;
  const Eigen::MatrixXd gram = sol.full_shapes.transpose() * sol.full_shapes;  // M = I
  EXPECT_LT((gram - Eigen::MatrixXd::Identity(12, 12)).cwiseAbs().maxCoeff(), 1e-10);
  // A block of columns per solve: fewer solves than single-vector Lanczos's one pass (ncv = 37).
  EXPECT_GT(sol.shift_invert_solves, 0);
}

// Two identical chains: every eigenvalue twice. A block of several columns spans both copies of
// a double eigenvalue from its first step; both must be found, in pairs.
TEST(SparseEigen, BlockLanczosFindsEveryCopyOfARepeatedEigenvalue) {
  const int n = 700;
  const Model model = FixedChains(n, 2);
  SolveOptions options;
  options.max_modes = 12;
  const Solution sol = Solve(model, options);
  ASSERT_TRUE(sol.sparse);
  const std::vector<double> lambda = Eigenvalues(sol);
  ASSERT_EQ(lambda.size(), 12u);
  for (int j = 0; j < 12; ++j) {
    const double expected = ChainEigenvalue(n, j / 2 + 1);
    EXPECT_NEAR(lambda[j], expected, 1e-10 * expected) << "mode " << j + 1;
  }
}

// Six free chains: six rigid-body modes at once (a free article's count) and every elastic
// eigenvalue six times, found with blocks of 4 columns (12 pairs wanted): a Krylov block holds at
// most 4 copies of an eigenvalue in exact arithmetic, the others come in through the restarts —
// all six of each must be there, in order.
TEST(SparseEigen, BlockLanczosFindsSixRigidBodyModesAndSixfoldEigenvalues) {
  const int n = 250;
  const Model model = FreeChains(n, 6);
  SolveOptions options;
  options.max_modes = 6;  // 6 + room for 6 rigid-body modes: 12 pairs wanted, blocks of 4
  const Solution sol = Solve(model, options);
  ASSERT_TRUE(sol.sparse);
  EXPECT_EQ(sol.rigid_body_frequencies_hz.size(), 6u);
  const std::vector<double> lambda = Eigenvalues(sol);
  ASSERT_EQ(lambda.size(), 6u);
  for (int j = 0; j < 6; ++j) {
    const double expected = kSpring * 4.0 * std::pow(std::sin((j / 6 + 1) * M_PI / (2.0 * n)), 2);
    EXPECT_NEAR(lambda[j], expected, 1e-9 * expected) << "mode " << j + 1;
  }
}

// 150 DOFs: below four bases of the block Lanczos, Spectra's single-vector Lanczos serves — the same
// spectrum to the same tolerance.
TEST(SparseEigen, SmallSparseModelsKeepSpectrasLanczos) {
  const int n = 150;
  const Model model = FixedChains(n, 1);
  SolveOptions options;
  options.max_modes = 10;
  options.sparse_threshold = 100;
  const Solution sol = Solve(model, options);
  ASSERT_TRUE(sol.sparse);
  const std::vector<double> lambda = Eigenvalues(sol);
  ASSERT_EQ(lambda.size(), 10u);
  for (int k = 1; k <= 10; ++k)
    EXPECT_NEAR(lambda[k - 1], ChainEigenvalue(n, k), 1e-10 * ChainEigenvalue(n, k)) << "mode " << k;
}

}  // namespace
}  // namespace ema::model
