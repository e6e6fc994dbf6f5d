// The reduced (Ritz) model of reduced.hpp: one full solve and one factorisation per model and
// setup, a basis per set of changes, eigen-solutions of a few dozen DOFs.
#include "ema/model/reduced.hpp"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <cmath>
#include <cstdio>

#include "ema/core/error.hpp"
#include "ema/model/effects.hpp"

namespace ema::model {

struct ReducedModelFactory::Factorisation {
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
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

// out += Vᵀ D V for a sparse D with few non-zeros (a spring, a point mass): a rank-one update per entry.
void AddProjected(const Eigen::SparseMatrix<double>& d, const Eigen::MatrixXd& v, Eigen::MatrixXd* out) {
  for (int c = 0; c < d.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(d, c); it; ++it)
      if (it.value() != 0.0) out->noalias() += it.value() * v.row(it.row()).transpose() * v.row(it.col());
}

// Vᵀ A V for a part matrix A on the FE rows of V.
Eigen::MatrixXd ProjectPart(const Eigen::SparseMatrix<double>& a, const Eigen::MatrixXd& v, int offset) {
  const auto fe = v.middleRows(offset, a.rows());
  const Eigen::MatrixXd av = a * fe;
  Eigen::MatrixXd out = fe.transpose() * av;
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
  solution_ = model::Solve(base, full);
  system_ = Assemble(base, options_);
  rest_ = Assemble(base, options_, FeAssembly::kNone);
  const auto m = solution_.full_shapes.cols();
  lambda_.resize(m);
  for (Eigen::Index j = 0; j < m; ++j)
    lambda_(j) = std::pow(kTwoPi * solution_.modes.modes[static_cast<std::size_t>(j)].frequency_hz, 2);
  // The same shift and rigid-body limit as the sparse solver (solve.cpp): K − σM is definite with
  // rigid-body modes and massless DOFs alike.
  const double scale = system_.stiffness.diagonal().sum() / system_.mass.diagonal().sum();
  const double sigma = -std::max(1.0, 1e-8 * scale);
  rigid_limit_ = std::max(std::pow(kTwoPi * options_.rigid_frequency_hz, 2), options_.rigid_tolerance * scale);
  factorisation_ = std::make_unique<Factorisation>();
  const Eigen::SparseMatrix<double> shifted = system_.stiffness - sigma * system_.mass;
  factorisation_->ldlt.compute(shifted);
  if (factorisation_->ldlt.info() != Eigen::Success)
    throw InputError(origin, "factorisation of K - sigma M failed (the reduced model of the diagnosis needs it)");
  skeleton_ = base;
  skeleton_.effects.clear();
  skeleton_.fe.mass.resize(0, 0);
  skeleton_.fe.stiffness.resize(0, 0);
}

ReducedModelFactory::~ReducedModelFactory() = default;

int ReducedModelFactory::DofCount() const { return static_cast<int>(system_.mass.rows()); }

ReducedModelFactory::Delta ReducedModelFactory::DeltaOf(const Model& changed, const SolveOptions& options,
                                                        bool parts) const {
  const System light = Assemble(changed, options, FeAssembly::kNone);
  Delta d{Eigen::SparseMatrix<double>(light.stiffness - rest_.stiffness),
          Eigen::SparseMatrix<double>(light.mass - rest_.mass)};
  if (parts) {
    const int n = DofCount(), offset = system_.body_dof_count;
    for (std::size_t p = 0; p < changed.fe.parts.size() && p < skeleton_.fe.parts.size(); ++p) {
      const FePart& now = changed.fe.parts[p];
      const FePart& was = skeleton_.fe.parts[p];
      if (now.stiffness && now.stiffness_factor != was.stiffness_factor)
        d.stiffness += (now.stiffness_factor - was.stiffness_factor) * Embedded(*now.stiffness, offset, n);
      if (now.mass && now.mass_factor != was.mass_factor)
        d.mass += (now.mass_factor - was.mass_factor) * Embedded(*now.mass, offset, n);
    }
  }
  d.stiffness.prune(0.0);
  d.mass.prune(0.0);
  return d;
}

const Eigen::MatrixXd& ReducedModelFactory::Responses(const std::vector<Effect>& probe) const {
  std::string key;
  for (const Effect& e : probe) key += Describe(e) + ";";
  auto it = responses_.find(key);
  if (it != responses_.end()) return it->second;
  Model changed = skeleton_;
  for (const Effect& e : probe) changed = ApplyEffect(changed, e);
  const Delta d = DeltaOf(changed, options_, true);
  const auto q = std::min<Eigen::Index>(reduced_options_.enriched_modes, lambda_.size());
  const Eigen::MatrixXd& phi = solution_.full_shapes;
  Eigen::MatrixXd rhs = d.stiffness * phi.leftCols(q);
  if (d.mass.nonZeros() > 0) rhs -= (d.mass * phi.leftCols(q)) * lambda_.head(q).asDiagonal();
  // First and second order: w1 = A⁻¹ (ΔK − λΔM) φ (the mode-shape sensitivity's direction),
  // w2 = A⁻¹ (ΔK − λΔM) w1 (what a large change — a joint 20× softer — adds to it).
  Eigen::MatrixXd w(rhs.rows(), 2 * rhs.cols());
  for (Eigen::Index j = 0; j < q; ++j) w.col(j) = factorisation_->ldlt.solve(rhs.col(j));
  Eigen::MatrixXd rhs2 = d.stiffness * w.leftCols(q);
  if (d.mass.nonZeros() > 0) rhs2 -= (d.mass * w.leftCols(q)) * lambda_.head(q).asDiagonal();
  for (Eigen::Index j = 0; j < q; ++j) w.col(q + j) = factorisation_->ldlt.solve(rhs2.col(j));
  return responses_.emplace(key, std::move(w)).first->second;
}

std::unique_ptr<ReducedModel> ReducedModelFactory::Make(const std::vector<std::vector<Effect>>& probes) const {
  std::unique_ptr<ReducedModel> r(new ReducedModel(this));
  const Eigen::MatrixXd& phi = solution_.full_shapes;
  const Eigen::SparseMatrix<double>& mass = system_.mass;
  const int n = DofCount();
  // Candidates: the base's modes (M-orthonormal already), then each probe's responses, kept when
  // they add a direction (Gram–Schmidt in the M inner product, twice for round-off).
  std::vector<const Eigen::MatrixXd*> blocks{&phi};
  for (const auto& probe : probes) blocks.push_back(&Responses(probe));
  Eigen::Index total = 0;
  for (const auto* b : blocks) total += b->cols();
  Eigen::MatrixXd v(n, total), mv(n, total);
  Eigen::Index kept = 0;
  for (const auto* b : blocks)
    for (Eigen::Index c = 0; c < b->cols(); ++c) {
      Eigen::VectorXd x = b->col(c);
      Eigen::VectorXd mx = mass * x;
      const double before = std::sqrt(std::max(0.0, x.dot(mx)));
      if (!(before > 0.0)) continue;
      for (int pass = 0; pass < 2 && kept > 0; ++pass) {
        const Eigen::VectorXd coefficients = mv.leftCols(kept).transpose() * x;
        x -= v.leftCols(kept) * coefficients;
      }
      mx = mass * x;
      const double after = std::sqrt(std::max(0.0, x.dot(mx)));
      if (!(after > reduced_options_.drop_tolerance * before)) continue;
      v.col(kept) = x / after;
      mv.col(kept) = mx / after;
      ++kept;
    }
  r->basis_ = v.leftCols(kept);
  const Eigen::MatrixXd kv = system_.stiffness * r->basis_;
  r->k0_ = r->basis_.transpose() * kv;
  r->k0_ = 0.5 * (r->k0_ + r->k0_.transpose()).eval();
  r->m0_ = r->basis_.transpose() * mv.leftCols(kept);
  r->m0_ = 0.5 * (r->m0_ + r->m0_.transpose()).eval();
  r->part_k_.resize(skeleton_.fe.parts.size());
  r->part_m_.resize(skeleton_.fe.parts.size());
  r->projected_.assign(skeleton_.fe.parts.size(), 0);
  for (const auto& probe : probes) {
    Model changed = skeleton_;
    for (const Effect& e : probe) changed = ApplyEffect(changed, e);
    r->ProjectParts(changed);
  }
  r->observed_basis_ = system_.observation * r->basis_;
  return r;
}

void ReducedModel::ProjectParts(const Model& changed) const {
  const ReducedModelFactory& f = *factory_;
  const int offset = f.system_.body_dof_count;
  for (std::size_t p = 0; p < changed.fe.parts.size() && p < f.skeleton_.fe.parts.size(); ++p) {
    const FePart& now = changed.fe.parts[p];
    const FePart& was = f.skeleton_.fe.parts[p];
    if (projected_[p] || (now.stiffness_factor == was.stiffness_factor && now.mass_factor == was.mass_factor)) continue;
    if (now.stiffness) part_k_[p] = ProjectPart(*now.stiffness, basis_, offset);
    if (now.mass) part_m_[p] = ProjectPart(*now.mass, basis_, offset);
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
    const ReducedModelFactory::Delta rest = f.DeltaOf(changed, options, false);
    AddProjected(rest.stiffness, basis_, &k);
    AddProjected(rest.mass, basis_, &m);
    mass_changed = rest.mass.nonZeros() > 0;
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
