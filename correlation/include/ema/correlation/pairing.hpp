// Mode pairing by a linear assignment that maximises the total MAC (algorithms.md §5.4).
#pragma once

#include <string>

#include <Eigen/Core>
#include <vector>

namespace ema::correlation {

/// Minimum-cost assignment (Hungarian method with potentials, O(n^3)) for a rectangular cost
/// matrix. Returns, for every row, the column assigned to it, or -1 when the matrix has more rows
/// than columns and the row was left out. Every column is used at most once.
std::vector<int> SolveAssignment(const Eigen::MatrixXd& cost);

struct PairingOptions {
  /// Pairs need MAC ≥ mac_min (spec default 0.6). Pairs below it are not admissible at all, so
  /// a poor pair can never push a good one out of the assignment.
  double mac_min = 0.6;
  /// Weight of the relative frequency difference |f_t − f_m| / max(f_t, f_m) subtracted from the
  /// MAC in the assignment. The default is small: it only breaks ties (equal MAC, e.g. modes
  /// whose shapes the few shared DOFs cannot tell apart) in favour of the closer frequency.
  double frequency_weight = 1e-3;
  /// Pairs whose relative frequency difference exceeds this are rejected (1.0 = off in practice).
  double max_relative_frequency_difference = 1.0;

  /// True when every option is in range; else false with the violated condition in *why.
  bool IsValid(std::string* why) const {
    if (!(mac_min >= 0.0 && mac_min <= 1.0)) return *why = "mac_min (--mac-min) must lie in [0, 1]", false;
    if (!(frequency_weight >= 0.0)) return *why = "frequency_weight must be >= 0", false;
    if (!(max_relative_frequency_difference > 0.0)) return *why = "max_relative_frequency_difference must be > 0", false;
    return true;
  }
};

struct ModePair {
  int test = -1;   ///< index into the test modes
  int model = -1;  ///< index into the model modes
  double mac = 0.0;
};

struct Pairing {
  std::vector<ModePair> pairs;      ///< ordered by test index
  std::vector<int> unpaired_test;   ///< test-only modes
  std::vector<int> unpaired_model;  ///< model-only modes
};

/// Pairs test modes (rows of `mac`) with model modes (columns) so that the total MAC of the
/// admissible pairs is maximal. `test_hz` and `model_hz` are the frequencies (tie-break and
/// frequency gate).
Pairing PairModes(const Eigen::MatrixXd& mac, const Eigen::VectorXd& test_hz, const Eigen::VectorXd& model_hz,
                  const PairingOptions& options = {});

}  // namespace ema::correlation
