// The reduced (Ritz) model of reduced.hpp: one full solve and one factorisation per model and
// setup, a basis per set of changes, eigen-solutions of a few dozen DOFs.
#include "ema/model/reduced.hpp"

#include <Eigen/Dense>
#include <Eigen/QR>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "assembly.hpp"
#include "ema/core/error.hpp"
#include "ema/model/effects.hpp"
#include "sparse_factor.hpp"

namespace ema::model {

struct ReducedModelFactory::Factorisation {
  std::unique_ptr<detail::SparseFactor> ldlt;
};

namespace {

// Rows of an FE-sized part matrix sit after the bodies' DOFs in the system.
Eigen::SparseMatrix<double> Embedded(const Eigen::SparseMatrix<double>& part, int offset, int n) {
  if (offset == 0 && part.rows() == n) return part;
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(part.nonZeros()));
  for (int c = 0; c < part.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(part, c); it; ++it)
      t.emplace_back(offset + static_cast<int>(it.row()), offset + static_cast<int>(it.col()), it.value());
  Eigen::SparseMatrix<double> out(n, n);
  out.setFromTriplets(t.begin(), t.end());
  return out;
}

// Triplets summed per entry (duplicates in their order, as setFromTriplets sums them), column by
// column, rows ascending.
std::vector<Eigen::Triplet<double>> Summed(std::vector<Eigen::Triplet<double>> t) {
  std::stable_sort(t.begin(), t.end(), [](const auto& a, const auto& b) {
    return a.col() != b.col() ? a.col() < b.col() : a.row() < b.row();
  });
  std::vector<Eigen::Triplet<double>> out;
  for (const auto& e : t) {
    if (!out.empty() && out.back().row() == e.row() && out.back().col() == e.col())
      out.back() = Eigen::Triplet<double>(e.row(), e.col(), out.back().value() + e.value());
    else
      out.push_back(e);
  }
  return out;
}

// a − b of two summed lists in the same order, exact zeros dropped (an unchanged spring cancels
// exactly): the entries of the sparse difference of the two assembled matrices after prune(0).
std::vector<Eigen::Triplet<double>> Difference(const std::vector<Eigen::Triplet<double>>& a,
                                               const std::vector<Eigen::Triplet<double>>& b) {
  std::vector<Eigen::Triplet<double>> out;
  auto before = [](const auto& x, const auto& y) { return x.col() != y.col() ? x.col() < y.col() : x.row() < y.row(); };
  auto push = [&](int row, int col, double v) {
    if (std::abs(v) > 0.0) out.emplace_back(row, col, v);
  };
  size_t i = 0, j = 0;
  while (i < a.size() || j < b.size()) {
    if (j == b.size() || (i < a.size() && before(a[i], b[j]))) push(a[i].row(), a[i].col(), a[i].value()), ++i;
    else if (i == a.size() || before(b[j], a[i])) push(b[j].row(), b[j].col(), -b[j].value()), ++j;
    else push(a[i].row(), a[i].col(), a[i].value() - b[j].value()), ++i, ++j;
  }
  return out;
}

// Vᵀ A V for a part matrix A (FE-sized, its entries on `rows` of the system only), given those
// rows of V: a joint zone touches a few dozen of the model's DOFs.
Eigen::MatrixXd ProjectPart(const Eigen::SparseMatrix<double>& a, const Eigen::MatrixXd& vr, int offset,
                            const std::vector<int>& rows) {
  std::vector<int> local(static_cast<size_t>(a.rows()), -1);
  for (size_t k = 0; k < rows.size(); ++k) local[static_cast<size_t>(rows[k] - offset)] = static_cast<int>(k);
  Eigen::MatrixXd av = Eigen::MatrixXd::Zero(vr.rows(), vr.cols());
  for (int c = 0; c < a.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(a, c); it; ++it)
      av.row(local[static_cast<size_t>(it.row())]) += it.value() * vr.row(local[static_cast<size_t>(it.col())]);
  Eigen::MatrixXd out = vr.transpose() * av;
  return 0.5 * (out + out.transpose());
}

}  // namespace

