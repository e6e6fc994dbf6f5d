// A rehearsal in `ema run` (issue 40): a project test with plan = "PLAN.toml" is simulated from the
// plan (pipeline::SimulateTest, the code of `ema simulate`) on the truth it names, then run as a
// measured test. The guideway's planned tests on its truth (the carriage with a Hertz contact at
// every stud, samples/guideway/truth) must name that contact at rank 1 with the truth's stiffness;
// the same plans on the nominal model itself must find nothing missing.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <variant>
#include <vector>

#include "ema/core/error.hpp"
#include "ema/formats/project_file.hpp"
#include "ema/pipeline/run.hpp"

namespace ema::pipeline {
namespace {

namespace fs = std::filesystem;

const fs::path kGuideway = fs::path(EMA_SOURCE_DIR) / "samples" / "guideway";

// A guideway project whose tests are the sample's plans for `setups`, simulated on `truth` (none:
// the project's model); `extra` goes into the first [[test]].
fs::path WriteProject(const std::string& name, const std::string& truth, const std::vector<std::string>& setups,
                      const std::string& extra = "") {
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / ("rehearsal-" + name);
  fs::create_directories(dir);
  const fs::path file = dir / "project.toml";
  std::ofstream out(file);
  out << "[project]\nname = \"" << name << "\"\nmodel = \"" << (kGuideway / "model.toml").string() << "\"\n";
  for (const std::string& setup : setups) {
    out << "[[test]]\nsetup = \"" << setup << "\"\nplan = \"" << (kGuideway / "truth" / ("plan-" + std::string(setup) + ".toml")).string()
        << "\"\nsensor_mass = 0.0112\n";
    if (!truth.empty()) out << "truth = \"" << truth << "\"\n";
    if (setup == setups.front()) out << extra;
  }
  out << "[fit]\nband = [100.0, 450.0]\n";
  return file;
}

TEST(Rehearsal, PlannedTestsOnTheTruthNameItsHertzContactAtItsStiffness) {
  const fs::path project = WriteProject("truth", (kGuideway / "truth" / "model.toml").string(), {"stud-5um", "stud-9um"});
  const RunResult run = pipeline::Run(PlanFromProject(formats::ReadProjectFile(project), project.parent_path() / "out"));
  ASSERT_TRUE(run.Succeeded());
  ASSERT_EQ(run.tests.size(), 2u);
  for (const TestResult& t : run.tests) {
    ASSERT_TRUE(t.simulated);
    // The plans: 4 roving sets, 3 hammer references, 5 impacts each, the carriage's 5 rigid-body modes.
    EXPECT_EQ(t.simulated->sets, 4);
    EXPECT_EQ(t.simulated->references, 3);
    EXPECT_EQ(t.simulated->modes, 5);
    ASSERT_TRUE(t.fit);
    EXPECT_EQ(t.fit->fit.modes.modes.size(), 5u);
  }
  EXPECT_EQ(run.steps.front().kind, StepKind::kSimulate);
  ASSERT_TRUE(run.diagnosis);
  const Findings& f = run.diagnosis->findings;
  ASSERT_EQ(f.effects.size(), 1u);
  EXPECT_EQ(f.effects[0].effect.target, model::EffectTarget::Named("bearings"));
  ASSERT_TRUE(f.effects[0].effect.law);
  const auto* series = std::get_if<model::SeriesLaw>(&f.effects[0].effect.law->value);
  const model::HertzLaw* hertz = std::get_if<model::HertzLaw>(&f.effects[0].effect.law->value);
  if (!hertz && series)
    for (const model::Law& e : series->elements)
      if (!hertz) hertz = std::get_if<model::HertzLaw>(&e.value);
  ASSERT_TRUE(hertz) << "rank 1's law is " << f.effects[0].effect.law->KindName();
  // A Hertz contact's stiffness goes with E'·√R' (k = 2 E' √(R' δ)... at a given force, k³ ∝ E'² R'
  // F): the fit fixes R' and finds E', so E'·√R' is what the data determine. The truth's studs:
  // E' = 58 GPa, R' = 8.29 mm. 1 %: the 1 % noise of the plans moves the five frequencies ~0.02 %.
  const double truth = 5.8e10 * std::sqrt(0.00829);
  EXPECT_NEAR(hertz->modulus * std::sqrt(hertz->radius) / truth, 1.0, 0.01);
  EXPECT_TRUE(f.adequate);
  EXPECT_GT(f.rank_one_probability, 0.9);
}

TEST(Rehearsal, PlannedTestsOnTheNominalModelFindNothingMissing) {
  // stud-9um only: at stud-5um the nominal model's modes (its air film alone, far stiffer than the
  // truth's film in series with the studs) lie above the 450 Hz band — that rehearsal finds no mode.
  const fs::path project = WriteProject("nominal", "", {"stud-9um"});
  const RunResult run = pipeline::Run(PlanFromProject(formats::ReadProjectFile(project), project.parent_path() / "out"));
  ASSERT_TRUE(run.Succeeded());
  ASSERT_TRUE(run.diagnosis);
  EXPECT_TRUE(run.diagnosis->diagnosis.candidates.front().IsNone())
      << "rank 1: " << run.diagnosis->diagnosis.candidates.front().kind << " on "
      << run.diagnosis->diagnosis.candidates.front().target;
  EXPECT_TRUE(run.diagnosis->findings.adequate);
}

TEST(Rehearsal, AProjectTestTakesOneSourceAndATruthOnlyWithAPlan) {
  // plan beside time: one source per test.
  const fs::path both =
      WriteProject("both", "", {"stud-5um"}, "time = [\"" + (kGuideway / "data" / "stud-5um.unv").string() + "\"]\n");
  try {
    formats::ReadProjectFile(both);
    ADD_FAILURE() << "a test with both plan and time was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(both.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("more than one of time, frf and plan"), std::string::npos) << e.what();
  }
  // truth without plan.
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / "rehearsal-truth-alone";
  fs::create_directories(dir);
  const fs::path file = dir / "project.toml";
  std::ofstream(file) << "[project]\nmodel = \"" << (kGuideway / "model.toml").string() << "\"\n[[test]]\nsetup = \"stud-5um\"\ntime = [\""
                      << (kGuideway / "data" / "stud-5um.unv").string() << "\"]\ntruth = \""
                      << (kGuideway / "truth" / "model.toml").string() << "\"\n";
  try {
    formats::ReadProjectFile(file);
    ADD_FAILURE() << "a truth without a plan was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(file.string() + ":6"), std::string::npos) << e.what();  // the truth's line
    EXPECT_NE(std::string(e.what()).find("give plan"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ema::pipeline
