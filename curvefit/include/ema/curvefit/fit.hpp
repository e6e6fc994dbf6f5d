// The whole `ema fit` computation on an FrfSet: PolyMAX poles for every order, stabilisation
// labels, pole selection and LSFD shapes (or peak picking). No file I/O.
#pragma once

#include <string>
#include <vector>

#include "ema/core/names.hpp"
#include "ema/core/progress.hpp"
#include "ema/core/types.hpp"
#include "ema/curvefit/fit_data.hpp"
#include "ema/curvefit/lsfd.hpp"
#include "ema/curvefit/ml_refine.hpp"
#include "ema/curvefit/peak.hpp"
#include "ema/curvefit/polymax.hpp"
#include "ema/curvefit/stabilisation.hpp"

namespace ema::curvefit {

enum class FitMethod { kPolymax, kPeak };
/// `ema fit --method`.
inline constexpr EnumName<FitMethod> kFitMethodNames[] = {{FitMethod::kPolymax, "polymax"}, {FitMethod::kPeak, "peak"}};

/// Automatic selection's check for one mode fitted as two poles (roving-set inconsistency).
struct SplitPoleOptions {
  bool enabled = true;
  /// Two poles with overlapping half-power bands whose participation vectors (m >= 2) have at
  /// least this MAC are excited alike by the references...
  double participation_mac_min = 0.9;
  /// ...and whose |shape|^2 distributions (each summing to 1) share at most this much
  /// (sum over outputs of the smaller share) live on different outputs: one mode, two poles.
  double support_overlap_max = 0.35;
};

/// A pole automatic selection picked and then dropped, with the reason (MODES.json "dropped").
struct DroppedPole {
  double frequency_hz = 0.0;
  double damping_ratio = 0.0;
  double merged_into_hz = kNaN;  ///< the kept pole it duplicated
  std::string reason;
};

struct FitOptions {
  FitMethod method = FitMethod::kPolymax;
  FitDataOptions data;              ///< band, NaN handling, reciprocity
  PolymaxOptions polymax;           ///< orders
  StabilityOptions stability;       ///< 1 % / 5 % / MAC 0.98
  AutoSelectOptions auto_select;    ///< used when select_frequencies_hz is empty
  std::vector<double> select_frequencies_hz;  ///< --select F1,F2,..; empty = automatic
  LsfdOptions lsfd;
  PeakOptions peak;
  /// Narrow band: with at most this many lines in the band (few lines support few orders),
  /// automatic selection is also tried with relaxed criteria (SelectPolesNarrowBand), and that
  /// result is kept when it finds more modes. 0 = never.
  int narrow_band_max_lines = 100;
  /// `--refine`: ML refinement of the selected poles (default), or none (PolyMAX/LSFD values kept,
  /// their sigma still estimated at the PolyMAX poles).
  RefineMethod refine = RefineMethod::kMl;
  MlRefineOptions ml;
  /// Roving-sensor tests (FRFs that know their roving sets): the ML refinement fits each set's FRFs
  /// with that set's own poles — the same modes, shifted by the set's sensor masses — and reports
  /// each mode as the mean over the sets with every set's frequency (Mode::set_frequency_hz). The
  /// shapes are fitted with each set's poles. Falls back to one pole per mode for every FRF when a
  /// set's refinement is not usable.
  bool per_set_poles = true;
  SplitPoleOptions split_poles;  ///< automatic selection only