ReducedModelFactory::ReducedModelFactory(const Model& input, const SolveOptions& solve,
                                         const ReducedModelOptions& options)
    : reduced_options_(options) {
  if (std::string why; !options.IsValid(&why)) throw UsageError("reduced model options: " + why);
  const Model base = input.effects.empty() ? input : ApplyEffects(input);
  const std::string origin = base.origin.empty() ? "model" : base.origin;
  options_ = solve;
  options_.extra_masses.clear();
  SolveOptions full = options_;
  full.max_modes = std::max(options.modes, solve.max_modes);
  factorisation_ = std::make_unique<Factorisation>();
  // The solve's own assembly (its options differ from options_ in max_modes only): an assembly of
  // a 220 941-DOF model is over a second, and a diagnosis makes a factory per centre.
  solution_ = detail::SolveKeepingFactor(base, full, &factorisation_->ldlt, &system_);
  rest_ = Assemble(base, options_, FeAssembly::kNone);
  const auto m = solution_.full_shapes.cols();
  lambda_.resize(m);
  for (Eigen::Index j = 0; j < m; ++j)
    lambda_(j) = std::pow(kTwoPi * solution_.modes.modes[static_cast<std::size_t>(j)].frequency_hz, 2);
  // The same shift and rigid-body limit as the sparse solver (solve.cpp): K − σM is definite with
  // rigid-body modes and massless DOFs alike. The solve's own factorisation when it took the
  // sparse path (the same matrix but for the massless DOFs' 1e-12 mass), else one made here.
  const double scale = system_.stiffness.diagonal().sum() / system_.mass.diagonal().sum();
  const double sigma = -std::max(1.0, options_.sparse_shift * scale);
  rigid_limit_ = std::max(std::pow(kTwoPi * options_.rigid_frequency_hz, 2), options_.rigid_tolerance * scale);
  if (!factorisation_->ldlt) {
    factorisation_->ldlt = std::make_unique<detail::SparseFactor>();
    const Eigen::SparseMatrix<double> shifted = system_.stiffness - sigma * system_.mass;
    if (!factorisation_->ldlt->Compute(shifted))
      throw InputError(origin, "factorisation of K - sigma M failed (the reduced model of the diagnosis needs it)");
  }
  mass_modes_ = system_.mass * solution_.full_shapes;
  observed_modes_ = system_.observation * solution_.full_shapes;
  rest_assembler_ = std::make_unique<detail::RestAssembler>(base);
  {
    std::vector<Eigen::Triplet<double>> mt, kt;
    rest_assembler_->Assemble(base, options_, &mt, &kt);
    rest_mass_ = Summed(std::move(mt));
    rest_stiffness_ = Summed(std::move(kt));
  }
  part_rows_.resize(base.fe.parts.size());
  skeleton_ = base;
  skeleton_.effects.clear();
  skeleton_.fe.mass.resize(0, 0);
  skeleton_.fe.stiffness.resize(0, 0);
}

ReducedModelFactory::~ReducedModelFactory() = default;

int ReducedModelFactory::DofCount() const { return static_cast<int>(system_.mass.rows()); }

ReducedModelFactory::Delta ReducedModelFactory::DeltaOf(const Model& changed, const SolveOptions& options) const {
  const System light = Assemble(changed, options, FeAssembly::kNone);
  Delta d{Eigen::SparseMatrix<double>(light.stiffness - rest_.stiffness),
          Eigen::SparseMatrix<double>(light.mass - rest_.mass)};
  const int n = DofCount(), offset = system_.body_dof_count;
  for (std::size_t p = 0; p < changed.fe.parts.size() && p < skeleton_.fe.parts.size(); ++p) {
    const FePart& now = changed.fe.parts[p];
    const FePart& was = skeleton_.fe.parts[p];
    if (now.stiffness && now.stiffness_factor != was.stiffness_factor)
      d.stiffness += (now.stiffness_factor - was.stiffness_factor) * Embedded(*now.stiffness, offset, n);
    if (now.mass && now.mass_factor != was.mass_factor)
      d.mass += (now.mass_factor - was.mass_factor) * Embedded(*now.mass, offset, n);
  }
  d.stiffness.prune(0.0);
  d.mass.prune(0.0);
  return d;
}

ReducedModelFactory::RestDelta ReducedModelFactory::RestDeltaOf(const Model& changed, const SolveOptions& options) const {
  if (!rest_assembler_->Fits(changed))
    throw InputError(changed.origin.empty() ? "model" : changed.origin,
                     "the changed model's bodies are not those of its reduced model's base");
  std::vector<Eigen::Triplet<double>> mt, kt;
  rest_assembler_->Assemble(changed, options, &mt, &kt);
  return {Difference(Summed(std::move(kt)), rest_stiffness_), Difference(Summed(std::move(mt)), rest_mass_)};
}

