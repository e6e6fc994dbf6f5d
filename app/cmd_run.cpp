// ema run PROJECT.toml [-o OUTDIR]: the whole story — frf → fit → correlate (before) → diagnose →
// correlate (after) — with every intermediate file kept in OUTDIR, a one-screen summary and the
// self-contained HTML report (OUTDIR/report.html).
//
// Each step is the typed stage of the subcommand of the same name (stages.hpp): the project file
// gives each stage its config, each stage takes the previous stages' typed results and writes its
// own files (exactly what that subcommand writes), and what it prints goes to
// OUTDIR/logs/<step>.txt under the equivalent command line. Nothing written here is read back. A
// failed step is reported, the steps that depend on it are skipped, the report is still written
// with what exists, and the exit code is 1.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>

#include "cli.hpp"
#include "ema/core/error.hpp"
#include "ema/core/text.hpp"
#include "ema/formats/atomic_file.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/json_codecs.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/formats/project_file.hpp"
#include "quality_json.hpp"
#include "report.hpp"
#include "pick/pick_server.hpp"
#include "pick/pick_session.hpp"
#include "run_history.hpp"
#include "stages.hpp"

namespace ema {

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// Runs the pipeline's steps, captures their stdout, keeps the list of problems and files.
class StepRunner {
 public:
  StepRunner(fs::path out, int total_steps) : out_(std::move(out)), total_(total_steps) {}

  /// Runs `stage` (a typed stage printing to the stream it is given) and keeps its printout in
  /// OUTDIR/logs/<log_name>.txt under `command_line`; true when it succeeded.
  bool Run(const std::string& label, const std::string& log_name, const std::string& command_line,
           const std::function<void(std::ostream&)>& stage) {
    cli::DrawProgress(static_cast<double>(done_) / total_, label);
    std::ostringstream printed;
    std::string failure;
    try {
      stage(printed);
    } catch (const std::exception& e) {
      failure = e.what();
    }
    std::string log = "$ ema " + command_line + "\n" + printed.str();
    if (!failure.empty()) log += "\nFAILED: " + failure + "\n";
    const fs::path log_path = out_ / "logs" / (log_name + ".txt");
    try {
      formats::WriteTextFileAtomically(log_path, log);
    } catch (const std::exception&) {
      // The log is a convenience; the step's own outputs and the problem list matter more.
    }
    ++done_;
    if (!failure.empty()) {
      if (cli::StderrIsTerminal()) std::fprintf(stderr, "\n");
      std::cerr << "ema run: " << label << " failed: " << failure << "\n";
      problems_.push_back(label + ": " + failure + " (log: " + log_path.string() + ")");
      return false;
    }
    return true;
  }

  void Skip(const std::string& label, const std::string& why) {
    ++done_;
    problems_.push_back(label + ": skipped (" + why + ")");
  }
  void Advance() { ++done_; }
  void Problem(const std::string& text) { problems_.push_back(text); }
  void Progress(const std::string& label) { cli::DrawProgress(static_cast<double>(done_) / total_, label); }
  void Finish() { cli::DrawProgress(1.0, "done"); }
  const std::vector<std::string>& problems() const { return problems_; }

