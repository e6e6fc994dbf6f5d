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
#include "ema/acquisition/hammer_measurement.hpp"
#include "ema/diagnose/diagnose.hpp"
#include "ema/formats/plan_file.hpp"
#include "ema/frf/hammer_frf.hpp"
#include "ema/model/model.hpp"
#include "ema/pipeline/findings.hpp"

namespace ema::pipeline {

// ---- a simulated test (`ema simulate`; a project test's plan = "PLAN.toml") ----

struct SimulateStage {
  std::vector<TimeRecord> records;  ///< force and response records of every roving set and impact
  bool in_time = false;             ///< integrated in time (the plan's integration = "time")
  int sets = 0, references = 0, impacts_per_reference = 0;
  int force_levels = 0;             ///< the plan's force levels (0: one peak force)
  int modes = 0;                    ///< modal: the modes of the truth (the first set's)
  int nonlinear_elements = 0;       ///< in time: springs whose law is non-linear in time
  bool undamped = false;            ///< a mode of the truth has no damping: the records will not decay
};

/// The roving hammer test `plan` on `model` (docs/plan-format.md; the plan's setup is used: set it
/// before to override it): per roving set the model with that set's sensor masses is solved and its
/// modes — or, with integration = "time", its non-linear springs integrated in time — give the
/// records. `model_path`, `plan_path` name the files in messages. InputError naming the plan for a
/// point the model does not have.
SimulateStage SimulateTest(const model::Model& model, const formats::Plan& plan, const std::string& model_path,
                           const std::string& plan_path, const ProgressCallback& progress = {});

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
/// The same from records in memory (a simulated test): one RecordSet per roving set or file.
FrfStage EstimateFrfs(std::vector<acquisition::RecordSet> sets, const frf::FrfOptions& options, bool binary,
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