std::string ReducedModelFactory::KeyOf(const std::vector<Effect>& probe) {
  std::string key;
  for (const Effect& e : probe) key += Describe(e) + ";";
  return key;
}

const ReducedModelFactory::ProbeBlock& ReducedModelFactory::Block(const std::vector<Effect>& probe) const {
  const std::string key = KeyOf(probe);
  auto it = blocks_.find(key);
  if (it != blocks_.end()) return it->second;
  ProbeBlock block;
  block.responses = Responses(probe);
  // M-orthogonal to Φ (twice, for round-off): the reduced models' k0 then has Λ on Φ's block and
  // no coupling to the responses.
  for (int pass = 0; pass < 2 && block.responses.cols() > 0; ++pass)
    block.responses -= solution_.full_shapes * (mass_modes_.transpose() * block.responses);
  block.observed = system_.observation * block.responses;
  block.mass_gram = block.responses.transpose() * (system_.mass * block.responses);
  block.stiffness_gram = block.responses.transpose() * (system_.stiffness * block.responses);
  return blocks_.emplace(key, std::move(block)).first->second;
}

const ReducedModelFactory::CrossGram& ReducedModelFactory::Cross(const std::string& first, const ProbeBlock& a,
                                                                 const std::string& second,
                                                                 const ProbeBlock& b) const {
  auto it = cross_.find({first, second});
  if (it != cross_.end()) return it->second;
  CrossGram g;
  g.mass = a.responses.transpose() * (system_.mass * b.responses);
  g.stiffness = a.responses.transpose() * (system_.stiffness * b.responses);
  return cross_.emplace(std::make_pair(first, second), std::move(g)).first->second;
}

Eigen::MatrixXd ReducedModelFactory::Responses(const std::vector<Effect>& probe) const {
  Model changed = skeleton_;
  for (const Effect& e : probe) changed = ApplyEffect(changed, e);
  const Delta d = DeltaOf(changed, options_);
  const auto q = std::min<Eigen::Index>(reduced_options_.enriched_modes, lambda_.size());
  // A change confined to a few DOFs (a support, a bolted joint, a point mass): the static responses
  // to unit loads on those DOFs span every mode's change, whatever its size (the attachment modes
  // of component-mode synthesis) — exact in the static limit, where the modal responses below are
  // only first and second order in the change.
  std::vector<int> rows;
  {
    std::vector<char> touched(static_cast<size_t>(DofCount()), 0);
    for (const auto* a : {&d.stiffness, &d.mass})
      for (int c = 0; c < a->outerSize(); ++c)
        for (Eigen::SparseMatrix<double>::InnerIterator it(*a, c); it; ++it)
          if (it.value() != 0.0) touched[static_cast<size_t>(it.row())] = 1;
    for (int i = 0; i < DofCount(); ++i)
      if (touched[static_cast<size_t>(i)]) rows.push_back(i);
  }
  if (!rows.empty() && static_cast<Eigen::Index>(rows.size()) <= std::max<Eigen::Index>(24, 2 * q)) {
    // One solve with a block of unit loads (BLAS-3 in the supernodal solve, the factor read once).
    Eigen::MatrixXd unit = Eigen::MatrixXd::Zero(DofCount(), static_cast<Eigen::Index>(rows.size()));
    for (size_t k = 0; k < rows.size(); ++k) unit(rows[k], static_cast<Eigen::Index>(k)) = 1.0;
    const Eigen::MatrixXd w = factorisation_->ldlt->Solve(unit);
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(w);
    qr.setThreshold(1e-10);
    Eigen::MatrixXd basis = qr.householderQ() * Eigen::MatrixXd::Identity(w.rows(), qr.rank());
    return basis;
  }
  const Eigen::MatrixXd& phi = solution_.full_shapes;
  Eigen::MatrixXd rhs = d.stiffness * phi.leftCols(q);
  if (d.mass.nonZeros() > 0) rhs -= (d.mass * phi.leftCols(q)) * lambda_.head(q).asDiagonal();
  // First and second order: w1 = A⁻¹ (ΔK − λΔM) φ (the mode-shape sensitivity's direction),
  // w2 = A⁻¹ (ΔK − λΔM) w1 (what a large change — a joint 20× softer — adds to it).
  Eigen::MatrixXd w(rhs.rows(), 2 * rhs.cols());
  w.leftCols(q) = factorisation_->ldlt->Solve(rhs);
  Eigen::MatrixXd rhs2 = d.stiffness * w.leftCols(q);
  if (d.mass.nonZeros() > 0) rhs2 -= (d.mass * w.leftCols(q)) * lambda_.head(q).asDiagonal();
  w.rightCols(q) = factorisation_->ldlt->Solve(rhs2);
  // Kept as an orthonormal basis of their span (column-pivoted QR, directions below 1e-8 of the
  // largest dropped): a low-rank change has few directions, and each costs memory per DOF.
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(w);
  qr.setThreshold(1e-8);
  const Eigen::Index rank = qr.rank();
  Eigen::MatrixXd basis = qr.householderQ() * Eigen::MatrixXd::Identity(w.rows(), rank);
  return basis;
}

