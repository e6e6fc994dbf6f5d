// CheckPositiveDefinite (model/definiteness.hpp): matrices whose inertia is known by hand.
#include "ema/model/definiteness.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace ema::model {
namespace {

Eigen::SparseMatrix<double> Tridiagonal(int n, double diagonal, double off) {
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, diagonal);
    if (i + 1 < n) t.emplace_back(i + 1, i, off), t.emplace_back(i, i + 1, off);
  }
  Eigen::SparseMatrix<double> a(n, n);
  a.setFromTriplets(t.begin(), t.end());
  return a;
}

// The stiffness of a chain of unit springs fixed at one end: tridiag(-1, 2, -1) with the free end's
// diagonal 1 — positive definite (eigenvalues 4 sin²((2k − 1)π / (4n + 2)) > 0).
TEST(CheckPositiveDefinite, AFixedChainIsPositiveDefinite) {
  Eigen::SparseMatrix<double> k = Tridiagonal(200, 2.0, -1.0);
  k.coeffRef(199, 199) = 1.0;
  const DefinitenessCheck check = CheckPositiveDefinite(k);
  EXPECT_TRUE(check.PositiveDefinite());
  EXPECT_EQ(check.first_failure, -1);
}

// The free chain (both end diagonals 1) is singular: one zero eigenvalue (the rigid translation),
// found by the LLᵀ somewhere and counted once by the LDLᵀ (its last pivot rounds to about 1e-15,
// either sign: counted as ≤ 0 only when it is).
TEST(CheckPositiveDefinite, AFreeChainIsNotAndAShiftMakesIt) {
  Eigen::SparseMatrix<double> k = Tridiagonal(50, 2.0, -1.0);
  k.coeffRef(0, 0) = 1.0;
  k.coeffRef(49, 49) = 1.0;
  // −τ on the diagonal makes the zero eigenvalue −τ: exactly one negative eigenvalue.
  Eigen::SparseMatrix<double> shifted = k;
  for (int i = 0; i < 50; ++i) shifted.coeffRef(i, i) -= 1e-6;
  const DefinitenessCheck bad = CheckPositiveDefinite(shifted);
  EXPECT_FALSE(bad.PositiveDefinite());
  EXPECT_GE(bad.first_failure, 0);
  EXPECT_LT(bad.first_failure, 50);
  EXPECT_EQ(bad.non_positive_pivots, 1);
  // +τ: every eigenvalue ≥ τ.
  for (int i = 0; i < 50; ++i) shifted.coeffRef(i, i) += 2e-6;
  EXPECT_TRUE(CheckPositiveDefinite(shifted).PositiveDefinite());
}

// diag(1, 2, −3, 4, −5): two negative eigenvalues; the LLᵀ breaks at row 2 or 4 (whichever its
// ordering eliminates first), the LDLᵀ counts both. Above count_limit rows they are not counted.
TEST(CheckPositiveDefinite, NamesABrokenRowAndCountsTheNegativeEigenvalues) {
  Eigen::SparseMatrix<double> d(5, 5);
  const double values[] = {1.0, 2.0, -3.0, 4.0, -5.0};
  for (int i = 0; i < 5; ++i) d.insert(i, i) = values[i];
  const DefinitenessCheck check = CheckPositiveDefinite(d);
  EXPECT_TRUE(check.first_failure == 2 || check.first_failure == 4) << check.first_failure;
  EXPECT_EQ(check.non_positive_pivots, 2);
  const DefinitenessCheck quick = CheckPositiveDefinite(d, 4);
  EXPECT_TRUE(quick.first_failure == 2 || quick.first_failure == 4) << quick.first_failure;
  // -1 with CHOLMOD (not counted above the limit); without it the LDLᵀ is the check and counts.
  EXPECT_TRUE(quick.non_positive_pivots == -1 || quick.non_positive_pivots == 2) << quick.non_positive_pivots;
}

// Only the lower triangle is read: an upper triangle that would make it indefinite is ignored.
TEST(CheckPositiveDefinite, ReadsTheLowerTriangle) {
  Eigen::SparseMatrix<double> a(2, 2);
  a.insert(0, 0) = 1.0;
  a.insert(1, 1) = 1.0;
  a.insert(1, 0) = 0.5;
  a.insert(0, 1) = 10.0;  // not read
  EXPECT_TRUE(CheckPositiveDefinite(a).PositiveDefinite());
}

}  // namespace
}  // namespace ema::model
