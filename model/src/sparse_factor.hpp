// The sparse Cholesky factorisation of the model's solves: K − σM with σ below the lowest
// eigenvalue (symmetric positive definite), for the shift-invert eigen-solutions (solve.cpp) and
// the reduced models of the diagnosis (reduced.cpp). CHOLMOD's supernodal LLᵀ (SuiteSparse, the
// factorisation FE codes use: dense BLAS kernels on the supernodes of 3-D meshes) when the build
// found it (EMA_HAVE_CHOLMOD), else Eigen's SimplicialLDLT; a matrix CHOLMOD finds not positive
// definite (round-off on a nearly singular model) is factorised by the LDLᵀ instead.
#pragma once

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <memory>

#include "ema/model/solve.hpp"

#ifdef EMA_HAVE_CHOLMOD
#include <Eigen/CholmodSupport>
#endif

namespace ema::model::detail {

#ifdef EMA_HAVE_CHOLMOD
/// CHOLMOD's supernodal LLᵀ, analysed with the fill-reducing ordering of an earlier matrix of the
/// same sparsity pattern where there was one: METIS's nested dissection is seconds at 220 941 DOFs
/// (CHOLMOD tries it and AMD and keeps the better), and the diagnosis factorises K − σM of one
/// pattern at every centre it checks — part factors, masses at nodes and the shift change values,
/// not the pattern. The ordering is kept per pattern (OrderingCache in sparse_factor.cpp); any
/// ordering gives the exact factorisation, the same one gives the same factor to the last bit.
class SupernodalLlt : public Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> {
 public:
  /// Analyses and factorises `a` (symmetric, lower triangle read).
  void Factorise(const Eigen::SparseMatrix<double>& a);
};
#endif

class SparseFactor {
 public:
  /// Factorises `a` (symmetric, full storage); false when neither factorisation succeeds.
  bool Compute(const Eigen::SparseMatrix<double>& a) {
#ifdef EMA_HAVE_CHOLMOD
    cholmod_ = std::make_unique<SupernodalLlt>();
    cholmod_->Factorise(a);
    if (cholmod_->info() == Eigen::Success) return ldlt_.reset(), true;
    cholmod_.reset();
#endif
    ldlt_ = std::make_unique<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>>(a);
    return ldlt_->info() == Eigen::Success;
  }

  /// A⁻¹ b for a vector or a dense block of columns.
  template <class Rhs>
  Eigen::Matrix<double, Eigen::Dynamic, Rhs::ColsAtCompileTime> Solve(const Eigen::MatrixBase<Rhs>& b) const {
#ifdef EMA_HAVE_CHOLMOD
    if (cholmod_) return cholmod_->solve(b);
#endif
    return ldlt_->solve(b);
  }

  /// Which factorisation holds the matrix (for benchmarks and tests).
  bool Supernodal() const {
#ifdef EMA_HAVE_CHOLMOD
    return cholmod_ != nullptr;
#else
    return false;
#endif
  }

 private:
#ifdef EMA_HAVE_CHOLMOD
  std::unique_ptr<SupernodalLlt> cholmod_;
#endif
  std::unique_ptr<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>> ldlt_;
};

/// model::Solve, keeping the sparse path's factorisation of K − σM (σ: solve.cpp's shift) in
/// *kept_factor when it is not null — the reduced models of the diagnosis solve with the same
/// matrix, and at 220 941 DOFs a factorisation is seconds and gigabytes. Null after the dense path.
/// The assembled system (Assemble(input, options)) goes to *kept_system when it is not null.
Solution SolveKeepingFactor(const Model& input, const SolveOptions& options, std::unique_ptr<SparseFactor>* kept_factor,
                            System* kept_system = nullptr);

}  // namespace ema::model::detail