std::unique_ptr<ReducedModel> ReducedModelFactory::Make(const std::vector<std::vector<Effect>>& probes) const {
  std::unique_ptr<ReducedModel> r(new ReducedModel(this));
  const auto m = solution_.full_shapes.cols();
  // The probes' blocks (M-orthogonal to Φ), M-orthonormalised among themselves through the
  // eigen-decomposition of their M-Gram matrix (directions below drop_tolerance of the largest
  // dropped) — the Gram matrices assembled from the blocks' own and pairwise ones, kept in the
  // factory: a reduced model costs a few dozen squared, not n times that.
  std::vector<std::string> keys;
  std::vector<Eigen::Index> start;
  Eigen::Index total = 0;
  for (const auto& probe : probes) {
    const ProbeBlock& block = Block(probe);
    if (block.responses.cols() == 0) continue;
    keys.push_back(KeyOf(probe));
    r->blocks_.push_back(&block);
    start.push_back(total);
    total += block.responses.cols();
  }
  Eigen::MatrixXd gram(total, total), stiffness(total, total);
  for (size_t i = 0; i < r->blocks_.size(); ++i) {
    const ProbeBlock& a = *r->blocks_[i];
    const Eigen::Index ta = a.responses.cols();
    gram.block(start[i], start[i], ta, ta) = a.mass_gram;
    stiffness.block(start[i], start[i], ta, ta) = a.stiffness_gram;
    for (size_t j = i + 1; j < r->blocks_.size(); ++j) {
      const ProbeBlock& c = *r->blocks_[j];
      const Eigen::Index tc = c.responses.cols();
      // Kept for the pair in one order (the keys sorted): {A, B} and {B, A} share it.
      const bool swapped = keys[j] < keys[i];
      const CrossGram& g = swapped ? Cross(keys[j], c, keys[i], a) : Cross(keys[i], a, keys[j], c);
      const Eigen::MatrixXd mass = swapped ? Eigen::MatrixXd(g.mass.transpose()) : g.mass;
      const Eigen::MatrixXd stiff = swapped ? Eigen::MatrixXd(g.stiffness.transpose()) : g.stiffness;
      gram.block(start[i], start[j], ta, tc) = mass;
      gram.block(start[j], start[i], tc, ta) = mass.transpose();
      stiffness.block(start[i], start[j], ta, tc) = stiff;
      stiffness.block(start[j], start[i], tc, ta) = stiff.transpose();
    }
  }
  if (total > 0) {
    gram = 0.5 * (gram + gram.transpose()).eval();
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(gram);
    const double largest = std::max(0.0, es.eigenvalues().maxCoeff());
    std::vector<Eigen::Index> keep;
    for (Eigen::Index k = 0; k < es.eigenvalues().size(); ++k)
      if (es.eigenvalues()(k) > reduced_options_.drop_tolerance * reduced_options_.drop_tolerance * largest)
        keep.push_back(k);
    r->coefficients_.resize(total, static_cast<Eigen::Index>(keep.size()));
    for (size_t k = 0; k < keep.size(); ++k)
      r->coefficients_.col(static_cast<Eigen::Index>(k)) =
          es.eigenvectors().col(keep[k]) / std::sqrt(es.eigenvalues()(keep[k]));
  }
  const Eigen::Index kept = r->coefficients_.cols();
  const Eigen::Index b = m + kept;
  // VᵀKV: Φ's block is Λ and its coupling to the responses vanishes (KΦ = MΦΛ and the responses
  // are M-orthogonal to Φ); the responses' own block is Cᵀ (WᵀKW) C. VᵀMV = I.
  r->k0_ = Eigen::MatrixXd::Zero(b, b);
  r->k0_.topLeftCorner(m, m).diagonal() = lambda_;
  if (kept > 0) {
    const Eigen::MatrixXd kww = r->coefficients_.transpose() * stiffness * r->coefficients_;
    r->k0_.bottomRightCorner(kept, kept) = 0.5 * (kww + kww.transpose());
  }
  r->m0_ = Eigen::MatrixXd::Identity(b, b);
  r->observed_basis_.resize(observed_modes_.rows(), b);
  r->observed_basis_.leftCols(m) = observed_modes_;
  r->observed_basis_.rightCols(kept).setZero();
  for (size_t k = 0; k < r->blocks_.size(); ++k)
    r->observed_basis_.rightCols(kept).noalias() +=
        r->blocks_[k]->observed * r->coefficients_.middleRows(start[k], r->blocks_[k]->responses.cols());
  r->part_k_.resize(skeleton_.fe.parts.size());
  r->part_m_.resize(skeleton_.fe.parts.size());
  r->projected_.assign(skeleton_.fe.parts.size(), 0);
  for (const auto& probe : probes) {
    Model changed = skeleton_;
    for (const Effect& e : probe) changed = ApplyEffect(changed, e);
    r->ProjectParts(changed);
  }
  return r;
}

