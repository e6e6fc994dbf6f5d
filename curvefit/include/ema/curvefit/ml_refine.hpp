// Maximum-likelihood refinement of a modal model (poles, residues, residual terms) against the
// measured FRFs, with the poles' uncertainty from the Fisher information (algorithms.md §2.11:
// the LS PolyMAX estimate is biased under noise; an ML frequency-domain refinement started from
// it removes the bias and gives confidence bounds).
//
// Model of FRF c = (output o, reference i) at line f (receptance residues, the FRF-type factor
// (jw)^k as in LSFD, algorithms.md §1.9):
//
//   H_c(w) = (jw)^k [ sum_r R_cr/(jw - lambda_r) + conj(R_cr)/(jw - conj(lambda_r))
//                     + LR_c/(jw)^2 + UR_c ]
//
// with poles lambda_r shared by every FRF, complex residues R_cr and real residual terms per FRF
// (no rank-one constraint: the classic single-reference LSFD model, §4.1). The cost is
//
//   sum_c sum_f |H_c(w_f) - model|^2 / sigma_c^2(f)      (complex Gaussian noise, ML)
//
// Structure exploited (variable projection, Golub-Pereyra with Kaufman's Jacobian): for given
// poles the residues are a weighted linear LS problem per FRF, so the non-linear solver (Ceres,
// Levenberg-Marquardt) sees only the 2N pole parameters; the per-FRF linear parameters are
// eliminated exactly (the reduced Gauss-Newton matrix is the Schur complement of the full one).
// The noise variance is modelled piecewise constant over S frequency segments per FRF, so every
// per-line product is shared by all FRFs: the work per iteration is one real matrix product of
// (p + 2N) basis columns with the data, plus O(S (p + 2N)^2) per FRF.
#pragma once

#include <Eigen/Core>
#include <complex>
#include <string>
#include <vector>

#include "ema/core/names.hpp"
#include "ema/core/progress.hpp"
#include "ema/curvefit/fit_data.hpp"
#include "ema/curvefit/stabilisation.hpp"

namespace ema::curvefit {

/// `ema fit --refine`: what follows PolyMAX/LSFD.
enum class RefineMethod { kNone, kMl };
inline constexpr EnumName<RefineMethod> kRefineMethodNames[] = {{RefineMethod::kMl, "ml"}, {RefineMethod::kNone, "none"}};
std::string RefineMethodToString(RefineMethod method);
/// "none" or "ml"; false for anything else.
bool StringToRefineMethod(const std::string& text, RefineMethod* method);

/// Where the noise variance of each FRF line came from.
enum class NoiseSource {
  kCoherence,  ///< var = |H|^2 (1 - coh) / (n_avg coh), pooled over frequency segments
  kResidual,   ///< per-FRF constant, from the residual of the fit itself
};
std::string NoiseSourceToString(NoiseSource source);

struct MlRefineOptions {
  int max_iterations = 50;             ///< Levenberg-Marquardt iterations per solve
  /// Ceres: relative cost change to stop. The cost is ~ the number of residuals, so 1e-9 is far
  /// below a change of one unit (a pole moving by a small fraction of its sigma).
  double function_tolerance = 1e-9;
  double parameter_tolerance = 1e-10;  ///< Ceres: relative pole step to stop (|lambda| ~ 1e3 rad/s)
  bool lower_residual = true;          ///< real lower residual term per FRF (as LSFD)
  bool upper_residual = true;          ///< real upper residual term per FRF
  /// Use FitData::noise_variance (from coherence) when present; otherwise (or when false) the
  /// variance is estimated per FRF from the fit residual.
  bool use_coherence = true;
  /// Frequency segments over which the coherence-based variance is pooled (each segment's
  /// variance is the mean of its lines'). Fewer segments: steadier weights; more: closer to
  /// per-line weights. Clamped to the line count / 8.
  int noise_segments = 32;
  /// Refinement is rejected (PolyMAX poles kept, with a warning) when a pole moves by more than
  /// this many of its half-power bandwidths (2 zeta w) or leaves 0 < zeta < 1.
  double max_pole_shift_bandwidths = 2.0;
  /// With a measured noise level (coherence), a refined model whose misfit stays above this many
  /// times the noise (reduced chi-square) is not the ML estimate of anything: the modal model
  /// misses part of the data (leakage of a truncated record, roving-sensor mass loading,
  /// non-linearity) and the high-order PolyMAX poles are the better estimate. The refinement is
  /// then rejected (PolyMAX poles kept, sigma still given, inflated by the misfit).
  double max_reduced_chi2 = 3.0;
  /// Keep the given poles and only compute their uncertainty and the residues (`--refine none`).
  bool estimate_only = false;
  /// Worker threads for the per-FRF stage (0 = hardware).
  int threads = 0;

