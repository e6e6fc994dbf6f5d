// Mode indicator functions of an FRF matrix: the CMIF (singular values of H(w), outputs ×
// references, per frequency line) and the MMIF (the multivariate MIF, eigenvalues of the
// real-part energy ratio). They show close and repeated modes that the sum of |H| hides:
// two modes at nearly one frequency give one peak in the sum but a peak in the first and one in
// the second singular value (with two or more references). No file I/O.
#pragma once

#include <Eigen/Core>

#include "ema/curvefit/fit_data.hpp"

namespace ema::curvefit {

struct ModeIndicators {
  Eigen::VectorXd frequency_hz;  ///< the FitData lines (lines skipped for NaN hold NaN below)
  /// CMIF: lines × min(l, m) singular values of H(w), largest first (pyEMA/Ewins: CMIF).
  Eigen::MatrixXd cmif;
  /// MMIF: lines × m eigenvalues lambda of Re^T Re f = lambda (Re^T Re + Im^T Im) f, smallest
  /// first, each in [0, 1]; the smallest dips towards 0 at each resonance (as many dips at a
  /// frequency as modes there, up to m). Re/Im of receptance or accelerance; for mobility the
  /// FRFs are turned by -j first so the quadrature (resonant) part is again the imaginary one.
  Eigen::MatrixXd mmif;
};

/// CMIF and MMIF on every line of `data` (unweighted H, as measured).
ModeIndicators ComputeModeIndicators(const FitData& data);

}  // namespace ema::curvefit
