// Peak picking with half-power damping (thesis Eq. 4.44-4.45): a quick look, no curve fit.
#pragma once

#include "ema/core/types.hpp"
#include "ema/curvefit/fit_data.hpp"

namespace ema::curvefit {

struct PeakOptions {
  /// A local maximum of the mode indicator counts as a peak when it stands this factor above the
  /// higher of its two neighbouring valleys (2 = 6 dB).
  double prominence = 2.0;
};

/// Peaks of the weighted sum of |H| over every FRF; damping from the half-power bandwidth,
/// zeta = eta/2 with eta = (w_a^2 - w_b^2)/(2 w_r^2); shapes are H at the peak line for the
/// strongest reference, normalised to unit largest entry. Window damping is removed.
ModeSet PeakPick(const FitData& data, const PeakOptions& options = {});

}  // namespace ema::curvefit
