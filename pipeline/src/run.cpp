#include "ema/pipeline/run.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "ema/core/error.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/model_file.hpp"
#include "ema/formats/plan_file.hpp"

namespace ema::pipeline {

namespace {

// Runs the steps in order, keeps each one's record and reports the share done.
class StepRunner {
 public:
  StepRunner(RunResult* result, const ProgressCallback& progress, int total)
      : result_(result), progress_(progress), total_(total) {}

  /// Runs `stage`; false when it threw (recorded as failed with the message). RunStopped passes.
  template <class Stage>
  bool Run(StepKind kind, int test, Stage&& stage) {
    Report(kind, test);
    StepRecord record{kind, test, StepStatus::kDone, ""};
    try {
      stage();
    } catch (const RunStopped&) {
      throw;
    } catch (const std::exception& e) {
      record.status = StepStatus::kFailed;
      record.error = e.what();
    }
    Done(std::move(record));
    return result_->steps.back().status == StepStatus::kDone;
  }
  void Skip(StepKind kind, int test, std::string why) { Done({kind, test, StepStatus::kSkipped, std::move(why)}); }
  void Given(StepKind kind, int test) { Done({kind, test, StepStatus::kGiven, ""}); }
  void Report(StepKind kind, int test) {
    if (!progress_) return;
    const std::string label =
        (test >= 0 ? result_->plan.project.tests[static_cast<size_t>(test)].name + ": " : std::string()) + StepName(kind);
    progress_(static_cast<double>(done_) / total_, label);
  }
  void Report(const std::string& label) {
    if (progress_) progress_(static_cast<double>(done_) / total_, label);
  }

