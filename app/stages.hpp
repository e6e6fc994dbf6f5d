// The edges of the `ema` commands (COLMAP style): each command is parsing (Parse<Name>Args: the
// command line → a <Name>Config), the typed stage (pipeline/stages.hpp, computing only), and the
// edge of its result: Write<Name> writes the files the config names through the one writer of each
// format, Print<Name> says what the command prints, CommandLine(config) is the command line that
// runs it. Run<Name>Stage is the three in a row. `ema run` (pipeline::Run) calls the same stages
// and app/run_outputs.cpp the same Write/Print functions on its RunResult.
#pragma once

#include <iosfwd>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ema/core/text.hpp"
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
#include "ema/pipeline/stages.hpp"

namespace ema::app {

using ema::ExactNumberText;  // core/text.hpp

/// `text` as one shell word (single-quoted when it holds anything but [A-Za-z0-9_./:=,+-]).
std::string ShellWord(const std::string& text);

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

/// nullopt when --help was given (usage printed). UsageError for a bad command line.
std::optional<FrfConfig> ParseFrfArgs(const std::vector<std::string>& args);
/// `ema frf`: pipeline::EstimateFrfs, then WriteFrf and PrintFrf (force bins: their own files;
/// the result is then empty).
pipeline::FrfStage RunFrfStage(const FrfConfig& config, std::ostream& out);
/// The FRF file and the --json summary the config names.
void WriteFrf(const FrfConfig& config, const pipeline::FrfStage& stage);
void PrintFrf(const pipeline::FrfStage& stage, std::ostream& out);
/// The command line that runs this config (`ema frf ...`, without "ema ").
std::string CommandLine(const FrfConfig& config);

// ---- ema fit ----

struct FitConfig {
  std::string input;                 ///< FRF file (names the FRFs in messages)
  std::string output;                ///< modes (UFF 55)
  std::string json_path, stabilisation_path, plot_path;
  curvefit::FitOptions options;
};

/// `require_input` false: only options (`ema pick`'s fit options, a project's [fit] args).
/// `base`: the options the arguments start from (their defaults), e.g. the project's [fit] keys.
/// `usage`: the usage line of the command whose arguments these are (`ema pick`), for --help and
/// the messages; "" = `ema fit`'s.
std::optional<FitConfig> ParseFitArgs(const std::vector<std::string>& args, bool require_input = true,
                                      const curvefit::FitOptions& base = {}, const std::string& usage = "");
/// `--select`: "auto" (empty) or F1,F2,... in Hz (UsageError otherwise).
std::vector<double> ParseSelect(const std::string& select);
/// `ema fit`: pipeline::FitModes of `frfs` (read from config.input by the command), then WriteFit
/// and PrintFit.
pipeline::FitStage RunFitStage(const FitConfig& config, const FrfSet& frfs, std::ostream& out);
/// Writes -o, --json (pipeline::FitModesJson), --stabilisation (pipeline::FitStabilisationJson), --plot.
void WriteFit(const FitConfig& config, const pipeline::FitStage& stage, const FrfSet& frfs);
/// The fit's notes and mode table; its warnings go to stderr.
void PrintFit(const FitConfig& config, const pipeline::FitStage& stage, std::ostream& out);
std::string CommandLine(const FitConfig& config);

// ---- ema model ----

struct ModelConfig {
  std::string model_path, output, json_path;
  model::SolveOptions options;       ///< setup, max_modes
  bool binary = false, explain = false;
};

std::optional<ModelConfig> ParseModelArgs(const std::vector<std::string>& args);
/// Solves `model` (read from config.model_path by the command), then WriteModel and PrintModel.
model::Solution RunModelStage(const ModelConfig& config, const model::Model& model, std::ostream& out);
void WriteModel(const ModelConfig& config, const model::Model& model, const model::Solution& solution);
/// The modes; the solver's warnings go to stderr.
void PrintModel(const ModelConfig& config, const model::Model& model, const model::Solution& solution, std::ostream& out);
std::string CommandLine(const ModelConfig& config);

// ---- ema correlate ----

struct CorrelateConfig {
  std::string test_path, model_path, setup, json_path, table_path;
  correlation::CorrelationOptions options;
  correlation::TableFormat table_format = correlation::TableFormat::kMarkdown;
};

std::optional<CorrelateConfig> ParseCorrelateArgs(const std::vector<std::string>& args);
correlation::CorrelationResult RunCorrelateStage(const CorrelateConfig& config, const ModeSet& test, const ModeSet& model,
                                                 std::ostream& out);
void WriteCorrelation(const CorrelateConfig& config, const correlation::CorrelationResult& result, const ModeSet& test,
                      const ModeSet& model);
/// The table; a geometry-unit guess goes to stderr where nodes were paired by distance.
void PrintCorrelation(const CorrelateConfig& config, const correlation::CorrelationResult& result, const ModeSet& test,
                      const ModeSet& model, std::ostream& out);
std::string CommandLine(const CorrelateConfig& config);

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

/// `require_inputs` false: only options (the `args` of a project file's [diagnose]). `base`: the
/// options the arguments start from.
std::optional<DiagnoseConfig> ParseDiagnoseArgs(const std::vector<std::string>& args, bool require_inputs = true,
                                                const diagnose::DiagnoseOptions& base = {});
/// `ema diagnose`: pipeline::DiagnoseModel (with the config's force levels read), then
/// WriteDiagnosis and PrintDiagnosis.
pipeline::DiagnoseStage RunDiagnoseStage(const DiagnoseConfig& config, const model::Model& model,
                                         const std::vector<diagnose::SetupModes>& tests, std::ostream& out);
/// DIAG.json (pipeline::DiagnosisJson) and the updated model (-o, rank 1's effects added to the file config.model_path).
void WriteDiagnosis(const DiagnoseConfig& config, const pipeline::DiagnoseStage& stage);
/// The first screen (DiagnosisSummary), the explanation, the ranking and the before/after table.
void PrintDiagnosis(const pipeline::DiagnoseStage& stage, std::ostream& out);
/// The first screen: what is missing, how sure, adequacy, look-alikes, what to check.
std::string DiagnosisSummary(const pipeline::DiagnoseStage& stage);
std::string CommandLine(const DiagnoseConfig& config);

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
/// Follows the modes over `levels` (formats::ReadAmplitudeLevels of config.level_args).
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
/// `ema simulate MODEL --plan PLAN -o OUT [--setup S] [--binary]`.
std::string CommandLine(const SimulateConfig& config);
/// "simulated 480 records: 4 roving set(s), 1 reference(s), 5 impacts each, 8 modes".
std::string SimulateSummary(const pipeline::SimulateStage& stage);

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
