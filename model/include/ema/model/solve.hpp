// Operating-point solve, assembly of M and K, and the generalised eigenproblem (the laws
// linearise in laws.hpp).
//
// DOF layout: 6 per body (ux uy uz rx ry rz at the body's centre, bodies in model order), then
// the FE matrix rows in file order. A point r of a body moves u = u0 + theta x (r - centre).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <string>
#include <vector>

#include "ema/core/types.hpp"
#include "ema/model/laws.hpp"
#include "ema/model/model.hpp"

namespace ema::model {

struct SolveOptions {
  std::string setup;                    ///< setup name; empty = the nominal operating points
  int max_modes = 0;                    ///< elastic modes kept; 0 = all (dense) / 30 (sparse)
  std::vector<PointMass> extra_masses;  ///< added for this solve only (roving sensors)
  /// Models with at least this many DOF use the sparse shift-invert solver (the lowest modes only:
  /// a dense solution of every mode of a 1000-DOF mesh takes seconds and is never used).
  int sparse_threshold = 1000;
  /// Rigid-body (zero) modes: eigenvalues below rigid_tolerance x the largest |eigenvalue| (dense
  /// path) or x trace(K)/trace(M) (sparse path: the mean eigenvalue), or below
  /// (2 pi rigid_frequency_hz)^2. Every computed eigenvalue carries a round-off of about 1e-16 of
  /// that scale (7e-17 measured on a free-free beam of 1 000 elements); 1e-14 is 100x above it,
  /// where an elastic eigenvalue is still known to 1 %. Not larger: the scale grows as the element
  /// size to the -4 in a beam mesh, and at 1e-12 a 50 004-DOF frame lost its four lowest elastic
  /// modes (0.86-4.6 Hz, 3.5e-14 to 1e-12 of the scale) as "rigid-body".
  double rigid_tolerance = 1e-14;
  double rigid_frequency_hz = 1e-3;
  /// The sparse path's shift σ below zero, relative to trace(K)/trace(M): K − σM is then positive
  /// definite with rigid-body modes (100× the rigid_tolerance limit, 10⁴× their round-off), and σ sits
  /// close to the lowest eigenvalues, so the shift-inverted spectrum keeps them apart. At 1e-8
  /// (until 2026-11-29) σ was far below a fine mesh's lowest modes (−8.4e6 (rad/s)² against
  /// 29 to 3.4e5 for the 30 lowest of the 50 004-DOF frame): they all mapped to about 1/|σ|
  /// and Lanczos needed 8 restarts (297 solves) where 1e-12 needs none (74): 11.6 s → 2.1 s.
  double sparse_shift = 1e-12;

  /// True when every option is in range; else false with the violated condition in *why
  /// (Ceres style).
  bool IsValid(std::string* why) const {
    if (max_modes < 0) return *why = "max_modes (--max-modes) must be >= 0", false;
    if (sparse_threshold < 1) return *why = "sparse_threshold must be >= 1", false;
    if (!(rigid_tolerance >= 0.0)) return *why = "rigid_tolerance must be >= 0", false;
    if (!(rigid_frequency_hz >= 0.0)) return *why = "rigid_frequency_hz must be >= 0", false;
    if (!(sparse_shift > 0.0 && sparse_shift < 1.0)) return *why = "sparse_shift must be in (0, 1)", false;
    return true;
  }
};

/// Kinetic-energy share of each body (and "fe" for the FE part) in each mode.
struct EnergyShare {
  std::string body;
  std::vector<double> share;  ///< per mode of Solution::modes, 0..1
};

/// The assembled linear system at the operating point.
struct System {
  Eigen::SparseMatrix<double> mass;
  Eigen::SparseMatrix<double> stiffness;
  std::vector<std::string> dof_names;   ///< "carriage:ux", "fe:1234:uz"
  std::vector<SpringState> springs;
  /// Per spring (model order): its deflection δ = Σ coefficient × DOF, n·(u_a − u_b) along its
  /// direction (about it for rotational springs); the stiffness matrix holds k g gᵀ. Entries
  /// may repeat a DOF (add them).
  std::vector<std::vector<std::pair<int, double>>> spring_coefficients;
  /// Rows: test point x (+X,+Y,+Z), in ModeSet::dofs order; columns: system DOFs.
  Eigen::SparseMatrix<double> observation;
  std::vector<Dof> observed_dofs;
  std::vector<Node> geometry;           ///< test point positions
  int body_dof_count = 0;
};

struct Solution {
  /// Elastic modes: shapes at test points x (+X,+Y,+Z), real values stored as complex,
  /// mass-normalised (unit modal mass), damping from [damping], poles from (f, zeta).
  ModeSet modes;
  std::vector<double> rigid_body_frequencies_hz;  ///< zero modes, reported apart
  std::vector<SpringState> springs;
  std::vector<EnergyShare> energy;
  Eigen::MatrixXd full_shapes;                    ///< system DOFs x modes, mass-normalised
  std::vector<std::string> dof_names;
  bool sparse = false;                            ///< solved with the sparse shift-invert path
  /// Sparse path: how many times the eigen-solution applied (K − σM)⁻¹ M (one pair of triangular
  /// solves each; Spectra's num_operations). One Lanczos pass of `ncv` vectors when the lowest
  /// modes lie well apart after the shift-inversion (SolveOptions::sparse_shift); 0 when dense.
  int shift_invert_solves = 0;
  /// Usable but suspect results, each naming the model file (e.g. no elastic mode at all: an
  /// all-free model). `ema model` prints them on stderr as "warning: ...".
  std::vector<std::string> warnings;
};

/// What Assemble takes of the FE matrices ([fe] and its parts, scaled by their factors): all of
/// them, or none — bodies, springs and point masses only, on the same DOFs (the reduced model of
/// reduced.hpp adds the FE matrices through their projections).
enum class FeAssembly { kAll, kNone };

/// Assembles M and K at the operating point of `options.setup`.
System Assemble(const Model& model, const SolveOptions& options = {}, FeAssembly fe = FeAssembly::kAll);

/// Solves the model: applies pending effects, assembles, and solves the eigenproblem.
Solution Solve(const Model& model, const SolveOptions& options = {});

/// Human-readable explanation (ema model --explain): springs, chains, energy shares.
std::string Explain(const Solution& solution);

}  // namespace ema::model
