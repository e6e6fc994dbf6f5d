// PolyMAX (polyreference least-squares complex frequency-domain estimator, pLSCF):
// poles and participation factors for every model order 1..N from one build of the reduced
// normal equations (algorithms.md §2). Single-reference LSCF is the case m = 1.
#pragma once

#include <Eigen/Core>
#include <complex>
#include <limits>
#include <string>
#include <vector>

#include "ema/core/progress.hpp"
#include "ema/curvefit/fit_data.hpp"

namespace ema::curvefit {

struct PolymaxOptions {
  /// Highest polynomial order N (poles per order = m·p). 0 = automatic: ceil(120/m), clamped to
  /// what the number of lines supports.
  int order_max = 0;
  int order_min = 1;
  double damping_max = 0.2;  ///< hard criterion: 0 < zeta < damping_max (algorithms.md §3.1)
  /// Threads for the per-order solve + eigenvalue stage (orders are independent). 0 = hardware.
  int threads = 0;
};

/// One pole of one order (the member with Im(lambda) > 0).
struct Pole {
  int order = 0;
  std::complex<double> lambda;        ///< rad/s, window damping already removed
  std::complex<double> lambda_fitted; ///< rad/s as fitted (what the FRFs carry, for LSFD)
  double frequency_hz = 0.0;          ///< |lambda|/2pi
  double damping_ratio = 0.0;         ///< -Re(lambda)/|lambda|
  Eigen::VectorXcd participation;     ///< m entries, unit norm (m = 1: numerator shape, see below)
  /// For m = 1 the participation vector carries no information; `shape` is then B(Omega_r) at the
  /// outputs (unit norm), used for the vector-stability test. Empty for m >= 2.
  Eigen::VectorXcd shape;
  bool physical = false;  ///< passes the hard criteria: in band, 0 < zeta < damping_max
  char label = 'o';       ///< stabilisation: 'o' new, 'f' frequency, 'd' f+damping, 'v' f+vector, 's' all
  double match_distance = std::numeric_limits<double>::quiet_NaN();  ///< d_lambda + (1 - MAC) to its
                                                                      ///< previous-order match
};

/// Poles per order, plus what the diagram picture needs.
struct StabilisationDiagram {
  std::vector<std::vector<Pole>> orders;  ///< orders[k] holds order order_min + k
  int order_min = 1;
  int order_max = 0;
  int references = 1;
  double band_lo_hz = 0.0, band_hi_hz = 0.0;
  Eigen::VectorXd frequency_hz;           ///< lines of the band
  Eigen::VectorXd sum_frf;                ///< sum over all FRFs of |H| (mode indicator)
  bool zoom_mapped = false;               ///< the band was spread over the circle (FrequencyMap)
  std::vector<std::string> warnings;
};

/// Split of one estimation in seconds. CPU times are per-thread CPU clocks (summed over the
/// worker threads), which stay meaningful on a busy machine; wall times are elapsed time.
struct PolymaxTiming {
  double normal_equations = 0.0;  ///< CPU: FFT lag sums, Toeplitz blocks, Cholesky, elimination
  double solves = 0.0;            ///< CPU: per-order constrained LS solves for alpha
  double eigenvalues = 0.0;       ///< CPU: companion eigenproblems + participation vectors
  double normal_equations_wall = 0.0;
  double solve_and_eigen_wall = 0.0;  ///< wall time of the (threaded) per-order stage
};

/// CPU time of the calling thread (seconds).
double ThreadCpuSeconds();

/// Runs pLSCF on `data` for orders order_min..order_max. Throws InputError when there are fewer
/// lines than the requested order needs. `progress` gets the share of orders done, from the
/// per-order worker threads one at a time; what it throws stops every worker at its next order and
/// is rethrown here.
StabilisationDiagram EstimatePoles(const FitData& data, const PolymaxOptions& options,
                                   const ProgressCallback& progress = {}, PolymaxTiming* timing = nullptr);

/// How the band's frequencies map onto the unit circle, Omega = exp(-j w dt) (algorithms.md §2.9).
struct FrequencyMap {
  int fft_length = 0;        ///< N': dt = 1/(N' df), the lag sums are FFTs of this length
  double dt = 0.0;           ///< s
  /// 0 for the full-band map (f_hi at angle ~pi). For a zoom band (narrower than
  /// kZoomBandFraction of f_hi) the band is spread over most of the upper half circle and the
  /// frequencies below it wrap round; a pole's frequency is then its angle/dt plus this (rad/s).
  double alias_rad_s = 0.0;
};
/// Bands narrower than this fraction of their upper frequency get the zoom map.
inline constexpr double kZoomBandFraction = 0.125;
FrequencyMap MapBandToUnitCircle(const FitData& data);

/// Highest order the data support (lines needed per order) and the automatic default.
int MaxSupportedOrder(const FitData& data);
int DefaultOrderMax(const FitData& data);

}  // namespace ema::curvefit