  /// false with a message naming the field when an option is out of range.
  bool IsValid(std::string* error) const;
};

enum class RefineTermination {
  kConverged,       ///< Ceres converged; refined values used
  kNoConvergence,   ///< iteration limit; refined values used (cost still decreased)
  kRejected,        ///< result implausible (see message); PolyMAX values kept
  kFailed,          ///< numerical failure; PolyMAX values kept
};
std::string RefineTerminationToString(RefineTermination termination);

/// One pole after refinement, with its 1-sigma uncertainty.
struct RefinedPole {
  std::complex<double> lambda_fitted;  ///< rad/s as in the FRFs (window damping included)
  std::complex<double> lambda;         ///< rad/s, window damping removed
  double frequency_hz = 0.0;
  double damping_ratio = 0.0;
  double frequency_std_hz = kNaN;      ///< 1 sigma from the Fisher information
  double damping_ratio_std = kNaN;
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Constant(kNaN);  ///< of (Re, Im) lambda, (rad/s)^2
  /// Wald statistic of the pole's residues over all FRFs against zero (sum of R^T Cov^-1 R), and
  /// its degrees of freedom (2 per FRF): a pole whose statistic is near its degrees of freedom
  /// explains nothing but noise.
  double residue_chi2 = 0.0;
  int residue_dof = 0;
};

struct MlRefineSummary {
  RefineTermination termination = RefineTermination::kFailed;
  std::string message;
  NoiseSource noise_source = NoiseSource::kResidual;
  int iterations = 0;
  double initial_cost = 0.0;      ///< sum of squared normalised residuals at the PolyMAX poles
  double final_cost = 0.0;
  double reduced_chi2 = kNaN;     ///< final_cost / (residuals - parameters); ~1 when the noise model fits
  double seconds = 0.0;           ///< CPU time of the calling thread
  bool uncertainty_only = false;  ///< MlRefineOptions::estimate_only: the poles were kept, only σ computed
  /// Every refined pole stayed stable and inside its neighbourhood: true when the result is usable
  /// and when only the misfit test rejected it (the poles then say nothing wrong, the data's
  /// misfit does), false when a pole was pulled away or the solve failed.
  bool poles_plausible = false;

  std::string BriefReport() const;
  bool IsSolutionUsable() const {
    return termination == RefineTermination::kConverged || termination == RefineTermination::kNoConvergence;
  }
};

/// The refined modal model in FitData's orientation: FRF column c = o·m + i.
struct MlRefineResult {
  std::vector<RefinedPole> poles;   ///< same order as the input poles
  Eigen::MatrixXcd residues;        ///< (l·m) × N receptance residues R_cr (free per FRF)
  Eigen::MatrixXd residue_std;      ///< (l·m) × N: 1 sigma of |R_cr| (poles held fixed)
  Eigen::VectorXd lower_residual;   ///< l·m (zero when not fitted)
  Eigen::VectorXd upper_residual;   ///< l·m
  MlRefineSummary summary;
};

/// Refines `poles` (their lambda_fitted) against `data`. Never throws for numerical trouble: the
/// summary says what happened and, when not usable, the poles are returned unchanged (σ still
/// computed at the PolyMAX poles where possible). Throws InputError when there are fewer lines
/// than unknowns per FRF. `progress` gets the share of the iteration limit used, at the start and
/// after each Levenberg-Marquardt iteration; what it throws (a cancellation) stops the solver
/// and reaches the caller.
MlRefineResult RefineModalModel(const FitData& data, const std::vector<SelectedPole>& poles,
                                const MlRefineOptions& options = {}, const ProgressCallback& progress = {});

/// Standard deviations of f = |lambda|/2pi and zeta = -Re lambda/|lambda| from the covariance of
/// (Re lambda, Im lambda) (first-order propagation).
void PoleStdToFrequencyAndDamping(std::complex<double> lambda, const Eigen::Matrix2d& covariance,
                                  double* frequency_std_hz, double* damping_ratio_std);

}  // namespace ema::curvefit
