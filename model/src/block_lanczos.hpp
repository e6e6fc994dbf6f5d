// The lowest eigenpairs of K φ = λ M φ for FE-sized models: block Lanczos in shift-invert mode,
// (K − σM)⁻¹M, with full M-reorthogonalisation and thick restarts (Grimes, Lewis & Simon, SIAM J.
// Matrix Anal. Appl. 15 (1994), the shifted block Lanczos of MSC Nastran; Wu & Simon 2000 for the
// thick restart). Why not Spectra's single-vector Lanczos: at 220 941 DOFs it made 131 solves with
// the factor, one right-hand side each, every one reading the 1.5 GB supernodal factor twice
// through matrix-vector BLAS (memory-bound), and re-orthogonalised by matrix-vector products: 77 s
// of a 118-s solve. A block of b columns reads the factor once per b solves (matrix-matrix BLAS in
// CHOLMOD) and is orthogonalised by matrix products: 27 blocks of 12, 35 s (docs/model.md).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <string>

#include "sparse_factor.hpp"

namespace ema::model::detail {

struct BlockLanczosOptions {
  int wanted = 0;            ///< eigenpairs returned: the lowest, ≥ 1
  int block_size = 8;        ///< columns per block (solves with the factor at once)
  /// Largest basis before a thick restart, in columns; 0 = max(3 × wanted, wanted + 4 blocks).
  int max_basis = 0;
  /// A Ritz pair (θ, x) of (K − σM)⁻¹M has converged when ‖(K − σM)⁻¹Mx − θx‖_M ≤ tolerance × θ
  /// (Spectra's test, the same 1e-10: eigenvalues to ~1e-16, shapes to ~1e-10 of the gap).
  double tolerance = 1e-10;
  int max_block_solves = 1000;
  /// The iteration ends when the lowest pairs have converged up to this many elastic ones (λ above
  /// `rigid_limit`), the rigid-body pairs below them counted on top; 0: all `wanted` pairs. The
  /// caller asks for room beyond what it keeps (six pairs for the rigid-body modes a model may
  /// have): a clamped model has none, and converging six pairs it drops cost a fifth of a
  /// 220 941-DOF solve's Lanczos (22.9 → 18.3 s). The pairs beyond are returned unconverged.
  int converged_elastic = 0;
  double rigid_limit = 0.0;  ///< λ at or below it is a rigid-body pair (with converged_elastic)
  unsigned seed = 20261129;  ///< the random start block: fixed, so every solve is repeatable

  bool IsValid(std::string* why) const {
    if (wanted < 1) return *why = "wanted must be >= 1", false;
    if (block_size < 1) return *why = "block_size must be >= 1", false;
    if (max_basis < 0) return *why = "max_basis must be >= 0", false;
    if (!(tolerance > 0.0)) return *why = "tolerance must be > 0", false;
    if (max_block_solves < 1) return *why = "max_block_solves must be >= 1", false;
    if (converged_elastic < 0) return *why = "converged_elastic must be >= 0", false;
    return true;
  }
};

/// The columns the solver holds: the largest basis (`max_basis`, or its default) and the next block.
/// It needs more DOFs than this; solve.cpp uses it only where the model has four times as many.
int BasisColumns(const BlockLanczosOptions& options);

struct BlockLanczosSummary {
  Eigen::VectorXd eigenvalues;  ///< λ, ascending (wanted of them)
  Eigen::MatrixXd vectors;      ///< M-orthonormal eigenvectors, one column per λ
  bool converged = false;
  int block_solves = 0;         ///< solves with the factor, a block of columns each
  int columns_solved = 0;       ///< right-hand sides in total
  int restarts = 0;
};

/// `factor` holds K − σM (positive definite: σ below the lowest eigenvalue); `mass` is M (n × n,
/// positive semi-definite, full storage). Needs n > wanted.
BlockLanczosSummary LowestEigenpairs(const SparseFactor& factor, double sigma, const Eigen::SparseMatrix<double>& mass,
                                     const BlockLanczosOptions& options);

}  // namespace ema::model::detail
