// A reduced (Ritz) model: many eigen-solutions of one FE-sized model under changes of its
// parameters — what the diagnosis needs (hundreds of part factors, masses and springs tried, each
// a full eigen-solution otherwise). docs/model.md "Reduced model".
//
// ReducedModelFactory is built once per model and setup: one full solve (its lowest modes Φ,
// eigenvalues λ) and one factorisation of K − σM. For each change a reduced model must represent
// (a part scaled, a point mass added, a spring softened: a "probe") it computes the static response
// of the lowest modes to that change, (K − σM)⁻¹ (ΔK − λ_j ΔM) φ_j — the direction in which each
// mode moves, the analytic mode-shape sensitivity up to the modal truncation — once, and keeps it.
// A ReducedModel's basis V = [Φ, the responses of its probes], M-orthonormalised, carries every FE
// matrix as its projection VᵀKV (each part's too), so a solve of a changed model is an
// eigen-solution of a few dozen DOFs plus the projection of what the change touches. Its
// eigenvalues are exact to first order in the change (their derivative φᵀ(ΔK − λΔM)φ is in the
// basis) and Rayleigh–Ritz upper bounds beyond; the diagnosis re-centres a basis on the values it
// fits and checks the results it reports with full solves.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "ema/model/model.hpp"
#include "ema/model/solve.hpp"

namespace ema::model {

namespace detail {
class RestAssembler;
}

struct ReducedModelOptions {
  /// Elastic modes of the full solve kept in every basis.
  int modes = 30;
  /// Lowest elastic modes whose static response to each probe joins a basis.
  int enriched_modes = 12;
  /// A basis vector whose M-norm after orthogonalisation to the others falls below this share of
  /// its own is dropped (it adds nothing the basis does not hold).
  double drop_tolerance = 1e-8;

  bool IsValid(std::string* why) const {
    if (modes < 1) return *why = "modes must be >= 1", false;
    if (enriched_modes < 0) return *why = "enriched_modes must be >= 0", false;
    if (!(drop_tolerance > 0.0 && drop_tolerance < 1.0)) return *why = "drop_tolerance must lie in (0, 1)", false;
    return true;
  }
};

class ReducedModel;

class ReducedModelFactory {
 public:
  /// Solves `base` (its pending effects applied) in full at `solve` (its setup; extra masses are
  /// not part of the base: give them to ReducedModel::Solve) and factorises K − σM. Throws
  /// InputError as Solve does, UsageError for invalid options.
  ReducedModelFactory(const Model& base, const SolveOptions& solve, const ReducedModelOptions& options = {});
  ~ReducedModelFactory();
  ReducedModelFactory(const ReducedModelFactory&) = delete;
  ReducedModelFactory& operator=(const ReducedModelFactory&) = delete;

  /// The base without its [fe] mass and stiffness (parts keep their shared matrices): apply
  /// effects to a copy of it — cheap at any size — and hand the result to ReducedModel::Solve.
  const Model& Skeleton() const { return skeleton_; }
  /// The full solution of the base (modes at the test points, full shapes).
  const Solution& BaseSolution() const { return solution_; }

  /// A reduced model whose basis holds the base's modes and the static responses to each probe
  /// (a list of effects applied to Skeleton()); the responses are computed once per probe and
  /// kept, keyed by `Describe` of its effects, as an orthonormal basis of their span (a point
  /// mass changes three DOFs: its responses span at most six directions, whatever the modes).
  std::unique_ptr<ReducedModel> Make(const std::vector<std::vector<Effect>>& probes) const;

  int DofCount() const;
  int ModeCount() const { return static_cast<int>(lambda_.size()); }

 private:
  friend class ReducedModel;
  struct Delta {
    Eigen::SparseMatrix<double> stiffness, mass;
  };
  // ΔK, ΔM of `changed` (a skeleton with effects) against the base, FE parts included: n × n, for
  // a probe's responses (once per probe).
  Delta DeltaOf(const Model& changed, const SolveOptions& options) const;
  /// ΔK, ΔM of the bodies, springs and point masses of `changed` (the options' extra masses too)
  /// against the base's — the entries of the difference of the two assembled matrices without
  /// zeros, column by column — from triplets alone: no n × n matrix, DOF name or observation is
  /// built per reduced solve.
  struct RestDelta {
    std::vector<Eigen::Triplet<double>> stiffness, mass;
  };
  RestDelta RestDeltaOf(const Model& changed, const SolveOptions& options) const;
  /// A probe's static responses as a basis block: M-orthogonal to the base's modes Φ (twice, for
  /// round-off), with what every reduced model holding it needs from them, computed once per probe
  /// and kept — a reduced model stores only coefficients on the blocks, never an n × b basis (the
  /// diagnosis makes hundreds of reduced models of one or two probes each; forming, orthogonalising
  /// and projecting an n × b basis for each was most of its time on 50 000 DOFs).
  struct ProbeBlock {
    Eigen::MatrixXd responses;           ///< n × t
    Eigen::MatrixXd observed;            ///< observation × responses
    Eigen::MatrixXd mass_gram;           ///< responsesᵀ M responses
    Eigen::MatrixXd stiffness_gram;      ///< responsesᵀ K responses
  };
  const ProbeBlock& Block(const std::vector<Effect>& probe) const;
  /// The static responses to a probe as an orthonormal basis of their span (not kept: Block is).
  Eigen::MatrixXd Responses(const std::vector<Effect>& probe) const;
  /// wᵀ M v and wᵀ K v of two probes' blocks (kept per pair).
  struct CrossGram {
    Eigen::MatrixXd mass, stiffness;
  };
  const CrossGram& Cross(const std::string& first, const ProbeBlock& a, const std::string& second,
                         const ProbeBlock& b) const;
  static std::string KeyOf(const std::vector<Effect>& probe);

