// The whole `ema fit` computation on an FrfSet: PolyMAX poles for every order, stabilisation
// labels, pole selection and LSFD shapes (or peak picking). No file I/O.
#pragma once

#include <string>
#include <vector>

#include "ema/core/progress.hpp"
#include "ema/core/types.hpp"
#include "ema/curvefit/fit_data.hpp"
#include "ema/curvefit/lsfd.hpp"
#include "ema/curvefit/peak.hpp"
#include "ema/curvefit/polymax.hpp"
#include "ema/curvefit/stabilisation.hpp"

namespace ema::curvefit {

enum class FitMethod { kPolymax, kPeak };

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
};

/// The narrow-band retry of automatic selection: stability labels recomputed with the damping
/// criterion relaxed to 20 % and clusters needing 3 orders instead of 4. Empty when the band
/// holds more than options.narrow_band_max_lines lines or the retry finds nothing; `note`
/// (optional) gets the warning that says what was relaxed.
std::vector<SelectedPole> SelectPolesNarrowBand(const StabilisationDiagram& diagram, const FitOptions& options,
                                                std::string* note = nullptr);

/// Seconds; stage figures are CPU times of the calling thread (see PolymaxTiming).
struct FitTiming {
  PolymaxTiming polymax;
  double stabilisation_and_selection = 0.0;
  double lsfd = 0.0;
  double total = 0.0;  ///< wall
};

struct FitResult {
  ModeSet modes;                      ///< shapes at the fitted outputs (hammer points if transposed)
  StabilisationDiagram diagram;       ///< empty for the peak method
  std::vector<SelectedPole> selected; ///< the poles behind `modes`
  double synthesis_error = 0.0;       ///< LSFD relative residual
  bool transposed = false;
  std::vector<std::string> warnings;
  FitTiming timing;
};

/// `source` names the input in messages. Throws InputError for bad input (see PrepareFitData and
/// EstimatePoles).
FitResult Fit(const FrfSet& frfs, const FitOptions& options, const std::string& source = "FRF set",
              const ProgressCallback& progress = {});

}  // namespace ema::curvefit
