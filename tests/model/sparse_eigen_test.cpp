// The sparse path of Solve (model/src/solve.cpp): block Lanczos for FE-sized models, Spectra's
// Lanczos for the few hundred DOFs below that — against spectra known in closed form.
#include "ema/model/solve.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "ema/core/types.hpp"

namespace ema::model {
namespace {

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

// `chains` uncoupled free chains of n unit masses on springs of kSpring (both ends free): each
// has a rigid-body mode (λ = 0) and λ_k = kSpring 4 sin²(kπ/(2n)), k = 1..n − 1.
Model FreeChains(int n, int chains) {
  Model m = FixedChains(n, chains);
  for (int c = 0; c < chains; ++c) m.fe.stiffness.coeffRef(c * n, c * n) = kSpring;  // the fixed end freed
  return m;
}

double ChainEigenvalue(int n, int k) { return kSpring * 4.0 * std::pow(std::sin((2 * k - 1) * M_PI / (4.0 * n + 2.0)), 2); }

// The model's sparse solution with `max_modes` modes, whose eigenvalues ω² must be `expected`, each
// to `relative` of itself.
Solution ExpectSpectrum(const Model& model, SolveOptions options, int max_modes, const std::vector<double>& expected,
                        double relative) {
  options.max_modes = max_modes;
  const Solution sol = Solve(model, options);
  EXPECT_TRUE(sol.sparse);
  EXPECT_EQ(sol.modes.modes.size(), expected.size());
  for (size_t j = 0; j < std::min(expected.size(), sol.modes.modes.size()); ++j)
    EXPECT_NEAR(std::pow(kTwoPi * sol.modes.modes[j].frequency_hz, 2), expected[j], relative * expected[j])
        << "mode " << j + 1;
  return sol;
}

// 1 200 DOFs, 12 modes: the block Lanczos (the basis, 18 pairs wanted in blocks of 6, is far below
// the model). Every eigenvalue to 1e-10 relative — the solver's tolerance is on the residual,
// which bounds a symmetric eigenvalue's error by its square over the gap — and the shapes
// M-orthonormal.
TEST(SparseEigen, BlockLanczosFindsTheChainsSpectrum) {
  const int n = 1200;
  std::vector<double> expected;
  for (int k = 1; k <= 12; ++k) expected.push_back(ChainEigenvalue(n, k));
  const Solution sol = ExpectSpectrum(FixedChains(n, 1), {}, 12, expected, 1e-10);
  ASSERT_EQ(sol.full_shapes.cols(), 12);
  const Eigen::MatrixXd gram = sol.full_shapes.transpose() * sol.full_shapes;  // M = I
  EXPECT_LT((gram - Eigen::MatrixXd::Identity(12, 12)).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_GT(sol.shift_invert_solves, 0);  // the columns solved are counted
}

// Two identical chains: every eigenvalue twice. A block of several columns spans both copies of
// a double eigenvalue from its first step; both must be found, in pairs.
TEST(SparseEigen, BlockLanczosFindsEveryCopyOfARepeatedEigenvalue) {
  const int n = 700;
  std::vector<double> expected;
  for (int j = 0; j < 12; ++j) expected.push_back(ChainEigenvalue(n, j / 2 + 1));
  ExpectSpectrum(FixedChains(n, 2), {}, 12, expected, 1e-10);
}

// Six free chains: six rigid-body modes at once (a free article's count) and every elastic
// eigenvalue six times, found with blocks of 4 columns (12 pairs wanted): a Krylov block holds at
// most 4 copies of an eigenvalue in exact arithmetic, the others come in through the restarts —
// all six of each must be there, in order.
TEST(SparseEigen, BlockLanczosFindsSixRigidBodyModesAndSixfoldEigenvalues) {
  const int n = 250;
  // 6 modes + room for 6 rigid-body modes: 12 pairs wanted, blocks of 4.
  const std::vector<double> expected(6, kSpring * 4.0 * std::pow(std::sin(M_PI / (2.0 * n)), 2));
  const Solution sol = ExpectSpectrum(FreeChains(n, 6), {}, 6, expected, 1e-9);
  EXPECT_EQ(sol.rigid_body_frequencies_hz.size(), 6u);
}

// The supernodal factorisation keeps the ordering of each sparsity pattern it met
// (model/src/sparse_factor.cpp): the same chain solved again with every spring twice as stiff —
// the same pattern, other values — is analysed with the first one's ordering and must give its own
// spectrum, twice the first, to the same tolerance; and the first model solved again, the same
// modes to the last bit (the same ordering, the same factor).
TEST(SparseEigen, ASecondMatrixOfTheSamePatternReusesTheOrderingExactly) {
  const int n = 1200;
  std::vector<double> expected, doubled;
  for (int k = 1; k <= 8; ++k) expected.push_back(ChainEigenvalue(n, k)), doubled.push_back(2.0 * ChainEigenvalue(n, k));
  const Model first = FixedChains(n, 1);
  Model stiffer = first;
  stiffer.fe.stiffness *= 2.0;
  const Solution a = ExpectSpectrum(first, {}, 8, expected, 1e-10);
  ExpectSpectrum(stiffer, {}, 8, doubled, 1e-10);
  const Solution again = ExpectSpectrum(first, {}, 8, expected, 1e-10);
  ASSERT_EQ(a.full_shapes.cols(), again.full_shapes.cols());
  EXPECT_EQ((a.full_shapes - again.full_shapes).cwiseAbs().maxCoeff(), 0.0);
}

// 150 DOFs: below four bases of the block Lanczos, Spectra's single-vector Lanczos serves — the same
// spectrum to the same tolerance.
TEST(SparseEigen, SmallSparseModelsKeepSpectrasLanczos) {
  const int n = 150;
  std::vector<double> expected;
  for (int k = 1; k <= 10; ++k) expected.push_back(ChainEigenvalue(n, k));
  SolveOptions options;
  options.sparse_threshold = 100;
  ExpectSpectrum(FixedChains(n, 1), options, 10, expected, 1e-10);
}

}  // namespace
}  // namespace ema::model