  /// True when the options a user sets are in range; else false with the violated condition in
  /// *why (Ceres style; the CLI option in parentheses).
  bool IsValid(std::string* why) const {
    if (!(data.band_lo_hz >= 0.0 && (data.band_hi_hz <= 0.0 || data.band_hi_hz > data.band_lo_hz)))
      return *why = "data band (--band): expected 0 <= low < high", false;
    if (polymax.order_max < 0) return *why = "polymax.order_max (--order-max) must be >= 0 (0: automatic)", false;
    if (polymax.threads < 0) return *why = "polymax.threads (--threads): expected 0 (all cores) or a positive count", false;
    for (const double f : select_frequencies_hz)
      if (!(f > 0.0)) return *why = "select_frequencies_hz (--select): frequencies must be positive", false;
    if (!(stability.frequency_tol > 0.0)) return *why = "stability.frequency_tol (--freq-tol) must be > 0", false;
    if (!(stability.damping_tol > 0.0)) return *why = "stability.damping_tol (--damping-tol) must be > 0", false;
    if (!(stability.mac_min >= 0.0 && stability.mac_min <= 1.0))
      return *why = "stability.mac_min (--mac-min) must lie in [0, 1]", false;
    return true;
  }
};

/// The narrow-band retry of automatic selection: stability labels recomputed with the damping
/// criterion relaxed to 20 % and clusters needing 3 orders instead of 4. Empty when the band
/// holds more than options.narrow_band_max_lines lines or the retry finds nothing; `note`
/// (optional) gets the warning that says what was relaxed.
std::vector<SelectedPole> SelectPolesNarrowBand(const StabilisationDiagram& diagram, const FitOptions& options,
                                                std::string* note = nullptr);

/// The modal model the fit produced, in the fitting orientation (FitData): FRF column c = o·m + i
/// is from reference `references[i]` to output `outputs[o]` (swapped back to the measured
/// orientation by reciprocity when `transposed`). Evaluate with SynthesiseFrf.
struct ModalModel {
  std::vector<Dof> outputs;
  std::vector<Dof> references;
  bool transposed = false;
  FrfType frf_type = FrfType::kAccelerance;
  double band_lo_hz = 0.0, band_hi_hz = 0.0;
  std::vector<std::complex<double>> poles_fitted;  ///< rad/s as the FRFs carry them (window included)
  Eigen::MatrixXcd residues;                       ///< (l·m) × N receptance residues (LSFD, phi l^T)
  Eigen::VectorXd lower_residual, upper_residual;  ///< l·m real residual terms (algorithms.md §1.9)
};

/// The model's FRF from reference i to output o (FitData indices) at `frequency_hz`.
Eigen::VectorXcd SynthesiseFrf(const ModalModel& model, int output, int reference, const Eigen::VectorXd& frequency_hz);

/// The model's FRF from `reference` to `response` named as the measured FRF set names them
/// (reciprocity undone when `transposed`), on the lines with f > 0 inside the model's band; NaN
/// elsewhere, and on every line when the model does not hold that FRF (nothing is re-fitted).
Eigen::VectorXcd SynthesiseMeasuredFrf(const ModalModel& model, const Dof& response, const Dof& reference,
                                       const Eigen::VectorXd& frequency_hz);

/// Seconds; stage figures are CPU times of the calling thread (see PolymaxTiming).
struct FitTiming {
  PolymaxTiming polymax;
  double stabilisation_and_selection = 0.0;
  double lsfd = 0.0;
  double refine = 0.0;  ///< ML refinement (CPU of the calling thread; its worker threads not included)
  double refine_wall = 0.0;
  double total = 0.0;  ///< wall
};

struct FitResult {
  ModeSet modes;                      ///< shapes at the fitted outputs (hammer points if transposed)
  StabilisationDiagram diagram;       ///< empty for the peak method
  std::vector<SelectedPole> selected; ///< the poles behind `modes`
  double synthesis_error = 0.0;       ///< LSFD relative residual
  bool transposed = false;
  /// What the user should act on (suspect data, a refinement that failed). What the fit handled
  /// itself — a pole dropped as the duplicate of a kept mode or as noise — is in `dropped`.
  std::vector<std::string> warnings;
  FitTiming timing;
  MlRefineSummary refine;             ///< what the refinement did (termination kFailed when not run)
  ModalModel model;                   ///< poles, residues and residual terms behind `modes`
  std::vector<DroppedPole> dropped;   ///< selected poles dropped (duplicates of a kept mode, noise poles)
  /// How the poles were chosen: "given frequencies" (--select), "automatic" (stable clusters) or
  /// "automatic, narrow band" (relaxed criteria: damping within 20 %, clusters over 3 orders).
  std::string selection_rule;
};

/// `source` names the input in messages: every InputError it throws for bad input (see
/// PrepareFitData and EstimatePoles) is placed there ("FRF.unv: polymax: ..."). `progress`: the
/// PolyMAX orders done ("poles", from the per-order threads), then the refinement's iterations and
/// the shapes, 1 when done; what it throws from any of those threads (`ema::Cancelled`) stops the
/// fit and reaches the caller.
FitResult Fit(const FrfSet& frfs, const FitOptions& options, const std::string& source = "FRF set",
              const ProgressCallback& progress = {});

}  // namespace ema::curvefit