 private:
  fs::path out_;
  int total_ = 1;
  int done_ = 0;
  std::vector<std::string> problems_;
};

// The summary's numbers: "-" where a value does not exist.
std::string Fixed(double value, int digits) { return FixedPoint(value, digits, "-"); }


// The report's "Data quality" section: the `ema quality` checks of the test's FRFs in the fit band.
template <class Runner>
nlohmann::json ReportQuality(const FrfSet& frfs, double lo_hz, double hi_hz, const std::string& source, Runner* runner) {
  try {
    frf::QualityOptions options;
    if (hi_hz > lo_hz) {
      options.band_lo_hz = lo_hz;
      options.band_hi_hz = hi_hz;
    }
    return QualityJson(frf::CheckFrfQuality({frfs}, options, {source}), {}, options);
  } catch (const std::exception& e) {
    runner->Problem("report: data-quality checks of " + source + ": " + e.what());
    return nlohmann::json::object();
  }
}

// Per-test file names inside OUTDIR/<test>/.
struct TestFiles {
  fs::path dir, frf, frf_json, modes, modes_json, stabilisation, model_before, model_before_json, corr_before,
      corr_before_table, model_after, model_after_json, corr_after, corr_after_table;
  explicit TestFiles(const fs::path& d)
      : dir(d),
        frf(d / "frf.unv"),
        frf_json(d / "frf.json"),
        modes(d / "modes.unv"),
        modes_json(d / "modes.json"),
        stabilisation(d / "stabilisation.json"),
        model_before(d / "model-before.unv"),
        model_before_json(d / "model-before.json"),
        corr_before(d / "correlation-before.json"),
        corr_before_table(d / "correlation-before.md"),
        model_after(d / "model-after.unv"),
        model_after_json(d / "model-after.json"),
        corr_after(d / "correlation-after.json"),
        corr_after_table(d / "correlation-after.md") {}
};

// Every file `ema run` writes (docs/project-file.md), for cli.md's "outputs never replace inputs".
std::vector<cli::PathArg> RunOutputs(const fs::path& out, const formats::Project& project) {
  std::vector<cli::PathArg> o = {{"-o", out.string()}};
  auto add = [&](const fs::path& p) { o.push_back({"-o", p.string()}); };
  for (const char* name : {"diagnosis.json", "updated-model.toml", "report.html", "summary.txt", "history.json"})
    add(out / name);
  add(out / "logs" / "diagnose.txt");
  for (const formats::ProjectTest& test : project.tests) {
    const TestFiles f(out / test.name);
    for (const fs::path& p : {f.modes, f.modes_json, f.stabilisation, f.model_before, f.model_before_json, f.corr_before,
                              f.corr_before_table, f.model_after, f.model_after_json, f.corr_after, f.corr_after_table})
      add(p);
    if (!test.frf) add(f.frf), add(f.frf_json);
    for (const char* step : {"-frf", "-fit", "-model-before", "-correlate-before", "-model-after", "-correlate-after"})
      add(out / "logs" / (test.name + step + ".txt"));
  }
  return o;
}

std::string Stamp() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  char text[64];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  return text;
}

// Test points of the model's [[point]] entries given by position (points given by FE node have
// none), for the report's geometry.
std::vector<Node> ModelPoints(const model::Model& model) {
  std::vector<Node> nodes;
  for (const model::TestPoint& p : model.points)
    if (!p.where.IsNode() && p.where.has_at) nodes.push_back(Node{p.id, p.where.at});
  return nodes;
}

std::string Joined(const std::vector<std::string>& words) {
  std::string text;
  for (const std::string& w : words) text += (text.empty() ? "" : " ") + w;
  return text;
}

std::string Joined(const std::vector<fs::path>& paths) {
  std::vector<std::string> words;
  for (const fs::path& p : paths) words.push_back(p.string());
  return Joined(words);
}

