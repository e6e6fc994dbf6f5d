// Mode shapes by least-squares frequency-domain fitting with known poles and participation
// factors, real lower and upper residuals (algorithms.md §4).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "ema/core/progress.hpp"
#include "ema/core/types.hpp"
#include "ema/curvefit/fit_data.hpp"
#include "ema/curvefit/stabilisation.hpp"

namespace ema::curvefit {

struct LsfdOptions {
  bool lower_residual = true;
  bool upper_residual = true;
};

struct LsfdResult {
  ModeSet modes;                     ///< one mode per pole, shapes at FitData::outputs
  Eigen::MatrixXcd residues;         ///< (l·m) × N receptance residues phi_or·l_ir (column per mode)
  Eigen::VectorXd lower_residual;    ///< l·m real lower residual terms LR_oi (0 when not fitted), §1.9 form
  Eigen::VectorXd upper_residual;    ///< l·m real upper residual terms UR_oi (0 when not fitted)
  double synthesis_error = 0.0;      ///< ||H - H_fit|| / ||H|| over the band (weighted as fitted)
  std::vector<std::string> warnings; ///< e.g. driving-point residues of the wrong sign
};

/// Roving-sensor tests: per roving set, the outputs measured in it and the poles (lambda_fitted,
/// one per mode) its FRFs are fitted with — the same modes, seen at each set's own frequency.
struct SetPoles {
  std::vector<std::vector<int>> outputs;
  std::vector<std::vector<std::complex<double>>> lambda_fitted;
};

/// Fits the shapes phi_r of H_o = sum_r phi_or l_r^T/(jw - lambda_r) + c.c. + residuals, with the
/// FRF-type factor (jw)^k so the unknowns are receptance residues (§1.9). Uses the fitted poles
/// (with window damping) and reports the corrected ones. Shapes are scaled to unit modal mass
/// where a driving point exists, otherwise to unit largest component.
/// With `set_poles`, each set's outputs are fitted with that set's poles (the participation
/// factors stay common, so the shapes of all sets are scaled alike). `progress` gets the share done
/// ("mode shapes"); what it throws (a cancellation) stops the fit and reaches the caller.
LsfdResult EstimateModeShapes(const FitData& data, const std::vector<SelectedPole>& poles,
                              const LsfdOptions& options = {}, const SetPoles* set_poles = nullptr,
                              const ProgressCallback& progress = {});

}  // namespace ema::curvefit