 private:
  void Done(StepRecord record) {
    result_->steps.push_back(std::move(record));
    ++done_;
  }
  RunResult* result_;
  const ProgressCallback& progress_;
  int total_ = 1;
  int done_ = 0;
};

// A model's modes named by the file they came from when the solver left them unnamed.
model::Solution Named(model::Solution solution, const std::filesystem::path& file) {
  if (solution.modes.source.empty()) solution.modes.source = file.string();
  return solution;
}

model::Solution SolveSetup(const model::Model& model, const std::string& setup, const std::filesystem::path& file) {
  model::SolveOptions options;
  options.setup = setup;
  return Named(model::Solve(model, options), file);
}

// The test modes the diagnosis weighs: as the modes file holds them, with each mode's σ and
// per-set frequencies as the fit found them (what `ema diagnose` reads beside the modes file).
diagnose::SetupModes DiagnosisTest(const formats::ProjectTest& test, const TestResult& r) {
  ModeSet modes = r.fit->stored_modes;
  const ModeSet& fitted = r.fit->fit.modes;
  for (std::size_t m = 0; m < modes.modes.size() && m < fitted.modes.size(); ++m) {
    modes.modes[m].frequency_std_hz = fitted.modes[m].frequency_std_hz;
    modes.modes[m].damping_ratio_std = fitted.modes[m].damping_ratio_std;
    modes.modes[m].set_frequency_hz = fitted.modes[m].set_frequency_hz;
    modes.modes[m].set_damping_ratio = fitted.modes[m].set_damping_ratio;
    modes.modes[m].set_frequency_std_hz = fitted.modes[m].set_frequency_std_hz;
  }
  diagnose::SetupModes out{test.setup, std::move(modes)};
  out.sensor_mass = test.sensor_mass;
  // Each roving set's sensors load the article while that set is measured.
  if (out.sensor_mass > 0.0 && r.frfs) {
    out.roving_sets = r.frfs->RovingSetNodes();
    if (r.frfs->references.size() == 1) out.reference = r.frfs->references[0];
  }
  return out;
}

// The readings a diagnosis cannot separate from its rank 1 (diagnose::IsLookAlike), rank 1 first,
// at most `limit`.
std::vector<planning::Reading> LookAlikeReadings(const diagnose::Diagnosis& d, std::size_t limit) {
  std::vector<planning::Reading> out;
  const diagnose::Candidate& first = d.candidates.front();
  for (const diagnose::Candidate& c : d.candidates) {
    if (c.effects.empty() || !c.error.empty()) continue;
    if (c.rank != first.rank && !diagnose::IsLookAlike(c.probability, first.probability)) continue;
    out.push_back({c.kind + " on " + c.target, c.effects, "the diagnosis, candidate rank " + std::to_string(c.rank)});
    if (out.size() == limit) break;
  }
  return out;
}

}  // namespace

void SeparateInModelError(const diagnose::ModelError& error, planning::PlanOptions* options) {
  if (!error.dominates) return;
  options->frequency_model_error_rel = error.frequency_rel;
  options->shape_model_error = error.shape;
}

std::optional<NextTest> PlanNextTest(const model::Model& model, const formats::Project& project,
                                     const std::vector<TestResult>& tests, const diagnose::Diagnosis& diagnosis) {
  const std::vector<planning::Reading> readings = LookAlikeReadings(diagnosis, 10);
  if (readings.size() < 2) return std::nullopt;
  NextTest next;
  std::size_t t = 0;
  while (t < tests.size() && !(tests[t].fit && tests[t].frfs)) ++t;
  if (t == tests.size()) throw InputError("", "no test with modes to extend");
  next.test = static_cast<int>(t);
  const FrfSet& frfs = *tests[t].frfs;
  std::vector<std::vector<Dof>> sets = frfs.RovingSets();
  if (sets.empty()) sets.push_back(frfs.outputs);  // sets unknown: the test as one
  // Triaxial sensors when every measured point has its three directions.
  std::map<int, int> directions;
  for (const Dof& d : frfs.outputs) ++directions[d.node];
  const bool triaxial = std::all_of(directions.begin(), directions.end(), [](const auto& n) { return n.second == 3; });
  std::size_t largest = 0;
  for (const auto& set : sets) largest = std::max(largest, set.size());
  planning::PlanOptions options;
  options.setup = project.tests[t].setup;
  options.triaxial = triaxial;
  options.sensors_per_set = static_cast<int>(triaxial ? largest / 3 : largest);
  options.sets = 1;  // the new set; the kept ones come on top
  options.references = static_cast<int>(frfs.references.size());
  options.sensor_mass_kg = project.tests[t].sensor_mass;
  if (project.fit.data.band_hi_hz > project.fit.data.band_lo_hz) {
    options.band_lo_hz = project.fit.data.band_lo_hz;
    options.band_hi_hz = project.fit.data.band_hi_hz;
  }
  SeparateInModelError(diagnosis.candidates.front().model_error, &options);
  for (const planning::Reading& r : readings) next.readings.push_back(r.label);
  next.kept_sets = static_cast<int>(sets.size());
  next.plan = planning::PlanTest(model, options, readings, sets, frfs.references);
  return next;
}

namespace {

void Mean(const std::vector<TestResult>& tests, bool after, double* agreement, double* mac) {
  double a = 0.0, m = 0.0;
  int n = 0;
  for (const TestResult& r : tests) {
    const auto& c = after ? r.correlation_after : r.correlation_before;
    if (!c || !std::isfinite(c->mean_agreement_pct)) continue;
    a += c->mean_agreement_pct;
    m += c->mean_mac;
    ++n;
  }
  if (n) *agreement = a / n, *mac = m / n;
}

}  // namespace

std::string StepName(StepKind kind) {
  switch (kind) {
    case StepKind::kFrf: return "frf";
    case StepKind::kFit: return "fit";
    case StepKind::kModelBefore: return "model (nominal)";
    case StepKind::kCorrelateBefore: return "correlate (nominal)";
    case StepKind::kDiagnose: return "diagnose";
    case StepKind::kModelAfter: return "model (updated)";
    case StepKind::kCorrelateAfter: return "correlate (updated)";
    case StepKind::kSimulate: return "simulate";
  }
  return "?";
}

RunPlan PlanFromProject(formats::Project project, std::filesystem::path output_dir) {
  RunPlan plan;
  plan.project = std::move(project);
  plan.output_dir = std::move(output_dir);
  return plan;
}

std::filesystem::path RunResult::TimePath(std::size_t test) const {
  return plan.output_dir / plan.project.tests[test].name / "time.unv";
}

std::filesystem::path RunResult::TruthPath(std::size_t test) const {
  const formats::ProjectTest& t = plan.project.tests[test];
  return t.truth ? *t.truth : plan.project.model;
}

std::filesystem::path RunResult::FrfPath(std::size_t test) const {
  const formats::ProjectTest& t = plan.project.tests[test];
  return t.frf ? *t.frf : plan.output_dir / t.name / "frf.unv";
}

std::filesystem::path RunResult::ModesPath(std::size_t test) const {
  return plan.output_dir / plan.project.tests[test].name / "modes.unv";
}

bool RunResult::Succeeded() const {
  for (const StepRecord& s : steps)
    if (s.status == StepStatus::kFailed || s.status == StepStatus::kSkipped) return false;
  return problems.empty();
}

RunResult Run(const RunPlan& plan, const ProgressCallback& progress) {
  RunResult result;
  result.plan = plan;
  const formats::Project& project = result.plan.project;
  const std::size_t test_count = project.tests.size();
  result.tests.resize(test_count);
  const int planned = static_cast<int>(std::count_if(project.tests.begin(), project.tests.end(),
                                                      [](const formats::ProjectTest& t) { return t.plan.has_value(); }));
  StepRunner runner(&result, progress, 6 * static_cast<int>(test_count) + planned + 2);
  try {
    result.nominal = formats::ReadModelFile(project.model);
  } catch (const std::exception& e) {
    result.nominal_error = e.what();
  }
  auto nominal = [&]() -> const model::Model& {
    if (!result.nominal) throw InputError(result.nominal_error);
    return *result.nominal;
  };

  // frf → fit → model → correlate (before), per test.
  for (std::size_t t = 0; t < test_count; ++t) {
    const formats::ProjectTest& test = project.tests[t];
    TestResult& r = result.tests[t];
    const int ti = static_cast<int>(t);
    const std::string frf_source = result.FrfPath(t).string();
    auto frfs = [&]() -> const FrfSet& {
      if (!r.frfs) r.frfs = formats::ReadFrfSet(*test.frf);  // the FRFs the project gives
      return *r.frfs;
    };
    bool have_frf = true;
    if (test.frf) {
      runner.Given(StepKind::kFrf, ti);
    } else if (test.plan) {
      // A rehearsal: the planned test simulated on the truth (the project's model unless the test
      // names a variant), then estimated as measured records would be.
      const bool simulated = runner.Run(StepKind::kSimulate, ti, [&] {
        const model::Model truth = test.truth ? formats::ReadModelFile(*test.truth) : nominal();
        formats::Plan test_plan = formats::ReadPlanFile(test.plan->string());
        if (!test.setup.empty()) test_plan.setup = test.setup;
        r.simulated = SimulateTest(truth, test_plan, result.TruthPath(t).string(),
                                   test.plan->string(), progress);
      });
      if (simulated) {
        have_frf = runner.Run(StepKind::kFrf, ti, [&] {
          std::vector<acquisition::RecordSet> sets = {{result.TimePath(t).string(), r.simulated->records}};
          r.frf = EstimateFrfs(std::move(sets), project.frf, project.binary, progress);
          r.frfs = r.frf->stored;
        });
      } else {
        have_frf = false;
        runner.Skip(StepKind::kFrf, ti, "no simulated test");
      }
    } else {
      have_frf = runner.Run(StepKind::kFrf, ti, [&] {
        std::vector<std::string> files;
        for (const auto& p : test.time) files.push_back(p.string());
        r.frf = EstimateFrfs(files, project.frf, project.binary, progress);
        r.frfs = r.frf->stored;
      });
    }
    r.fit_options = project.fit;
    r.fit_options.select_frequencies_hz = test.select_hz ? *test.select_hz : project.select_hz;
    if (have_frf) {
      if (test.pick && plan.pick) {
        // The picker for this test (docs/pick.md): the run goes on with the selection on screen
        // when Done is pressed. A picker that cannot start leaves the project's selection.
        runner.Report(test.name + ": pick");
        try {
          const PickResult picked = plan.pick(test, frfs(), r.fit_options);
          if (!picked) {
            result.problems.push_back({ti, "pick", "nothing was picked when Done was pressed"});
          } else {
            r.picked_by_hand = !picked->empty();
            r.fit_options.select_frequencies_hz = *picked;
          }
        } catch (const RunStopped&) {
          throw;
        } catch (const std::exception& e) {
          result.problems.push_back({ti, "pick", e.what()});
        }
      }
      runner.Run(StepKind::kFit, ti, [&] {
        r.fit = FitModes(frfs(), r.fit_options, frf_source, result.ModesPath(t).string(), progress);
      });
    } else {
      runner.Skip(StepKind::kFit, ti, "no FRFs");
    }
    runner.Run(StepKind::kModelBefore, ti, [&] { r.model_before = SolveSetup(nominal(), test.setup, project.model); });
    if (r.fit) {
      runner.Run(StepKind::kCorrelateBefore, ti, [&] {
        if (!r.model_before) throw InputError(project.model.string(), "the nominal model's modes are missing");
        r.correlation_before = correlation::Correlate(r.fit->stored_modes, r.model_before->modes, {});
      });
    } else {
      runner.Skip(StepKind::kCorrelateBefore, ti, "no test modes");
    }
  }

  // diagnose, all tests at once.
  const bool any_modes = std::any_of(result.tests.begin(), result.tests.end(), [](const TestResult& r) { return r.fit.has_value(); });
  if (any_modes) {
    runner.Run(StepKind::kDiagnose, -1, [&] {
      std::vector<diagnose::SetupModes> tests;
      for (std::size_t t = 0; t < test_count; ++t)
        if (result.tests[t].fit) tests.push_back(DiagnosisTest(project.tests[t], result.tests[t]));
      result.diagnosis = DiagnoseModel(nominal(), tests, project.diagnose, {}, progress);
      result.diagnosis->updated.origin = result.UpdatedModelPath();
    });
  } else {
    runner.Skip(StepKind::kDiagnose, -1, "no test modes");
  }

  // When rank 1 has look-alikes: the test that tells them apart (not a step: a run without it is
  // complete, and why it could not be planned is said).
  if (result.diagnosis && result.nominal) {
    runner.Report("plan the next test");
    try {
      result.next_test = PlanNextTest(*result.nominal, project, result.tests, result.diagnosis->diagnosis);
    } catch (const std::exception& e) {
      result.next_test_error = e.what();
    }
  }

  // model → correlate (after), per test.
  for (std::size_t t = 0; t < test_count; ++t) {
    const formats::ProjectTest& test = project.tests[t];
    TestResult& r = result.tests[t];
    const int ti = static_cast<int>(t);
    if (!result.diagnosis) {
      runner.Skip(StepKind::kModelAfter, ti, "no updated model");
      runner.Skip(StepKind::kCorrelateAfter, ti, "no updated model");
      continue;
    }
    runner.Run(StepKind::kModelAfter, ti,
               [&] { r.model_after = SolveSetup(result.diagnosis->updated, test.setup, result.UpdatedModelPath()); });
    if (!r.fit) {
      runner.Skip(StepKind::kCorrelateAfter, ti, "no test modes");
      continue;
    }
    runner.Run(StepKind::kCorrelateAfter, ti, [&] {
      if (!r.model_after) throw InputError(result.UpdatedModelPath().string(), "the updated model's modes are missing");
      r.correlation_after = correlation::Correlate(r.fit->stored_modes, r.model_after->modes, {});
    });
  }

  // The data-quality checks of each test's FRFs in the fit band (the report's "Data quality").
  for (std::size_t t = 0; t < test_count; ++t) {
    const formats::ProjectTest& test = project.tests[t];
    TestResult& r = result.tests[t];
    if (!r.frfs && test.frf) {
      try {
        r.frfs = formats::ReadFrfSet(*test.frf);
      } catch (const std::exception& e) {
        result.problems.push_back({static_cast<int>(t), "FRFs", e.what()});
      }
    }
    if (!r.frfs) continue;
    const curvefit::FitDataOptions& band = project.fit.data;
    if (band.band_hi_hz > band.band_lo_hz) {
      r.quality_options.band_lo_hz = band.band_lo_hz;
      r.quality_options.band_hi_hz = band.band_hi_hz;
    }
    try {
      r.quality = frf::CheckFrfQuality({*r.frfs}, r.quality_options, {result.FrfPath(t).string()});
    } catch (const std::exception& e) {
      result.problems.push_back({static_cast<int>(t), "data-quality checks", e.what()});
    }
  }
  Mean(result.tests, false, &result.mean_agreement_before, &result.mean_mac_before);
  Mean(result.tests, true, &result.mean_agreement_after, &result.mean_mac_after);
  return result;
}

}  // namespace ema::pipeline
