// The typed stages of the chain (COLMAP style): each `ema <x>` subcommand is parsing → the stage
// here → writing its files and printing (app/), and `ema run` (pipeline::Run) calls the same
// stages on the previous stages' typed results. A stage reads the inputs it is handed or names,
// computes, and returns data: it writes no file and prints no word.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "ema/core/progress.hpp"
#include "ema/core/types.hpp"
#include "ema/correlation/amplitude.hpp"
#include "ema/curvefit/fit.hpp"
#include "ema/diagnose/diagnose.hpp"
#include "ema/frf/hammer_frf.hpp"
#include "ema/model/model.hpp"
#include "ema/pipeline/findings.hpp"

namespace ema::pipeline {

// ---- FRFs (`ema frf`) ----

struct FrfStage {
  frf::FrfResult result;  ///< the FRFs as estimated and their summary (averages, rejected impacts)
  FrfSet stored;          ///< the FRFs as their file holds them (formats::StoredFrfSet)
  int file_count = 0;     ///< time-data files read (roving sets)
};

/// Reads each time-data file (one roving set each; UFF 58/58b, CSV, .mat), assembles the hammer
/// test and estimates every FRF. `binary`: the view of the file is 58b. UsageError for a file
/// given twice; InputError for bad data.
FrfStage EstimateFrfs(const std::vector<std::string>& time_files, const frf::FrfOptions& options, bool binary,
                      const ProgressCallback& progress = {});

// ---- modes (`ema fit`) ----

struct FitStage {
  curvefit::FitResult fit;        ///< modes (source = the FRFs' name), diagram, modal model, dropped poles
  ModeSet stored_modes;           ///< the modes as the modes file holds them (formats::StoredModeSet)
  curvefit::FitOptions options;   ///< as used
};

/// Fits `frfs` (named `source` in messages). `modes_path`: the modes file the result is for (the
/// stored view's source). InputError naming `source` when no mode is found, with what to change.
FitStage FitModes(const FrfSet& frfs, const curvefit::FitOptions& options, const std::string& source,
                  const std::string& modes_path, const ProgressCallback& progress = {});

// ---- diagnosis (`ema diagnose`) ----

struct DiagnoseStage {
  diagnose::Diagnosis diagnosis;
  diagnose::DiagnoseOptions options;  ///< as used (DIAG.json records them)
  Findings findings;                  ///< the first screen as numbers (pipeline::FindingsOf)
  model::Model updated;               ///< the model with rank 1's effects added
  /// With modes at two or more force levels: their amplitude analysis (as `ema amplitude`).
  std::optional<correlation::AmplitudeResult> nonlinearity;
};

/// Ranks the effects `model` misses against `tests` and finds what the first screen says.
/// `force_levels`: modes per impact force level (none, or at least two).
DiagnoseStage DiagnoseModel(const model::Model& model, const std::vector<diagnose::SetupModes>& tests,
                            const diagnose::DiagnoseOptions& options,
                            std::vector<correlation::AmplitudeLevel> force_levels = {},
                            const ProgressCallback& progress = {});

}  // namespace ema::pipeline
