// Stabilisation diagram labels and pole selection (algorithms.md §3).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "ema/curvefit/polymax.hpp"

namespace ema::curvefit {

struct StabilityOptions {
  double frequency_tol = 0.01;  ///< |f_p - f_{p-1}| / f_{p-1} below this: 'f'
  double damping_tol = 0.05;    ///< |zeta_p - zeta_{p-1}| / zeta_{p-1} below this: 'd'
  double mac_min = 0.98;        ///< MAC of participation vectors (m >= 2) or shapes (m = 1): 'v'
};

/// Labels every physical pole against the physical poles of the previous order, matched one to
/// one by greedy nearest relative frequency (the IMAT procedure). Non-physical poles keep 'o'.
void ClassifyStability(StabilisationDiagram* diagram, const StabilityOptions& options = {});

/// The vector a pole is compared by: participation (m >= 2) or numerator shape (m = 1).
const Eigen::VectorXcd& PoleVector(const Pole& pole);

/// |a^H b|^2 / (|a|^2 |b|^2); 1 for empty vectors (nothing to compare).
double Mac(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b);

/// A chosen pole and, for automatic selection, the statistics of its cluster.
struct SelectedPole {
  Pole pole;
  double frequency_spread_hz = 0.0;  ///< std. dev. of f over the cluster (one pole per order)
  double damping_spread = 0.0;       ///< std. dev. of zeta over the cluster
  int cluster_size = 1;              ///< orders the cluster spans
  int first_order = 0, last_order = 0;  ///< the lowest and highest order of its cluster (0: not from one)
};

struct AutoSelectOptions {
  /// Clustering cut-off on d = |dlambda|/max|lambda| + (1 - MAC). <= 0: data-driven, mean + 2 std
  /// of the stable poles' distances to their previous-order match, clamped to [0.005, 0.05].
  double cutoff = 0.0;
  /// A cluster must span at least max(min_orders, min_span_fraction × orders scanned) orders.
  int min_orders = 4;
  double min_span_fraction = 0.3;
  /// Clusters that never share an order and whose median frequencies differ by at most this
  /// (relative) are fragments of one column and are joined before the span test (a mode whose
  /// vector drifts along the orders, e.g. seen by roving sets that load it differently). <= 0: off.
  double fragment_frequency_tol = 0.01;
};

/// Fully automatic selection: hierarchical (average-linkage) clustering of the stable poles
/// ('s'; 'd' when there are no stable vectors) across orders; a column cut in two by a frequency
/// drift counts once (its upper part); clusters persisting over a wide
/// span of orders are kept; representative = the cluster medoid. Sorted by frequency.
std::vector<SelectedPole> SelectPolesAuto(const StabilisationDiagram& diagram, const AutoSelectOptions& options = {});

/// For each requested frequency, the stable pole nearest to it (falling back to 'd', 'f', then
/// any physical pole, highest order first on ties). Throws InputError when none is within 10 %.
std::vector<SelectedPole> SelectPolesNear(const StabilisationDiagram& diagram, const std::vector<double>& frequencies_hz);

}  // namespace ema::curvefit
