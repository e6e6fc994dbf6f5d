// CheckPositiveDefinite (definiteness.hpp): CHOLMOD's LLᵀ stops at the first pivot ≤ 0 and says
// where (quick return), the LDLᵀ counts them.
#include "ema/model/definiteness.hpp"

#include <Eigen/SparseCholesky>
#include <stdexcept>
#include <string>
#include <vector>

#ifdef EMA_HAVE_CHOLMOD
#include <cholmod.h>
#endif

namespace ema::model {
namespace {

#ifdef EMA_HAVE_CHOLMOD
// The row (of `a`, lower triangle) where CHOLMOD's LLᵀ of `a` breaks, or -1 when `a` is positive
// definite.
Eigen::Index CholmodFirstFailure(Eigen::SparseMatrix<double> a) {
  a.makeCompressed();
  cholmod_common c;
  cholmod_start(&c);
  c.print = 0;
  c.error_handler = nullptr;
  c.quick_return_if_not_posdef = 1;
  c.supernodal = CHOLMOD_SUPERNODAL;  // always LLᵀ (the simplicial LDLᵀ takes negative pivots)
  cholmod_sparse view{};
  view.nrow = view.ncol = static_cast<std::size_t>(a.rows());
  view.nzmax = static_cast<std::size_t>(a.nonZeros());
  view.p = a.outerIndexPtr();
  view.i = a.innerIndexPtr();
  view.x = a.valuePtr();
  view.stype = -1;  // the lower triangle
  view.itype = CHOLMOD_INT;
  view.xtype = CHOLMOD_REAL;
  view.dtype = CHOLMOD_DOUBLE;
  view.sorted = 1;
  view.packed = 1;
  cholmod_factor* factor = cholmod_analyze(&view, &c);
  Eigen::Index bad = -1;
  int status = c.status;
  if (factor) {
    cholmod_factorize(&view, factor, &c);
    status = c.status;
    if (status == CHOLMOD_NOT_POSDEF && factor->minor < factor->n)
      bad = static_cast<const int*>(factor->Perm)[factor->minor];
    cholmod_free_factor(&factor, &c);
  }
  cholmod_finish(&c);
  if (status != CHOLMOD_OK && status != CHOLMOD_NOT_POSDEF)
    throw std::runtime_error("the sparse Cholesky factorisation (CHOLMOD) failed, status " + std::to_string(status) +
                             (status == CHOLMOD_OUT_OF_MEMORY ? " (out of memory)" : ""));
  return bad;
}
#endif

}  // namespace

DefinitenessCheck CheckPositiveDefinite(const Eigen::SparseMatrix<double>& a, Eigen::Index count_limit) {
  DefinitenessCheck out;
  const Eigen::Index m = a.rows();
#ifdef EMA_HAVE_CHOLMOD
  out.first_failure = CholmodFirstFailure(a);
  if (out.first_failure < 0) return out;
  if (m > count_limit) {
    out.non_positive_pivots = -1;
    return out;
  }
#endif
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> ldlt(a);
  if (ldlt.info() == Eigen::Success) {
    // D in elimination order; the first non-positive pivot is where an LLᵀ would have broken.
    const Eigen::VectorXd d = ldlt.vectorD();
    const auto& perm = ldlt.permutationP().indices();  // original row → elimination position
    std::vector<Eigen::Index> original(static_cast<std::size_t>(m));
    for (Eigen::Index i = 0; i < m; ++i) original[static_cast<std::size_t>(perm[i])] = i;
    Eigen::Index first = -1;
    for (Eigen::Index k = 0; k < m; ++k)
      if (!(d[k] > 0.0)) {
        if (first < 0) first = original[static_cast<std::size_t>(k)];
        ++out.non_positive_pivots;
      }
    if (out.first_failure < 0) out.first_failure = first;
  } else if (out.first_failure < 0) {
    out.first_failure = 0;  // an exactly zero pivot: not positive definite, row unknown
  }
  return out;
}

}  // namespace ema::model
