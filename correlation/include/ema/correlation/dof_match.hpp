// Matching test DOFs to model (FE) DOFs (algorithms.md §5.1): by node id, an id map, or the
// nearest model node within a tolerance; directions by sign and, when a test node's measurement
// frame is rotated with respect to the model's global frame, by projection.
#pragma once

#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

#include "ema/core/types.hpp"

namespace ema::correlation {

struct DofMatchOptions {
  /// Explicit test node id → model node id. Takes precedence over everything else.
  std::map<int, int> node_map;
  /// When > 0 and both sets carry geometry: a test node without an explicit or same-id match is
  /// matched with the nearest model node closer than this (metres). 0 = off.
  double tolerance_m = 0.0;
  /// Optional measurement frames of test nodes (dataset 18/2420 displacement coordinate
  /// systems): columns are the node's local X, Y, Z axes in the model's global frame. A test DOF
  /// along local axis d then measures n_d · u of the model node. Nodes not listed use identity.
  std::map<int, Eigen::Matrix3d> test_frames;
};

/// One shared DOF: the test DOF and the weighted model DOFs whose sum it measures.
struct SharedDof {
  int test_index = -1;           ///< into the test ModeSet::dofs
  Dof test_dof;
  int model_node = 0;
  std::vector<std::pair<int, double>> model_terms;  ///< (index into model dofs, weight)
};

struct DofMatch {
  std::vector<SharedDof> shared;
  std::vector<Dof> test_only;    ///< test DOFs the model could not provide
  int nodes_by_id = 0, nodes_by_map = 0, nodes_by_distance = 0;

  int Count() const { return static_cast<int>(shared.size()); }
  /// Test shapes restricted to the shared DOFs: one column per mode.
  Eigen::MatrixXcd TestShapes(const ModeSet& test) const;
  /// Model shapes projected onto the shared DOFs: one column per mode.
  Eigen::MatrixXcd ModelShapes(const ModeSet& model) const;
};

/// Matches the DOFs of `test` to those of `model`. Never throws for an empty result (the caller
/// decides: Correlate throws an InputError when nothing is shared).
DofMatch MatchDofs(const ModeSet& test, const ModeSet& model, const DofMatchOptions& options = {});

}  // namespace ema::correlation
