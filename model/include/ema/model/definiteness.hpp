// Is a sparse symmetric matrix positive definite, and if not, where does that show? The check a
// stiffness matrix from another program needs before it is used (an FE part, `ema fe-import`):
// the row at which its Cholesky factorisation breaks names the DOF to look at.
#pragma once

#include <Eigen/SparseCore>

namespace ema::model {

struct DefinitenessCheck {
  /// Row of the matrix where its LLᵀ factorisation met a pivot ≤ 0 (in the factorisation's
  /// elimination order, the first one); -1 when the matrix is positive definite.
  Eigen::Index first_failure = -1;
  /// Pivots ≤ 0 of its LDLᵀ factorisation (its eigenvalues ≤ 0, by Sylvester's law of inertia);
  /// -1 when not counted (a matrix above `count_limit` rows, where the LDLᵀ is slow).
  Eigen::Index non_positive_pivots = 0;
  bool PositiveDefinite() const { return first_failure < 0; }
};

/// Checks `a` (square; its lower triangle is read) with CHOLMOD's supernodal LLᵀ when the build
/// has CHOLMOD (the first failing row), and counts the pivots ≤ 0 of Eigen's SimplicialLDLT when
/// it is not positive definite and has at most `count_limit` rows (or without CHOLMOD). Throws
/// std::runtime_error when CHOLMOD itself fails (out of memory).
DefinitenessCheck CheckPositiveDefinite(const Eigen::SparseMatrix<double>& a, Eigen::Index count_limit = 5000);

}  // namespace ema::model