// What one test's stages produced (empty where a stage failed or was skipped).
struct TestResults {
  std::optional<FrfSet> frfs;
  nlohmann::json frf_summary;
  std::optional<app::FitStageResult> fit;
  std::string select;          ///< the selection the fit used ("auto" or F1,F2,...)
  bool picked_by_hand = false; ///< chosen in `ema pick` during the run (pick = true)
  std::string fit_command;     ///< the equivalent `ema fit` command
  std::optional<app::ModelStageResult> model_before, model_after;
  std::optional<app::CorrelateStageResult> correlation_before, correlation_after;
};

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

  const formats::Project project = formats::ReadProjectFile(vm["project"].as<std::string>());
  const fs::path out = vm["output"].as<std::string>();
  cli::RefuseOutputsOverInputs({{"", project.file.string()}}, RunOutputs(out, project));
  std::error_code ec;
  fs::create_directories(out / "logs", ec);
  if (ec) throw InputError(out.string(), "cannot create the output folder: " + ec.message());
  for (const formats::ProjectTest& test : project.tests) fs::create_directories(out / test.name);

  const fs::path diagnosis_json = out / "diagnosis.json", updated_model = out / "updated-model.toml";
  const int steps_per_test = 6;  // frf, fit, model, correlate, model (after), correlate (after)
  StepRunner runner(out, steps_per_test * static_cast<int>(project.tests.size()) + 2);
  const std::string model_path = project.model.string();
  // The nominal model, read once; a model that cannot be read fails every step that needs it.
  std::optional<model::Model> nominal;
  std::string nominal_error;
  try {
    nominal = formats::ReadModelFile(project.model);
  } catch (const std::exception& e) {
    nominal_error = e.what();
  }
  auto nominal_model = [&]() -> const model::Model& {
    if (!nominal) throw InputError(nominal_error);
    return *nominal;
  };
  std::vector<TestResults> results(project.tests.size());
  std::vector<std::string> files;

  // frf → fit → model → correlate (before), per test.
  for (std::size_t t = 0; t < project.tests.size(); ++t) {
    const formats::ProjectTest& test = project.tests[t];
    TestResults& r = results[t];
    const TestFiles f(out / test.name);
    const std::string tag = test.name + ": ";
    bool have_frf = true;
    const fs::path frf_path = test.frf ? *test.frf : f.frf;
    if (test.frf) {
      runner.Advance();  // the project gives FRFs: nothing to estimate
    } else {
      const std::string command = Joined(test.time) + " -o " + f.frf.string() + " --estimator " + project.estimator +
                                  " --json " + f.frf_json.string() + (project.binary ? " --binary" : "");
      have_frf = runner.Run(tag + "frf", test.name + "-frf", "frf " + command, [&](std::ostream& log) {
        app::FrfConfig config;
        for (const fs::path& p : test.time) config.inputs.push_back(p.string());
        config.output = f.frf.string();
        config.json_path = f.frf_json.string();
        try {
          config.options.estimator = frf::ParseEstimator(project.estimator);
        } catch (const std::invalid_argument& e) {
          throw UsageError(std::string("--estimator: ") + e.what());
        }
        config.binary = project.binary;
        app::FrfStageResult stage = app::RunFrfStage(config, log);
        r.frfs = std::move(stage.stored);
        r.frf_summary = std::move(stage.summary_json);
      });
    }
    if (have_frf) {
      // [fit] args are `ema fit` options; band, order_max and select are the project's own keys.
      auto fit_config = [&](const std::string& select) {
        std::optional<app::FitConfig> config = app::ParseFitArgs(project.fit_extra, false);
        if (!config) throw UsageError("[fit] args: --help is not an option of a project");
        config->input = frf_path.string();
        config->output = f.modes.string();
        config->json_path = f.modes_json.string();
        config->stabilisation_path = f.stabilisation.string();
        config->options.select_frequencies_hz = app::ParseSelect(select);
        if (project.band_hz) std::tie(config->options.data.band_lo_hz, config->options.data.band_hi_hz) = *project.band_hz;
        if (project.order_max) config->options.polymax.order_max = *project.order_max;
        return *config;
      };
      r.select = test.select.empty() ? project.select : test.select;
      if (test.pick && !vm.count("no-pick")) {
        // The picker for this test (docs/pick.md): the run waits for its Done and goes on with the
        // selection on screen. A picker that cannot start leaves the project's selection.
        runner.Progress(tag + "pick");
        try {
          if (!r.frfs) r.frfs = formats::ReadFrfSet(frf_path);
          app::PickOptions pick_options;
          pick_options.open_browser = !vm.count("no-browser");
          app::PickSession session(fit_config(r.select), *r.frfs, pick_options);
          if (cli::StderrIsTerminal()) std::fprintf(stderr, "\n");
          std::cout << test.name << ": pick the poles in the browser (pick = true); Done goes on with the pick on screen\n"
                    << session.Summary() << std::flush;
          if (const int signal = app::ServePick(session, pick_options, std::cout); signal != 0) {
            std::cerr << "ema run: stopped (" << (signal == SIGTERM ? "SIGTERM" : "Ctrl-C") << ") while picking the poles of "
                      << test.name << "; the steps after it were not run\n";
            return 128 + signal;
          }
          const std::string picked = session.SelectText();
          if (picked.empty()) {
            runner.Problem(tag + "pick: nothing was picked when Done was pressed; the run goes on with select = " + r.select);
          } else {
            r.picked_by_hand = picked != "auto";
            r.select = picked;
          }
        } catch (const std::exception& e) {
          runner.Problem(tag + "pick: " + e.what() + " (the run goes on with select = " + r.select + ")");
        }
      }
      std::string command = frf_path.string() + " -o " + f.modes.string() + " --json " + f.modes_json.string() +
                            " --stabilisation " + f.stabilisation.string() + " --select " + r.select;
      if (project.band_hz) command += " --band " + Fixed(project.band_hz->first, 3) + ":" + Fixed(project.band_hz->second, 3);
      if (project.order_max) command += " --order-max " + std::to_string(*project.order_max);
      if (!project.fit_extra.empty()) command += " " + Joined(project.fit_extra);
      r.fit_command = "ema fit " + command;
      runner.Run(tag + "fit", test.name + "-fit", "fit " + command, [&](std::ostream& log) {
        const app::FitConfig config = fit_config(r.select);
        if (!r.frfs) r.frfs = formats::ReadFrfSet(frf_path);  // FRFs the project gives
        r.fit = app::RunFitStage(config, *r.frfs, log);
      });
    } else {
      runner.Skip(tag + "fit", "no FRFs");
    }
    const std::string setup_args = test.setup.empty() ? "" : " --setup " + test.setup;
    runner.Run(tag + "model (nominal)", test.name + "-model-before",
               "model " + model_path + " -o " + f.model_before.string() + " --json " + f.model_before_json.string() + setup_args,
               [&](std::ostream& log) {
                 app::ModelConfig config;
                 config.model_path = model_path;
                 config.output = f.model_before.string();
                 config.json_path = f.model_before_json.string();
                 config.options.setup = test.setup;
                 r.model_before = app::RunModelStage(config, nominal_model(), log);
               });
    if (r.fit) {
      runner.Run(tag + "correlate (nominal)", test.name + "-correlate-before",
                 "correlate " + f.modes.string() + " " + model_path + " --json " + f.corr_before.string() + " --table " +
                     f.corr_before_table.string() + setup_args,
                 [&](std::ostream& log) {
                   if (!r.model_before) throw InputError(model_path, "the nominal model's modes are missing");
                   app::CorrelateConfig config;
                   config.test_path = f.modes.string();
                   config.model_path = model_path;
                   config.setup = test.setup;
                   config.json_path = f.corr_before.string();
                   config.table_path = f.corr_before_table.string();
                   ModeSet model_modes = r.model_before->solution.modes;
                   if (model_modes.source.empty()) model_modes.source = model_path;
                   r.correlation_before = app::RunCorrelateStage(config, r.fit->stored_modes, model_modes, log);
                 });
    } else {
      runner.Skip(tag + "correlate (nominal)", "no test modes");
    }
  }

  // diagnose, all tests at once.
  std::optional<app::DiagnoseStageResult> diagnosis;
  bool any_modes = false;
  for (const TestResults& r : results) any_modes = any_modes || r.fit.has_value();
  if (any_modes) {
    std::string command = model_path;
    for (std::size_t t = 0; t < project.tests.size(); ++t)
      if (results[t].fit)
        command += " --test " + (project.tests[t].setup.empty() ? std::string() : project.tests[t].setup + "=") +
                   TestFiles(out / project.tests[t].name).modes.string();
    command += " --json " + diagnosis_json.string() + " -o " + updated_model.string();
    // The tests' own sensors ([[test]] sensor_mass): `ema diagnose --sensor-mass` gives one mass to
    // every test, and finds each test's roving sets in the `ema fit --json` file beside its modes.
    double sensor_mass = 0.0;
    for (std::size_t t = 0; t < project.tests.size(); ++t)
      if (results[t].fit) sensor_mass = std::max(sensor_mass, project.tests[t].sensor_mass);
    if (sensor_mass > 0.0) {
      char text[32];
      std::snprintf(text, sizeof text, "%.17g", sensor_mass);
      command += std::string(" --sensor-mass ") + text;
    }
    const bool bundle = vm.count("bundle") > 0;
    if (bundle) command += " --bundle";
    if (!project.diagnose_extra.empty()) command += " " + Joined(project.diagnose_extra);
    runner.Run("diagnose", "diagnose", "diagnose " + command, [&](std::ostream& log) {
      // [diagnose] args are `ema diagnose` options.
      std::optional<app::DiagnoseConfig> config = app::ParseDiagnoseArgs(project.diagnose_extra, false);
      if (!config) throw UsageError("[diagnose] args: --help is not an option of a project");
      config->model_path = model_path;
      config->json_path = diagnosis_json.string();
      config->output = updated_model.string();
      config->bundle = bundle;
      std::vector<diagnose::SetupModes> tests;
      for (std::size_t t = 0; t < project.tests.size(); ++t) {
        if (!results[t].fit) continue;
        // The modes as the modes file holds them, with each mode's σ as `ema diagnose` finds it
        // in the `ema fit --json` file beside it (app::AttachSidecarUncertainty).
        ModeSet modes = results[t].fit->stored_modes;
        const ModeSet& fitted = results[t].fit->fit.modes;
        for (std::size_t m = 0; m < modes.modes.size() && m < fitted.modes.size(); ++m) {
          modes.modes[m].frequency_std_hz = fitted.modes[m].frequency_std_hz;
          modes.modes[m].damping_ratio_std = fitted.modes[m].damping_ratio_std;
          modes.modes[m].set_frequency_hz = fitted.modes[m].set_frequency_hz;
          modes.modes[m].set_damping_ratio = fitted.modes[m].set_damping_ratio;
          modes.modes[m].set_frequency_std_hz = fitted.modes[m].set_frequency_std_hz;
        }
        diagnose::SetupModes test{project.tests[t].setup, std::move(modes)};
        test.sensor_mass = project.tests[t].sensor_mass;
        if (test.sensor_mass > 0.0 && results[t].frfs)
          formats::ReadTestSets(formats::TestSetsJson(*results[t].frfs), &test.roving_sets, &test.reference);
        tests.push_back(std::move(test));
      }
      diagnosis = app::RunDiagnoseStage(*config, nominal_model(), tests, log);
    });
  } else {
    runner.Skip("diagnose", "no test modes");
  }

  // model → correlate (after), per test.
  for (std::size_t t = 0; t < project.tests.size(); ++t) {
    const formats::ProjectTest& test = project.tests[t];
    TestResults& r = results[t];
    const TestFiles f(out / test.name);
    const std::string tag = test.name + ": ";
    if (!diagnosis) {
      runner.Skip(tag + "model (updated)", "no updated model");
      runner.Skip(tag + "correlate (updated)", "no updated model");
      continue;
    }
    const std::string setup_args = test.setup.empty() ? "" : " --setup " + test.setup;
    runner.Run(tag + "model (updated)", test.name + "-model-after",
               "model " + updated_model.string() + " -o " + f.model_after.string() + " --json " + f.model_after_json.string() +
                   setup_args,
               [&](std::ostream& log) {
                 app::ModelConfig config;
                 config.model_path = updated_model.string();
                 config.output = f.model_after.string();
                 config.json_path = f.model_after_json.string();
                 config.options.setup = test.setup;
                 r.model_after = app::RunModelStage(config, diagnosis->updated, log);
               });
    if (!r.fit) {
      runner.Skip(tag + "correlate (updated)", "no test modes");
      continue;
    }
    runner.Run(tag + "correlate (updated)", test.name + "-correlate-after",
               "correlate " + f.modes.string() + " " + updated_model.string() + " --json " + f.corr_after.string() + " --table " +
                   f.corr_after_table.string() + setup_args,
               [&](std::ostream& log) {
                 if (!r.model_after) throw InputError(updated_model.string(), "the updated model's modes are missing");
                 app::CorrelateConfig config;
                 config.test_path = f.modes.string();
                 config.model_path = updated_model.string();
                 config.setup = test.setup;
                 config.json_path = f.corr_after.string();
                 config.table_path = f.corr_after_table.string();
                 ModeSet model_modes = r.model_after->solution.modes;
                 if (model_modes.source.empty()) model_modes.source = updated_model.string();
                 r.correlation_after = app::RunCorrelateStage(config, r.fit->stored_modes, model_modes, log);
               });
  }

  // Summary.
  const json diagnosis_data = diagnosis ? diagnosis->json : json();
  std::vector<std::string> summary;
  summary.push_back("ema run: " + project.name + "  (" + project.file.filename().string() + ", model " +
                    project.model.filename().string() + ")");
  char line[256];
  std::snprintf(line, sizeof line, "  %-12s %5s %8s %6s  %-22s %-22s", "test", "FRFs", "rejected", "modes",
                "nominal: agree / MAC", "updated: agree / MAC");
  summary.push_back(line);
  report::ReportInput input;
  double agree_before = 0.0, mac_before = 0.0, agree_after = 0.0, mac_after = 0.0;
  int n_before = 0, n_after = 0;
  const std::vector<Node> geometry = nominal ? ModelPoints(*nominal) : std::vector<Node>();
  for (std::size_t t = 0; t < project.tests.size(); ++t) {
    const formats::ProjectTest& test = project.tests[t];
    TestResults& r = results[t];
    report::SetupResults s;
    s.name = test.name;
    s.frf_summary = r.frf_summary;
    if (r.fit) {
      s.stabilisation = r.fit->stabilisation_json;
      s.fit = r.fit->fit;
      s.refine = r.fit->refine;
      s.selection = {{"select", r.select},
                     {"by_hand", r.picked_by_hand},
                     {"rule", r.fit->fit.selection_rule},
                     {"command", r.fit_command},
                     {"modes_json", (fs::path(test.name) / "modes.json").generic_string()}};
      if (r.correlation_before && r.model_before)
        s.correlation_before = report::CorrelationView{r.correlation_before->result, r.fit->stored_modes, r.model_before->solution.modes};
      if (r.correlation_after && r.model_after)
        s.correlation_after = report::CorrelationView{r.correlation_after->result, r.fit->stored_modes, r.model_after->solution.modes};
    }
    s.geometry = geometry;
    s.lines = project.lines;
    if (project.band_hz) {
      s.band_lo_hz = project.band_hz->first;
      s.band_hi_hz = project.band_hz->second;
    }
    const fs::path frf_path = test.frf ? *test.frf : TestFiles(out / test.name).frf;
    if (!r.frfs && test.frf) {
      try {
        r.frfs = formats::ReadFrfSet(frf_path);  // FRFs the project gives
      } catch (const std::exception& e) {
        runner.Problem("report: cannot read " + frf_path.string() + ": " + e.what());
      }
    }
    if (r.frfs) {
      s.frfs = r.frfs;
      s.quality = ReportQuality(*s.frfs, s.band_lo_hz, s.band_hi_hz, frf_path.string(), &runner);
    }
    int frf_count = 0, rejected = 0;
    if (s.frf_summary.contains("frfs") && s.frf_summary["frfs"].is_array()) {
      frf_count = static_cast<int>(s.frf_summary["frfs"].size());
      for (const json& r : s.frf_summary["frfs"])
        if (r.contains("rejected") && r["rejected"].is_array()) rejected += static_cast<int>(r["rejected"].size());
    } else if (s.frfs) {
      frf_count = s.frfs->OutputCount() * s.frfs->ReferenceCount();
    }
    const int modes = r.fit ? static_cast<int>(r.fit->fit.modes.modes.size()) : 0;
    // Mean agreement and MAC of a correlation; NaN when it does not exist.
    auto means = [](const std::optional<app::CorrelateStageResult>& c) {
      return c ? std::make_pair(c->result.mean_agreement_pct, c->result.mean_mac) : std::make_pair(kNaN, kNaN);
    };
    const auto [agreement_nominal, mac_nominal] = means(r.correlation_before);
    const auto [agreement_updated, mac_updated] = means(r.correlation_after);
    const std::string before = Fixed(agreement_nominal, 1) + " % / " + Fixed(mac_nominal, 3);
    const std::string after = Fixed(agreement_updated, 1) + " % / " + Fixed(mac_updated, 3);
    std::snprintf(line, sizeof line, "  %-12s %5d %8d %6d  %-22s %-22s", test.name.c_str(), frf_count, rejected, modes,
                  before.c_str(), after.c_str());
    summary.push_back(line);
    if (r.fit && r.picked_by_hand)  // a hand pick is kept only in this run: say how to repeat it
      summary.push_back("  " + std::string(12, ' ') + " poles picked by hand (ema pick); to repeat without the browser: " +
                        "select = \"" + r.select + "\" in its [[test]]");
    if (std::isfinite(agreement_nominal)) {
      agree_before += agreement_nominal;
      mac_before += mac_nominal;
      ++n_before;
    }
    if (std::isfinite(agreement_updated)) {
      agree_after += agreement_updated;
      mac_after += mac_updated;
      ++n_after;
    }
    input.setups.push_back(std::move(s));
  }
  if (diagnosis) {
    // The diagnosis's first screen (app::RunDiagnoseStage): what is missing, how sure, adequacy.
    std::istringstream lines(diagnosis->summary);
    for (std::string l; std::getline(lines, l);) summary.push_back("  " + l);
  }
  // The model's story over runs into this folder (history.json) and where rank 1 acts.
  app::RunRecord record;
  record.stamp = Stamp();
  record.model = project.model;
  record.agreement_before = n_before ? agree_before / n_before : std::nan("");
  record.mac_before = n_before ? mac_before / n_before : std::nan("");
  record.agreement_after = n_after ? agree_after / n_after : std::nan("");
  record.mac_after = n_after ? mac_after / n_after : std::nan("");
  record.diagnosis = diagnosis_data;
  input.history = app::AppendRunHistory(out, record);
  input.diagnosed_places = nominal ? app::DiagnosedPlaces(*nominal, diagnosis_data) : json::array();
  if (input.history.size() > 1) {
    const json& prev = input.history[input.history.size() - 2];
    if (prev.contains("mean_agreement_pct_before") && prev["mean_agreement_pct_before"].is_number())
      summary.push_back("  history: model version " + std::to_string(input.history.size()) + ", mean agreement " +
                        Fixed(prev["mean_agreement_pct_before"].get<double>(), 1) + " % (version " +
                        std::to_string(input.history.size() - 1) + ") -> " + Fixed(record.agreement_before, 1) + " %");
  }
  const fs::path report_path = out / "report.html";
  if (!vm.count("no-report")) summary.push_back("  report: " + report_path.string());
  summary.push_back("  every intermediate file: " + out.string() + "/  (logs/ holds each step's output)");

  if (!vm.count("no-report")) {
    runner.Progress("report");
    input.title = project.title;
    input.subtitle = project.file.filename().string() + " · model " + project.model.filename().string() + " · " + Stamp();
    input.summary = summary;
    input.diagnosis = diagnosis_data;
    input.problems = runner.problems();
    for (const auto& entry : fs::recursive_directory_iterator(out)) {
      if (!entry.is_regular_file()) continue;
      const std::string name = fs::relative(entry.path(), out).string();
      if (name.find(".tmp") == std::string::npos && name != "report.html") files.push_back(name);
    }
    std::sort(files.begin(), files.end());
    input.steps = files;
    formats::WriteTextFileAtomically(report_path, report::RenderHtml(input));
  }
  runner.Finish();

  std::string text;
  for (const std::string& l : summary) text += l + "\n";
  for (const std::string& p : runner.problems()) text += "  problem: " + p + "\n";
  formats::WriteTextFileAtomically(out / "summary.txt", text);
  std::cout << text;
  return runner.problems().empty() ? 0 : 1;
}

}  // namespace ema
