// `ema run` as a library: a typed RunPlan (the project file, read and validated once by
// formats::ReadProjectFile) → pipeline::Run → a typed RunResult holding every stage's result.
// Run reads the inputs the plan names (time data, FRFs, the model) and writes nothing; every
// output — the files of OUTDIR, the terminal summary, the HTML report, Python's dicts — is a
// function of the RunResult (app/run_outputs.hpp, app/report).
#pragma once

#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "ema/core/progress.hpp"
#include "ema/correlation/correlate.hpp"
#include "ema/formats/project_file.hpp"
#include "ema/frf/quality.hpp"
#include "ema/model/solve.hpp"
#include "ema/pipeline/stages.hpp"
#include "ema/planning/plan.hpp"

namespace ema::pipeline {

/// A run's stages, in the order they run for each test (the diagnosis runs once, between);
/// kSimulate comes first for a test the project simulates from a plan (a rehearsal).
enum class StepKind { kFrf, kFit, kModelBefore, kCorrelateBefore, kDiagnose, kModelAfter, kCorrelateAfter, kSimulate };

enum class StepStatus {
  kDone,
  kFailed,   ///< threw: `error` holds the message
  kSkipped,  ///< a stage it needs failed or gave nothing: `error` holds why
  kGiven,    ///< not needed: the project gives its result (FRFs from a file)
};

struct StepRecord {
  StepKind kind = StepKind::kFrf;
  int test = -1;                 ///< index into RunPlan::project.tests; -1 for the diagnosis
  StepStatus status = StepStatus::kDone;
  std::string error;
};

/// What a `pick = true` test's picker returns: the frequencies picked (empty: automatic
/// selection), or nullopt when Done was pressed with nothing picked (the project's selection stays).
using PickResult = std::optional<std::vector<double>>;
/// Opens the picker on one test's FRFs with the fit's options; throws RunStopped to stop the run.
using PickHook =
    std::function<PickResult(const formats::ProjectTest& test, const FrfSet& frfs, const curvefit::FitOptions& fit)>;

/// Thrown by a PickHook when the user stopped the run (Ctrl-C, SIGTERM) while picking.
class RunStopped : public std::runtime_error {
 public:
  RunStopped(int signal, std::string test) : std::runtime_error("stopped while picking " + test), signal_(signal), test_(std::move(test)) {}
  int signal() const { return signal_; }
  const std::string& test() const { return test_; }

 private:
  int signal_;
  std::string test_;
};

struct RunPlan {
  formats::Project project;          ///< tests, model, the steps' typed options ([frf], [fit], [diagnose])
  /// The folder the run's files go to: it names the results' sources (the modes file a correlation
  /// read, the updated model's origin) exactly as the subcommands run one after the other would.
  std::filesystem::path output_dir;
  PickHook pick;                     ///< for `pick = true` tests; empty: their selection is used
};

/// A plan from a project file read by formats::ReadProjectFile.
RunPlan PlanFromProject(formats::Project project, std::filesystem::path output_dir);

/// Per test: each stage's typed result, empty where it failed or was skipped.
struct TestResult {
  std::optional<SimulateStage> simulated;      ///< a planned test (plan = "PLAN.toml"): its records
  std::optional<FrfStage> frf;                 ///< estimated in this run (not when the project gives FRFs)
  std::optional<FrfSet> frfs;                  ///< the FRFs of the test as stored: estimated or the project's file
  curvefit::FitOptions fit_options;            ///< as the fit used them (band, order, selection)
  bool picked_by_hand = false;                 ///< the selection was picked in `ema pick` during the run
  std::optional<FitStage> fit;
  std::optional<model::Solution> model_before, model_after;  ///< modes' source = the model file
  std::optional<correlation::CorrelationResult> correlation_before, correlation_after;
  /// The data-quality checks of the FRFs in the fit band (the report's "Data quality").
  std::optional<frf::FrfQualityReport> quality;
  frf::QualityOptions quality_options;
};

/// A problem that is not a failed step: a picker that could not start, a check that could not run.
struct RunProblem {
  int test = -1;
  std::string what;        ///< "pick", "data-quality checks", "FRFs"
  std::string error;       ///< the error's message
};

/// When rank 1 has look-alikes: the test that would tell them apart — one more roving set beside
/// a test's own sets and references, chosen to separate the readings (`ema plan --candidates
/// --keep`, docs/plan.md).
struct NextTest {
  int test = 0;                       ///< the test it extends (its setup, roving sets, references)
  std::vector<std::string> readings;  ///< the readings it separates ("kind on target"), rank 1 first
  planning::TestPlan plan;            ///< the test's own sets first (`kept_sets` of them), then the new one
  int kept_sets = 0;
};

struct RunResult {
  RunPlan plan;
  std::optional<model::Model> nominal;         ///< the model as given; empty when it cannot be read
  std::string nominal_error;
  std::vector<TestResult> tests;               ///< one per plan.project.tests
  std::optional<DiagnoseStage> diagnosis;      ///< over every test with modes
  std::optional<NextTest> next_test;           ///< when rank 1 has look-alikes and a test could be planned
  std::string next_test_error;                 ///< why it could not be planned ("" otherwise)
  std::vector<StepRecord> steps;               ///< every step, in the order run
  std::vector<RunProblem> problems;
  /// Mean agreement (%) and MAC over the tests' correlations with the nominal and the updated
  /// model; NaN when none.
  double mean_agreement_before = std::numeric_limits<double>::quiet_NaN();
  double mean_mac_before = mean_agreement_before, mean_agreement_after = mean_agreement_before,
         mean_mac_after = mean_agreement_before;

