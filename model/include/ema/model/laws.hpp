// Interface laws at their operating point (model-format.md "Laws"): the force, compression and
// linearised stiffness of one law, defined in laws.cpp. solve.hpp assembles them into K.
#pragma once

#include <string>
#include <vector>

#include "ema/core/types.hpp"
#include "ema/model/model.hpp"

namespace ema::model {

/// The operating point and linearised stiffness of one spring (for --explain and diagnosis).
struct SpringState {
  std::string name;
  std::string group;
  std::string law;           ///< law kind name
  double force = 0.0;        ///< N (N m for rotational), compression positive
  double deflection = 0.0;   ///< compression of the whole law, m
  double stiffness = 0.0;    ///< linearised stiffness incl. stiffness_factor, N/m
  /// Series chains: solved air gap (NaN without air film) and each element's compression and
  /// stiffness, in element order.
  double gap = kNaN;
  std::vector<double> element_deflections;
  std::vector<double> element_stiffnesses;
};

/// Operating point and linearised stiffness of one law. `override_value` (NaN = none) replaces
/// the law's operating value. Throws InputError (with `where`) when there is no equilibrium or
/// the operating point lies outside a table.
SpringState LinearizeLaw(const Law& law, const std::string& where, double override_value = kNaN);

}  // namespace ema::model
