// The edge of `ema run`: every file of OUTDIR, the logs, the one-screen summary and the report,
// each a function of the run's typed result (pipeline::RunResult). Each step's files are written
// by the writer of the subcommand of the same name on the config that subcommand would get
// (RunFrfConfig, ...), so `ema run` writes what the subcommands run one after the other write.
#pragma once

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli.hpp"
#include "ema/pipeline/run.hpp"
#include "stages.hpp"

namespace ema::app {

/// Each step's config in a run (its files in OUTDIR/<test>/, as docs/project-file.md lists them).
SimulateConfig RunSimulateConfig(const pipeline::RunResult& run, std::size_t test);
FrfConfig RunFrfConfig(const pipeline::RunResult& run, std::size_t test);
FitConfig RunFitConfig(const pipeline::RunResult& run, std::size_t test);
ModelConfig RunModelConfig(const pipeline::RunResult& run, std::size_t test, bool updated);
CorrelateConfig RunCorrelateConfig(const pipeline::RunResult& run, std::size_t test, bool updated);
DiagnoseConfig RunDiagnoseConfig(const pipeline::RunResult& run, bool bundle);

/// Every file `ema run` may write into `out` for `project` (cli.md "outputs never replace inputs").
std::vector<cli::PathArg> RunOutputs(const std::filesystem::path& out, const formats::Project& project);

/// Writes each step's files and its log (OUTDIR/logs/<step>.txt: the command line, what the
/// subcommand prints, or FAILED and why), diagnosis.json and updated-model.toml. Returns the
/// problems met while writing, in words.
std::vector<std::string> WriteRunFiles(const pipeline::RunResult& run, bool bundle);

/// The run's problems in words: failed and skipped steps (with their log), pick and check problems.
std::vector<std::string> RunProblems(const pipeline::RunResult& run);

/// The words of a run's one-screen summary (RunSummary), given the history after this run and the
/// run's problems in words.
using RunSummaryWords = std::function<std::string(const pipeline::RunResult& run, const nlohmann::json& history,
                                                  bool with_report, const std::vector<std::string>& problems)>;

struct RunOutputOptions {
  bool report = true;    ///< write OUTDIR/report.html
  bool bundle = false;   ///< copy the files updated-model.toml names beside it (`ema diagnose --bundle`)
  std::string stamp;     ///< when (UTC), for history.json and the report's subtitle
};

struct RunOutputsWritten {
  std::string summary;                ///< what OUTDIR/summary.txt holds (and the terminal shows)
  std::vector<std::string> problems;  ///< the run's problems and those met while writing, in words
};

/// Every output of a run into run.plan.output_dir: WriteRunFiles, history.json, report.html, and
/// summary.txt = `summary(...)`. Nothing but summary.txt depends on `summary` (a test proves it by
/// rewording it).
RunOutputsWritten WriteRunOutputs(const pipeline::RunResult& run, const RunOutputOptions& options,
                                  const RunSummaryWords& summary);

/// The one-screen summary (also OUTDIR/summary.txt): per test the FRFs, rejected impacts, modes
/// and the agreement before and after; the diagnosis's first screen; the model's history.
std::string RunSummary(const pipeline::RunResult& run, const nlohmann::json& history, bool with_report,
                       const std::vector<std::string>& problems);

}  // namespace ema::app
