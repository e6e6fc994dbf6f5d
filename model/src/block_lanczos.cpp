// Shifted block Lanczos with full M-reorthogonalisation and thick restarts (block_lanczos.hpp).
#include "block_lanczos.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>

#include "ema/core/error.hpp"

namespace ema::model::detail {
namespace {

using Eigen::MatrixXd;

#ifdef EMA_HAVE_BLAS
extern "C" void dgemm_(const char* transa, const char* transb, const int* m, const int* n, const int* k,
                       const double* alpha, const double* a, const int* lda, const double* b, const int* ldb,
                       const double* beta, double* c, const int* ldc);
#endif

// c = alpha op(a) b + beta c, op(a) = aᵀ when `transpose`. The basis products of a 220 941-DOF
// model are gigaflops per block step: the machine's BLAS (runtime-dispatched vector kernels and
// threads in OpenBLAS) where the build found one, Eigen's own (the build's instruction set) else.
void Product(bool transpose, const Eigen::Ref<const MatrixXd>& a, const Eigen::Ref<const MatrixXd>& b, double alpha,
             double beta, Eigen::Ref<MatrixXd> c) {
  if (c.size() == 0) return;
#ifdef EMA_HAVE_BLAS
  const int m = static_cast<int>(c.rows()), n = static_cast<int>(c.cols());
  const int k = static_cast<int>(transpose ? a.rows() : a.cols());
  const int lda = static_cast<int>(std::max<Eigen::Index>(1, a.outerStride()));
  const int ldb = static_cast<int>(std::max<Eigen::Index>(1, b.outerStride()));
  const int ldc = static_cast<int>(std::max<Eigen::Index>(1, c.outerStride()));
  if (k == 0) {
    c *= beta;
    return;
  }
  const char ta = transpose ? 'T' : 'N', tb = 'N';
  dgemm_(&ta, &tb, &m, &n, &k, &alpha, a.data(), &lda, b.data(), &ldb, &beta, c.data(), &ldc);
#else
  if (transpose) c = alpha * (a.transpose() * b) + beta * c;
  else c = alpha * (a * b) + beta * c;
#endif
}

// n × columns of independent standard normal numbers: the start block, and new directions where
// the Krylov space has none left.
MatrixXd RandomBlock(Eigen::Index n, Eigen::Index columns, std::mt19937* rng) {
  std::normal_distribution<double> normal;
  MatrixXd out(n, columns);
  for (Eigen::Index j = 0; j < columns; ++j)
    for (Eigen::Index i = 0; i < n; ++i) out(i, j) = normal(*rng);
  return out;
}

// The largest M-norm among the columns of x (mx = M x).
double LargestMassNorm(const MatrixXd& x, const MatrixXd& mx) {
  return std::sqrt(x.cwiseProduct(mx).colwise().sum().maxCoeff());
}

// A block of vectors with M times it, kept alongside: every update of one is made to the other,
// so M-inner products with the basis are products with MV, not sparse products with M.
struct Block {
  MatrixXd x, mx;
};

// Removes from w.x its components along the M-orthonormal columns of `basis` (`mass_basis` = M
// times it) and returns the coefficients basisᵀ M w: first along the `recent` last columns (where
// a Lanczos step's new block has nearly all of them), then along all — once, and a second time
// only where a column lost more than half its norm to that pass (Daniel, Gragg, Kaufman & Stewart
// 1976: one pass of classical Gram–Schmidt keeps orthogonality unless the vector shrinks). w.mx
// is not used and left stale: the caller multiplies by M once at the end.
MatrixXd Reorthogonalise(const Eigen::Ref<const MatrixXd>& basis, const Eigen::Ref<const MatrixXd>& mass_basis,
                         Eigen::Index recent, MatrixXd* w) {
  const Eigen::Index all = basis.cols(), b = w->cols();
  MatrixXd total = MatrixXd::Zero(all, b);
  if (all == 0) return total;
  recent = std::min(recent, all);
  {
    MatrixXd c(recent, b);
    Product(true, mass_basis.rightCols(recent), *w, 1.0, 0.0, c);
    Product(false, basis.rightCols(recent), c, -1.0, 1.0, *w);
    total.bottomRows(recent) = c;
  }
  const Eigen::VectorXd norm_before = w->colwise().norm();
  MatrixXd c(all, b);
  Product(true, mass_basis, *w, 1.0, 0.0, c);
  Product(false, basis, c, -1.0, 1.0, *w);
  total += c;
  const Eigen::VectorXd norm_after = w->colwise().norm();
  if ((norm_after.array() < 0.5 * norm_before.array()).any()) {
    Product(true, mass_basis, *w, 1.0, 0.0, c);
    Product(false, basis, c, -1.0, 1.0, *w);
    total += c;
  }
  return total;
}

// Makes the columns of `w` (M-orthogonal to `basis` already) M-orthonormal among themselves and
// returns R with w_before = w_after R. Directions of w below 1e-10 of `scale` (the largest M-norm
// of its columns before they were orthogonalised: the block Krylov space has become invariant
// there) are replaced by random ones orthogonal to everything, with zero rows in R — the Krylov
// space goes on in new directions instead of breaking down.
MatrixXd OrthonormaliseBlock(const Eigen::SparseMatrix<double>& mass, const Eigen::Ref<const MatrixXd>& basis,
                             const Eigen::Ref<const MatrixXd>& mass_basis, double scale, Block* w,
                             std::mt19937* rng) {
  const Eigen::Index n = w->x.rows(), b = w->x.cols();
  MatrixXd g = w->x.transpose() * w->mx;
  g = 0.5 * (g + g.transpose()).eval();
  Eigen::SelfAdjointEigenSolver<MatrixXd> es(g);
  const Eigen::VectorXd d = es.eigenvalues();
  const double floor = 1e-20 * scale * scale;
  std::vector<Eigen::Index> kept;
  for (Eigen::Index i = b - 1; i >= 0; --i)
    if (d(i) > floor) kept.push_back(i);
  const auto rank = static_cast<Eigen::Index>(kept.size());
  MatrixXd q(b, rank), r = MatrixXd::Zero(b, b);
  for (Eigen::Index k = 0; k < rank; ++k) {
    const Eigen::Index i = kept[static_cast<size_t>(k)];
    const double s = std::sqrt(d(i));
    q.col(k) = es.eigenvectors().col(i) / s;
    r.row(k) = s * es.eigenvectors().col(i).transpose();
  }
  Block next{MatrixXd(n, b), MatrixXd(n, b)};
  next.x.leftCols(rank) = w->x * q;
  next.mx.leftCols(rank) = w->mx * q;
  if (rank < b) {
    Block fill{RandomBlock(n, b - rank, rng), MatrixXd()};
    for (int pass = 0; pass < 2; ++pass) {
      Reorthogonalise(basis, mass_basis, 0, &fill.x);
      if (rank > 0) Reorthogonalise(next.x.leftCols(rank), next.mx.leftCols(rank), 0, &fill.x);
    }
    fill.mx = mass * fill.x;
    MatrixXd gf = fill.x.transpose() * fill.mx;
    Eigen::LLT<MatrixXd> llt(0.5 * (gf + gf.transpose()));
    if (llt.info() != Eigen::Success) throw ConvergenceError("", "block Lanczos: no direction left to extend the basis");
    next.x.rightCols(b - rank) = llt.matrixU().solve<Eigen::OnTheRight>(fill.x);
    next.mx.rightCols(b - rank) = llt.matrixU().solve<Eigen::OnTheRight>(fill.mx);
  }
  // Once more as a Cholesky QR: the eigen-decomposition leaves the columns orthonormal only to
  // about ε × the condition number of g.
  MatrixXd g2 = next.x.transpose() * next.mx;
  Eigen::LLT<MatrixXd> llt(0.5 * (g2 + g2.transpose()));
  if (llt.info() != Eigen::Success) throw ConvergenceError("", "block Lanczos: the new block lost its rank");
  const MatrixXd upper = llt.matrixU();
  w->x = upper.triangularView<Eigen::Upper>().solve<Eigen::OnTheRight>(next.x);
  w->mx = upper.triangularView<Eigen::Upper>().solve<Eigen::OnTheRight>(next.mx);
  return upper.triangularView<Eigen::Upper>() * r;
}

}  // namespace

int BasisColumns(const BlockLanczosOptions& options) {
  const int nev = options.wanted, b = options.block_size;
  const int max_basis = options.max_basis > 0 ? std::max(options.max_basis, nev + 3 * b) : std::max(3 * nev, nev + 4 * b);
  return max_basis + b;
}

BlockLanczosSummary LowestEigenpairs(const SparseFactor& factor, double sigma, const Eigen::SparseMatrix<double>& mass,
                                     const BlockLanczosOptions& options) {
  if (std::string why; !options.IsValid(&why)) throw UsageError("block Lanczos options: " + why);
  const Eigen::Index n = mass.rows();
  const int nev = options.wanted, b = options.block_size;
  const int max_basis = BasisColumns(options) - b;
  if (n < max_basis + b) throw UsageError("block Lanczos needs more DOFs than its basis (" + std::to_string(max_basis + b) + ")");
  const int kept_on_restart = nev + b;  // ≤ max_basis − 2b: a restart always frees a block or more

  BlockLanczosSummary out;
  std::mt19937 rng(options.seed);
  // The basis V and MV, then the next block after their `used` columns.
  MatrixXd v(n, max_basis + b), mv(n, max_basis + b);
  MatrixXd t = MatrixXd::Zero(max_basis + b, max_basis + b);  // Vᵀ M (K − σM)⁻¹ M V
  {
    Block start{RandomBlock(n, b, &rng), MatrixXd()};
    start.mx = mass * start.x;
    OrthonormaliseBlock(mass, v.leftCols(0), mv.leftCols(0), LargestMassNorm(start.x, start.mx), &start, &rng);
    v.leftCols(b) = start.x;
    mv.leftCols(b) = start.mx;
  }
  int used = 0;
  Eigen::VectorXd theta;
  MatrixXd y;
  while (true) {
    // The next block: (K − σM)⁻¹ M V_j, orthogonalised against the basis and itself.
    Block w{factor.Solve(mv.middleCols(used, b)), MatrixXd()};
    ++out.block_solves;
    out.columns_solved += b;
    const int all = used + b;
    const MatrixXd c = Reorthogonalise(v.leftCols(all), mv.leftCols(all), 2 * b, &w.x);
    w.mx = mass * w.x;
    // The M-norm of each column before it was orthogonalised: what is left, and the coefficients.
    const double scale =
        std::sqrt((w.x.cwiseProduct(w.mx).colwise().sum() + c.colwise().squaredNorm()).maxCoeff());
    t.block(0, used, all, b) = c;
    t.block(used, 0, b, all) = c.transpose();
    t.block(used, used, b, b) = 0.5 * (c.bottomRows(b) + c.bottomRows(b).transpose());
    const MatrixXd coupling = OrthonormaliseBlock(mass, v.leftCols(all), mv.leftCols(all), scale, &w, &rng);
    t.block(all, used, b, b) = coupling;
    t.block(used, all, b, b) = coupling.transpose();
    v.middleCols(all, b) = w.x;
    mv.middleCols(all, b) = w.mx;
    used = all;
    if (used < nev) continue;

    // Rayleigh–Ritz: the Ritz pairs of the basis; the residual of each is the next block times
    // the coupling times the Ritz vector's last rows (only the newest block couples outwards).
    Eigen::SelfAdjointEigenSolver<MatrixXd> es(t.topLeftCorner(used, used));
    theta = es.eigenvalues();  // ascending: the largest θ are the lowest λ
    y = es.eigenvectors();
    const MatrixXd last = t.block(used, used - b, b, b) * y.bottomRows(b);
    // From the lowest λ up: every pair until enough elastic ones (or all `wanted`) have converged.
    bool converged = true;
    const int needed = options.converged_elastic > 0 ? std::min(options.converged_elastic, nev) : nev;
    for (int i = used - 1, counted = 0; i >= used - nev && converged && counted < needed; --i) {
      converged = last.col(i).norm() <= options.tolerance * std::abs(theta(i));
      if (options.converged_elastic == 0 || sigma + 1.0 / theta(i) > options.rigid_limit) ++counted;
    }
    if (converged) {
      out.converged = true;
      break;
    }
    if (out.block_solves >= options.max_block_solves) break;
    if (used + b > max_basis) {
      // Thick restart: keep the best Ritz vectors (their T is diagonal) and the next block,
      // which couples to each of them by its residual's coefficients.
      const int k = kept_on_restart;
      const MatrixXd yk = y.rightCols(k);
      const MatrixXd s = last.rightCols(k);
      MatrixXd ritz(n, k);
      Product(false, v.leftCols(used), yk, 1.0, 0.0, ritz);
      v.leftCols(k) = ritz;
      Product(false, mv.leftCols(used), yk, 1.0, 0.0, ritz);
      mv.leftCols(k) = ritz;
      v.middleCols(k, b) = v.middleCols(used, b).eval();
      mv.middleCols(k, b) = mv.middleCols(used, b).eval();
      t.setZero();
      t.topLeftCorner(k, k).diagonal() = theta.tail(k);
      t.block(k, 0, b, k) = s;
      t.block(0, k, k, b) = s.transpose();
      used = k;
      ++out.restarts;
    }
  }
  // The wanted pairs, lowest λ = σ + 1/θ first.
  out.eigenvalues.resize(nev);
  out.vectors.resize(n, nev);
  Product(false, v.leftCols(used), y.rightCols(nev).rowwise().reverse().eval(), 1.0, 0.0, out.vectors);
  for (int j = 0; j < nev; ++j) out.eigenvalues(j) = sigma + 1.0 / theta(used - 1 - j);
  return out;
}

}  // namespace ema::model::detail
