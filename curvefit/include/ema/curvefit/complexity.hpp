// Complexity of mode shapes: MPC, MPD and MCF, and a pass/warn verdict per mode (the data-quality
// stage of `ema quality --modes`; the FRF checks are in ema/frf/quality.hpp). No file I/O.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "ema/core/types.hpp"
#include "ema/frf/quality.hpp"

namespace ema::curvefit {

/// MPC (eigenvalue form, 0..1, 1 = real mode) and MPD (degrees, 0 = real mode), §4.4. NaN for
/// a zero (MPC) or empty (MPD) shape.
double ModalPhaseCollinearity(const Eigen::VectorXcd& shape);
double MeanPhaseDeviationDeg(const Eigen::VectorXcd& shape);

/// Mode complexity factor (pyEMA/sdypy: MCF): 1 - |phi^T phi|^2 / (phi^H phi)^2, i.e.
/// 1 - ((Sxx - Syy)^2 + 4 Sxy^2) / (Sxx + Syy)^2 with Sxx = Re.Re, Syy = Im.Im, Sxy = Re.Im.
/// 0 for a real (monophase) shape whatever its global phase, 1 for a circular one (a travelling
/// wave, phi and j·phi equally strong). It is the complement of the eigenvalue form of MPC,
/// reported beside it because test reports quote it under this name. NaN for a zero shape.
double ModeComplexityFactor(const Eigen::VectorXcd& shape);

struct ComplexityOptions {
  double mpc_min = 0.9;    ///< a mode warns below this MPC (normal modes of a lightly damped structure: > 0.95)
  double mpd_max_deg = 10.0;  ///< ... or above this MPD [degrees]
  bool IsValid(std::string* error) const;
};

struct ModeComplexityCheck {
  int index = 0;           ///< 0-based mode number in the set
  double frequency_hz = kNaN;
  double mpc = kNaN, mpd_deg = kNaN, mcf = kNaN;
  frf::Verdict verdict = frf::Verdict::kPass;
  std::string reason;
};

/// MPC, MPD and MCF of each mode's shape (recomputed from the shape, not read from the Mode).
std::vector<ModeComplexityCheck> CheckModeComplexity(const ModeSet& modes, const ComplexityOptions& options = {});

}  // namespace ema::curvefit