const std::vector<int>& ReducedModelFactory::PartRows(std::size_t p) const {
  std::vector<int>& rows = part_rows_[p];
  if (!rows.empty()) return rows;
  const FePart& part = skeleton_.fe.parts[p];
  const int offset = system_.body_dof_count;
  std::vector<char> used(static_cast<size_t>(DofCount()), 0);
  for (const auto* a : {part.stiffness.get(), part.mass.get()})
    if (a)
      for (int c = 0; c < a->outerSize(); ++c)
        for (Eigen::SparseMatrix<double>::InnerIterator it(*a, c); it; ++it) used[static_cast<size_t>(offset + it.row())] = 1;
  for (int i = 0; i < DofCount(); ++i)
    if (used[static_cast<size_t>(i)]) rows.push_back(i);
  return rows;
}

Eigen::MatrixXd ReducedModel::BasisRows(const std::vector<int>& rows) const {
  const ReducedModelFactory& f = *factory_;
  const auto m = f.solution_.full_shapes.cols();
  Eigen::MatrixXd out(static_cast<Eigen::Index>(rows.size()), m + coefficients_.cols());
  out.leftCols(m) = f.solution_.full_shapes(rows, Eigen::all);
  out.rightCols(coefficients_.cols()).setZero();
  for (Eigen::Index k = 0, start = 0; k < static_cast<Eigen::Index>(blocks_.size()); ++k) {
    const Eigen::MatrixXd& w = blocks_[static_cast<size_t>(k)]->responses;
    out.rightCols(coefficients_.cols()).noalias() += w(rows, Eigen::all) * coefficients_.middleRows(start, w.cols());
    start += w.cols();
  }
  return out;
}

void ReducedModel::AddProjected(const std::vector<Eigen::Triplet<double>>& d, Eigen::MatrixXd* out) const {
  if (d.empty()) return;
  std::vector<int> rows;
  for (const auto& e : d) rows.push_back(e.row()), rows.push_back(e.col());
  std::sort(rows.begin(), rows.end());
  rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
  const Eigen::MatrixXd v = BasisRows(rows);
  auto at = [&](int dof) { return std::lower_bound(rows.begin(), rows.end(), dof) - rows.begin(); };
  // A rank-one update per entry.
  for (const auto& e : d) out->noalias() += e.value() * v.row(at(e.row())).transpose() * v.row(at(e.col()));
}