  struct Factorisation;
  /// The rows (in system DOFs) on which part p has entries, for projecting it on those rows only.
  const std::vector<int>& PartRows(std::size_t part) const;
  Model skeleton_;
  SolveOptions options_;
  ReducedModelOptions reduced_options_;
  Solution solution_;
  System system_;                      ///< full K, M of the base
  System rest_;                        ///< bodies, springs, point masses of the base (no FE matrices)
  std::unique_ptr<detail::RestAssembler> rest_assembler_;           ///< the base's DOF layout, kept
  std::vector<Eigen::Triplet<double>> rest_mass_, rest_stiffness_;  ///< rest_'s entries, column by column
  Eigen::VectorXd lambda_;             ///< eigenvalues of the kept elastic modes
  Eigen::MatrixXd mass_modes_;         ///< M Φ (for M-orthogonalising responses against Φ)
  mutable std::vector<std::vector<int>> part_rows_;  ///< per part, its non-zero rows (filled on use)
  double rigid_limit_ = 0.0;
  std::unique_ptr<Factorisation> factorisation_;
  Eigen::MatrixXd observed_modes_;     ///< observation × Φ
  mutable std::map<std::string, ProbeBlock> blocks_;                          ///< per probe
  mutable std::map<std::pair<std::string, std::string>, CrossGram> cross_;   ///< per pair of probes
};

class ReducedModel {
 public:
  /// The eigen-solution of `changed` (the factory's Skeleton() with effects applied) with the
  /// extra masses of `options` (roving sensors), in the reduced basis: modes at the test points
  /// (mass-normalised, damping from [damping]) and rigid-body frequencies; no full shapes, springs
  /// or energy shares. Throws InputError for a stiffness that is not positive semi-definite.
  /// `rest_changed` false: the caller knows that only part factors changed and `options` adds no
  /// extra mass (the bodies, springs and point masses are not assembled again). The [fe] DOF map
  /// and node positions of `changed` are not read (the factory's stand for them: effects change
  /// neither), so a skeleton without them will do.
  Solution Solve(const Model& changed, const SolveOptions& options, bool rest_changed = true) const;

  int BasisSize() const { return static_cast<int>(k0_.cols()); }

 private:
  friend class ReducedModelFactory;
  explicit ReducedModel(const ReducedModelFactory* factory) : factory_(factory) {}

  const ReducedModelFactory* factory_;
  /// The basis V = [Φ, [w_1 … w_P] C], M-orthonormal, held as the factory's probe blocks w_p and
  /// the coefficients C (Σ t_p × kept): its rows are formed where they are needed (a part's rows,
  /// a spring's, the test points'), never all n of them.
  std::vector<const ReducedModelFactory::ProbeBlock*> blocks_;
  Eigen::MatrixXd coefficients_;
  Eigen::MatrixXd observed_basis_;     ///< observation × basis
  /// Rows `rows` (system DOFs) of V.
  Eigen::MatrixXd BasisRows(const std::vector<int>& rows) const;
  /// out += Vᵀ D V for a D with few entries (a spring, a point mass, sensors).
  void AddProjected(const std::vector<Eigen::Triplet<double>>& d, Eigen::MatrixXd* out) const;
  Eigen::MatrixXd k0_, m0_;            ///< VᵀKV, VᵀMV of the base
  /// VᵀK_pV, VᵀM_pV per part, projected when a solve first changes that part's factor (the probes'
  /// parts at Make): most reduced models change two or three of hundreds of parts.
  mutable std::vector<Eigen::MatrixXd> part_k_, part_m_;
  mutable std::vector<char> projected_;
  void ProjectParts(const Model& changed) const;
};

}  // namespace ema::model
