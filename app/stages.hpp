// The typed stages of the `ema` commands (COLMAP style): each command is parsing
// (Parse<Name>Args: the command line → a <Name>Config) and a stage (Run<Name>Stage: the config and
// typed inputs → a typed result). The stage writes the files its config names, through the one
// writer of each format, and prints what the command prints to `out`; `ema run` (cmd_run.cpp)
// chains the stages on the typed results, with every stage's printout kept in OUTDIR/logs/.
#pragma once

#include <iosfwd>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ema/core/types.hpp"
#include "ema/correlation/amplitude.hpp"
#include "ema/correlation/correlate.hpp"
#include "ema/curvefit/complexity.hpp"
#include "ema/curvefit/fit.hpp"
#include "ema/diagnose/diagnose.hpp"
#include "ema/frf/hammer_frf.hpp"
#include "ema/formats/info.hpp"
#include "ema/formats/plan_file.hpp"
#include "ema/frf/quality.hpp"
#include "ema/model/model.hpp"
#include "ema/model/solve.hpp"
#include "ema/planning/plan.hpp"

namespace ema::app {

// ---- ema frf ----

struct FrfConfig {
  std::vector<std::string> inputs;   ///< time-data files, one per roving set
  std::string output;                ///< FRFs (UFF 58)
  std::string json_path;             ///< summary JSON ("" = none)
  frf::FrfOptions options;
  bool binary = false;               ///< 58b records
  int force_bins = 0;                ///< > 0: that many force-level bins
  std::vector<double> force_bin_edges;  ///< or bins between these peak forces, N
};

struct FrfStageResult {
  frf::FrfResult result;             ///< FRFs and summary (empty for force bins)
  nlohmann::json summary_json;       ///< what --json holds
  FrfSet stored;                     ///< what the FRF file holds (formats::StoredFrfSet)
};

/// nullopt when --help was given (usage printed). UsageError for a bad command line.
std::optional<FrfConfig> ParseFrfArgs(const std::vector<std::string>& args);
FrfStageResult RunFrfStage(const FrfConfig& config, std::ostream& out);

// ---- ema fit ----

struct FitConfig {
  std::string input;                 ///< FRF file (names the FRFs in messages)
  std::string output;                ///< modes (UFF 55)
  std::string json_path, stabilisation_path, plot_path;
  curvefit::FitOptions options;
};

struct FitStageResult {
  curvefit::FitResult fit;           ///< modes (source = the FRF file), diagram, modal model
  nlohmann::json modes_json;         ///< `ema fit --json`
  nlohmann::json stabilisation_json; ///< `ema fit --stabilisation` (with CMIF/MMIF)
  ModeSet stored_modes;              ///< what the modes file holds (formats::StoredModeSet)
  curvefit::RefineMethod refine = curvefit::RefineMethod::kMl;  ///< as configured
};

/// `require_input` false: only options (the `args` of a project file's [fit]).
std::optional<FitConfig> ParseFitArgs(const std::vector<std::string>& args, bool require_input = true);
/// `--select`: "auto" (empty) or F1,F2,... in Hz (UsageError otherwise).
std::vector<double> ParseSelect(const std::string& select);
/// Fits `frfs` (read from config.input by the command).
FitStageResult RunFitStage(const FitConfig& config, const FrfSet& frfs, std::ostream& out);

// ---- ema model ----

struct ModelConfig {
  std::string model_path, output, json_path;
  model::SolveOptions options;       ///< setup, max_modes
  bool binary = false, explain = false;
};

struct ModelStageResult {
  model::Solution solution;
  nlohmann::json json;               ///< `ema model --json`
};

std::optional<ModelConfig> ParseModelArgs(const std::vector<std::string>& args);
/// Solves `model` (read from config.model_path by the command); warnings go to stderr.
ModelStageResult RunModelStage(const ModelConfig& config, const model::Model& model, std::ostream& out);

// ---- ema correlate ----

struct CorrelateConfig {
  std::string test_path, model_path, setup, json_path, table_path;
  correlation::CorrelationOptions options;
  correlation::TableFormat table_format = correlation::TableFormat::kMarkdown;
};

struct CorrelateStageResult {
  correlation::CorrelationResult result;
  nlohmann::json json;               ///< `ema correlate --json`
};

std::optional<CorrelateConfig> ParseCorrelateArgs(const std::vector<std::string>& args);
CorrelateStageResult RunCorrelateStage(const CorrelateConfig& config, const ModeSet& test, const ModeSet& model,
                                       std::ostream& out);

// ---- ema diagnose ----

struct DiagnoseConfig {
  std::string model_path, json_path, output;
  std::vector<std::pair<std::string, std::string>> tests;  ///< (setup, modes file)
  std::vector<std::string> force_levels;                   ///< FORCE_N=MODES.unv
  diagnose::DiagnoseOptions options;
  /// --sensor-mass: kg of the transducer at each measured node of every test (cli.md, added turn 3).
  double sensor_mass = 0.0;
  /// --bundle: the files the written model names are copied beside it (formats::ModelWriteOptions).
  bool bundle = false;
};

struct DiagnoseStageResult {
  diagnose::Diagnosis diagnosis;
  nlohmann::json json;               ///< `ema diagnose --json`
  model::Model updated;              ///< the model with rank 1's effects added (what -o holds)
  std::string summary;               ///< the first screen: what is missing, how sure, adequacy, look-alikes
};

/// `require_inputs` false: only options (the `args` of a project file's [diagnose]).
std::optional<DiagnoseConfig> ParseDiagnoseArgs(const std::vector<std::string>& args, bool require_inputs = true);
DiagnoseStageResult RunDiagnoseStage(const DiagnoseConfig& config, const model::Model& model,
                                     const std::vector<diagnose::SetupModes>& tests, std::ostream& out);

// ---- ema quality ----

struct QualityConfig {
  std::vector<std::string> inputs;   ///< FRF files (names in messages and the report)
  std::string modes_path, json_path;
  frf::QualityOptions quality;
  curvefit::ComplexityOptions complexity;
};

struct QualityStageResult {
  frf::FrfQualityReport frfs;
  std::vector<curvefit::ModeComplexityCheck> modes;
  nlohmann::json json;               ///< `ema quality --json`
};

std::optional<QualityConfig> ParseQualityArgs(const std::vector<std::string>& args);
/// Checks `sets` (one per input) and, when given, the complexity of `modes`.
QualityStageResult RunQualityStage(const QualityConfig& config, const std::vector<FrfSet>& sets,
                                   const std::optional<ModeSet>& modes, std::ostream& out);

// ---- ema info ----

struct InfoConfig {
  std::string file, json_path;
};

std::optional<InfoConfig> ParseInfoArgs(const std::vector<std::string>& args);
formats::FileSummary RunInfoStage(const InfoConfig& config, std::ostream& out);

// ---- ema amplitude ----

struct AmplitudeConfig {
  std::vector<std::string> level_args;  ///< LEVEL=MODES.unv
  correlation::LevelKind kind = correlation::LevelKind::kPeakForce;
  std::string json_path, report_path;
  correlation::AmplitudeOptions options;
};

std::optional<AmplitudeConfig> ParseAmplitudeArgs(const std::vector<std::string>& args);
/// Follows the modes over `levels` (app::ReadAmplitudeLevels of config.level_args).
correlation::AmplitudeResult RunAmplitudeStage(const AmplitudeConfig& config,
                                               std::vector<correlation::AmplitudeLevel> levels, std::ostream& out);

// ---- ema simulate ----

struct SimulateConfig {
  std::string model_path, plan_path, output;
  std::string setup;                 ///< overrides the plan's setup when given
  bool binary = false;
};

std::optional<SimulateConfig> ParseSimulateArgs(const std::vector<std::string>& args);
/// Simulates the test `plan` of `model` and writes the time records (config.output).
std::vector<TimeRecord> RunSimulateStage(const SimulateConfig& config, const model::Model& model, formats::Plan plan,
                                         std::ostream& out);

// ---- ema plan ----

struct PlanConfig {
  std::string model_path, output, json_path;
  std::string candidates_path;       ///< DIAG.json whose rank 1 and look-alikes the plan separates
  std::string keep_path;             ///< an earlier plan whose sets stay
  planning::PlanOptions options;
};

struct PlanStageResult {
  planning::TestPlan plan;
  formats::Plan file;                ///< what PLAN.toml holds
  nlohmann::json json;               ///< `ema plan --json`
};

std::optional<PlanConfig> ParsePlanArgs(const std::vector<std::string>& args);
/// Plans the test of `model` (read from config.model_path by the command) to tell `readings`
/// apart (none: for the modes alone), extending `keep` when given; writes PLAN.toml (and JSON).
PlanStageResult RunPlanStage(const PlanConfig& config, const model::Model& model,
                             const std::vector<planning::Reading>& readings, const std::optional<formats::Plan>& keep,
                             std::ostream& out);

}  // namespace ema::app
