#include "run_outputs.hpp"

#include <cmath>
#include <algorithm>
#include <cstdio>
#include <limits>
#include <sstream>

#include "ema/core/text.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/io.hpp"
#include "report.hpp"
#include "run_history.hpp"
#include "words.hpp"

namespace ema::app {

namespace {

namespace fs = std::filesystem;
using pipeline::StepKind;
using pipeline::StepStatus;

fs::path TestDir(const pipeline::RunResult& run, std::size_t test) {
  return run.plan.output_dir / run.plan.project.tests[test].name;
}

// "stud-5um-fit": a step's log name.
std::string LogName(const pipeline::RunResult& run, const pipeline::StepRecord& step) {
  static const char* const kSuffix[] = {"-frf",         "-fit",           "-model-before",    "-correlate-before",
                                        "diagnose",     "-model-after",   "-correlate-after", "-simulate"};
  const char* suffix = kSuffix[static_cast<int>(step.kind)];
  return step.test < 0 ? std::string(suffix) : run.plan.project.tests[static_cast<std::size_t>(step.test)].name + suffix;
}

fs::path LogPath(const pipeline::RunResult& run, const pipeline::StepRecord& step) {
  return run.plan.output_dir / "logs" / (LogName(run, step) + ".txt");
}

std::string Label(const pipeline::RunResult& run, int test, const std::string& what) {
  return (test >= 0 ? run.plan.project.tests[static_cast<std::size_t>(test)].name + ": " : std::string()) + what;
}

// The modes of a model solution as the correlation read them.
const ModeSet& ModelModes(const pipeline::TestResult& r, bool updated) {
  return updated ? r.model_after->modes : r.model_before->modes;
}

// A step's command line and printout (its log), writing its files on the way; "" for a step that
// wrote nothing (given or skipped).
std::string WriteStep(const pipeline::RunResult& run, const pipeline::StepRecord& step, bool bundle) {
  std::ostringstream out;
  const std::size_t t = static_cast<std::size_t>(step.test);
  const bool done = step.status == StepStatus::kDone;
  switch (step.kind) {
    case StepKind::kSimulate: {
      const SimulateConfig config = RunSimulateConfig(run, t);
      out << "$ ema " << CommandLine(config) << "\n";
      if (done) {
        formats::WriteOptions binary;
        binary.binary = config.binary;
        formats::WriteTimeRecords(config.output, run.tests[t].simulated->records, binary);
        out << SimulateSummary(*run.tests[t].simulated) << "\n";
      }
      break;
    }
    case StepKind::kFrf: {
      const FrfConfig config = RunFrfConfig(run, t);
      out << "$ ema " << CommandLine(config) << "\n";
      if (done) WriteFrf(config, *run.tests[t].frf), PrintFrf(*run.tests[t].frf, out);
      break;
    }
    case StepKind::kFit: {
      const FitConfig config = RunFitConfig(run, t);
      out << "$ ema " << CommandLine(config) << "\n";
      if (done) {
        const pipeline::TestResult& r = run.tests[t];
        WriteFit(config, *r.fit, *r.frfs);
        PrintFit(config, *r.fit, out);
      }
      break;
    }
    case StepKind::kModelBefore:
    case StepKind::kModelAfter: {
      const bool updated = step.kind == StepKind::kModelAfter;
      const ModelConfig config = RunModelConfig(run, t, updated);
      out << "$ ema " << CommandLine(config) << "\n";
      if (done) {
        const model::Model& model = updated ? run.diagnosis->updated : *run.nominal;
        const model::Solution& solution = updated ? *run.tests[t].model_after : *run.tests[t].model_before;
        WriteModel(config, model, solution);
        PrintModel(config, model, solution, out);
      }
      break;
    }
    case StepKind::kCorrelateBefore:
    case StepKind::kCorrelateAfter: {
      const bool updated = step.kind == StepKind::kCorrelateAfter;
      const CorrelateConfig config = RunCorrelateConfig(run, t, updated);
      out << "$ ema " << CommandLine(config) << "\n";
      if (done) {
        const pipeline::TestResult& r = run.tests[t];
        const correlation::CorrelationResult& c = updated ? *r.correlation_after : *r.correlation_before;
        WriteCorrelation(config, c, r.fit->stored_modes, ModelModes(r, updated));
        PrintCorrelation(config, c, r.fit->stored_modes, ModelModes(r, updated), out);
      }
      break;
    }
    case StepKind::kDiagnose: {
      const DiagnoseConfig config = RunDiagnoseConfig(run, bundle);
      out << "$ ema " << CommandLine(config) << "\n";
      if (done) WriteDiagnosis(config, *run.diagnosis), PrintDiagnosis(*run.diagnosis, out);
      break;
    }
  }
  if (step.status == StepStatus::kFailed) out << "\nFAILED: " << step.error << "\n";
  return out.str();
}

// The summary's numbers: "-" where a value does not exist.
std::string Fixed(double value, int digits) { return FixedPoint(value, digits, "-"); }

}  // namespace

SimulateConfig RunSimulateConfig(const pipeline::RunResult& run, std::size_t test) {
  const formats::ProjectTest& t = run.plan.project.tests[test];
  SimulateConfig config;
  config.model_path = run.TruthPath(test).string();
  config.plan_path = t.plan ? t.plan->string() : std::string();
  config.output = run.TimePath(test).string();
  config.setup = t.setup;
  config.binary = true;  // 58b: the records at full precision, as the run estimated them
  return config;
}

FrfConfig RunFrfConfig(const pipeline::RunResult& run, std::size_t test) {
  const formats::ProjectTest& t = run.plan.project.tests[test];
  FrfConfig config;
  for (const fs::path& p : t.time) config.inputs.push_back(p.string());
  if (t.plan) config.inputs.push_back(run.TimePath(test).string());
  config.output = (TestDir(run, test) / "frf.unv").string();
  config.json_path = (TestDir(run, test) / "frf.json").string();
  config.options = run.plan.project.frf;
  config.binary = run.plan.project.binary;
  return config;
}

FitConfig RunFitConfig(const pipeline::RunResult& run, std::size_t test) {
  FitConfig config;
  config.input = run.FrfPath(test).string();
  config.output = run.ModesPath(test).string();
  config.json_path = (TestDir(run, test) / "modes.json").string();
  config.stabilisation_path = (TestDir(run, test) / "stabilisation.json").string();
  config.options = run.tests[test].fit_options;
  return config;
}

ModelConfig RunModelConfig(const pipeline::RunResult& run, std::size_t test, bool updated) {
  ModelConfig config;
  config.model_path = updated ? run.UpdatedModelPath().string() : run.plan.project.model.string();
  config.output = (TestDir(run, test) / (updated ? "model-after.unv" : "model-before.unv")).string();
  config.json_path = (TestDir(run, test) / (updated ? "model-after.json" : "model-before.json")).string();
  config.options.setup = run.plan.project.tests[test].setup;
  return config;
}

CorrelateConfig RunCorrelateConfig(const pipeline::RunResult& run, std::size_t test, bool updated) {
  CorrelateConfig config;
  config.test_path = run.ModesPath(test).string();
  config.model_path = updated ? run.UpdatedModelPath().string() : run.plan.project.model.string();
  config.setup = run.plan.project.tests[test].setup;
  const std::string stem = updated ? "correlation-after" : "correlation-before";
  config.json_path = (TestDir(run, test) / (stem + ".json")).string();
  config.table_path = (TestDir(run, test) / (stem + ".md")).string();
  return config;
}

DiagnoseConfig RunDiagnoseConfig(const pipeline::RunResult& run, bool bundle) {
  const formats::Project& project = run.plan.project;
  DiagnoseConfig config;
  config.model_path = project.model.string();
  for (std::size_t t = 0; t < project.tests.size(); ++t)
    if (run.tests[t].fit) {
      config.tests.push_back({project.tests[t].setup, run.ModesPath(t).string()});
      // `ema diagnose --sensor-mass` gives one mass to every test; the run gives each its own.
      config.sensor_mass = std::max(config.sensor_mass, project.tests[t].sensor_mass);
    }
  config.json_path = (run.plan.output_dir / "diagnosis.json").string();
  config.output = run.UpdatedModelPath().string();
  config.options = project.diagnose;
  config.bundle = bundle;
  return config;
}

std::vector<cli::PathArg> RunOutputs(const fs::path& out, const formats::Project& project) {
  std::vector<cli::PathArg> o = {{"-o", out.string()}};
  auto add = [&](const fs::path& p) { o.push_back({"-o", p.string()}); };
  for (const char* name : {"diagnosis.json", "updated-model.toml", "report.html", "summary.txt", "history.json"})
    add(out / name);
  add(out / "logs" / "diagnose.txt");
  for (const formats::ProjectTest& test : project.tests) {
    const fs::path d = out / test.name;
    for (const char* name : {"modes.unv", "modes.json", "stabilisation.json", "model-before.unv", "model-before.json",
                             "correlation-before.json", "correlation-before.md", "model-after.unv", "model-after.json",
                             "correlation-after.json", "correlation-after.md"})
      add(d / name);
    if (!test.frf) add(d / "frf.unv"), add(d / "frf.json");
    if (test.plan) add(d / "time.unv"), add(out / "logs" / (test.name + "-simulate.txt"));
    for (const char* step : {"-frf", "-fit", "-model-before", "-correlate-before", "-model-after", "-correlate-after"})
      add(out / "logs" / (test.name + step + ".txt"));
  }
  return o;
}

std::vector<std::string> WriteRunFiles(const pipeline::RunResult& run, bool bundle) {
  std::vector<std::string> problems;
  for (const pipeline::StepRecord& step : run.steps) {
    if (step.status == StepStatus::kGiven || step.status == StepStatus::kSkipped) continue;
    std::string log;
    try {
      log = WriteStep(run, step, bundle);
    } catch (const std::exception& e) {
      problems.push_back(Label(run, step.test, pipeline::StepName(step.kind)) + ": writing its files failed: " + e.what());
      log = std::string("writing the files failed: ") + e.what() + "\n";
    }
    try {
      formats::WriteTextFileAtomically(LogPath(run, step), log);
    } catch (const std::exception&) {
      // The log is a convenience; the step's own outputs and the problem list matter more.
    }
  }
  return problems;
}

std::vector<std::string> RunProblems(const pipeline::RunResult& run) {
  std::vector<std::string> problems;
  for (const pipeline::StepRecord& step : run.steps) {
    const std::string label = Label(run, step.test, pipeline::StepName(step.kind));
    if (step.status == StepStatus::kFailed)
      problems.push_back(label + ": " + step.error + " (log: " + LogPath(run, step).string() + ")");
    else if (step.status == StepStatus::kSkipped)
      problems.push_back(label + ": skipped (" + step.error + ")");
  }
  for (const pipeline::RunProblem& p : run.problems) {
    const std::size_t t = static_cast<std::size_t>(p.test);
    if (p.what == "pick")
      problems.push_back(Label(run, p.test, "pick: ") + p.error + "; the run goes on with select = " +
                         report::SelectText(run.tests[t].fit_options.select_frequencies_hz));
    else
      problems.push_back("report: " + p.what + " of " + run.plan.project.tests[t].name + ": " + p.error);
  }
  return problems;
}

std::string RunSummary(const pipeline::RunResult& run, const nlohmann::json& history, bool with_report,
                       const std::vector<std::string>& problems) {
  const formats::Project& project = run.plan.project;
  std::vector<std::string> lines;
  lines.push_back("ema run: " + project.name + "  (" + project.file.filename().string() + ", model " +
                  project.model.filename().string() + ")");
  char line[256];
  std::snprintf(line, sizeof line, "  %-12s %5s %8s %6s  %-22s %-22s", "test", "FRFs", "rejected", "modes",
                "nominal: agree / MAC", "updated: agree / MAC");
  lines.push_back(line);
  for (std::size_t t = 0; t < project.tests.size(); ++t) {
    const pipeline::TestResult& r = run.tests[t];
    int frf_count = 0, rejected = 0;
    if (r.frf) {
      frf_count = static_cast<int>(r.frf->result.summary.frfs.size());
      for (const frf::FrfSummaryEntry& e : r.frf->result.summary.frfs) rejected += static_cast<int>(e.rejected.size());
    } else if (r.frfs) {
      frf_count = r.frfs->OutputCount() * r.frfs->ReferenceCount();
    }
    const int modes = r.fit ? static_cast<int>(r.fit->fit.modes.modes.size()) : 0;
    auto agreement = [](const std::optional<correlation::CorrelationResult>& c) {
      return c ? Fixed(c->mean_agreement_pct, 1) + " % / " + Fixed(c->mean_mac, 3) : std::string("- % / -");
    };
    std::snprintf(line, sizeof line, "  %-12s %5d %8d %6d  %-22s %-22s", project.tests[t].name.c_str(), frf_count, rejected,
                  modes, agreement(r.correlation_before).c_str(), agreement(r.correlation_after).c_str());
    lines.push_back(line);
    if (project.tests[t].plan)  // a rehearsal: say that its data were simulated, and on what
      lines.push_back("  " + std::string(12, ' ') + " " + report::RehearsalWords(project.tests[t]));
    if (r.fit && r.picked_by_hand)  // a hand pick is kept only in this run: say how to repeat it
      lines.push_back("  " + std::string(12, ' ') + " poles picked by hand (ema pick); to repeat without the browser: " +
                      "select = \"" + report::SelectText(r.fit_options.select_frequencies_hz) + "\" in its [[test]]");
  }
  // What the agreement columns compare, when the tests carried sensors the model leaves out.
  double sensor_mass_kg = 0.0;
  for (const formats::ProjectTest& test : project.tests) sensor_mass_kg = std::max(sensor_mass_kg, test.sensor_mass);
  if (const std::string note = report::AgreementBasisWords(sensor_mass_kg); !note.empty())
    lines.push_back("  " + note);
  if (run.diagnosis) {
    // The diagnosis's first screen, as `ema diagnose` prints it.
    std::istringstream first_screen(DiagnosisSummary(*run.diagnosis));
    for (std::string l; std::getline(first_screen, l);) lines.push_back("  " + l);
  }
  if (run.next_test) {
    // The test that tells rank 1's look-alikes apart, in one line (the report draws it).
    const pipeline::NextTest& next = *run.next_test;
    std::string dofs;
    for (std::size_t s = static_cast<std::size_t>(next.kept_sets); s < next.plan.sets.size(); ++s)
      for (const Dof& d : next.plan.sets[s]) dofs += (dofs.empty() ? "" : ", ") + DofName(d);
    double before = std::numeric_limits<double>::infinity(), after = before;
    for (const planning::Separation& sep : next.plan.separations)
      if (sep.sigma_before < before) before = sep.sigma_before, after = sep.sigma_after;
    lines.push_back("  Next test to tell them apart: one more roving set at " + dofs + " beside " +
                    project.tests[static_cast<std::size_t>(next.test)].name + "'s " + std::to_string(next.kept_sets) +
                    (std::isfinite(before) ? " — the closest pair from " + Fixed(before, 1) + " σ to " + Fixed(after, 1) + " σ apart" +
                                                 (next.plan.separations_include_model_error
                                                      ? " in the test's noise and the model's own error"
                                                      : "")
                                           : std::string()) +
                    " (ema plan --candidates; the report draws it).");
  } else if (!run.next_test_error.empty()) {
    lines.push_back("  Next test to tell them apart: could not be planned: " + run.next_test_error);
  }
  if (history.is_array() && history.size() > 1) {
    const nlohmann::json& prev = history[history.size() - 2];
    if (prev.contains("mean_agreement_pct_before") && prev["mean_agreement_pct_before"].is_number())
      lines.push_back("  history: model version " + std::to_string(history.size()) + ", mean agreement " +
                      Fixed(prev["mean_agreement_pct_before"].get<double>(), 1) + " % (version " +
                      std::to_string(history.size() - 1) + ") -> " + Fixed(run.mean_agreement_before, 1) + " %");
  }
  if (with_report) lines.push_back("  report: " + (run.plan.output_dir / "report.html").string());
  lines.push_back("  every intermediate file: " + run.plan.output_dir.string() + "/  (logs/ holds each step's output)");
  std::string text;
  for (const std::string& l : lines) text += l + "\n";
  for (const std::string& p : problems) text += "  problem: " + p + "\n";
  return text;
}

namespace {

// The files of OUTDIR, relative to it, for the report's list.
std::vector<std::string> WrittenFiles(const fs::path& out) {
  std::vector<std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(out)) {
    const std::string name = fs::relative(entry.path(), out).string();
    if (entry.is_regular_file() && name.find(".tmp") == std::string::npos && name != "report.html") files.push_back(name);
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

RunOutputsWritten WriteRunOutputs(const pipeline::RunResult& run, const RunOutputOptions& options,
                                  const RunSummaryWords& summary) {
  const fs::path& out = run.plan.output_dir;
  RunOutputsWritten written;
  written.problems = WriteRunFiles(run, options.bundle);
  for (const std::string& p : RunProblems(run)) written.problems.push_back(p);
  RunRecord record{options.stamp, run.plan.project.model, run.mean_agreement_before, run.mean_mac_before,
                   run.mean_agreement_after, run.mean_mac_after, std::nullopt};
  if (run.diagnosis) {
    const diagnose::Candidate& first = run.diagnosis->diagnosis.candidates.front();
    record.rank_one = RunRecord::RankOne{first.kind, first.target, first.probability};
  }
  const nlohmann::json history = AppendRunHistory(out, record);
  if (options.report) {
    const formats::Project& project = run.plan.project;
    report::RunPage page;
    page.subtitle = project.file.filename().string() + " · model " + project.model.filename().string() + " · " + options.stamp;
    page.files = WrittenFiles(out);
    page.history = history;
    page.problems = written.problems;
    for (std::size_t t = 0; t < run.tests.size(); ++t)
      page.fit_commands.push_back(run.tests[t].fit ? "ema " + CommandLine(RunFitConfig(run, t)) : "");
    formats::WriteTextFileAtomically(out / "report.html", report::RenderHtml(run, page));
  }
  written.summary = summary(run, history, options.report, written.problems);
  formats::WriteTextFileAtomically(out / "summary.txt", written.summary);
  return written;
}

}  // namespace ema::app
