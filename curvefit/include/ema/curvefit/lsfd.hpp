// Mode shapes by least-squares frequency-domain fitting with known poles and participation
// factors, real lower and upper residuals (algorithms.md §4).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

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

/// Fits the shapes phi_r of H_o = sum_r phi_or l_r^T/(jw - lambda_r) + c.c. + residuals, with the
/// FRF-type factor (jw)^k so the unknowns are receptance residues (§1.9). Uses the fitted poles
/// (with window damping) and reports the corrected ones. Shapes are scaled to unit modal mass
/// where a driving point exists, otherwise to unit largest component.
LsfdResult EstimateModeShapes(const FitData& data, const std::vector<SelectedPole>& poles,
                              const LsfdOptions& options = {});

}  // namespace ema::curvefit