  /// The updated model's file name in output_dir ("updated-model.toml").
  std::filesystem::path UpdatedModelPath() const { return plan.output_dir / "updated-model.toml"; }
  /// A planned test's simulated time data (OUTDIR/<test>/time.unv, UFF 58b).
  std::filesystem::path TimePath(std::size_t test) const;
  /// The model a planned test is simulated on: its `truth`, else the project's model.
  std::filesystem::path TruthPath(std::size_t test) const;
  /// The FRFs a test's fit reads: the project's FRF file, else the one the run estimates
  /// (OUTDIR/<test>/frf.unv).
  std::filesystem::path FrfPath(std::size_t test) const;
  /// A test's modes file (OUTDIR/<test>/modes.unv).
  std::filesystem::path ModesPath(std::size_t test) const;
  /// True when every step is done or given and no problem was met.
  bool Succeeded() const;
};

/// Runs the plan: per test [simulate →] frf → fit → model → correlate, then the diagnosis over all tests, then
/// per test model → correlate with the updated model. A failed step is recorded, the steps that
/// need it are skipped, the others run. `progress` gets the share of steps done and the step's
/// name. Throws RunStopped (from the pick hook) and what `progress` throws (ema::Cancelled:
/// Python's Ctrl-C); a failing step is recorded, never thrown.
RunResult Run(const RunPlan& plan, const ProgressCallback& progress = {});

/// Each reading of a diagnosis is a model, off the structure by the model's own error as well as
/// the test's noise: where the diagnosis found that error dominating (`error.dominates`, rank 1's),
/// the plan measures separations in both (PlanOptions::frequency_model_error_rel,
/// shape_model_error; docs/plan.md); otherwise `options` stays as it is.
void SeparateInModelError(const diagnose::ModelError& error, planning::PlanOptions* options);

/// The test that tells rank 1's look-alikes apart (Run calls it after the diagnosis): rank 1 and
/// the candidates diagnose::IsLookAlike keeps (at most 10), separated by one more roving set beside
/// the first test with modes — its own sets and references kept, the new set as large as its
/// largest (triaxial when it measured whole points). nullopt when rank 1 has no look-alike.
/// InputError/UsageError from planning::PlanTest when the plan cannot be made.
std::optional<NextTest> PlanNextTest(const model::Model& model, const formats::Project& project,
                                     const std::vector<TestResult>& tests, const diagnose::Diagnosis& diagnosis);

/// "frf", "fit", "model (nominal)", ...: a step's name.
std::string StepName(StepKind kind);

}  // namespace ema::pipeline