void ReducedModel::ProjectParts(const Model& changed) const {
  const ReducedModelFactory& f = *factory_;
  const int offset = f.system_.body_dof_count;
  for (std::size_t p = 0; p < changed.fe.parts.size() && p < f.skeleton_.fe.parts.size(); ++p) {
    const FePart& now = changed.fe.parts[p];
    const FePart& was = f.skeleton_.fe.parts[p];
    if (projected_[p] || (now.stiffness_factor == was.stiffness_factor && now.mass_factor == was.mass_factor)) continue;
    const std::vector<int>& rows = f.PartRows(p);
    const Eigen::MatrixXd vr = BasisRows(rows);
    if (now.stiffness) part_k_[p] = ProjectPart(*now.stiffness, vr, offset, rows);
    if (now.mass) part_m_[p] = ProjectPart(*now.mass, vr, offset, rows);
    projected_[p] = 1;
  }
}

Solution ReducedModel::Solve(const Model& changed, const SolveOptions& options, bool rest_changed) const {
  const ReducedModelFactory& f = *factory_;
  const std::string origin = changed.origin.empty() ? "model" : changed.origin;
  Eigen::MatrixXd k = k0_, m = m0_;
  bool mass_changed = false;
  // What is not an FE matrix (springs, bodies, point masses — sensors included): its difference
  // to the base, projected entry by entry.
  if (rest_changed || !options.extra_masses.empty()) {
    const ReducedModelFactory::RestDelta rest = f.RestDeltaOf(changed, options);
    AddProjected(rest.stiffness, &k);
    AddProjected(rest.mass, &m);
    mass_changed = !rest.mass.empty();
  }
  ProjectParts(changed);
  for (std::size_t p = 0; p < changed.fe.parts.size() && p < f.skeleton_.fe.parts.size(); ++p) {
    const FePart& now = changed.fe.parts[p];
    const FePart& was = f.skeleton_.fe.parts[p];
    if (now.stiffness_factor != was.stiffness_factor && part_k_[p].size() > 0)
      k += (now.stiffness_factor - was.stiffness_factor) * part_k_[p];
    if (now.mass_factor != was.mass_factor && part_m_[p].size() > 0)
      m += (now.mass_factor - was.mass_factor) * part_m_[p], mass_changed = true;
  }
  // The basis is M-orthonormal: with the mass unchanged the problem is a standard one.
  Eigen::VectorXd eigenvalues;
  Eigen::MatrixXd eigenvectors;
  if (!mass_changed && (m0_ - Eigen::MatrixXd::Identity(m0_.rows(), m0_.cols())).cwiseAbs().maxCoeff() < 1e-10) {
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(k);
    if (es.info() != Eigen::Success) throw InputError(origin, "the reduced eigenvalue solution failed");
    eigenvalues = es.eigenvalues();
    eigenvectors = es.eigenvectors();
  } else {
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(k, m, Eigen::ComputeEigenvectors | Eigen::Ax_lBx);
    if (es.info() != Eigen::Success)
      throw InputError(origin, "the reduced eigenvalue solution failed (a mass that is not positive definite?)");
    eigenvalues = es.eigenvalues();
    eigenvectors = es.eigenvectors();
  }
  Solution sol;
  sol.modes.dofs = f.system_.observed_dofs;
  sol.modes.geometry = f.system_.geometry;
  sol.modes.source = (changed.name.empty() ? origin : changed.name) + (options.setup.empty() ? "" : " [" + options.setup + "]");
  sol.dof_names = {};
  int elastic = 0;
  for (Eigen::Index i = 0; i < eigenvalues.size(); ++i) {
    const double lam = eigenvalues(i);
    if (lam < -f.rigid_limit_)
      throw InputError(origin, "negative eigenvalue " + std::to_string(lam) +
                                   " (rad/s)^2: the changed stiffness is not positive semi-definite");
    if (lam <= f.rigid_limit_) {
      sol.rigid_body_frequencies_hz.push_back(std::sqrt(std::max(0.0, lam)) / kTwoPi);
      continue;
    }
    if (options.max_modes > 0 && elastic >= options.max_modes) break;
    Mode mode;
    mode.frequency_hz = std::sqrt(lam) / kTwoPi;
    mode.damping_ratio = changed.damping.RatioOfMode(elastic);
    mode.pole = FrequencyAndDampingToPole(mode.frequency_hz, mode.damping_ratio);
    mode.shape = (observed_basis_ * eigenvectors.col(i)).cast<std::complex<double>>();
    mode.mpc = 1.0;
    mode.mpd = 0.0;
    mode.unit_modal_mass = true;
    sol.modes.modes.push_back(std::move(mode));
    ++elastic;
  }
  return sol;
}

}  // namespace ema::model
