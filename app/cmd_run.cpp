// ema run PROJECT.toml [-o OUTDIR]: the whole story — frf → fit → correlate (before) → diagnose →
// correlate (after) — with every intermediate file kept in OUTDIR, a one-screen summary and the
// self-contained HTML report (OUTDIR/report.html).
//
// Parse → pipeline::Run (the typed stages of the subcommands on a typed RunPlan) → write: every
// file, log, the summary and the report are functions of the RunResult (run_outputs.hpp, report/).
// A failed step is reported, the steps that depend on it are skipped, the report is still written
// with what exists, and the exit code is 1.
#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <optional>

#include "cli.hpp"
#include "ema/core/error.hpp"
#include "ema/formats/project_file.hpp"
#include "pick/pick_server.hpp"
#include "pick/pick_session.hpp"
#include "run_outputs.hpp"
#include "stages.hpp"

namespace ema {

namespace {

namespace fs = std::filesystem;

std::string Stamp() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  char text[64];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  return text;
}

// The project file's `[fit] args` / `[diagnose] args` (the old form of its keys): command-line
// arguments the user wrote, parsed once here by the subcommands' own parsers on top of the keys.
void ApplyArgs(formats::Project* project) {
  if (!project->fit_extra.empty()) {
    const std::optional<app::FitConfig> fit = app::ParseFitArgs(project->fit_extra, false, project->fit);
    if (!fit) throw UsageError("[fit] args: --help is not an option of a project");
    project->fit = fit->options;
  }
  if (!project->diagnose_extra.empty()) {
    const std::optional<app::DiagnoseConfig> diagnose = app::ParseDiagnoseArgs(project->diagnose_extra, false, project->diagnose);
    if (!diagnose) throw UsageError("[diagnose] args: --help is not an option of a project");
    project->diagnose = diagnose->options;
  }
}

// The picker of a `pick = true` test (docs/pick.md): the run waits for its Done and goes on with
// the selection on screen.
pipeline::PickHook Picker(const fs::path& out, bool open_browser) {
  return [out, open_browser](const formats::ProjectTest& test, const FrfSet& frfs, const curvefit::FitOptions& options) {
    app::FitConfig config;
    config.input = test.frf ? test.frf->string() : (out / test.name / "frf.unv").string();
    config.options = options;
    app::PickOptions pick_options;
    pick_options.open_browser = open_browser;
    app::PickSession session(config, frfs, pick_options);
    if (cli::StderrIsTerminal()) std::fprintf(stderr, "\n");
    std::cout << test.name << ": pick the poles in the browser (pick = true); Done goes on with the pick on screen\n"
              << session.Summary() << std::flush;
    if (const int signal = app::ServePick(session, pick_options, std::cout); signal != 0)
      throw pipeline::RunStopped(signal, test.name);
    return session.Selection();
  };
}

}  // namespace

int RunRun(const std::vector<std::string>& args) {
  namespace po = cli::po;
  po::options_description options("ema run options");
  cli::AddHelp(&options);
  options.add_options()
      ("project", po::value<std::string>()->required(), "project file (TOML, docs/project-file.md)")
      ("output,o", po::value<std::string>()->default_value("ema-run"), "output folder (created; files in it are replaced)")
      ("no-report", "skip the HTML report")
      ("bundle", "self-contained output: the files updated-model.toml names are copied into "
                 "OUTDIR/updated-model-files/, so the folder can be moved or sent")
      ("no-pick", "do not open ema pick for the tests that say pick = true (their select is used)")
      ("no-browser", "with pick = true: print the picker's URL, do not open it");
  po::positional_options_description positional;
  positional.add("project", 1);
  po::variables_map vm;
  if (!cli::Parse(args, "ema run PROJECT.toml [-o OUTDIR]", options, positional, &vm)) return 0;

  formats::Project project = formats::ReadProjectFile(vm["project"].as<std::string>());
  ApplyArgs(&project);
  const fs::path out = vm["output"].as<std::string>();
  cli::RefuseOutputsOverInputs({{"", project.file.string()}}, app::RunOutputs(out, project));
  std::error_code ec;
  fs::create_directories(out / "logs", ec);
  if (ec) throw InputError(out.string(), "cannot create the output folder: " + ec.message());
  for (const formats::ProjectTest& test : project.tests) fs::create_directories(out / test.name);

  pipeline::RunPlan plan = pipeline::PlanFromProject(std::move(project), out);
  if (!vm.count("no-pick")) plan.pick = Picker(out, !vm.count("no-browser"));
  pipeline::RunResult run;
  try {
    run = pipeline::Run(plan, [](double f, std::string_view stage) { cli::DrawProgress(f, std::string(stage)); });
  } catch (const pipeline::RunStopped& stop) {
    std::cerr << "ema run: stopped (" << (stop.signal() == SIGTERM ? "SIGTERM" : "Ctrl-C") << ") while picking the poles of "
              << stop.test() << "; the steps after it were not run\n";
    return 128 + stop.signal();
  }
  cli::DrawProgress(1.0, "done");
  if (cli::StderrIsTerminal()) std::fprintf(stderr, "\n");
  for (const pipeline::StepRecord& step : run.steps)
    if (step.status == pipeline::StepStatus::kFailed)
      std::cerr << "ema run: " << (step.test >= 0 ? run.plan.project.tests[static_cast<std::size_t>(step.test)].name + ": " : "")
                << pipeline::StepName(step.kind) << " failed: " << step.error << "\n";

  app::RunOutputOptions output_options{!vm.count("no-report"), vm.count("bundle") > 0, Stamp()};
  const app::RunOutputsWritten written = app::WriteRunOutputs(run, output_options, app::RunSummary);
  std::cout << written.summary;
  return written.problems.empty() ? 0 : 1;
}

}  // namespace ema
